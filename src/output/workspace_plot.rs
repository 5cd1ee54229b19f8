//! The slices of `lsdc workspace --plot`: the reachable positions of the point in four
//! horizontal slabs of equal height over its reach in z, each seen from above (x, y), coloured
//! by the dexterity (the condition number of the inverse velocity model, on a logarithmic
//! scale from yellow, well conditioned, to purple), the boundary samples ringed in black and
//! the singular loci (crossings between samples, singular points) as red crosses.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::studies::workspace::Workspace;
use crate::studies::workspace_positions::PositionWorkspace;

use super::plot::{write_figure, Figure, PlotError, Render, CAPTION_SIZE, LABEL_SIZE};

/// A reachable position and what the slices show of it.
#[derive(Clone, Copy, Debug)]
pub struct SlicePoint {
    pub position: [f64; 3],
    pub dexterity: Option<f64>,
    pub boundary: bool,
}

/// What the slices show: the reachable positions, and the singular loci.
#[derive(Clone, Debug)]
pub struct Slices {
    pub title: String,
    pub points: Vec<SlicePoint>,
    pub singular: Vec<[f64; 3]>,
}

/// The number of slabs (2 × 2 panels).
const SLABS: usize = 4;

/// Draws the slices to `path` (`.svg` or `.png`).
pub fn plot(slices: &Slices, path: &Path) -> Result<(), PlotError> {
    if slices.points.is_empty() {
        return Err(PlotError::NoOutputs);
    }
    write_figure(slices, path)
}

/// The smallest and largest of some values.
fn extent(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// The colours of the dexterity, shared by the slices and the viewer's workspace layer: a
/// logarithmic scale over the dexterities of the points, from yellow (the best conditioned) to
/// purple (the worst), through green and blue as viridis runs; grey where the dexterity is
/// infinite (a singular sample).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DexterityScale {
    /// log₁₀ of the smallest and largest finite dexterity (`None`: no finite one).
    pub logs: Option<(f64, f64)>,
}

impl DexterityScale {
    /// The scale spanning the dexterities of `points`.
    pub fn of(points: &[SlicePoint]) -> DexterityScale {
        let logs = extent(points.iter().filter_map(|p| p.dexterity).map(f64::log10));
        DexterityScale {
            logs: logs.0.is_finite().then_some(logs),
        }
    }

    /// The smallest and largest dexterity of the scale.
    pub fn range(&self) -> Option<(f64, f64)> {
        self.logs.map(|(lo, hi)| (10f64.powf(lo), 10f64.powf(hi)))
    }

    /// The colour (red, green, blue) of a dexterity.
    pub fn colour(&self, dexterity: Option<f64>) -> [u8; 3] {
        const SINGULAR: [u8; 3] = [160, 160, 160];
        match (dexterity, self.logs) {
            (Some(d), Some((lo, hi))) => viridis((d.log10() - lo) / (hi - lo).max(1e-12)),
            _ => SINGULAR,
        }
    }
}

/// A colour from yellow (0) to purple (1) through green and blue, as viridis runs.
fn viridis(t: f64) -> [u8; 3] {
    const STOPS: [(f64, f64, f64); 5] = [
        (253.0, 231.0, 37.0),
        (94.0, 201.0, 98.0),
        (33.0, 145.0, 140.0),
        (59.0, 82.0, 139.0),
        (68.0, 1.0, 84.0),
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - k as f64;
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    [mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2)]
}

impl From<&Workspace> for Slices {
    /// The slices of a workspace sampled over the actuated coordinates.
    fn from(workspace: &Workspace) -> Slices {
        Slices {
            title: format!(
                "workspace of `{}` over the actuated coordinates",
                workspace.point
            ),
            points: (workspace.samples.iter())
                .filter_map(|s| {
                    s.point.map(|position| SlicePoint {
                        position,
                        dexterity: s.dexterity,
                        boundary: s.boundary,
                    })
                })
                .collect(),
            singular: workspace.crossings.iter().map(|c| c.point).collect(),
        }
    }
}

