//! What the loops are, decided once at the start of a run and kept along it: which constraint
//! rows are independent (a planar loop of revolutes keeps 3 of its 6 rows, a ball joint 3, an
//! overconstrained Bennett linkage 3), how many of the motions they allow carry no mass, and the
//! length that makes rows in radians and rows in metres comparable. The equations of motion are
//! then the same smooth function of the state all along the run: no rank is decided by a
//! threshold inside an evaluation.
//!
//! Units: rotation rows are in radians, translation rows in metres, and the columns of sliding
//! coordinates in metres per unit of their rate. Every decision is taken on the rows and columns
//! made dimensionless by each loop's own length ℓ (`loop_lengths`: the diagonal of the box
//! holding the frames of the joints on its cycle and its closing frames): a loop's translation
//! rows are divided by its ℓ, and the columns of sliding motions multiplied by the largest ℓ of
//! the loops they move. The four-bar in millimetres and in metres then take the same decisions,
//! and so do a loop alone and the same loop among a thousand others: with one length for the
//! whole mechanism (its box's diagonal, L), a ladder of N loops of 1 m had its translation rows
//! at 1/N of its rotation rows, its rows' conditioning falling as 1/N (1.95e-4 at N = 1,000),
//! and its projections' damping (`PROJECTION_DAMPING`) taking the place of their solution.

use nalgebra::{DMatrix, DVector, Vector3};

use super::basis::SOLVE_TOLERANCE;
use super::elimination::sparse_rows;
use super::factored::{loop_row_scale, Damped, Factored, RowChoice, DAMPING};
use super::jacobian::ConstraintJacobian;
use super::massless::{column_scales, massless_count, turning_columns};
use super::project::close_configuration;
use super::rows::{active_rows, constraints, Constraints, Extent};
use crate::dynamics::algorithms::Data;
use crate::dynamics::model::Model;
use crate::elimination::{in_order, norm, pivoted, Sparse};
use crate::kinematics::eval::EvalError;

/// For the rank reported to people (redundant constraints, `lsdc tree`): a row counts as
/// independent when its part orthogonal to the earlier rows is above this fraction of the
/// largest row. Far above round-off because some closure conditions act only at second order
/// (maille1, maille2): at a configuration closed to 1e-15 the corresponding part is still about
/// 1e-8.
pub const RANK_TOLERANCE: f64 = crate::kinematics::mobility::RANK_TOLERANCE;

pub use super::factored::KEEP_TOLERANCE;

/// Size of the displacement (dimensionless: radians, or lengths divided by L) along the allowed
/// motions used to look at the closed configurations next to the start.
const NEARBY_STEP: f64 = 1e-3;

/// The decisions taken on the loops at the start of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// The rows the equations of motion keep (indices among the 6 per loop): independent at the
    /// start up to round-off (`KEEP_TOLERANCE`), in loop order then row order, each with the
    /// factor that makes it dimensionless (1 for a rotation row, 1/ℓ for a translation row of
    /// a loop of length ℓ).
    pub choice: RowChoice,
    /// The mechanism's characteristic length L, in metres: the scale of the bodies' velocities
    /// and of the motions along sliding coordinates in the count of massless motions and the
    /// look at the closed configurations next to the start.
    pub length: f64,
    /// Each loop's length ℓ, in metres (`loop_lengths`): the scale of its translation rows.
    pub lengths: Vec<f64>,
    /// The rows implied by earlier ones at the start, at the reporting tolerance.
    pub redundant: Vec<usize>,
    /// The number of independent rows at the reporting tolerance.
    pub rank: usize,
    /// How many of the allowed motions of `free` carry no mass.
    pub massless: usize,
    /// Coordinates that parametrise the allowed motions (one per allowed motion) but the idle
    /// ones: the equations of motion are solved on the allowed parts of their unit motions.
    pub free: Vec<usize>,
    /// The free coordinates that are a complementary link's own and appear in no kept row (a
    /// ball's angles): their unit motions are allowed as they are and move no mass, so the
    /// equations of motion leave them at rest without solving for them (their values follow
    /// the bodies' poses, `rows::seat_ball_angles`).
    pub idle: Vec<usize>,
    /// The tree's velocities (`Model::nv`): the columns after them are the complementary
    /// links' coordinates.
    pub tree_velocities: usize,
    /// How well they did when chosen (`Damped::free_quality_into`: the smallest squared Cholesky
    /// pivot of the block of the projector onto the allowed motions over the free coordinates;
    /// 1 when the allowed motions are exactly the free coordinates' motions, 0 when the free
    /// coordinates no longer parametrise them).
    pub free_quality: f64,
    /// How well the kept rows reproduce the active rows left out (`Damped::reproduction`, 1
    /// when none is left out but rows at round-off) when they were chosen.
    pub chosen_reproduction: f64,
    /// Which rows are active (a ball joint's three rotation rows are not), 6 per loop.
    pub active_rows: Vec<bool>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum StructureError {
    Evaluation(EvalError),
    /// The start is a singular configuration: closed configurations next to it have more
    /// independent rows (this one, the first of them) than the start has.
    SingularStart {
        row: usize,
    },
}

