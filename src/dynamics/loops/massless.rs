//! How many of the motions the loops' kept rows allow move no mass (rod spins, the angles of
//! complementary ball joints), decided from the bodies' inertias rather than from the spectrum
//! of the reduced mass matrix NᵀMN.
//!
//! The spectrum cannot decide it: on a long chain, or one whose masses span orders of
//! magnitude, the eigenvalues of NᵀMN span more than any threshold legitimately (the necklace
//! of 1,000 rods: 251 of its 998 motions below 1e-10 of the largest, though every rod has full
//! inertia), and the null-space method leaves a motion counted massless at rest.
//!
//! What decides it instead: the tree's map from joint rates to body velocities is injective
//! (each joint's motion subspace has full rank, and a joint's rate is read back from its child's
//! velocity relative to its parent's). So where every body the tree moves has a positive
//! definite spatial inertia, an allowed motion moves no mass exactly when it moves no body,
//! that is, when only the complementary links' own coordinates move (which carry no inertia):
//! the count is the nullity of the kept rows over those columns, a few per loop. Only bodies
//! with a rank-deficient inertia (point masses, thin rods, massless bodies) can carry other
//! massless motions; then the count is the nullity of the stacked map [P_b J_b] N over the
//! bodies (P_b an orthonormal basis of the range of body b's inertia, the identity for a body
//! of full inertia; J_b its velocity in the joint rates; N the allowed motions), taken from
//! that map's singular values, whose spread is the geometry's, not the masses'.

use nalgebra::{DMatrix, Matrix6, Vector6};

use super::basis::SOLVE_TOLERANCE;
use super::factored::{row_scale, RowChoice};
use super::jacobian::ConstraintJacobian;
use crate::dynamics::algorithms::{body_motions, Data};
use crate::dynamics::elements::BodyInertia;
use crate::dynamics::model::Model;
use crate::elimination::{pivoted, Elimination, Sparse};
use crate::spatial::Motion;

/// A direction of a body's inertia (made dimensionless by its mass and the characteristic
/// length L) counts as without mass when its eigenvalue is at most this fraction of the
/// largest: a rotational inertia about the centre of mass below 1e-12 m L². Far above the
/// round-off of an inertia moved to the body's origin (about 1e-16 m |c|², |c| ≤ L), far below
/// a body's declared inertia (a thin rod of radius r: m r²/2, at 1e-12 m L² for r = 1.4e-6 L).
/// The same fraction as the range-space method's test of a full inertia
/// (`range_space::applies_to`).
const WITHOUT_MASS: f64 = 1e-12;

/// A motion counts as massless when its singular value in the stacked map is at most this
/// fraction of the largest. The map is dimensionless and unweighted by the masses: where the
/// bodies have full inertia its rows are their velocities (ω, v/L), and its smallest singular
/// value is at least about 1/3 whatever the chain's length and masses (a joint's rate is its
/// child's velocity less its parent's carried over a lever arm of at most L, so the inverse
/// map's norm is at most about 3). A massless motion's singular value is round-off, about
/// 1e-16 × the map's norm × the square root of its size (below 1e-12 for a thousand motions).
/// Between the two, what the tolerance decides is geometry: a thin rod's axis that misses the
/// line of its two ball joints by less than 1e-8 L has its spin counted massless.
const MASSLESS_MOTION: f64 = 1e-8;

/// The directions of a body's velocity (ω, v/L) that carry its mass.
enum Massive {
    /// Every direction: a positive definite inertia.
    Every,
    /// An orthonormal basis of the range of its inertia: fewer than 6 directions (none for a
    /// massless body).
    Some(Vec<Vector6<f64>>),
}

/// The directions of `body`'s velocity, made dimensionless by `length`, that carry its mass.
fn massive_directions(body: &BodyInertia, length: f64) -> Massive {
    if body.massless || body.mass <= 0.0 {
        return Massive::Some(Vec::new());
    }
    // The kinetic energy's form in (ω, v/L): [J, ĥ L; ĥᵀ L, m L²] for the inertia [J ĥ; ĥᵀ m]
    // about the body's origin, divided by m L².
    let scale = Vector6::new(1.0, 1.0, 1.0, length, length, length);
    let form: Matrix6<f64> = Matrix6::from_fn(|i, j| body.inertia[(i, j)] * scale[i] * scale[j])
        / (body.mass * length * length);
    let eigen = form.symmetric_eigen();
    let largest = eigen.eigenvalues.max();
    let kept: Vec<Vector6<f64>> = (0..6)
        .filter(|&k| eigen.eigenvalues[k] > WITHOUT_MASS * largest)
        .map(|k| eigen.eigenvectors.column(k).into_owned())
        .collect();
    match kept.len() {
        6 => Massive::Every,
        _ => Massive::Some(kept),
    }
}

