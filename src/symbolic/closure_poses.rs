//! The loops at position level: for each complementary link, the pose (rotation and origin, fixed
//! axes) of the end of its chain and of its target frame, which coincide exactly where the loop
//! is closed; and every body's twist per coordinate rate (the columns of the thesis's Ψᵢ). The
//! exact mobility (`kinematics::exact`) evaluates them to prove that a configuration is closed
//! and to count the tree's degrees of freedom; the equations of motion do not need them.

use super::expr::{ExprId, Pool};
use super::generator::Generator;
use super::lower::{LowerError, Variables};
use super::vector::{Mat3, Vec3};
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::topology::Topology;

/// One complementary link's two frames as expressions of the coordinates.
pub struct LoopPoses {
    /// The join's name.
    pub name: String,
    /// The first frame carried along the link's dof chain.
    pub end: (Mat3, Vec3),
    /// The second frame.
    pub target: (Mat3, Vec3),
}

pub struct ClosurePoses {
    pub pool: Pool,
    pub variables: Variables,
    pub loops: Vec<LoopPoses>,
    /// Per body (by number, earth left out), per coordinate: its angular velocity and the
    /// velocity of its origin for a unit rate of that coordinate (`None` when both are zero).
    pub body_columns: Vec<Vec<Option<[Vec3; 2]>>>,
}

/// The poses of every loop and the bodies' twist columns of a mechanism numbered by `topology`.
pub fn closure_poses(
    mechanism: &Mechanism,
    topology: &Topology,
) -> Result<ClosurePoses, Vec<Diagnostic>> {
    let mut generator = Generator::new(mechanism, topology);
    generator.poses().map_err(|e| {
        let error = Diagnostic::error(
            "E1101",
            format!("the loops' closure cannot be written: {}", e.0),
        );
        vec![match generator.context {
            Some(span) => error.primary(span, "in this declaration"),
            None => error,
        }]
    })
}

impl Generator<'_> {
    fn poses(&mut self) -> Result<ClosurePoses, LowerError> {
        self.place_bodies()?;
        let mut loops = Vec::new();
        for link in &self.topology.complementary {
            let (end, target) = self.loop_frames(link)?;
            loops.push(LoopPoses {
                name: self.mechanism.join_name(link.join),
                end: (end.rotation, end.origin),
                target: (target.rotation, target.origin),
            });
        }
        let body_columns = self.bodies[1..].iter().map(|b| b.columns.clone()).collect();
        Ok(ClosurePoses {
            pool: std::mem::take(&mut self.pool),
            variables: self.lowering.variables.clone(),
            loops,
            body_columns,
        })
    }
}

/// Every expression of `poses`, for a caller that walks them.
pub fn roots(poses: &ClosurePoses) -> Vec<ExprId> {
    let mut roots = Vec::new();
    for l in &poses.loops {
        for (r, o) in [&l.end, &l.target] {
            roots.extend(r.iter().flatten().copied());
            roots.extend(o.iter().copied());
        }
    }
    roots
}
