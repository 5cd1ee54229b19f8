//! Mobility by rank, never by counting: at an assembled configuration, the closure Jacobian's
//! rank gives the number of independent constraints, rank(Δ), and tree DOF − rank(Δ) is the
//! first-order mobility. The mobility itself is the dimension of the set of closed
//! configurations around the assembled one, measured by assembling from small perturbations:
//! it equals the first-order mobility unless some constraint acts only at second order (as in
//! the thesis's meshes, where the tangent space is one dimension larger than the closed set).
//! Also: redundant constraints, singular configurations (a rank lower than at nearby assembled
//! configurations), and internal mobilities (a body that can move while every other body stands
//! still, such as a rod spinning between two ball joints).

use nalgebra::DMatrix;
use serde::Serialize;

use super::assembly::{assemble, jitter, singular_values, AssemblyError, AssemblyOptions};
use super::closure::{closure, ClosureJacobian};
use super::eval::EvalError;
use super::model::KinematicModel;

/// Relative tolerance on singular values: σ counts if σ > RANK_TOLERANCE · σ_max. Assembly
/// leaves residuals near 1e-15; along directions where constraints act only at second order the
/// configuration can then be 1e-7 from the closed set, which shows as singular values near
/// 1e-8 · σ_max: they must count as zero.
pub const RANK_TOLERANCE: f64 = 1e-6;

/// Size of the perturbations used to sample the closed set, and the relative singular value
/// below which a sampled direction is a second-order effect, not a direction of motion.
const SAMPLE_STEP: f64 = 1e-3;
const SAMPLE_TOLERANCE: f64 = 2e-2;

/// A sampled direction is a motion only if the closed configurations move along it by more
/// than this per unit of perturbation: assembly closes to about 1e-12, so a mechanism that
/// cannot move shows displacements of 1e-9 per unit at most, never a motion.
const ROUND_OFF_MOTION: f64 = 1e-6;

#[derive(Clone, Debug, Serialize)]
pub struct Mobility {
    /// Degrees of freedom of the spanning tree (coordinates of the principal links).
    pub tree_dof: usize,
    /// Constraint equations of the complementary links (Σ of their degrees of constraint).
    pub constraint_rows: usize,
    /// Independent constraints at this configuration: rank(Δ).
    pub rank: usize,
    /// tree_dof − rank.
    pub first_order_mobility: usize,
    /// Dimension of the set of closed configurations around this one.
    pub mobility: usize,
    /// constraint_rows − rank.
    pub redundant: usize,
    /// rank(Δ) at other assembled configurations (nearby, and spread over the mechanism), when
    /// higher than here (a singular configuration).
    pub generic_rank: usize,
    pub singular: bool,
    /// Bodies that can move alone (body number, how many ways).
    pub internal: Vec<(usize, usize)>,
    pub tolerance: f64,
}

impl Mobility {
    /// The mobility with `couplings` mimic joints more (links' `mimic`): each holds one
    /// coordinate of the tree to another, a constraint row independent of every other (its
    /// follower appears in no other row).
    pub fn with_couplings(mut self, couplings: usize) -> Mobility {
        self.constraint_rows += couplings;
        self.rank += couplings;
        self.generic_rank += couplings;
        self.first_order_mobility = self.first_order_mobility.saturating_sub(couplings);
        self.mobility = self.mobility.saturating_sub(couplings);
        self
    }

    /// A tree: no constraints.
    pub fn of_tree(tree_dof: usize) -> Mobility {
        Mobility {
            tree_dof,
            constraint_rows: 0,
            rank: 0,
            first_order_mobility: tree_dof,
            mobility: tree_dof,
            redundant: 0,
            generic_rank: 0,
            singular: false,
            internal: Vec::new(),
            tolerance: RANK_TOLERANCE,
        }
    }
}

pub fn rank(m: &DMatrix<f64>) -> usize {
    let values = singular_values(m);
    let largest = values.iter().copied().fold(0.0, f64::max);
    if largest == 0.0 {
        return 0;
    }
    values
        .iter()
        .filter(|&&s| s > RANK_TOLERANCE * largest)
        .count()
}

/// rank(Δ) at q: rank of the full closure Jacobian minus the ranks of the cut joints' own motion
/// subspaces (their columns only appear in their own loop's rows).
pub fn constraint_rank(model: &KinematicModel, q: &[f64]) -> Result<(usize, usize), EvalError> {
    let closure = closure(model, q)?;
    let mut cut_rank = 0;
    let mut rows = 0;
    for joint in model.complementary() {
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (_, subspace) = joint.chain(coordinates)?;
        let r = rank(&subspace);
        cut_rank += r;
        rows += 6 - r;
    }
    Ok((rows_rank(&closure.jacobian).saturating_sub(cut_rank), rows))
}

