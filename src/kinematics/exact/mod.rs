//! Exact mobility (Papegay 1992, chapter 4): the rank of the closure Jacobian Δ at a closed
//! configuration computed exactly, the kernel Ψ (the velocities written in independent ones,
//! q̇ = Ψ 𝒫̇, Δ Ψ = 0) and the reduced mass matrix Ψᵀ M Ψ of the equations in the independent
//! velocities (thesis §4.1.4, L6031).
//!
//! The thesis computes the rank over ℚ(tan θᵢ/2) by modular arithmetic at random points, which
//! gives an upper bound only, since random points are not closed configurations (its Rem. 4.6;
//! on the two-level antenna mesh it found 13 where the rank on the closed set is lower). Here the
//! rank is taken *at* a configuration proved closed: every coordinate is an exact number (a
//! length, or an angle by its exact cosine and sine, from its half-angle tangent), the loops'
//! poses are evaluated exactly and must coincide, and Δ is evaluated and reduced by Gauss–Jordan
//! elimination in exact arithmetic over ℚ(√d), where the mechanism's constants live (rotations
//! by 120° need √3). No threshold decides anything.
//!
//! - `rational`, `field`: the numbers; `recognise`: a double read as the exact number it stands
//!   for; `evaluate`: the equations' expressions evaluated exactly; `elimination`: rank and
//!   kernel; `configuration`: the exact configuration, given or read from an assembled one.

pub mod configuration;
pub mod elimination;
pub mod evaluate;
mod failure;
pub mod field;
pub mod rational;
mod recognise;

use std::collections::HashMap;

// `GivenValue` is read by the tests alone.
#[cfg_attr(not(lsdc_internals), allow(unused_imports))]
pub use configuration::{Given, GivenValue};
pub use failure::ExactFailure;
pub use field::Number;

use crate::elab::mechanism::Mechanism;
use crate::symbolic::closure_poses::{closure_poses, roots as pose_roots};
use crate::symbolic::generate;
use crate::topology::Topology;
use configuration::{exact_configuration, ExactCoordinate};
use evaluate::{Evaluator, SymbolValue};
use recognise::Recogniser;

/// The exact analysis at one closed configuration.
#[derive(serde::Serialize)]
pub struct ExactMobility {
    /// d of the field ℚ(√d) the numbers live in (1: ℚ).
    pub radicand: u64,
    /// Every coordinate (tree first, then the complementary links'), with its exact value and
    /// whether the command line gave it.
    pub configuration: Vec<ExactCoordinate>,
    /// Degrees of freedom of the tree: exact rank of its bodies' twists.
    pub tree_dof: usize,
    pub tree_coordinates: usize,
    /// Rank of the 6-rows-per-loop closure Jacobian over every coordinate.
    pub closure_rank: usize,
    /// Σ ranks of the complementary links' own columns (their motion subspaces).
    pub cut_rank: usize,
    /// rank(Δ) = closure_rank − cut_rank.
    pub rank: usize,
    /// Σ (6 − rank of each complementary link's own columns).
    pub constraint_rows: usize,
    /// Names of the independent coordinates, whose rates 𝒫̇ parametrise the velocities.
    pub independent: Vec<String>,
    /// Ψ: per coordinate (in `configuration` order), its rate's coefficients on the
    /// independent rates.
    pub kernel: Vec<Vec<Number>>,
    /// Ψᵀ M Ψ and Ψᵀ F at rest, or why they were not computed.
    pub reduced: Result<Reduced, String>,
}

impl ExactMobility {
    /// tree dof − rank(Δ): the dimension of the space of velocities that keep the loops closed.
    pub fn first_order_mobility(&self) -> usize {
        self.tree_dof - self.rank
    }
}

/// The equations of motion in the independent velocities at the configuration, at rest:
/// 𝐌 𝒫̈ = 𝐅 with 𝐌 = Ψᵀ M Ψ and 𝐅 = Ψᵀ F (the velocity terms vanish at rest).
#[derive(serde::Serialize)]
pub struct Reduced {
    pub mass: Vec<Vec<Number>>,
    pub forces: Vec<Number>,
}

