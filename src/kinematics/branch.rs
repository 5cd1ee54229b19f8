//! Which branch an assembled configuration lies on. A closed mechanism's closed configurations
//! fall into several branches (a linkage folded or open, a Delta robot's nacelle below or above
//! its base), and assembly lands on whichever its iteration reaches from the starting values.
//! Three signs that it is not the branch meant, each measured here and reported by
//! `kinematics::initial` as a warning:
//! - the configuration is singular: the loops' constraints have a lower rank than at the
//!   mechanism's other closed configurations (`mobility::spread_configurations`), so it moves in
//!   more ways here than elsewhere (a folded linkage);
//! - two joins stand at one point here that stand apart at other closed configurations (two
//!   pivots of a folded linkage);
//! - assembly moved a starting guess by more than a quarter turn (whole turns aside): the
//!   guesses described another configuration, and what was reached may lie on another branch.

use nalgebra::Vector3;

use super::eval::EvalError;
use super::forward::poses;
use super::mobility::{
    constraint_rank, generic_rank, nearby_rank, spread_configurations, spread_start, tree_dof,
};
use super::model::KinematicModel;

/// What an assembled configuration shows of its branch.
#[derive(Clone, Debug)]
pub struct Branch {
    /// Degrees of freedom of the tree.
    pub tree_dof: usize,
    /// rank(Δ) here.
    pub rank: usize,
    /// The largest rank(Δ) at closed configurations spread over the mechanism (at least
    /// `rank`).
    pub generic_rank: usize,
    /// Pairs of joins at one point here and apart elsewhere.
    pub coinciding: Vec<Coincidence>,
}

impl Branch {
    /// A lower rank than the mechanism's generic one.
    pub fn singular(&self) -> bool {
        self.rank < self.generic_rank
    }
}

/// Two joins (indices into `KinematicModel::joints`) whose points coincide.
#[derive(Clone, Debug)]
pub struct Coincidence {
    pub first: usize,
    pub second: usize,
    /// Where, in the fixed axes.
    pub point: Vector3<f64>,
    /// Their largest distance at the other closed configurations sampled.
    pub apart: f64,
}

/// Points closer than this, relative to the mechanism's size, coincide (assembly closes the
/// loops to about 1e-12, and a singular configuration can leave them 1e-7 from exact).
const COINCIDENT: f64 = 1e-6;

/// Points farther apart than this, relative to the mechanism's size, stand apart.
const APART: f64 = 1e-3;

/// The branch of the closed configuration `q` of `model`. Sampling the mechanism's other
/// closed configurations takes assemblies from far starts (0.7 s for a row of 40 four-bars),
/// so it is done only when cheaper tests find a sign: a rank lower than at a configuration
/// that is not closed (the rank anywhere bounds the generic one from above, so a rank equal
/// to it is generic) and than at closed configurations nearby, or two joins at one point that
/// share no point of a body. A singular configuration that is generic among its neighbours
/// and brings no joins together (a higher-dimensional branch crossing the working one, without
/// folding it onto itself) is not detected.
pub fn examine(model: &KinematicModel, q: &[f64]) -> Result<Branch, EvalError> {
    let rank = constraint_rank(model, q)?.0;
    let here = join_points(model, q)?;
    let turning = model.turning();
    let open = spread_start(q, &turning, OPEN_SEED);
    let rank_anywhere = rank.max(constraint_rank(model, &open)?.0);
    let shared = sharing_groups(model);
    let scale = size(&here);
    let brought_together = (0..here.len())
        .any(|i| (0..i).any(|j| shared[i] != shared[j] && coincide(&here, scale, i, j)));
    let mut branch = Branch {
        tree_dof: tree_dof(model, q)?,
        rank,
        generic_rank: rank,
        coinciding: Vec::new(),
    };
    // A rank below the bound may be the mechanism's own (a row of parallelograms has rows that
    // are independent only off its closed set): when it is also the rank at closed
    // configurations nearby, and no joins were brought together, the configuration is taken as
    // generic.
    let generic_nearby = || -> Result<bool, EvalError> { Ok(nearby_rank(model, q)? <= rank) };
    if !brought_together && (rank == rank_anywhere || generic_nearby()?) {
        return Ok(branch);
    }
    let spread = spread_configurations(model, q)?;
    let elsewhere = (spread.iter())
        .map(|s| join_points(model, s))
        .collect::<Result<Vec<_>, _>>()?;
    branch.generic_rank = generic_rank(model, rank, &spread)?;
    branch.coinciding = coinciding(&here, &elsewhere);
    Ok(branch)
}

/// The sample number given to `jitter` for the configuration that is not closed.
const OPEN_SEED: usize = 2000;

/// Whether joins i and j stand at one point among `points` of size `scale`.
fn coincide(points: &[Vector3<f64>], scale: f64, i: usize, j: usize) -> bool {
    (points[i] - points[j]).norm() <= COINCIDENT * scale
}