/// The rank of a closure Jacobian's rows at `RANK_TOLERANCE`: the rows whose part orthogonal
/// to those taken before is above that fraction of the largest row, by the pivoted sparse
/// elimination of the rows (`elimination::pivoted`, Gram–Schmidt's parts with the largest part
/// taken first), the loops' own test of their reported rank (`loops::structure`). An SVD of
/// the dense 6m × n Jacobian cost the cube of a chain of m loops at every rank taken (the
/// start, an open configuration and the nearby assemblies of `branch::examine`: 84 % of the
/// start of a ladder of 100 parallelograms).
fn rows_rank(m: &ClosureJacobian) -> usize {
    let every: Vec<usize> = (0..m.nrows()).collect();
    crate::elimination::pivoted(m.sparse_rows(), m.ncols(), &every, RANK_TOLERANCE)
        .picked()
        .len()
}

pub fn mobility(model: &KinematicModel, q: &[f64]) -> Result<Mobility, EvalError> {
    let (rank_here, rows) = constraint_rank(model, q)?;
    // Degrees of freedom of the tree: the ranks of the principal joints' motion subspaces (the
    // coordinate count, unless a link's coordinates are redundant).
    let tree_dof = tree_dof(model, q)?;
    let spread = spread_configurations(model, q)?;
    let generic_rank = nearby_rank(model, q)?.max(generic_rank(model, rank_here, &spread)?);
    let first_order = tree_dof.saturating_sub(rank_here);
    Ok(Mobility {
        tree_dof,
        constraint_rows: rows,
        rank: rank_here,
        first_order_mobility: first_order,
        mobility: if first_order == 0 {
            // Rigid to first order is rigid.
            0
        } else {
            // The closed set has at most the tangent space's dimension.
            closed_set_dimension(model, q)?
                .unwrap_or(first_order)
                .min(first_order)
        },
        redundant: rows.saturating_sub(rank_here),
        generic_rank,
        singular: generic_rank > rank_here,
        internal: internal_mobilities(model, q)?,
        tolerance: RANK_TOLERANCE,
    })
}

/// The degrees of freedom at q a motion must impose: the mobility with `couplings` mimic
/// couplings, less the bodies' internal motions (a rod spinning between two ball joints),
/// which no drive reaches and no effort needs.
pub fn useful_degrees(
    model: &KinematicModel,
    q: &[f64],
    couplings: usize,
) -> Result<usize, EvalError> {
    let found = mobility(model, q)?.with_couplings(couplings);
    let internal: usize = found.internal.iter().map(|(_, ways)| ways).sum();
    Ok(found.mobility.saturating_sub(internal))
}

/// Degrees of freedom of the tree at q: the ranks of the principal joints' motion subspaces
/// over their declared coordinates (the coordinate count, unless a link's coordinates are
/// redundant).
pub fn tree_dof(model: &KinematicModel, q: &[f64]) -> Result<usize, EvalError> {
    let mut dof = 0;
    for joint in model.principal() {
        let (_, subspace) =
            joint.chain(&q[joint.offset..joint.offset + joint.coordinate_count()])?;
        // A rheonomic chain's hidden coordinates (the last ones) are imposed, not freedoms.
        dof += rank(&subspace.columns(0, joint.declared_count()).into_owned());
    }
    Ok(dof)
}

/// Closed configurations spread over the mechanism, for what it is generically (its rank,
/// which joins stand apart): assembled, nothing held, from starts that turn every angle of q by
/// up to half a turn and move every other coordinate by up to 0.5 (deterministic). Perturbations
/// of a few hundredths (`nearby_rank`) are not enough: a folded linkage's closed set can be of
/// higher dimension than its working branch, and nearby starts assemble folded again. The starts
/// that do not assemble are left out.
pub fn spread_configurations(
    model: &KinematicModel,
    q: &[f64],
) -> Result<Vec<Vec<f64>>, EvalError> {
    if model.complementary().is_empty() {
        return Ok(Vec::new());
    }
    let turning = model.turning();
    let fixed = vec![false; model.coordinate_count];
    let options = AssemblyOptions::default();
    let mut spread = Vec::new();
    for sample in 0..SPREAD_SAMPLES {
        let start = spread_start(q, &turning, SPREAD_SEED + sample);
        match assemble(model, &start, &fixed, &options) {
            Ok(assembled) => spread.push(assembled.q),
            Err(AssemblyError::Evaluation(e)) => return Err(e),
            Err(AssemblyError::NoAssembly { .. }) => {}
        }
    }
    Ok(spread)
}

