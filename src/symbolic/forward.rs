//! The tree's forward dynamics set up for the articulated-body recursion (`articulated`), in each
//! body's own axes: there the body's inertia and its joint's columns are the program's
//! constants (a revolute joint's column is its axis), so the generated code folds them, as the
//! numeric algorithms keep them in body frames. Bodies welded to their parent ride with their
//! anchor (`inertia`).

use super::articulated::{self, Spatial};
use super::expr::ExprId;
use super::generator::Generator;
use super::kinematics::{LinkCoordinates, Step};
use super::quaternion_joints;
use super::vector::Wrench;
use super::vector::{self as v, Vec3};

impl Generator<'_> {
    /// The coordinates' second derivatives of a tree, given the applied efforts (wrenches at the
    /// bodies' origins, fixed axes) and the links' generalised forces.
    pub(super) fn articulated(
        &mut self,
        applied: &[Option<Wrench>],
        link_forces: &[ExprId],
    ) -> Vec<ExprId> {
        let loads = self.loads_on_anchors(applied);
        let zero = self.pool.constant(0.0);
        let moving: Vec<usize> = (1..=self.topology.body_count())
            .filter(|&b| self.anchors[b] == b)
            .collect();
        let mut index = vec![0; self.topology.body_count() + 1];
        let root = articulated::Body {
            parent: 0,
            arm: v::zero(&mut self.pool),
            rotation: None,
            columns: Vec::new(),
            bias: [zero; 6],
            inertia: None,
            bias_force: [zero; 6],
        };
        let mut bodies = vec![root];
        let mut velocities: Vec<Spatial> = vec![[zero; 6]];
        for &b in &moving {
            index[b] = bodies.len();
            let parent = index[self.anchors[self.topology.parent(b)]];
            let (body, velocity) = self.articulated_body(b, parent, &velocities[parent], &loads[b]);
            bodies.push(body);
            velocities.push(velocity);
        }
        articulated::accelerations(&mut self.pool, &bodies, link_forces)
    }

    /// The applied wrenches, those of welded bodies moved to their anchors' origins.
    fn loads_on_anchors(&mut self, applied: &[Option<Wrench>]) -> Vec<Option<Wrench>> {
        let mut loads: Vec<Option<Wrench>> = vec![None; applied.len()];
        for (b, wrench) in applied.iter().enumerate().skip(1) {
            let (Some(wrench), anchor) = (wrench, self.anchors[b]) else {
                continue;
            };
            if anchor == 0 {
                continue; // On a body welded to earth.
            }
            let pool = &mut self.pool;
            let arm = v::sub(pool, &self.bodies[b].origin, &self.bodies[anchor].origin);
            let lever = v::cross(pool, &arm, &wrench[0]);
            let moment = v::add(pool, &wrench[1], &lever);
            loads[anchor] = Some(match loads[anchor] {
                Some([f, m]) => [v::add(pool, &f, &wrench[0]), v::add(pool, &m, &moment)],
                None => [wrench[0], moment],
            });
        }
        loads
    }

    /// Body `b` for the recursion, below `parent` (moving with `parent_velocity`), and its velocity.
    fn articulated_body(
        &mut self,
        b: usize,
        parent: usize,
        parent_velocity: &Spatial,
        loads: &Option<Wrench>,
    ) -> (articulated::Body, Spatial) {
        let steps = self.steps_from_anchor(b);
        let coordinates = self.link_coordinates(self.topology.principal[b - 1].join);
        let (rotation, arm) = self.compose(&steps);
        let columns = self.child_frame_columns(&steps, &coordinates);
        let pool = &mut self.pool;
        let derivatives = &mut self.derivatives;
        let zero = pool.constant(0.0);
        // v_J = S q̇ and c_J = Ṡ q̇ (S's derivative in the body's own axes).
        let mut joint_velocity = [zero; 6];
        for (column, &rate) in columns.iter().zip(&coordinates.rates) {
            let scaled = column.map(|x| pool.mul(x, rate));
            joint_velocity = articulated::add(pool, &joint_velocity, &scaled);
        }
        let mut joint_bias = [zero; 6];
        let position_rates = coordinates
            .positions
            .iter()
            .zip(&coordinates.position_rates);
        for (&position, &rate) in position_rates {
            let derivative = joint_velocity.map(|x| derivatives.of(pool, x, position));
            let scaled = derivative.map(|x| pool.mul(x, rate));
            joint_bias = articulated::add(pool, &joint_bias, &scaled);
        }
        let mut body = articulated::Body {
            parent,
            arm,
            rotation: Some(rotation),
            columns: coordinates.columns.iter().copied().zip(columns).collect(),
            bias: [zero; 6],
            inertia: None,
            bias_force: [zero; 6],
        };
        let carried = articulated::motion_to_child(pool, &body, parent_velocity);
        let velocity = articulated::add(pool, &carried, &joint_velocity);
        let coupling = cross_motion(pool, &velocity, &joint_velocity);
        body.bias = articulated::add(pool, &joint_bias, &coupling);
        let inertia = self.local_inertias[b];
        let products = match inertia {
            Some(m) => {
                let momentum = m.times(pool, &angular(&velocity), &linear(&velocity));
                cross_force(pool, &velocity, &momentum)
            }
            None => [v::zero(pool); 2],
        };
        let frame = v::transpose(&self.bodies[b].rotation);
        let applied = loads
            .map(|[f, m]| [v::mat_vec(pool, &frame, &f), v::mat_vec(pool, &frame, &m)])
            .unwrap_or([v::zero(pool); 2]);
        let force = v::sub(pool, &products[0], &applied[0]);
        let moment = v::sub(pool, &products[1], &applied[1]);
        body.bias_force = [
            force[0], force[1], force[2], moment[0], moment[1], moment[2],
        ];
        body.inertia = inertia.map(|m| m.matrix(pool));
        (body, velocity)
    }

    /// The steps from `b`'s anchor parent to `b`: through the bodies welded between them.
    fn steps_from_anchor(&self, b: usize) -> Vec<Step> {
        let anchor = self.anchors[self.topology.parent(b)];
        let mut path = vec![b];
        let mut w = self.topology.parent(b);
        while w != anchor {
            path.push(w);
            w = self.topology.parent(w);
        }
        path.iter()
            .rev()
            .flat_map(|&w| self.link_steps[w].iter().cloned())
            .collect()
    }

    /// The columns S of a chain of steps in the axes of its end frame, at its origin (linear
    /// part first), one per rate of `link`: each step's own motion moved along the steps that
    /// follow it.
    fn child_frame_columns(&mut self, steps: &[Step], link: &LinkCoordinates) -> Vec<Spatial> {
        let zero = self.pool.constant(0.0);
        let mut columns = vec![[zero; 6]; link.rates.len()];
        // The end frame's pose in the frame after the current step.
        let mut turned = v::identity(&mut self.pool);
        let mut offset = v::zero(&mut self.pool);
        for step in steps.iter().rev() {
            let count = match step {
                Step::Ball { .. } => link.rates.len(),
                // A ball's link: its positions only its own step reads.
                _ if link.positions.len() != link.rates.len() => 0,
                _ => link.positions.len(),
            };
            for (k, total) in columns.iter_mut().enumerate().take(count) {
                let Some((angular, linear)) = self.own_motion(step, link, k) else {
                    continue;
                };
                let pool = &mut self.pool;
                let back = v::transpose(&turned);
                let spin = v::cross(pool, &angular, &offset);
                let moved = v::add(pool, &linear, &spin);
                let (w, u) = (
                    v::mat_vec(pool, &back, &angular),
                    v::mat_vec(pool, &back, &moved),
                );
                let column = [u[0], u[1], u[2], w[0], w[1], w[2]];
                *total = articulated::add(pool, total, &column);
            }
            let pool = &mut self.pool;
            match step {
                Step::Rotation { axis, angle } => {
                    let turn = v::rotation(pool, axis, *angle);
                    turned = v::mat_mul(pool, &turn, &turned);
                    offset = v::mat_vec(pool, &turn, &offset);
                }
                Step::Translation(t) => offset = v::add(pool, t, &offset),
                Step::Ball {
                    translation,
                    quaternion,
                } => {
                    let turn = quaternion_joints::rotation(pool, quaternion);
                    turned = v::mat_mul(pool, &turn, &turned);
                    offset = v::mat_vec(pool, &turn, &offset);
                    if let Some(t) = translation {
                        offset = v::add(pool, t, &offset);
                    }
                }
            }
        }
        columns
    }

    /// The motion (angular, linear) a unit rate k of `link` gives `step`'s end frame, in the
    /// axes after the step and at its origin; `None` where it gives none. A declared
    /// coordinate's rate is its position's: the step's derivative by it. A ball's rates are its
    /// body twist, in the axes after it: unit motions there (angular, then linear).
    fn own_motion(
        &mut self,
        step: &Step,
        link: &LinkCoordinates,
        k: usize,
    ) -> Option<(Vec3, Vec3)> {
        let pool = &mut self.pool;
        let (angular, linear) = match step {
            Step::Ball { .. } => {
                let mut unit = [0.0; 3];
                unit[k % 3] = 1.0;
                let (unit, zero) = (v::constant(pool, unit), v::zero(pool));
                return Some(if k < 3 { (unit, zero) } else { (zero, unit) });
            }
            Step::Rotation { axis, angle } => {
                let rate = self.derivatives.of(pool, *angle, link.positions[k]);
                (v::scale(pool, rate, axis), v::zero(pool))
            }
            Step::Translation(t) => {
                let rates = t.map(|x| self.derivatives.of(pool, x, link.positions[k]));
                (v::zero(pool), rates)
            }
        };
        let moves = !v::is_zero(pool, &angular) || !v::is_zero(pool, &linear);
        moves.then_some((angular, linear))
    }
}

