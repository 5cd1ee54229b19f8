//! The efforts of the equations: the applied efforts as wrenches on their bodies (𝔉), and the
//! links' own efforts as generalised forces on their coordinates.

use super::expr::ExprId;
use super::generator::Generator;
use super::kinematics::{LinkCoordinates, Moving, Step};
use super::lower::{FrameState, LowerError};
use super::vector::Wrench;
use super::vector::{self as v, Vec3};
use crate::elab::mechanism::EffortKind;
use crate::elab::value::{BodyRef, JoinId};

impl Generator<'_> {
    /// The state of every frame the efforts refer to (`position(F)`, …), for the lowering.
    pub(super) fn frame_states(&mut self) -> Result<(), LowerError> {
        let mut frames = Vec::new();
        let applied = self
            .mechanism
            .applications
            .iter()
            .flat_map(|a| self.mechanism.effort(a.effort).value.value().iter());
        let links = self.mechanism.links.iter().flat_map(|l| {
            l.forces
                .iter()
                .chain(&l.torques)
                .flat_map(|(_, v)| v.iter())
        });
        for s in applied.chain(links) {
            s.frames_used(&mut frames);
        }
        for frame in frames {
            let steps = self.steps(&frame.displacement, None)?;
            let body = match frame.body {
                BodyRef::Earth => 0,
                BodyRef::Body(id) => *self.topology.number_of.get(&id).ok_or_else(|| {
                    LowerError("the state of a frame on a body outside the mechanism".to_string())
                })?,
            };
            let mut moving = self.bodies[body].clone();
            self.walk(&mut moving, &steps, &LinkCoordinates::default());
            let state = FrameState {
                position: moving.origin,
                velocity: moving.velocity,
                angular_velocity: moving.angular_velocity,
                orientation: moving.rotation,
            };
            self.lowering.frames.push((frame, state));
        }
        Ok(())
    }

    /// 𝔉: every `apply` as a wrench at its body's origin, fixed axes.
    pub(super) fn applied_wrenches(&mut self) -> Result<Vec<Option<Wrench>>, LowerError> {
        let mut wrenches: Vec<Option<Wrench>> = vec![None; self.topology.body_count() + 1];
        for application in &self.mechanism.applications {
            let b = self.topology.number(application.target.body);
            if b == 0 {
                continue;
            }
            self.context = Some(application.span);
            let effort = self.mechanism.effort(application.effort);
            let value = self
                .lowering
                .vector(&mut self.pool, effort.value.value(), None)?;
            let value = match effort.basis {
                BodyRef::Earth => value,
                BodyRef::Body(id) => {
                    let basis = self.topology.number_of.get(&id).copied().ok_or_else(|| {
                        LowerError(
                            "an effort is written in the basis of a body outside the mechanism"
                                .to_string(),
                        )
                    })?;
                    v::mat_vec(&mut self.pool, &self.bodies[basis].rotation, &value)
                }
            };
            let zero = v::zero(&mut self.pool);
            let wrench = match effort.kind {
                EffortKind::Torque => [zero, value],
                EffortKind::Force => {
                    let (_, point) = self.pose(&application.target.displacement)?;
                    let arm = v::mat_vec(&mut self.pool, &self.bodies[b].rotation, &point);
                    [value, v::cross(&mut self.pool, &arm, &value)]
                }
            };
            wrenches[b] = Some(match wrenches[b] {
                Some([f, m]) => [
                    v::add(&mut self.pool, &f, &wrench[0]),
                    v::add(&mut self.pool, &m, &wrench[1]),
                ],
                None => wrench,
            });
        }
        Ok(wrenches)
    }

    /// The links' own efforts (`force`, `torque`, `forceN`, `torqueN`): the wrench, in the frame
    /// of the chain's start (or of step N), against the twist each coordinate gives there.
    pub(super) fn add_link_efforts(&mut self, forces: &mut [ExprId]) -> Result<(), LowerError> {
        let joins: Vec<JoinId> = self
            .topology
            .principal
            .iter()
            .map(|l| l.join)
            .chain(self.topology.complementary.iter().map(|l| l.join))
            .collect();
        for join in joins {
            self.context = Some(self.mechanism.join(join).span);
            let link = self.mechanism.link(self.mechanism.join(join).link);
            let efforts: Vec<_> = [
                (EffortKind::Force, &link.forces),
                (EffortKind::Torque, &link.torques),
            ]
            .into_iter()
            .flat_map(|(kind, list)| {
                list.iter()
                    .map(move |(step, value)| (kind, *step, value.clone()))
            })
            .collect();
            if efforts.is_empty() {
                continue;
            }
            let coordinates = self.link_coordinates(join);
            let chain = self.chain(join)?;
            for (kind, step, value) in efforts {
                if step != 0 && self.lowering.ball(join).is_some() {
                    return Err(LowerError(format!(
                        "an effort on step {step} of `{}`, whose chain the simulator's state holds as a quaternion",
                        self.mechanism.join_name(join)
                    )));
                }
                let value = self.lowering.vector(&mut self.pool, &value, Some(join))?;
                let twists = self.chain_twists(&chain, step, &coordinates);
                for (k, [angular, linear]) in twists.into_iter().enumerate() {
                    let along = match kind {
                        EffortKind::Force => v::dot(&mut self.pool, &linear, &value),
                        EffortKind::Torque => v::dot(&mut self.pool, &angular, &value),
                    };
                    let column = coordinates.columns[k];
                    forces[column] = self.pool.add(forces[column], along);
                }
            }
        }
        Ok(())
    }

    /// Per coordinate of the link, the twist (angular, linear at the frame's origin) a unit rate
    /// gives: of the chain's end in its first frame (`step` 0), or of step N in its own frame.
    fn chain_twists(
        &mut self,
        chain: &[Step],
        step: u8,
        coordinates: &LinkCoordinates,
    ) -> Vec<[Vec3; 2]> {
        let columns = self.columns();
        let mut frame = Moving::fixed(&mut self.pool, columns);
        let steps = if step == 0 {
            chain
        } else {
            &chain[step as usize - 1..step as usize]
        };
        self.walk(&mut frame, steps, coordinates);
        let zero = v::zero(&mut self.pool);
        coordinates
            .columns
            .iter()
            .map(|&c| {
                let [angular, linear] = frame.column(c).copied().unwrap_or([zero, zero]);
                if step != 0 {
                    return [angular, linear];
                }
                // At the first frame's origin: v − ω ∧ (end origin).
                let lever = v::cross(&mut self.pool, &angular, &frame.origin);
                [angular, v::sub(&mut self.pool, &linear, &lever)]
            })
            .collect()
    }
}