/// The exact mobility of `mechanism` at the configuration of `given` coordinates, the others
/// read from `numeric` (an assembled configuration, by coordinate name).
pub fn exact_mobility(
    mechanism: &Mechanism,
    topology: &Topology,
    given: &[Given],
    numeric: &HashMap<String, f64>,
) -> Result<ExactMobility, ExactFailure> {
    let joined = |d: Vec<crate::diag::Diagnostic>| {
        ExactFailure::Input(
            d.iter()
                .map(|d| d.message.clone())
                .collect::<Vec<_>>()
                .join("; "),
        )
    };
    let poses = closure_poses(mechanism, topology).map_err(joined)?;
    let equations = generate(mechanism, topology).map_err(joined)?;
    let mut recogniser = Recogniser::new();
    let pose_expressions = pose_roots(&poses);
    let configuration = exact_configuration(
        &poses.pool,
        &pose_expressions,
        &poses.variables.positions,
        given,
        numeric,
        &mut recogniser,
    )?;
    let by_name: HashMap<&str, &ExactCoordinate> =
        configuration.iter().map(|c| (c.name.as_str(), c)).collect();
    let symbol_values = |pool: &crate::symbolic::expr::Pool,
                         parameters: &[crate::symbolic::lower::Variable],
                         recogniser: &mut Recogniser| {
        (0..pool.symbol_count() as u32)
            .map(|i| {
                let name = pool.symbol_name(i);
                if let Some(c) = by_name.get(name) {
                    return Some(c.value.clone());
                }
                if name.ends_with('\'') {
                    // A rate: the analysis is at rest.
                    return Some(SymbolValue::Number(Number::integer(0, 1)));
                }
                let parameter = parameters.iter().find(|p| p.name == name)?;
                let value = recogniser.number(parameter.given?)?;
                Some(SymbolValue::Number(value))
            })
            .collect::<Vec<_>>()
    };

    // The loops must close exactly.
    let values = symbol_values(&poses.pool, &poses.variables.parameters, &mut recogniser);
    let mut evaluator = Evaluator::new(&poses.pool, values);
    let exact = evaluator
        .values(&pose_expressions, &mut recogniser)
        .map_err(ExactFailure::NotExact)?;
    for (l, frames) in poses.loops.iter().zip(exact.chunks(24)) {
        let (end, target) = frames.split_at(12);
        if end != target {
            let residual = (0..12)
                .map(|k| (end[k].to_f64() - target[k].to_f64()).abs())
                .fold(0.0, f64::max);
            return Err(ExactFailure::NotClosed {
                join: l.name.clone(),
                residual,
            });
        }
    }

    // The tree's degrees of freedom: the rank of its bodies' twists.
    let tree_coordinates = topology
        .principal
        .iter()
        .map(|l| {
            mechanism
                .link(mechanism.join(l.join).link)
                .coordinates
                .len()
        })
        .sum::<usize>();
    let mut twist_entries = Vec::new();
    for columns in &poses.body_columns {
        for part in 0..2 {
            for axis in 0..3 {
                for c in columns.iter().take(tree_coordinates) {
                    twist_entries.push(c.map(|twist| twist[part][axis]));
                }
            }
        }
    }
    let present: Vec<_> = twist_entries.iter().flatten().copied().collect();
    let present_values = evaluator
        .values(&present, &mut recogniser)
        .map_err(ExactFailure::NotExact)?;
    let mut present_values = present_values.into_iter();
    let twist_values: Vec<Number> = twist_entries
        .iter()
        .map(|e| match e {
            Some(_) => present_values.next().expect("one value per entry"),
            None => Number::integer(0, 1),
        })
        .collect();
    let twists: Vec<Vec<Number>> = if tree_coordinates == 0 {
        Vec::new()
    } else {
        twist_values
            .chunks(tree_coordinates)
            .map(|r| r.to_vec())
            .collect()
    };
    let tree_dof = elimination::rank(&twists);

    // Δ, exactly.
    let n = equations.dimension();
    let values = symbol_values(
        &equations.pool,
        &equations.variables.parameters,
        &mut recogniser,
    );
    let mut evaluator = Evaluator::new(&equations.pool, values);
    let delta_values = evaluator
        .values(&equations.constraints, &mut recogniser)
        .map_err(ExactFailure::NotExact)?;
    let delta: Vec<Vec<Number>> = if n == 0 {
        Vec::new()
    } else {
        delta_values.chunks(n).map(|r| r.to_vec()).collect()
    };
    let closure_rank = elimination::rank(&delta);
    // Each complementary link's own columns, in its own loop's six rows.
    let mut cut_rank = 0;
    let mut constraint_rows = 0;
    let mut offset = tree_coordinates;
    let mut cut_columns = Vec::new();
    for (k, link) in topology.complementary.iter().enumerate() {
        let count = mechanism
            .link(mechanism.join(link.join).link)
            .coordinates
            .len();
        let block: Vec<Vec<Number>> = delta[6 * k..6 * k + 6]
            .iter()
            .map(|row| row[offset..offset + count].to_vec())
            .collect();
        let r = if count == 0 {
            0
        } else {
            elimination::rank(&block)
        };
        cut_rank += r;
        constraint_rows += 6 - r;
        cut_columns.extend(offset..offset + count);
        offset += count;
    }
    let rank = closure_rank - cut_rank;

    // Ψ: the complementary links' coordinates are eliminated first, then the tree's from the
    // last to the first, so that the free (independent) coordinates are the tree's first ones
    // wherever they can be (the crank of a linkage, the first joint of a loop).
    let order: Vec<usize> = cut_columns
        .iter()
        .copied()
        .chain((0..tree_coordinates).rev())
        .collect();
    let echelon = elimination::echelon(&delta, &order);
    // The independent coordinates in the mechanism's order.
    let mut free_basis: Vec<(usize, Vec<Number>)> = echelon
        .free_columns()
        .into_iter()
        .zip(echelon.kernel())
        .collect();
    free_basis.sort_by_key(|(c, _)| *c);
    let (free, basis): (Vec<usize>, Vec<Vec<Number>>) = free_basis.into_iter().unzip();
    let independent = free
        .iter()
        .map(|&c| configuration[c].name.clone())
        .collect();
    let kernel: Vec<Vec<Number>> = (0..n)
        .map(|c| basis.iter().map(|v| v[c].clone()).collect())
        .collect();

    let reduced = reduced_equations(&mut evaluator, &equations, &kernel, &mut recogniser);
    Ok(ExactMobility {
        radicand: recogniser.radicand,
        configuration,
        tree_dof,
        tree_coordinates,
        closure_rank,
        cut_rank,
        rank,
        constraint_rows,
        independent,
        kernel,
        reduced,
    })
}