impl From<EvalError> for StructureError {
    fn from(error: EvalError) -> Self {
        StructureError::Evaluation(error)
    }
}

impl Structure {
    /// The structure of the loops at a closed configuration q.
    pub fn decide(model: &Model, data: &mut Data, q: &[f64]) -> Result<Structure, StructureError> {
        let rest = vec![0.0; model.velocities()];
        let c = constraints(model, data, q, &rest, Extent::Rows)?;
        let length = characteristic_length(model, data, &c);
        let lengths = loop_lengths(model, data, &c, length);
        let mut structure = Structure::at(model, &c, length, lengths);
        structure.choose_free(&c.jacobian);
        // `data` holds the joint transforms at q still (`gained_nearby` below moves them).
        structure.massless = massless_count(model, data, &c.jacobian, &structure.choice, length)
            .saturating_sub(structure.idle.len());
        if let Some(row) = structure.gained_nearby(model, data, q)? {
            return Err(StructureError::SingularStart { row });
        }
        Ok(structure)
    }

    /// The rows' decisions at the constraints `c`, with length L and the loops' lengths.
    fn at(model: &Model, c: &Constraints, length: f64, lengths: Vec<f64>) -> Structure {
        let active = active_rows(model);
        let scaled = dimensionless_rows(&c.jacobian, &lengths);
        let columns = c.jacobian.ncols();
        let rows = best_rows(&scaled, columns, &active, KEEP_TOLERANCE);
        let candidates: Vec<usize> = (0..scaled.len()).filter(|&r| active[r]).collect();
        let largest = scaled.iter().map(norm).fold(0.0, f64::max);
        let (reported, redundant) = in_order(
            scaled.clone(),
            columns,
            &candidates,
            RANK_TOLERANCE,
            largest,
        );
        let weak = rows.len().saturating_sub(reported.len());
        let rows = reproducing_rows(&scaled, columns, &active, rows, weak);
        let choice = RowChoice::new(rows, weak, &lengths);
        let chosen_reproduction = reproduction(&c.jacobian, &choice, &active, &lengths);
        Structure {
            choice,
            length,
            lengths,
            redundant,
            rank: reported.len(),
            massless: 0,
            free: Vec::new(),
            idle: Vec::new(),
            tree_velocities: model.nv,
            free_quality: 1.0,
            chosen_reproduction,
            active_rows: active,
        }
    }

