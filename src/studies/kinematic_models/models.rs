//! The kinematic models at one configuration: the direct and inverse velocity models, their
//! acceleration terms and conditioning, and the singularity the configuration is at, classified
//! and its motion named.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::error::KinematicsError;
use super::motion_basis::{motion_basis, MotionBasis};
use super::output::{Actuation, Output};
use super::second_order::second_order;
use super::singular_values::{condition, kth, pseudo_inverse, weakest};
use crate::dynamics::loops::Constraints;
use crate::dynamics::model::Model;

/// A matrix as rows, for JSON.
pub type Rows = Vec<Vec<f64>>;

fn rows_of(m: &DMatrix<f64>) -> Rows {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// The kind of a singular configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SingularKind {
    /// The inverse model loses rank: a motion of the actuators leaves the frame still (for a
    /// tree, the frame's Jacobian loses rank).
    Type1,
    /// The direct model loses rank: a motion of the frame with the actuators locked.
    Type2,
    /// Both at once.
    Both,
}

impl SingularKind {
    pub fn describe(self) -> &'static str {
        match self {
            SingularKind::Type1 => {
                "type 1 (inverse model singular: the actuators move, the frame does not)"
            }
            SingularKind::Type2 => {
                "type 2 (direct model singular: the frame moves, the actuators are locked)"
            }
            SingularKind::Both => "types 1 and 2 at once",
        }
    }
}

/// The motion a singular configuration lets through: the coordinates it moves (largest first)
/// and the loops whose rows those coordinates enter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SingularMotion {
    pub coordinates: Vec<String>,
    /// Each coordinate's rate in that motion (unit norm in the mechanism's units).
    pub rates: Vec<f64>,
    pub loops: Vec<String>,
}

/// How close a configuration is to each type of singularity, and which one it is at.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Singularity {
    /// `None` away from singular configurations.
    pub kind: Option<SingularKind>,
    /// The smallest singular value of B, the frame's motion (its lengths divided by L) on an
    /// orthonormal basis of the non-idle motions (sliding rates divided by L): 0 at a type 1.
    /// The frame's points lie in the box of diagonal L, so it is at most about 1.
    pub type1_measure: f64,
    /// The smallest singular value of A, the actuated rates on that basis: 0 at a type 2, at
    /// most 1 (A is a block of an orthonormal matrix).
    pub type2_measure: f64,
    pub tolerance: f64,
    /// The motion of the actuators that leaves the frame still (at a type 1).
    pub type1_motion: Option<SingularMotion>,
    /// The motion of the frame with the actuators locked (at a type 2).
    pub type2_motion: Option<SingularMotion>,
    /// The motions of the smallest singular values of B and A, singular or not: what a
    /// passage between samples lets through (`singularities`).
    #[serde(skip)]
    pub weakest_motions: [Option<SingularMotion>; 2],
}

/// The kinematic models at one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct KinematicModels {
    pub actuated: Vec<String>,
    pub outputs: Vec<String>,
    /// The mechanism's characteristic length L (metres): the unit of the measures' lengths.
    pub characteristic_length: f64,
    /// The motions the loops allow, and how many of them are idle (move neither the actuated
    /// coordinates nor the frame).
    pub motions: usize,
    pub idle_motions: usize,
    /// MCD: the frame's motion per unit actuated rate (outputs × actuated).
    pub direct: Rows,
    /// MCI: the actuated rates per unit motion of the frame (actuated × outputs).
    pub inverse: Rows,
    /// Condition numbers of the direct and inverse models made dimensionless by L (`None`:
    /// infinite, at a singular configuration).
    pub direct_condition: Option<f64>,
    pub inverse_condition: Option<f64>,
    /// The actuated rates the acceleration terms are taken at, and the frame's motion then.
    pub actuated_rates: Vec<f64>,
    pub output_rates: Vec<f64>,
    /// MAD: the frame's acceleration is `direct · ä + direct_acceleration_term`.
    pub direct_acceleration_term: Vec<f64>,
    /// MAI: the actuated accelerations are `inverse · ẍ + inverse_acceleration_term` (the Delta
    /// seed's H·α̇).
    pub inverse_acceleration_term: Vec<f64>,
    pub singularity: Singularity,
}

