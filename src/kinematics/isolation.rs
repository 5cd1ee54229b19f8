//! Whether a closed configuration is isolated: the loops allow motions to first order (the
//! closure Jacobian Φ′(q) has a kernel), yet every one of them opens the loops at second order,
//! so the mechanism cannot move at all. A chain stretched to its full length is the common case:
//! a four-bar whose three moving bars add up to its ground closes only with all of them on one
//! line, where tree dof − rank Φ′ counts one motion. A run from there has nowhere to go: its
//! steps shrink until the step limit.
//!
//! The test is prestress stability (Connelly and Whiteley, "Second-order rigidity and prestress
//! stability for tensegrity frameworks", SIAM J. Discrete Math. 9(3), 1996; written there for
//! bars, the argument holds for any smooth closure): a combination λ of the closure's rows
//! with λᵀΦ′(q) = 0 (a self-stress) whose form ω(v) = λᵀΦ″(q)(v, v) is positive definite on
//! the kernel K of Φ′(q) makes q an isolated closed configuration. Near q, a configuration
//! q + Ka + w with w orthogonal to K closes the loops only if Φ′w = −½Φ″(Ka, Ka) + O(|a|³),
//! so |w| = O(|a|²), and then λᵀΦ = ½ ω(Ka) + O(|a|³) > 0 for every small a ≠ 0. The test
//! is sound, not complete: no λ found claims nothing (a configuration rigid only at a higher
//! order, or a stuck loop in a mechanism that moves otherwise, is not detected).

use nalgebra::{DMatrix, DVector};

use super::branch::{join_points, size};
use super::closure::{closure, ClosureJacobian};
use super::eval::EvalError;
use super::mobility::{rank, RANK_TOLERANCE};
use super::model::KinematicModel;
use super::plane::motion_plane;
use crate::elimination::{pivoted, pivoted_in_blocks, Elimination};

/// A closed configuration the loops hold still, and the certificate.
#[derive(Clone, Debug)]
pub struct Isolated {
    /// Independent motions the loops allow to first order: the kernel's dimension.
    pub first_order: usize,
    /// The self-stress λ, one entry per row of the closure (loop after loop, three rotation
    /// rows then three position rows, the position rows per length of the mechanism).
    pub stress: DVector<f64>,
    /// The smallest eigenvalue of the stress's form on the first-order motions, relative to
    /// the closure's derivatives (`Bending::scale`): how clearly definite it is (read by the
    /// tests).
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub margin: f64,
    /// The coordinates that the first-order motions move.
    pub moving: Vec<usize>,
}

impl Isolated {
    /// The complementary link (index into `KinematicModel::complementary`) whose rows carry
    /// most of the stress: a loop that cannot move.
    pub fn stressed_loop(&self) -> usize {
        self.stress.iamax() / 6
    }
}

/// The stress's form must have its smallest eigenvalue above this fraction of the closure's
/// derivatives (`Bending::scale`). Assembly leaves q up to about 1e-7 from the exact
/// configuration along directions the loops close only at second order, and the central
/// differences err by about 1e-10: the forms are known to about 1e-6 of their size. Isolated
/// chains show margins of 4e-2 to 8e-2; a mechanism that moves, at most round-off above 0 (the
/// meshes of `examples/maille*.lsd`, whose one constraint acts at second order only, -8e-9).
const DEFINITE: f64 = 1e-4;

/// The columns of Φ′ searched together for the self-stresses' elimination: a loop's six rows
/// meet a few coordinates each, and the columns taken in blocks along the loops keep the fill
/// within neighbouring loops.
const COLUMN_BLOCK: usize = 8;

/// The step of the central differences of the closure Jacobian, in the dimensionless
/// coordinates (radians, lengths per length of the mechanism).
const STEP: f64 = 1e-5;

/// Forms of the self-stresses smaller than this fraction of the closure's second derivative
/// are round-off (rows that no motion of the kernel bends, as a planar loop's rows out of its
/// plane).
const ROUND_OFF: f64 = 1e-6;

/// Iterations of the search for a definite stress from each start, and how many starts.
const ITERATIONS: usize = 200;
const STARTS: usize = 4;

/// The certificate that `q`, a closed configuration of `model`, is isolated, or `None` when
/// none is found (the loops move, are rigid to first order, or the test cannot judge). A planar
/// mechanism whose in-plane rows are independent moves (`moves_in_its_plane`), and is not
/// differentiated at second order.
pub fn isolated(model: &KinematicModel, q: &[f64]) -> Result<Option<Isolated>, EvalError> {
    let Some(first) = FirstOrder::at(model, q)? else {
        return Ok(None);
    };
    if first.moves_in_plane(model) {
        return Ok(None);
    }
    first.second_order(model, q)
}