/// Ψᵀ M Ψ and Ψᵀ F at rest.
fn reduced_equations(
    evaluator: &mut Evaluator,
    equations: &crate::symbolic::Equations,
    kernel: &[Vec<Number>],
    recogniser: &mut Recogniser,
) -> Result<Reduced, String> {
    let n = equations.dimension();
    let mass = evaluator.values(&equations.mass, recogniser)?;
    let forces = evaluator.values(&equations.forces, recogniser)?;
    let k = kernel.first().map_or(0, |r| r.len());
    let zero = || Number::integer(0, recogniser.radicand);
    let mut reduced_mass = vec![vec![zero(); k]; k];
    let mut reduced_forces = vec![zero(); k];
    for a in 0..k {
        for i in 0..n {
            if kernel[i][a].is_zero() {
                continue;
            }
            reduced_forces[a] = reduced_forces[a].add(&kernel[i][a].mul(&forces[i]));
            for b in 0..k {
                for j in 0..n {
                    if kernel[j][b].is_zero() {
                        continue;
                    }
                    let term = kernel[i][a].mul(&mass[i * n + j]).mul(&kernel[j][b]);
                    reduced_mass[a][b] = reduced_mass[a][b].add(&term);
                }
            }
        }
    }
    Ok(Reduced {
        mass: reduced_mass,
        forces: reduced_forces,
    })
}