    /// A row independent at closed configurations next to q though dependent at q itself: q is
    /// then a singular configuration (a flat parallelogram), where the motion may leave along
    /// either branch.
    fn gained_nearby(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
    ) -> Result<Option<usize>, EvalError> {
        let rest = vec![0.0; model.velocities()];
        let c = constraints(model, data, q, &rest, Extent::Rows)?;
        // The motions every row allows, independent rows picked at the decompositions'
        // tolerance (`basis::SOLVE_TOLERANCE`).
        let every: Vec<usize> = (0..c.jacobian.nrows()).collect();
        let raw = sparse_rows(&c.jacobian, |_, _| 1.0);
        let elimination = pivoted(raw, c.jacobian.ncols(), &every, SOLVE_TOLERANCE);
        let allowed = elimination.null_space(elimination.picked().len());
        if allowed.ncols() == 0 {
            return Ok(None);
        }
        let columns = column_scales(&c.jacobian, self.length);
        // A fixed, generic combination of the allowed motions, in both directions.
        let weights = DVector::from_fn(allowed.ncols(), |k, _| 1.0 / (k as f64 + 1.0).sqrt());
        let direction = (&allowed * weights).normalize();
        for sign in [1.0, -1.0] {
            let step: Vec<f64> = direction
                .iter()
                .zip(&columns)
                .map(|(d, scale)| sign * NEARBY_STEP * d * scale)
                .collect();
            let mut nearby = q.to_vec();
            model.retract(&mut nearby, &step);
            close_configuration(model, data, &mut nearby)?;
            let there = constraints(model, data, &nearby, &rest, Extent::Rows)?;
            let active = active_rows(model);
            let rows = best_rows(
                &dimensionless_rows(&there.jacobian, &self.lengths),
                there.jacobian.ncols(),
                &active,
                KEEP_TOLERANCE,
            );
            if rows.len() > self.choice.rows.len() {
                return Ok(rows.into_iter().find(|r| !self.choice.rows.contains(r)));
            }
        }
        Ok(None)
    }
}

impl Structure {
    /// The number of active rows.
    pub fn active(&self) -> usize {
        self.active_rows.iter().filter(|&&a| a).count()
    }

    /// Chooses the kept rows again at G (`reproducing_rows`), if they reproduce the rows left
    /// out better than the current ones (by `RECHOOSE` at least, from `current`). Redundant rows
    /// make this necessary: of the six rows of a Bennett linkage, three are independent all
    /// along the motion, but not always the same three, and which reproduce the others with
    /// small coefficients changes along it. On the closed configurations every choice gives the
    /// same accelerations, so the equations of motion do not change; the choice is taken between
    /// steps, never inside an evaluation. Returns whether the rows changed.
    pub fn rechoose(&mut self, jacobian: &ConstraintJacobian, current: f64) -> bool {
        let scaled = dimensionless_rows(jacobian, &self.lengths);
        let rows = reproducing_rows(
            &scaled,
            jacobian.ncols(),
            &self.active_rows,
            self.choice.rows.clone(),
            self.choice.weak,
        );
        let candidate = RowChoice::new(rows, self.choice.weak, &self.lengths);
        if candidate == self.choice {
            return false;
        }
        let better = reproduction(jacobian, &candidate, &self.active_rows, &self.lengths);
        if better < RECHOOSE * current {
            return false;
        }
        self.choice = candidate;
        self.chosen_reproduction = better;
        true
    }

    /// Chooses the free coordinates at G: those along which the allowed motions are best
    /// conditioned together (pivoted Gram–Schmidt on the rows of an orthonormal basis of the
    /// allowed motions), and records how well they parametrise them.
    pub fn choose_free(&mut self, jacobian: &ConstraintJacobian) {
        let factored = Factored::new(jacobian, &self.choice);
        // Up to `DENSE_FREE_CHOICE_UP_TO` columns, the dense factorisation's basis, not the
        // sparse elimination's: the same span, but the choice between coordinates that
        // parametrise the motions equally well (the row of two four-bars' symmetric cranks) is
        // decided by round-off, and the sparse basis's decided the other way took that row
        // through its flat passages with an energy drift of 6.1e-9 at 1e-12
        // (`hard_loops::flat_passages_…`, bound 1e-9). Beyond, the dense QR's cost (the
        // columns squared times the rows) is the start's: the sparse bases (`sparse_free`).
        let chosen = if factored.columns() <= DENSE_FREE_CHOICE_UP_TO {
            let allowed = factored.dense_null_space();
            dense_best_rows(allowed, &vec![true; allowed.nrows()], KEEP_TOLERANCE)
        } else {
            sparse_free(&factored)
        };
        let idle = |&c: &usize| c >= self.tree_velocities && !factored.touches(c);
        (self.idle, self.free) = chosen.into_iter().partition(idle);
        self.free_quality = factored
            .damped(DAMPING)
            .map_or(0.0, |damped| self.free_quality_at(&damped));
    }