/// `isolated` with every closed configuration judged at second order, planar or not: the
/// second-order test that `moves_in_its_plane` spares, for the tests to compare with it.
#[cfg_attr(not(lsdc_internals), allow(dead_code))]
pub fn isolated_at_second_order(
    model: &KinematicModel,
    q: &[f64],
) -> Result<Option<Isolated>, EvalError> {
    match FirstOrder::at(model, q)? {
        Some(first) => first.second_order(model, q),
        None => Ok(None),
    }
}

/// Whether `q`, a closed configuration of `model`, is shown to move by its first derivatives
/// alone, the mechanism being planar: a planar mechanism's loops close in its plane, three
/// rows each (a rotation about the normal, a position in the plane); the other three vanish at
/// every configuration, not only at q (`plane::motion_plane`: the joints' axes keep their
/// directions). Where Φ′(q) has the rank of the in-plane rows, those rows are independent,
/// and by the implicit function theorem the closed configurations near q are a manifold of
/// dimension n − rank (Spivak, Calculus on Manifolds, 1965, Theorem 2-13), so q moves when
/// rank < n. The spatial form of the same
/// argument, every row independent, is where `isolated` finds no self-stress. The decision
/// costs two eliminations of Φ′'s rows, where the second-order test differentiates Φ′ along
/// each of the n − rank first-order motions: one loop of N rods has N − 2 of them, and its
/// test costs N³.
#[cfg_attr(not(lsdc_internals), allow(dead_code))]
pub fn moves_in_its_plane(model: &KinematicModel, q: &[f64]) -> Result<bool, EvalError> {
    Ok(FirstOrder::at(model, q)?.is_some_and(|first| first.moves_in_plane(model)))
}

/// Φ′(q), dimensionless, with the elimination of its rows, where the isolation test has to
/// look further: loops, joints of full rank, and a first-order motion.
struct FirstOrder {
    units: Units,
    jacobian: ClosureJacobian,
    rows: Elimination,
    rank: usize,
}

impl FirstOrder {
    fn at(model: &KinematicModel, q: &[f64]) -> Result<Option<FirstOrder>, EvalError> {
        if model.complementary().is_empty() || !coordinates_regular(model, q)? {
            return Ok(None);
        }
        let units = Units::of(model, q)?;
        let jacobian = units.dimensionless(&closure(model, q)?.jacobian);
        // The kernel and the self-stresses from sparse eliminations of Φ′'s rows and of its
        // columns at the rank's tolerance (`mobility::RANK_TOLERANCE`, the loops' own test),
        // not from singular value decompositions of the dense 6m × n matrix: a chain of loops
        // meets only neighbours in each, where the decompositions cost the cube of its length.
        let every_row: Vec<usize> = (0..jacobian.nrows()).collect();
        let rows = pivoted(
            jacobian.sparse_rows(),
            jacobian.ncols(),
            &every_row,
            RANK_TOLERANCE,
        );
        let rank = rows.picked().len();
        if rank == jacobian.ncols() {
            return Ok(None);
        }
        Ok(Some(FirstOrder {
            units,
            jacobian,
            rows,
            rank,
        }))
    }

    /// Planar, with Φ′ of the in-plane rows' rank (three per loop): see `moves_in_its_plane`.
    fn moves_in_plane(&self, model: &KinematicModel) -> bool {
        self.rank == 3 * model.complementary().len() && motion_plane(model).is_ok()
    }

    /// The second-order test (prestress stability, above) from the first derivatives.
    fn second_order(
        self,
        model: &KinematicModel,
        q: &[f64],
    ) -> Result<Option<Isolated>, EvalError> {
        let FirstOrder {
            units,
            jacobian,
            rows,
            rank,
        } = self;
        // Φ′'s columns in the order of their first row (loop after loop), searched a loop's
        // worth at a time: in the coordinates' order (a ladder's rungs, then its rails) each
        // column taken would fill the next rung's with the rows of every rung before it.
        let by_first_row = jacobian.sparse_columns();
        let mut order: Vec<usize> = (0..jacobian.ncols()).collect();
        order.sort_by_key(|&c| by_first_row[c].first().map_or(usize::MAX, |e| e.0));
        let columns = pivoted_in_blocks(
            by_first_row,
            jacobian.nrows(),
            &order,
            RANK_TOLERANCE,
            COLUMN_BLOCK,
        );
        let column_rank = columns.picked().len();
        if column_rank == jacobian.nrows() {
            return Ok(None);
        }
        let motions = rows.null_space(rank);
        let Some(bending) = second_derivatives(model, q, &units, &motions, jacobian.amax())? else {
            return Ok(None);
        };
        let stresses = bent_stresses(&bending, &columns, column_rank);
        if stresses.ncols() == 0 {
            return Ok(None);
        }
        let Some((stress, margin)) = definite_stress(&bending, &stresses) else {
            return Ok(None);
        };
        let moving = (0..motions.nrows())
            .filter(|&i| motions.row(i).norm() > ROUND_OFF)
            .collect();
        Ok(Some(Isolated {
            first_order: motions.ncols(),
            stress,
            margin,
            moving,
        }))
    }
}