impl From<&PositionWorkspace> for Slices {
    /// The slices of a workspace sampled over a box of positions.
    fn from(workspace: &PositionWorkspace) -> Slices {
        Slices {
            title: format!("workspace of `{}` over a box of positions", workspace.point),
            points: (workspace.samples.iter())
                .filter(|s| s.reachable)
                .map(|s| SlicePoint {
                    position: s.point,
                    dexterity: s.dexterity,
                    boundary: s.boundary,
                })
                .collect(),
            singular: (workspace.samples.iter())
                .filter(|s| s.reachable && s.dexterity.is_none())
                .map(|s| s.point)
                .collect(),
        }
    }
}

impl Figure for Slices {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        render: Render,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let error = PlotError::drawing::<DB::ErrorType>;
        let px = |length: f64| render.px(length);
        root.fill(&WHITE).map_err(error)?;
        let (x_range, y_range, z_range) = (
            extent(self.points.iter().map(|p| p.position[0])),
            extent(self.points.iter().map(|p| p.position[1])),
            extent(self.points.iter().map(|p| p.position[2])),
        );
        // Equal margins around the reach, the same in x and y (the slices are to scale).
        let half = 0.55 * (x_range.1 - x_range.0).max(y_range.1 - y_range.0).max(1e-9);
        let centre = (0.5 * (x_range.0 + x_range.1), 0.5 * (y_range.0 + y_range.1));
        let scale = DexterityScale::of(&self.points);
        let caption = match scale.range() {
            Some((best, worst)) => format!(
                "{}: dexterity from {best:.3} (yellow) to {worst:.3} (purple), boundary ringed, singular loci ×",
                self.title
            ),
            None => format!("{}: boundary ringed, singular loci ×", self.title),
        };
        let root = root
            .titled(&caption, render.font(CAPTION_SIZE * 0.8))
            .map_err(error)?;
        let height = (z_range.1 - z_range.0).max(1e-12) / SLABS as f64;
        for (slab, area) in root.split_evenly((2, 2)).iter().enumerate() {
            // From the top slab down.
            let top = z_range.1 - slab as f64 * height;
            let bottom = top - height;
            let inside = |z: f64| (bottom..=top).contains(&z);
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("z from {bottom:.4} to {top:.4} m"),
                    render.font(LABEL_SIZE),
                )
                .margin(px(10.0))
                .x_label_area_size(px(40.0))
                .y_label_area_size(px(64.0))
                .build_cartesian_2d(
                    centre.0 - half..centre.0 + half,
                    centre.1 - half..centre.1 + half,
                )
                .map_err(error)?;
            chart
                .configure_mesh()
                .x_desc("x (m)")
                .y_desc("y (m)")
                .label_style(render.font(LABEL_SIZE * 0.8))
                .axis_desc_style(render.font(LABEL_SIZE * 0.8))
                .bold_line_style(BLACK.mix(0.1).stroke_width(px(1.0)))
                .light_line_style(BLACK.mix(0.03).stroke_width(px(1.0)))
                .draw()
                .map_err(error)?;
            let in_slab: Vec<&SlicePoint> = (self.points.iter())
                .filter(|p| inside(p.position[2]))
                .collect();
            let at = |p: &[f64; 3]| (p[0], p[1]);
            chart
                .draw_series(in_slab.iter().map(|p| {
                    let [red, green, blue] = scale.colour(p.dexterity);
                    let fill = RGBColor(red, green, blue);
                    Circle::new(at(&p.position), px(3.0), fill.filled())
                }))
                .map_err(error)?;
            chart
                .draw_series(
                    (in_slab.iter().filter(|p| p.boundary)).map(|p| {
                        Circle::new(at(&p.position), px(4.0), BLACK.stroke_width(px(1.0)))
                    }),
                )
                .map_err(error)?;
            chart
                .draw_series(
                    (self.singular.iter().filter(|p| inside(p[2])))
                        .map(|p| Cross::new(at(p), px(6.0), RED.stroke_width(px(2.0)))),
                )
                .map_err(error)?;
        }
        Ok(())
    }
}