    /// How well the free coordinates parametrise the allowed motions of the factored rows (see
    /// `free_quality`).
    pub fn free_quality_at(&self, damped: &Damped) -> f64 {
        if self.free.is_empty() {
            return 1.0;
        }
        let (mut columns, mut block) = (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0));
        damped.free_quality_into(&self.free, &mut Vec::new(), &mut columns, &mut block)
    }
}

/// The most columns (coordinates of the tree and of the complementary links) for which the
/// free coordinates are chosen on the dense QR's basis of the allowed motions: about 3 · 10⁷
/// multiplications (the ladder of 100 loops, 302 columns, takes 0.03 s there).
const DENSE_FREE_CHOICE_UP_TO: usize = 400;

/// A new choice of rows must reproduce the rows left out better by this factor at least.
const RECHOOSE: f64 = 1.25;

/// The active rows that are best conditioned together: pivoted Gram–Schmidt, taking at each
/// step the row with the largest part orthogonal to those already taken, until that part is at
/// most `tolerance` times the largest row. In the order taken: the rows that close their loop
/// only at second order, independent by little, come last. On the sparse rows
/// (`elimination::pivoted`): each row picked meets only the rows that share a column with it.
fn best_rows(rows: &[Sparse], columns: usize, active: &[bool], tolerance: f64) -> Vec<usize> {
    let candidates: Vec<usize> = (0..rows.len()).filter(|&r| active[r]).collect();
    let elimination = pivoted(rows.to_vec(), columns, &candidates, tolerance);
    elimination.picked().iter().map(|&(row, _)| row).collect()
}

/// `best_rows` on the rows of a dense matrix (an orthonormal basis of a few allowed motions).
fn dense_best_rows(jacobian: &DMatrix<f64>, active: &[bool], tolerance: f64) -> Vec<usize> {
    let mut left: Vec<(usize, DVector<f64>)> = (0..jacobian.nrows())
        .filter(|&r| active[r])
        .map(|r| (r, jacobian.row(r).transpose()))
        .collect();
    let largest = left.iter().map(|(_, row)| row.norm()).fold(0.0, f64::max);
    let mut chosen = Vec::new();
    while !left.is_empty() {
        let (best, norm) = left
            .iter()
            .enumerate()
            .map(|(k, (_, row))| (k, row.norm()))
            .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if norm <= tolerance * largest || norm == 0.0 {
            break;
        }
        let (row, vector) = left.swap_remove(best);
        let unit = vector / norm;
        for (_, other) in &mut left {
            // Twice, for orthogonality in floating point.
            for _ in 0..2 {
                let along = unit.dot(other);
                *other -= &unit * along;
            }
        }
        chosen.push(row);
    }
    chosen
}

/// The free coordinates of a large mechanism, on the sparse elimination's bases: pivoted
/// Gram–Schmidt on the rows of the allowed motions' basis (n × k, `dense_best_rows`), whose
/// rows have the dense basis's lengths and inner products up to round-off, so the same choice
/// but for ties; it costs n k². Where the allowed motions outnumber the kept rows' rank r (one
/// loop of N rods: k = N − 3, r = 3, where n k² was most of the start), the same search on
/// the rows of the kept rows' orthonormal basis (n × r, n r²) for the r dependent coordinates,
/// the others free. Of an orthogonal [Q_r Q_k], a k × k minor of Q_k and the complementary
/// r × r minor of Q_r are equal in size (Jacobi's complementary minors: Horn & Johnson, Matrix
/// Analysis, 2nd ed., 2013, §0.8.4), so the free coordinates best conditioned together are
/// the complement of the dependent ones best conditioned together; the two greedy searches
/// can part between choices of nearly equal volume.
fn sparse_free(factored: &Factored) -> Vec<usize> {
    let elimination = factored.sparse_elimination();
    let (n, rank) = (factored.columns(), elimination.picked().len());
    let every = vec![true; n];
    if n - rank > rank {
        let dependent = dense_best_rows(&elimination.row_space(rank), &every, KEEP_TOLERANCE);
        if dependent.len() == rank {
            let mut is_dependent = vec![false; n];
            dependent.iter().for_each(|&c| is_dependent[c] = true);
            return (0..n).filter(|&c| !is_dependent[c]).collect();
        }
    }
    dense_best_rows(&elimination.null_space(rank), &every, KEEP_TOLERANCE)
}