/// Whether every joint's coordinates move its link independently at q (its motion subspace of
/// full rank). Where they do not (Euler angles at gimbal lock, two coordinates along one axis),
/// a point isolated among the coordinates need not be isolated among the links' motions.
fn coordinates_regular(model: &KinematicModel, q: &[f64]) -> Result<bool, EvalError> {
    for joint in &model.joints {
        let (_, subspace) =
            joint.chain(&q[joint.offset..joint.offset + joint.coordinate_count()])?;
        if rank(&subspace) < joint.coordinate_count() {
            return Ok(false);
        }
    }
    Ok(true)
}

/// The factors that make the closure dimensionless with the mechanism's length L: position
/// rows per L, lengths (coordinates that do not turn) in L.
struct Units {
    rows: Vec<f64>,
    columns: Vec<f64>,
}

impl Units {
    fn of(model: &KinematicModel, q: &[f64]) -> Result<Units, EvalError> {
        let length = size(&join_points(model, q)?);
        let length = if length.is_finite() && length > 1e-150 {
            length
        } else {
            1.0
        };
        let rows = (0..6 * model.complementary().len())
            .map(|r| if r % 6 < 3 { 1.0 } else { 1.0 / length })
            .collect();
        let columns = (model.turning().iter())
            .map(|&turns| if turns { 1.0 } else { length })
            .collect();
        Ok(Units { rows, columns })
    }

    fn dimensionless(&self, jacobian: &ClosureJacobian) -> ClosureJacobian {
        jacobian.scaled(&self.rows, &self.columns)
    }
}

/// Φ″(q)(m_a, m_b) for every pair of first-order motions (columns of `motions`, dimensionless),
/// dimensionless, as a vector over the closure's rows: central differences of the exact
/// Jacobian along m_a, applied to m_b, symmetrised. `None` when a configuration of the
/// differences cannot be evaluated or nothing bends.
fn second_derivatives(
    model: &KinematicModel,
    q: &[f64],
    units: &Units,
    motions: &DMatrix<f64>,
    first_derivatives: f64,
) -> Result<Option<Bending>, EvalError> {
    let k = motions.ncols();
    let moved = |sign: f64, a: usize| -> Vec<f64> {
        (0..q.len())
            .map(|i| q[i] + sign * STEP * units.columns[i] * motions[(i, a)])
            .collect()
    };
    let mut along = Vec::with_capacity(k);
    for a in 0..k {
        let (Ok(ahead), Ok(behind)) = (
            closure(model, &moved(1.0, a)),
            closure(model, &moved(-1.0, a)),
        ) else {
            return Ok(None);
        };
        let change = ahead.jacobian.difference(&behind.jacobian, 2.0 * STEP);
        along.push(units.dimensionless(&change).mul_dense(motions));
    }
    let pairs = DMatrix::from_fn(along[0].nrows(), k * k, |r, column| {
        let (a, b) = (column / k, column % k);
        0.5 * (along[a][(r, b)] + along[b][(r, a)])
    });
    let largest = (0..k * k)
        .map(|c| pairs.column(c).norm())
        .fold(0.0, f64::max);
    if !largest.is_finite() {
        return Ok(None);
    }
    // Differences of a Jacobian along a motion it does not bend are its round-off divided by
    // the step: measured against the first derivatives, they stay below `ROUND_OFF`.
    let scale = largest.max(first_derivatives);
    if !(scale > 0.0 && scale.is_finite()) {
        return Ok(None);
    }
    Ok(Some(Bending { k, pairs, scale }))
}

/// The closure's second derivatives along the first-order motions: column a·k + b holds
/// Φ″(m_a, m_b) over the rows.
struct Bending {
    k: usize,
    pairs: DMatrix<f64>,
    /// The largest of them (Euclidean norm over the rows), or the largest first derivative if
    /// larger: the scale of "definite".
    scale: f64,
}

impl Bending {
    /// The form of the stress λ on the motions, per the scale: λᵀΦ″(m_a, m_b) / scale.
    fn form(&self, stress: &DVector<f64>) -> DMatrix<f64> {
        let values = self.pairs.tr_mul(stress) / self.scale;
        DMatrix::from_fn(self.k, self.k, |a, b| values[a * self.k + b])
    }
}

