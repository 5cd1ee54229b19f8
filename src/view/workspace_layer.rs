//! The workspace as a layer of the viewer (`lsdc view --workspace FRAME`): the reachable
//! positions of a point sampled as `lsdc workspace` samples them, drawn in the 3-D scene as
//! dots coloured by their dexterity on the scale of `lsdc workspace --plot` (yellow, the best
//! conditioned, to purple; grey where singular), the boundary samples and the singular loci as
//! layers of their own, each toggled like the viewer's other layers.

use serde::Serialize;

use crate::output::workspace_plot::{DexterityScale, Slices};

/// What the page draws of a workspace; positions in the fixed frame (metres).
#[derive(Clone, Debug, Serialize)]
pub struct WorkspaceLayer {
    pub title: String,
    /// The reachable positions.
    pub points: Vec<[f64; 3]>,
    /// Each point's colour (red, green, blue), by its dexterity.
    pub colours: Vec<[u8; 3]>,
    /// The indices of the points on the boundary.
    pub boundary: Vec<usize>,
    /// Where singular loci cross the workspace.
    pub singular: Vec<[f64; 3]>,
    /// The smallest and largest finite dexterity: the scale's two ends (`None`: every point
    /// singular).
    pub dexterity: Option<[f64; 2]>,
}

impl From<&Slices> for WorkspaceLayer {
    fn from(slices: &Slices) -> WorkspaceLayer {
        let scale = DexterityScale::of(&slices.points);
        WorkspaceLayer {
            title: slices.title.clone(),
            points: slices.points.iter().map(|p| p.position).collect(),
            colours: (slices.points.iter())
                .map(|p| scale.colour(p.dexterity))
                .collect(),
            boundary: (slices.points.iter().enumerate())
                .filter(|(_, p)| p.boundary)
                .map(|(k, _)| k)
                .collect(),
            singular: slices.singular.clone(),
            dexterity: scale.range().map(|(best, worst)| [best, worst]),
        }
    }
}
