//! The dof chains as they were evaluated before they were compiled: trees walked with jets.
//! Kept only to check the compiled chains against it.

use nalgebra::{DMatrix, Vector3};

use crate::elab::value::Scalar;

use super::eval::{eval_by_trees as eval, eval_jet, Env, EvalError, UnknownValues};
use super::model::{ChainMotion, JointModel, Step};
use crate::spatial::{self, Pose, Twist};

impl JointModel {
    /// The chain's transform, motion subspace and, when rates are given, the acceleration of the
    /// chain's end (in the first frame, as a twist derivative) when the coordinates move at those
    /// rates with no coordinate acceleration: the bias term of the joint.
    pub fn interpreted_chain_motion(
        &self,
        q: &[f64],
        rates: Option<&[f64]>,
        unknowns: &UnknownValues,
    ) -> Result<ChainMotion, EvalError> {
        let mut motion = ChainMotion::default();
        self.interpreted_chain_motion_into(q, rates, unknowns, &mut motion)?;
        Ok(motion)
    }

    /// `chain_motion` into `out`, reusing its storage: nothing is allocated once it has held
    /// this chain's motion.
    pub fn interpreted_chain_motion_into(
        &self,
        q: &[f64],
        rates: Option<&[f64]>,
        unknowns: &UnknownValues,
        out: &mut ChainMotion,
    ) -> Result<(), EvalError> {
        let n = self.coordinate_count();
        let env = Env { coordinates: q };
        let (mut unit, mut rest) = (Vec::new(), Vec::new());
        let (unit, rest) = (&mut unit, &mut rest);
        let ChainMotion {
            pose,
            subspace,
            velocity,
            bias,
            ..
        } = out;
        rest.clear();
        rest.resize(n, 0.0);
        unit.clear();
        unit.resize(n, 0.0);
        let rates = rates.unwrap_or(rest);
        if subspace.ncols() == n {
            subspace.fill(0.0);
        } else {
            *subspace = DMatrix::zeros(6, n);
        }
        (*pose, *velocity, *bias) = (Pose::identity(), Twist::zeros(), Twist::zeros());
        if let Some(single) = self.single_motion() {
            // One rotation or translation along a fixed axis, proportional to the coordinate:
            // its subspace is that constant twist, its bias zero; nothing to evaluate.
            let column = match single {
                super::model::SingleMotion::Rotation { axis, scale } => {
                    *pose = spatial::rotation(&axis, scale * q[0]);
                    spatial::twist(axis * scale, Vector3::zeros())
                }
                super::model::SingleMotion::Translation { direction } => {
                    *pose = spatial::translation(direction * q[0]);
                    spatial::twist(Vector3::zeros(), direction)
                }
            };
            subspace.column_mut(0).copy_from(&column);
            *velocity = column * rates[0];
            return Ok(());
        }
        for step in &self.steps {
            // Value and derivatives of the step's parameters along the rates, then per
            // coordinate (a column of the subspace, moved to the first frame).
            let (transform, local_velocity, local_bias) = match step {
                Step::Translation(v) => {
                    let along = [0, 1, 2].map(|i| eval_jet(&v[i], unknowns, &env, rates));
                    let [x, y, z] = along;
                    let (x, y, z) = (x?, y?, z?);
                    for k in 0..n {
                        unit[k] = 1.0;
                        let d = |i: usize| eval_jet(&v[i], unknowns, &env, unit).map(|j| j.first);
                        let column =
                            spatial::twist(Vector3::zeros(), Vector3::new(d(0)?, d(1)?, d(2)?));
                        unit[k] = 0.0;
                        add_moved(subspace, k, pose, &column);
                    }
                    let value = Vector3::new(x.value, y.value, z.value);
                    let velocity =
                        spatial::twist(Vector3::zeros(), Vector3::new(x.first, y.first, z.first));
                    let bias = spatial::twist(
                        Vector3::zeros(),
                        Vector3::new(x.second, y.second, z.second),
                    );
                    (spatial::translation(value), velocity, bias)
                }
                Step::Rotation { angle, axis } => {
                    let jet = eval_jet(angle, unknowns, &env, rates)?;
                    for k in 0..n {
                        unit[k] = 1.0;
                        let rate = eval_jet(angle, unknowns, &env, unit)?.first;
                        unit[k] = 0.0;
                        add_moved(
                            subspace,
                            k,
                            pose,
                            &spatial::twist(axis * rate, Vector3::zeros()),
                        );
                    }
                    let velocity = spatial::twist(axis * jet.first, Vector3::zeros());
                    let bias = spatial::twist(axis * jet.second, Vector3::zeros());
                    (spatial::rotation(axis, jet.value), velocity, bias)
                }
            };
            // d/dt of Ad(P) ξ is V_P × Ad(P) ξ + Ad(P) ξ̇ (spatial twists in the first frame).
            let step_velocity = spatial::motion_to_parent(pose, &local_velocity);
            *bias += cross(velocity, &step_velocity) + spatial::motion_to_parent(pose, &local_bias);
            *velocity += step_velocity;
            *pose *= transform;
        }
        Ok(())
    }