/// An orthonormal basis of the self-stresses whose forms are not round-off: the parts of the
/// closure's second derivatives (`bending`'s columns) orthogonal to Φ′'s columns, the first
/// `rank` of which `columns` has picked. A self-stress λ (λᵀΦ′ = 0) has the form
/// λᵀΦ″(m_a, m_b) = λᵀΠΦ″(m_a, m_b), Π the projector onto the self-stresses, so λ's part
/// orthogonal to the span of the ΠΦ″(m_a, m_b) bends nothing: the search for a definite
/// stress over this span is the search over every self-stress, without a basis of all of them
/// (a planar chain of N loops has 3N, each out of its plane).
fn bent_stresses(bending: &Bending, columns: &Elimination, rank: usize) -> DMatrix<f64> {
    let k = bending.k;
    let mut basis: Vec<DVector<f64>> = Vec::new();
    for a in 0..k {
        for b in a..k {
            let mut part: DVector<f64> = bending.pairs.column(a * k + b).into_owned();
            columns.orthogonal_part(rank, part.as_mut_slice());
            // Gram–Schmidt against the directions kept, twice for orthogonality in floating
            // point; a part at most round-off of the second derivatives' scale bends nothing.
            for _ in 0..2 {
                for unit in &basis {
                    let along = unit.dot(&part);
                    part -= unit * along;
                }
            }
            let size = part.norm();
            if size > ROUND_OFF * bending.scale && basis.len() < part.len() {
                basis.push(part / size);
            }
        }
    }
    DMatrix::from_fn(bending.pairs.nrows(), basis.len(), |r, j| basis[j][r])
}

/// A self-stress (a unit combination of the columns of `stresses`) whose form is definite on
/// the motions, with its margin; `None` when the search finds none. The smallest eigenvalue of
/// the form is concave in the stress, so it is maximised over the unit ball by projected
/// supergradient ascent (the supergradient is xᵀF_i x for the eigenvector x of the smallest
/// eigenvalue), from the stresses whose forms are largest, with either sign.
fn definite_stress(bending: &Bending, stresses: &DMatrix<f64>) -> Option<(DVector<f64>, f64)> {
    let forms: Vec<DMatrix<f64>> = (0..stresses.ncols())
        .map(|i| bending.form(&stresses.column(i).into_owned()))
        .collect();
    // The combinations of stresses with forms above round-off, largest first: a basis of the
    // forms (each flattened to a vector) by singular value decomposition.
    let k = bending.k;
    let flattened = DMatrix::from_fn(forms.len(), k * k, |i, c| forms[i][(c / k, c % k)]);
    let decomposition = crate::linalg::svd(flattened, true, false)?;
    let u = decomposition.u?;
    let mut order: Vec<usize> = (0..decomposition.singular_values.len())
        .filter(|&j| decomposition.singular_values[j] > ROUND_OFF)
        .collect();
    order.sort_by(|&a, &b| {
        (decomposition.singular_values[b]).total_cmp(&decomposition.singular_values[a])
    });
    if order.is_empty() {
        return None;
    }
    let basis = DMatrix::from_fn(forms.len(), order.len(), |i, j| u[(i, order[j])]);
    let reduced: Vec<DMatrix<f64>> = (0..order.len())
        .map(|j| {
            (0..forms.len()).fold(DMatrix::zeros(k, k), |sum, i| {
                sum + &forms[i] * basis[(i, j)]
            })
        })
        .collect();
    let smallest = |mu: &DVector<f64>| {
        let combined =
            (0..reduced.len()).fold(DMatrix::zeros(k, k), |sum, j| sum + &reduced[j] * mu[j]);
        crate::linalg::smallest_eigenpair(&combined)
    };
    // The best stress found and its smallest eigenvalue, per the stress's size.
    let mut best: Option<(DVector<f64>, f64)> = None;
    let clear =
        |best: &Option<(DVector<f64>, f64)>| best.as_ref().is_some_and(|b| b.1 > 10.0 * DEFINITE);
    for start in 0..(2 * STARTS).min(2 * reduced.len()) {
        let mut mu = DVector::zeros(reduced.len());
        mu[start / 2] = if start % 2 == 0 { 1.0 } else { -1.0 };
        for iteration in 0..ITERATIONS {
            let (value, vector) = smallest(&mu)?;
            let relative = value / mu.norm();
            if best.as_ref().is_none_or(|b| relative > b.1) {
                best = Some((&mu / mu.norm(), relative));
            }
            if clear(&best) {
                break;
            }
            let ascent =
                DVector::from_fn(reduced.len(), |j, _| vector.dot(&(&reduced[j] * &vector)));
            mu += ascent * (0.5 / ((iteration + 1) as f64).sqrt());
            let norm = mu.norm();
            if norm > 1.0 {
                mu /= norm;
            }
            if norm == 0.0 {
                break;
            }
        }
        if clear(&best) {
            break;
        }
    }
    let (mu, margin) = best?;
    (margin > DEFINITE).then(|| (stresses * (&basis * &mu), margin))
}