/// The firm rows among `rows` (pivoted Gram–Schmidt on G, the last `weak` of them weak) chosen
/// again so that the kept rows reproduce the active rows left out with the smallest
/// coefficients: pivoted Gram–Schmidt on the rows of an orthonormal basis of the span of the
/// firm rows (a greedy search for the kept block of largest volume in that basis, which leaves
/// out the block of largest volume in a basis of the dependencies). Gram–Schmidt on G itself
/// takes the longest and most independent rows, and can leave out a row the others reproduce
/// only with coefficients of 20: off the closed set that row's violation is then 20 times the
/// kept rows', the accelerations vary as its square, and a Bricard linkage made dopri5 reject
/// steps by errors of 10³ times its tolerance. Without rows to leave out but rows at round-off
/// (planar loops), `rows` as they are.
fn reproducing_rows(
    scaled: &[Sparse],
    columns: usize,
    active: &[bool],
    rows: Vec<usize>,
    weak: usize,
) -> Vec<usize> {
    let firm = rows.len() - weak;
    let mut is_kept = vec![None; scaled.len()];
    for (k, &r) in rows.iter().enumerate() {
        is_kept[r] = Some(k < firm);
    }
    let candidates: Vec<usize> = (0..scaled.len())
        .filter(|&r| active[r] && is_kept[r] != Some(false))
        .collect();
    let amax = |r: usize| scaled[r].iter().map(|e| e.1.abs()).fold(0.0, f64::max);
    let largest = rows[..firm].iter().map(|&r| amax(r)).fold(0.0, f64::max);
    let others = candidates
        .iter()
        .filter(|&&r| is_kept[r].is_none())
        .any(|&r| amax(r) > KEEP_TOLERANCE * largest);
    if !others || firm == 0 {
        return rows;
    }
    let mut block = DMatrix::zeros(candidates.len(), columns);
    for (i, &r) in candidates.iter().enumerate() {
        for &(c, value) in &scaled[r] {
            block[(i, c)] = value;
        }
    }
    let Some(svd) = crate::linalg::svd(block, true, false) else {
        return rows;
    };
    let Some(u) = svd.u else { return rows };
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let basis = DMatrix::from_fn(candidates.len(), firm, |i, k| u[(i, order[k])]);
    let picked = dense_best_rows(&basis, &vec![true; candidates.len()], KEEP_TOLERANCE);
    if picked.len() != firm {
        return rows;
    }
    let mut chosen: Vec<usize> = picked.iter().map(|&i| candidates[i]).collect();
    chosen.extend_from_slice(&rows[firm..]);
    chosen
}

/// How well the rows of `choice` reproduce the active rows left out (`Damped::reproduction`),
/// factored at G; 0 if they cannot be factored.
fn reproduction(
    jacobian: &ConstraintJacobian,
    choice: &RowChoice,
    active: &[bool],
    lengths: &[f64],
) -> f64 {
    let factored = Factored::new(jacobian, choice);
    factored.damped(DAMPING).map_or(0.0, |damped| {
        damped.reproduction(jacobian, active, lengths, &mut Vec::new(), &mut Vec::new())
    })
}

/// The diagonal of the box holding the bodies' origins, the joints' frames and the loop points,
/// in metres; 1 for a mechanism whose points all coincide (only its rotations then matter).
pub fn characteristic_length(model: &Model, data: &Data, c: &Constraints) -> f64 {
    let mut points: Vec<Vector3<f64>> = data
        .world
        .iter()
        .map(|pose| pose.translation.vector)
        .collect();
    for joint in &model.joints {
        points.push(
            (data.world[joint.child] * joint.on_child)
                .translation
                .vector,
        );
    }
    points.extend(c.points.iter().copied());
    let diagonal = box_diagonal(&points);
    if diagonal.is_finite() && diagonal > 0.0 {
        diagonal
    } else {
        1.0
    }
}