/// A start spread from q: every angle that turns moved by up to half a turn, every other
/// coordinate by up to 0.5 (`jitter` of sample `sample`).
pub fn spread_start(q: &[f64], turning: &[bool], sample: usize) -> Vec<f64> {
    (q.iter().enumerate())
        .map(|(i, x)| {
            let reach = if turning[i] {
                std::f64::consts::PI
            } else {
                0.5
            };
            x + reach * jitter(sample, i)
        })
        .collect()
}

/// How many spread configurations are sampled, and the first sample number given to `jitter`
/// (apart from the numbers assembly's restarts and the closed set's sampling use).
const SPREAD_SAMPLES: usize = 4;
const SPREAD_SEED: usize = 1000;

/// The mechanism's generic rank(Δ): the largest of `rank_here` and the ranks at `spread`.
pub fn generic_rank(
    model: &KinematicModel,
    rank_here: usize,
    spread: &[Vec<f64>],
) -> Result<usize, EvalError> {
    let mut generic = rank_here;
    for q in spread {
        generic = generic.max(constraint_rank(model, q)?.0);
    }
    Ok(generic)
}

/// Dimension of the set of closed configurations near q: assemble from perturbations of size
/// SAMPLE_STEP and count the independent directions of the displacements, ignoring those a
/// hundred times smaller than the largest (second-order effects). `None` when too few samples
/// assemble.
fn closed_set_dimension(model: &KinematicModel, q: &[f64]) -> Result<Option<usize>, EvalError> {
    let nq = model.coordinate_count;
    let fixed = vec![false; nq];
    let options = AssemblyOptions::default();
    let samples = nq + 4;
    let mut displacements = DMatrix::zeros(nq, samples);
    let mut assembled = 0;
    for sample in 0..samples {
        let start: Vec<f64> = (0..nq)
            .map(|i| q[i] + SAMPLE_STEP * jitter(sample, i))
            .collect();
        if let Ok(result) = assemble(model, &start, &fixed, &options) {
            for i in 0..nq {
                displacements[(i, assembled)] = (result.q[i] - q[i]) / SAMPLE_STEP;
            }
            assembled += 1;
        }
    }
    if assembled < nq {
        return Ok(None);
    }
    let values = singular_values(&displacements.columns(0, assembled).into_owned());
    let largest = values.iter().copied().fold(0.0, f64::max);
    Ok(Some(
        values
            .iter()
            .filter(|&&s| s > SAMPLE_TOLERANCE * largest && s > ROUND_OFF_MOTION)
            .count(),
    ))
}

/// The largest rank(Δ) at assembled configurations near q (deterministic perturbations).
pub fn nearby_rank(model: &KinematicModel, q: &[f64]) -> Result<usize, EvalError> {
    if model.complementary().is_empty() {
        return Ok(0);
    }
    let fixed = vec![false; model.coordinate_count];
    let options = AssemblyOptions::default();
    let mut best = 0;
    for sample in 0..4 {
        let perturbed: Vec<f64> = q
            .iter()
            .enumerate()
            .map(|(i, x)| {
                x + 0.05
                    * ((1.0 + i as f64 * 0.7548776662 + sample as f64 * 0.5698402910) * 12.9898)
                        .sin()
            })
            .collect();
        if let Ok(assembled) = assemble(model, &perturbed, &fixed, &options) {
            best = best.max(constraint_rank(model, &assembled.q)?.0);
        }
    }
    Ok(best)
}

/// For each body, the number of independent motions of the mechanism in which it alone moves:
/// the motions that keep every other body still, less those that keep all bodies still.
fn internal_mobilities(
    model: &KinematicModel,
    q: &[f64],
) -> Result<Vec<(usize, usize)>, EvalError> {
    let closure = closure(model, q)?;
    let n = model.topology.body_count();
    let configuration = &closure.configuration;
    let loop_rows = closure.jacobian.dense();
    let stack = |bodies: &[usize]| {
        let rows = loop_rows.nrows() + 6 * bodies.len();
        let mut stacked = DMatrix::zeros(rows.max(1), model.coordinate_count);
        stacked.rows_mut(0, loop_rows.nrows()).copy_from(&loop_rows);
        for (i, &b) in bodies.iter().enumerate() {
            stacked
                .rows_mut(loop_rows.nrows() + 6 * i, 6)
                .copy_from(&configuration.jacobian(b));
        }
        rank(&stacked)
    };
    let all: Vec<usize> = (1..=n).collect();
    let still = stack(&all);
    let mut internal = Vec::new();
    for body in 1..=n {
        let others: Vec<usize> = all.iter().copied().filter(|&b| b != body).collect();
        let moving_alone = still - stack(&others);
        if moving_alone > 0 {
            internal.push((body, moving_alone));
        }
    }
    Ok(internal)
}
