//! The loops: six constraint rows per complementary link, Δ(p) q = 0, and their acceleration
//! terms Δ̇q.

use super::expr::ExprId;
use super::generator::Generator;
use super::kinematics::{LinkCoordinates, Moving};
use super::lower::LowerError;
use crate::topology::LoopLink;

/// The names of a complementary link's six constraint rows: rotations, then translations.
pub const ROW_NAMES: [&str; 6] = ["rx", "ry", "rz", "x", "y", "z"];

/// Δ (row-major), Δ̇q and the rows' names.
pub(super) struct Closure {
    pub rows: Vec<ExprId>,
    pub bias: Vec<ExprId>,
    pub names: Vec<String>,
}

impl Generator<'_> {
    /// A complementary link's two frames, from the bodies placed: its chain's end (the first
    /// body's frame, the link's first displacement, then the chain at the link's coordinates)
    /// and its target (the second body's frame and its displacement).
    pub(super) fn loop_frames(&mut self, link: &LoopLink) -> Result<(Moving, Moving), LowerError> {
        let join = self.mechanism.join(link.join);
        self.context = Some(join.span);
        let to_start = self.steps(&join.first.displacement, None)?;
        let chain = self.chain(link.join)?;
        let to_target = self.steps(&join.second.displacement, None)?;
        let coordinates = self.link_coordinates(link.join);
        let mut end = self.bodies[link.first].clone();
        self.walk(&mut end, &to_start, &LinkCoordinates::default());
        self.walk(&mut end, &chain, &coordinates);
        let mut target = self.bodies[link.second].clone();
        self.walk(&mut target, &to_target, &LinkCoordinates::default());
        Ok((end, target))
    }

    /// Six rows per complementary link: the twist of its target frame minus that of its chain's
    /// end, whose time derivative gives the acceleration rows.
    pub(super) fn loops(&mut self) -> Result<Closure, LowerError> {
        let n = self.columns();
        let (mut rows, mut bias, mut names) = (Vec::new(), Vec::new(), Vec::new());
        for link in &self.topology.complementary {
            let (end, target) = self.loop_frames(link)?;
            let name = self.mechanism.join_name(link.join);
            for (r, row) in ROW_NAMES.iter().enumerate() {
                let (part, i) = (r / 3, r % 3);
                for c in 0..n {
                    let component = |frame: &Moving| frame.column(c).map(|twist| twist[part][i]);
                    let zero = self.pool.constant(0.0);
                    let (t, e) = (
                        component(&target).unwrap_or(zero),
                        component(&end).unwrap_or(zero),
                    );
                    rows.push(self.pool.sub(t, e));
                }
                let pick = |frame: &Moving| {
                    if part == 0 {
                        frame.angular_bias[i]
                    } else {
                        frame.bias[i]
                    }
                };
                bias.push(self.pool.sub(pick(&target), pick(&end)));
                names.push(format!("{name}.{row}"));
            }
        }
        Ok(Closure { rows, bias, names })
    }
}