/// For every join, a group number: joins whose frames share a point of a body (the same body,
/// the same position on it) are in one group, and so are the joins linked through such shares.
fn sharing_groups(model: &KinematicModel) -> Vec<usize> {
    let frames: Vec<[(usize, Vector3<f64>); 2]> = (model.joints.iter())
        .map(|j| {
            [
                (j.first_body, j.first.translation.vector),
                (j.second_body, j.second.translation.vector),
            ]
        })
        .collect();
    let shares = |a: usize, b: usize| {
        frames[a].iter().any(|(body, p)| {
            (frames[b].iter())
                .any(|(other, r)| body == other && (p - r).norm() <= 1e-12 * (1.0 + p.norm()))
        })
    };
    let mut group: Vec<usize> = (0..frames.len()).collect();
    // Joins merged until no share links two groups (at most one pass per join).
    for _ in 0..frames.len() {
        let mut changed = false;
        for a in 0..frames.len() {
            for b in 0..a {
                if group[a] != group[b] && shares(a, b) {
                    let (keep, drop) = (group[a].min(group[b]), group[a].max(group[b]));
                    group
                        .iter_mut()
                        .filter(|g| **g == drop)
                        .for_each(|g| *g = keep);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    group
}

/// The origin of every join's first frame, in the fixed axes, in the model's joint order.
pub(super) fn join_points(
    model: &KinematicModel,
    q: &[f64],
) -> Result<Vec<Vector3<f64>>, EvalError> {
    let poses = poses(model, q)?;
    Ok((model.joints.iter())
        .map(|joint| (poses[joint.first_body] * joint.first).translation.vector)
        .collect())
}

/// The largest distance between two of `points`: the scale of "close" (never zero).
pub(super) fn size(points: &[Vector3<f64>]) -> f64 {
    let mut size = 1e-300_f64;
    for a in points {
        for b in points {
            size = size.max((a - b).norm());
        }
    }
    size
}

/// The pairs of joins that coincide `here` and stand apart in some configuration of
/// `elsewhere`, one pair per two groups of joins that always coincide (the two joins at one
/// pivot of a linkage are a group; a folded linkage brings two groups together).
fn coinciding(here: &[Vector3<f64>], elsewhere: &[Vec<Vector3<f64>>]) -> Vec<Coincidence> {
    let scale_here = size(here);
    let scales: Vec<f64> = elsewhere.iter().map(|e| size(e)).collect();
    let together = |i: usize, j: usize| coincide(here, scale_here, i, j);
    // How far apart two joins stand at sample k, relative to its size.
    let distance =
        |k: usize, i: usize, j: usize| (elsewhere[k][i] - elsewhere[k][j]).norm() / scales[k];
    // Each join's group: the first join that coincides with it here and everywhere else.
    let group: Vec<usize> = (0..here.len())
        .map(|i| {
            (0..i)
                .find(|&j| {
                    together(i, j) && (0..elsewhere.len()).all(|k| distance(k, i, j) <= COINCIDENT)
                })
                .unwrap_or(i)
        })
        .collect();
    let mut found = Vec::new();
    for i in (0..here.len()).filter(|&i| group[i] == i) {
        for j in (i + 1..here.len()).filter(|&j| group[j] == j && together(i, j)) {
            let farthest = (0..elsewhere.len())
                .max_by(|&a, &b| distance(a, i, j).total_cmp(&distance(b, i, j)));
            if let Some(k) = farthest.filter(|&k| distance(k, i, j) > APART) {
                found.push(Coincidence {
                    first: i,
                    second: j,
                    point: here[i],
                    apart: (elsewhere[k][i] - elsewhere[k][j]).norm(),
                });
            }
        }
    }
    found
}

/// A starting guess that assembly moved far.
#[derive(Clone, Debug, PartialEq)]
pub struct FarGuess {
    pub coordinate: usize,
    pub guess: f64,
    pub assembled: f64,
    /// The change, whole turns aside for an angle that turns.
    pub change: f64,
}

/// The guesses (`guessed`) that assembly moved by more than a quarter turn, whole turns aside:
/// the angles of the configuration reached are not those the guesses describe. Lengths are not
/// judged (no scale tells what is far for them).
pub fn far_guesses(
    model: &KinematicModel,
    start: &[f64],
    q: &[f64],
    guessed: &[bool],
) -> Vec<FarGuess> {
    let turning = model.turning();
    let quarter_turn = std::f64::consts::FRAC_PI_2;
    (0..q.len())
        .filter(|&i| guessed[i] && turning[i])
        .filter_map(|i| {
            let change = super::assembly::within_half_turn(q[i] - start[i]);
            (change.abs() > quarter_turn).then_some(FarGuess {
                coordinate: i,
                guess: start[i],
                assembled: q[i],
                change,
            })
        })
        .collect()
}