/// The models at the state positions `q`, the actuated coordinates moving at `actuated_rates`
/// (the other coordinates as the loops and the idle motions at rest make them).
pub fn models_at(
    model: &Model,
    actuation: &Actuation,
    output: &Output,
    q: &[f64],
    actuated_rates: &[f64],
    tolerance: f64,
) -> Result<KinematicModels, KinematicsError> {
    let MotionBasis {
        length,
        scales,
        allowed,
        basis,
        unit_rows,
        at_rest,
        a,
        b,
        a_svd,
        b_svd,
    } = motion_basis(model, actuation, output, q)?;
    let rows = output.rows();
    let n = model.velocities();
    let motions = basis.ncols();
    let type2_measure = kth(&a_svd.values, motions);
    let type1_measure = kth(&b_svd.values, motions.min(rows));
    let a_plus = pseudo_inverse(&a, &a_svd);
    let b_plus = pseudo_inverse(&b, &b_svd);
    let direct_scaled = &b * &a_plus;
    let inverse_scaled = &a * &b_plus;
    let actuated_scales: Vec<f64> = actuation.velocities.iter().map(|&v| scales[v]).collect();
    let direct = DMatrix::from_fn(rows, actuated_scales.len(), |r, c| {
        direct_scaled[(r, c)] * unit_rows[(r, 0)] / actuated_scales[c]
    });
    let inverse = DMatrix::from_fn(actuated_scales.len(), rows, |r, c| {
        inverse_scaled[(r, c)] * actuated_scales[r] / unit_rows[(c, 0)]
    });
    let singular_types = (type1_measure < tolerance, type2_measure < tolerance);
    let kind = match singular_types {
        (false, false) => None,
        (true, false) => Some(SingularKind::Type1),
        (false, true) => Some(SingularKind::Type2),
        (true, true) => Some(SingularKind::Both),
    };
    let name_motion = |xi: DVector<f64>| {
        let scaled = &basis * xi;
        singular_motion(model, &at_rest, &scaled)
    };
    let weakest_motions = [
        (motions > 0).then(|| name_motion(weakest(&b, &b_svd, motions))),
        (motions > 0).then(|| name_motion(weakest(&a, &a_svd, motions))),
    ];
    let type1_motion = weakest_motions[0].clone().filter(|_| singular_types.0);
    let type2_motion = weakest_motions[1].clone().filter(|_| singular_types.1);
    // The rates: the actuated ones given, the others as the allowed motions carry them.
    let actuated_scaled = DVector::from_iterator(
        actuated_rates.len(),
        (actuated_rates.iter().zip(&actuated_scales)).map(|(r, s)| r / s),
    );
    let v_scaled = &basis * (&a_plus * &actuated_scaled);
    let v: Vec<f64> = (0..n).map(|c| v_scaled[c] * scales[c]).collect();
    let (direct_term, inverse_term, output_rates) = acceleration_terms(
        model,
        output,
        q,
        &v,
        (&scales, length),
        (&direct, &inverse),
        actuation,
    )?;
    Ok(KinematicModels {
        actuated: actuation.names.clone(),
        outputs: output.names(),
        characteristic_length: length,
        motions: allowed.ncols(),
        idle_motions: allowed.ncols() - motions,
        direct: rows_of(&direct),
        inverse: rows_of(&inverse),
        direct_condition: condition(&direct_scaled),
        inverse_condition: condition(&inverse_scaled),
        actuated_rates: actuated_rates.to_vec(),
        output_rates,
        direct_acceleration_term: direct_term,
        inverse_acceleration_term: inverse_term,
        singularity: Singularity {
            kind,
            type1_measure,
            type2_measure,
            tolerance,
            type1_motion,
            type2_motion,
            weakest_motions,
        },
    })
}

/// The direct model's acceleration term, the inverse model's, and the frame's motion.
type AccelerationTerms = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The acceleration terms of the direct and inverse models at rates `v` (state velocities on
/// the loops' allowed motions), and the frame's motion at those rates: they are what the
/// accelerations of [`SecondOrder`] make them when the actuated (direct) or the frame's
/// (inverse) accelerations vanish.
fn acceleration_terms(
    model: &Model,
    output: &Output,
    q: &[f64],
    v: &[f64],
    (scales, length): (&[f64], f64),
    (direct, inverse): (&DMatrix<f64>, &DMatrix<f64>),
    actuation: &Actuation,
) -> Result<AccelerationTerms, KinematicsError> {
    let second = second_order(model, output, q, v, scales, length)?;
    let actuated_part = DVector::from_iterator(
        actuation.velocities.len(),
        actuation.velocities.iter().map(|&c| second.particular[c]),
    );
    let direct_term = &second.frame - direct * &actuated_part;
    let inverse_term = &actuated_part - inverse * &second.frame;
    Ok((
        direct_term.iter().copied().collect(),
        inverse_term.iter().copied().collect(),
        second.output_rates,
    ))
}

/// A singular motion (dimensionless state velocities) named: the coordinates it moves beyond a
/// hundredth of the largest, largest first, and the loops whose rows they enter.
fn singular_motion(model: &Model, c: &Constraints, scaled: &DVector<f64>) -> SingularMotion {
    let norm = scaled.norm();
    let largest = scaled.amax();
    let mut moved: Vec<usize> = (0..scaled.len())
        .filter(|&i| scaled[i].abs() > 1e-2 * largest)
        .collect();
    moved.sort_by(|&a, &b| scaled[b].abs().total_cmp(&scaled[a].abs()));
    let loops = (c.jacobian.blocks.iter().enumerate())
        .filter(|(_, block)| {
            moved.iter().any(|&i| {
                block
                    .columns
                    .binary_search(&i)
                    .is_ok_and(|local| (0..6).any(|r| block.values[(r, local)] != 0.0))
            })
        })
        .map(|(k, _)| model.loops[k].name.clone())
        .collect();
    SingularMotion {
        coordinates: moved.iter().map(|&i| model.velocity_name(i)).collect(),
        rates: moved.iter().map(|&i| scaled[i] / norm).collect(),
        loops,
    }
}