fn linear(x: &Spatial) -> Vec3 {
    [x[0], x[1], x[2]]
}

fn angular(x: &Spatial) -> Vec3 {
    [x[3], x[4], x[5]]
}

/// a ×ₘ b for motions (v, ω): (ω_a ∧ v_b + v_a ∧ ω_b, ω_a ∧ ω_b).
fn cross_motion(pool: &mut super::expr::Pool, a: &Spatial, b: &Spatial) -> Spatial {
    let l1 = v::cross(pool, &angular(a), &linear(b));
    let l2 = v::cross(pool, &linear(a), &angular(b));
    let l = v::add(pool, &l1, &l2);
    let w = v::cross(pool, &angular(a), &angular(b));
    [l[0], l[1], l[2], w[0], w[1], w[2]]
}

/// a ×f f for a motion (v, ω) and a force (F, N): (ω ∧ F, ω ∧ N + v ∧ F).
fn cross_force(pool: &mut super::expr::Pool, a: &Spatial, f: &Wrench) -> Wrench {
    let force = v::cross(pool, &angular(a), &f[0]);
    let n1 = v::cross(pool, &angular(a), &f[1]);
    let n2 = v::cross(pool, &linear(a), &f[0]);
    [force, v::add(pool, &n1, &n2)]
}