/// Per loop, its length ℓ: the diagonal of the box holding the frames of the joints on its
/// cycle (each tree joint whose velocity its rows depend on, on its parent and on its child),
/// its closing link's two frames and its loop point, where its rows' rates are taken. A
/// translation row's entry for a turning joint is the lever arm from that joint's axis to the
/// loop point, at most ℓ, so the loop's rows divided by ℓ are of order 1 whatever else the
/// mechanism holds. The bodies' origins are left out: a body's origin can lie far from its
/// joints (the ladder's beam swings about its end, a thousand rungs away from its last loop).
/// A loop whose frames all coincide has translation rows by rotation alone that vanish: the
/// mechanism's length L then. Each ℓ is taken as L times the power of two nearest the ratio of
/// that diagonal to L (`power_of_two_near`).
pub fn loop_lengths(model: &Model, data: &Data, c: &Constraints, length: f64) -> Vec<f64> {
    let mut points = Vec::new();
    (model.loops.iter().enumerate())
        .map(|(k, link)| {
            points.clear();
            points.push(c.points[k]);
            points.push(
                (data.world[link.first_body] * link.first)
                    .translation
                    .vector,
            );
            points.push(
                (data.world[link.second_body] * link.second)
                    .translation
                    .vector,
            );
            for &column in &c.jacobian.blocks[k].columns {
                if let Some(joint) = model.joint_of_velocity(column) {
                    let on_parent = data.world[joint.parent] * joint.on_parent;
                    let on_child = data.world[joint.child] * joint.on_child;
                    points.push(on_parent.translation.vector);
                    points.push(on_child.translation.vector);
                }
            }
            let diagonal = box_diagonal(&points);
            if diagonal.is_finite() && diagonal > 0.0 {
                length * power_of_two_near(diagonal / length)
            } else {
                length
            }
        })
        .collect()
}

/// The power of two nearest `ratio` (by ratio), within a factor √2 of it, which is all a scale
/// needs. A loop's length is the mechanism's L times such a power (`loop_lengths`): multiplying
/// by it is exact, so a loop's rows are scaled as with L alone but for an exponent, and two
/// forms of a mechanism whose boxes differ by round-off (the planar and the spatial form of a
/// four-bar) scale their rows alike and take the same decisions bit for bit; and since the
/// ratio has no unit, a mechanism in millimetres is scaled as in metres. This is how LAPACK
/// equilibrates (its routine DGEEQUB, LAPACK 3.2, rounds its row and column scale factors to
/// powers of the radix so that scaling introduces no rounding error).
fn power_of_two_near(ratio: f64) -> f64 {
    2.0_f64.powi(ratio.log2().round() as i32)
}

/// The diagonal of the box holding `points` (−∞ or NaN for none).
fn box_diagonal(points: &[Vector3<f64>]) -> f64 {
    let lowest = points
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(p));
    let highest = points
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
    (highest - lowest).norm()
}

/// G's rows made dimensionless by their loops' lengths, sparse: a loop's translation rows
/// divided by its ℓ, a sliding column multiplied by the largest ℓ of the loops it moves.
fn dimensionless_rows(jacobian: &ConstraintJacobian, lengths: &[f64]) -> Vec<Sparse> {
    let mut column_length = vec![0.0_f64; jacobian.ncols()];
    for (block, &length) in jacobian.blocks.iter().zip(lengths) {
        for &column in &block.columns {
            column_length[column] = column_length[column].max(length);
        }
    }
    let columns: Vec<f64> = (turning_columns(jacobian).into_iter().zip(column_length))
        .map(|(turns, length)| if turns { 1.0 } else { length })
        .collect();
    sparse_rows(jacobian, |r, c| loop_row_scale(r, lengths) * columns[c])
}