/// How many of the motions the rows of `choice` allow at the configuration whose joint
/// transforms `data` holds move no mass. `jacobian` is G there, `length` the characteristic
/// length. The count is a property of the mechanism: it is taken once at the start (between
/// projections, in the integrator's trial states slightly off the closed set, these motions
/// pick up inertias of 1e-9 of the largest or so, and dividing the residue of forces that
/// balance exactly by such inertias would make a spurious fast motion).
pub fn massless_count(
    model: &Model,
    data: &Data,
    jacobian: &ConstraintJacobian,
    choice: &RowChoice,
    length: f64,
) -> usize {
    let bodies: Vec<(usize, Massive)> = (model.dynamic_joints.iter())
        .map(|&k| model.joints[k].child)
        .map(|i| (i, massive_directions(&model.dynamic_bodies[i - 1], length)))
        .collect();
    let columns = column_scales(jacobian, length);
    if bodies.iter().all(|(_, m)| matches!(m, Massive::Every)) {
        return complementary_nullity(jacobian, choice, length, &columns, model.nv);
    }
    let rows: Vec<Sparse> = (choice.rows.iter())
        .map(|&r| {
            (jacobian.row(r))
                .filter(|&(_, value)| value != 0.0)
                .map(|(c, value)| (c, value * row_scale(r, length) * columns[c]))
                .collect()
        })
        .collect();
    let mut elimination = Elimination::new(rows, jacobian.ncols());
    for k in 0..choice.rows.len() {
        elimination.pick(k);
    }
    // An orthonormal basis of the dimensionless allowed motions y; the rates are x = D y.
    let allowed = elimination.null_space(choice.rows.len());
    if allowed.ncols() == 0 {
        return 0;
    }
    let height: usize = (bodies.iter())
        .map(|(_, m)| match m {
            Massive::Every => 6,
            Massive::Some(directions) => directions.len(),
        })
        .sum();
    let mut map = DMatrix::zeros(height, allowed.ncols());
    let mut motions = vec![Motion::zeros(); model.bodies.len() + 1];
    let mut rates = vec![0.0; model.nv];
    for k in 0..allowed.ncols() {
        for (c, rate) in rates.iter_mut().enumerate() {
            *rate = allowed[(c, k)] * columns[c];
        }
        body_motions(model, data, &rates, &mut motions);
        let mut row = 0;
        for (i, massive) in &bodies {
            let m = &motions[*i];
            let velocity = Vector6::new(
                m[0],
                m[1],
                m[2],
                m[3] / length,
                m[4] / length,
                m[5] / length,
            );
            match massive {
                Massive::Every => {
                    for value in velocity.iter() {
                        map[(row, k)] = *value;
                        row += 1;
                    }
                }
                Massive::Some(directions) => {
                    for direction in directions {
                        map[(row, k)] = direction.dot(&velocity);
                        row += 1;
                    }
                }
            }
        }
    }
    nullity(map)
}

/// The number of singular values of `map` at most `MASSLESS_MOTION` of the largest (all of
/// them when they are all zero), counting those a map with fewer rows than columns lacks. A tall map is reduced to its triangular
/// factor first (the same singular values).
fn nullity(map: DMatrix<f64>) -> usize {
    let columns = map.ncols();
    if map.nrows() == 0 {
        // No body with mass: every motion is massless.
        return columns;
    }
    let square = if map.nrows() > columns {
        map.qr().r()
    } else {
        map
    };
    let Some(svd) = crate::linalg::svd(square, false, false) else {
        return 0;
    };
    let values = &svd.singular_values;
    let largest = values.max();
    let large = values
        .iter()
        .filter(|&&s| s > MASSLESS_MOTION * largest)
        .count();
    columns - large
}

/// The allowed motions that move the complementary links' coordinates alone: the nullity of
/// the kept rows over the columns from `tree_velocities` on, by the sparse elimination of those
/// rows' parts there (made dimensionless: entries of order 1, and their rank a matter of the
/// joints' axes, not of round-off).
fn complementary_nullity(
    jacobian: &ConstraintJacobian,
    choice: &RowChoice,
    length: f64,
    columns: &[f64],
    tree_velocities: usize,
) -> usize {
    let complementary = jacobian.ncols() - tree_velocities;
    if complementary == 0 {
        return 0;
    }
    let rows: Vec<Sparse> = (choice.rows.iter())
        .map(|&r| {
            (jacobian.row(r))
                .filter(|&(c, value)| c >= tree_velocities && value != 0.0)
                .map(|(c, value)| {
                    (
                        c - tree_velocities,
                        value * row_scale(r, length) * columns[c],
                    )
                })
                .collect()
        })
        .collect();
    let every: Vec<usize> = (0..rows.len()).collect();
    let elimination = pivoted(rows, complementary, &every, SOLVE_TOLERANCE);
    complementary - elimination.picked().len()
}

/// Per column of G, the factor that makes it dimensionless: L for a sliding motion (no rotation
/// row moves with it), 1 otherwise.
pub fn column_scales(jacobian: &ConstraintJacobian, length: f64) -> Vec<f64> {
    turning_columns(jacobian)
        .into_iter()
        .map(|turns| if turns { 1.0 } else { length })
        .collect()
}

/// Per column of G, whether a rotation row moves with it (not a sliding motion).
pub fn turning_columns(jacobian: &ConstraintJacobian) -> Vec<bool> {
    let mut turns = vec![false; jacobian.ncols()];
    for r in (0..jacobian.nrows()).filter(|r| r % 6 < 3) {
        for (c, value) in jacobian.row(r) {
            turns[c] |= value != 0.0;
        }
    }
    turns
}
