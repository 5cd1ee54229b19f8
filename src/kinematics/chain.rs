//! A dof chain's parameters compiled once, when the model is built: every translation component
//! and rotation angle, as expressions of the link's coordinates, lowered into a pool with the
//! derivatives the kinematics needs, taken symbolically there, and evaluated as one tape.
//!
//! For a parameter p(q) of a chain of n coordinates, moving at rates v, the tape's roots are
//! p, its partials ∂p/∂q_k (the motion subspace's columns) and the mixed derivatives
//! ∂ṗ/∂q_l of its rate ṗ = Σ_k ∂p/∂q_k v_k (the rates are symbols too): their sum along the
//! rates is the second derivative p̈ when the coordinates have no acceleration (the joint's
//! bias), and along another direction the change of the joint's velocity with its coordinates.
//! The values and partials come first in the tape: without rates, only that prefix is evaluated.

use std::collections::HashMap;

use super::eval::{EvalError, Geometric, UnknownValues};
use crate::elab::value::SExpr;
use crate::symbolic::expr::{ExprId, Pool, Tape};
use crate::symbolic::program::Lower;

/// The compiled parameters of one chain.
#[derive(Clone, Debug)]
pub struct CompiledChain {
    tape: Tape,
    coordinates: usize,
    parameters: usize,
    /// The tape's first nodes that the values and partials need.
    without_rates: usize,
}

/// Where a chain's tape is evaluated: kept from one evaluation to the next, so that evaluating
/// allocates nothing once the buffers have their sizes.
#[derive(Clone, Debug, Default)]
pub struct ChainScratch {
    symbols: Vec<f64>,
    values: Vec<f64>,
}

impl CompiledChain {
    /// Lowers `parameters`, expressions of `coordinates` coordinates, unknowns folded to
    /// their values.
    pub fn new(
        parameters: &[&SExpr],
        coordinates: usize,
        unknowns: &UnknownValues,
    ) -> Result<CompiledChain, EvalError> {
        let mut lowering = Geometric {
            pool: Pool::new(),
            unknowns,
            coordinates: Vec::new(),
        };
        let positions: Vec<ExprId> = (0..coordinates)
            .map(|k| lowering.pool.symbol(&format!("q{k}")))
            .collect();
        let rates: Vec<ExprId> = (0..coordinates)
            .map(|k| lowering.pool.symbol(&format!("v{k}")))
            .collect();
        lowering.coordinates = positions.clone();
        let parameters = parameters
            .iter()
            .map(|p| lowering.lower(p))
            .collect::<Result<Vec<_>, _>>()?;
        let pool = &mut lowering.pool;
        let mut partials_memo = vec![HashMap::new(); coordinates];
        let mut first = Vec::new();
        for &p in &parameters {
            let partials: Vec<ExprId> = (0..coordinates)
                .map(|k| pool.derivative(p, positions[k], &mut partials_memo[k]))
                .collect();
            first.push(p);
            first.extend(&partials);
        }
        let mut mixed_memo = vec![HashMap::new(); coordinates];
        let mut second = Vec::new();
        for partials in first.chunks(1 + coordinates) {
            let terms: Vec<ExprId> = (0..coordinates)
                .map(|k| pool.mul(partials[1 + k], rates[k]))
                .collect();
            let rate = pool.sum(terms);
            second.extend(
                (0..coordinates).map(|l| pool.derivative(rate, positions[l], &mut mixed_memo[l])),
            );
        }
        let roots = [first.as_slice(), &second].concat();
        let tape = Tape::new(pool, &roots);
        let without_rates = tape.roots[..first.len()]
            .iter()
            .map(|&r| r + 1)
            .max()
            .unwrap_or(0);
        Ok(CompiledChain {
            tape,
            coordinates,
            parameters: parameters.len(),
            without_rates,
        })
    }

    /// Evaluates the parameters and their partials at coordinates `q`, and, given `rates`, their
    /// mixed derivatives along them, into `scratch`.
    pub fn eval(&self, q: &[f64], rates: Option<&[f64]>, scratch: &mut ChainScratch) {
        scratch.symbols.clear();
        scratch.symbols.extend_from_slice(q);
        match rates {
            Some(rates) => {
                scratch.symbols.extend_from_slice(rates);
                self.tape.eval_into(&scratch.symbols, &mut scratch.values);
            }
            None => {
                scratch.symbols.resize(2 * self.coordinates, 0.0);
                self.tape.eval_prefix_into(
                    &scratch.symbols,
                    &mut scratch.values,
                    self.without_rates,
                );
            }
        }
    }

    /// Parameter `p`'s value after [`CompiledChain::eval`].
    pub fn value(&self, scratch: &ChainScratch, p: usize) -> f64 {
        scratch.values[self.tape.roots[p * (1 + self.coordinates)]]
    }

    /// ∂p/∂q_k after [`CompiledChain::eval`].
    pub fn partial(&self, scratch: &ChainScratch, p: usize, k: usize) -> f64 {
        scratch.values[self.tape.roots[p * (1 + self.coordinates) + 1 + k]]
    }

    /// ∂ṗ/∂q_l after [`CompiledChain::eval`] with rates.
    pub fn mixed(&self, scratch: &ChainScratch, p: usize, l: usize) -> f64 {
        let first = self.parameters * (1 + self.coordinates);
        scratch.values[self.tape.roots[first + p * self.coordinates + l]]
    }

    /// Number of distinct nodes evaluated with rates.
    #[cfg(lsdc_internals)]
    pub fn size(&self) -> usize {
        self.tape.size()
    }
}