    /// ∂/∂q along `direction` of the chain's twist `S(q)·rates` (in the first frame): how the
    /// joint's velocity changes when its coordinates move while the rates stay put. With
    /// `direction = rates` this is the bias of `chain_motion`.
    pub fn interpreted_velocity_derivative(
        &self,
        q: &[f64],
        rates: &[f64],
        direction: &[f64],
        unknowns: &UnknownValues,
    ) -> Result<Twist, EvalError> {
        let env = Env { coordinates: q };
        let sum: Vec<f64> = rates.iter().zip(direction).map(|(a, b)| a + b).collect();
        // Mixed second derivative by polarisation: D²f[u, w] = (D²f[u + w] − D²f[u] − D²f[w]) / 2.
        let mixed = |s: &Scalar| -> Result<(f64, f64, f64), EvalError> {
            let along_rates = eval_jet(s, unknowns, &env, rates)?;
            let along_direction = eval_jet(s, unknowns, &env, direction)?;
            let along_sum = eval_jet(s, unknowns, &env, &sum)?;
            let second = 0.5 * (along_sum.second - along_rates.second - along_direction.second);
            Ok((along_rates.first, along_direction.first, second))
        };
        let mut pose = Pose::identity();
        let mut moved_frame = Twist::zeros();
        let mut derivative = Twist::zeros();
        for step in &self.steps {
            let (transform, local_rates, local_direction, local_mixed) = match step {
                Step::Translation(v) => {
                    let (x, y, z) = (mixed(&v[0])?, mixed(&v[1])?, mixed(&v[2])?);
                    let value = Vector3::new(
                        eval(&v[0], unknowns, q)?,
                        eval(&v[1], unknowns, q)?,
                        eval(&v[2], unknowns, q)?,
                    );
                    let zero = Vector3::zeros();
                    (
                        spatial::translation(value),
                        spatial::twist(zero, Vector3::new(x.0, y.0, z.0)),
                        spatial::twist(zero, Vector3::new(x.1, y.1, z.1)),
                        spatial::twist(zero, Vector3::new(x.2, y.2, z.2)),
                    )
                }
                Step::Rotation { angle, axis } => {
                    let (rate, along, second) = mixed(angle)?;
                    let zero = Vector3::zeros();
                    (
                        spatial::rotation(axis, eval(angle, unknowns, q)?),
                        spatial::twist(axis * rate, zero),
                        spatial::twist(axis * along, zero),
                        spatial::twist(axis * second, zero),
                    )
                }
            };
            let step_velocity = spatial::motion_to_parent(&pose, &local_rates);
            derivative += cross(&moved_frame, &step_velocity)
                + spatial::motion_to_parent(&pose, &local_mixed);
            moved_frame += spatial::motion_to_parent(&pose, &local_direction);
            pose *= transform;
        }
        Ok(derivative)
    }
}

fn add_moved(subspace: &mut DMatrix<f64>, k: usize, pose: &Pose, column: &Twist) {
    let moved = spatial::motion_to_parent(pose, column);
    for r in 0..6 {
        subspace[(r, k)] += moved[r];
    }
}

fn cross(a: &Twist, b: &Twist) -> Twist {
    let (wa, va) = (spatial::angular(a), spatial::linear(a));
    let (wb, vb) = (spatial::angular(b), spatial::linear(b));
    spatial::twist(wa.cross(&wb), wa.cross(&vb) + va.cross(&wb))
}
