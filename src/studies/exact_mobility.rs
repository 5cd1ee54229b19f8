//! What `lsdc tree --exact` reports: the exact rank of the loops' constraints at a closed
//! configuration (`kinematics::exact`) beside the numeric rank at the same configuration, so
//! that a threshold fooled near a singular configuration shows.

use std::collections::HashMap;

use crate::diag::Diagnostic;
use crate::elab::mechanism::{InitialValue, Mechanism};
use crate::elab::value::{num, JoinId};
use crate::kinematics::assembly::AssemblyOptions;
use crate::kinematics::exact::{exact_mobility, ExactMobility, Given};
use crate::kinematics::mobility::{constraint_rank, RANK_TOLERANCE};
use crate::topology;

use super::analysis::assembled_model;

#[derive(serde::Serialize)]
pub struct ExactReport {
    /// The exact analysis, or why there is none.
    pub exact: Result<ExactMobility, String>,
    /// rank(Δ) by SVD (relative tolerance `tolerance`) at the assembled configuration, or why
    /// there is none.
    pub numeric_rank: Result<usize, String>,
    pub tolerance: f64,
}

impl ExactReport {
    /// Whether the numeric rank disagrees with the exact one.
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub fn numeric_fooled(&self) -> bool {
        matches!((&self.exact, &self.numeric_rank), (Ok(e), Ok(r)) if e.rank != *r)
    }
}

/// Every join coordinate's name, `join.coordinate`.
fn coordinate_names(mechanism: &Mechanism) -> Vec<String> {
    (0..mechanism.joins.len())
        .flat_map(|index| {
            let join = JoinId(index as u32);
            let name = mechanism.join_name(join);
            let link = mechanism.link(mechanism.join(join).link);
            (link.coordinates.iter())
                .map(move |c| format!("{name}.{}", &**c))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// `--at '*=VALUE'` gives VALUE to every coordinate not given by name.
fn expanded(mechanism: &Mechanism, given: &[Given]) -> Vec<Given> {
    let named: Vec<&Given> = given.iter().filter(|g| g.name != "*").collect();
    let mut all: Vec<Given> = named.iter().map(|g| (*g).clone()).collect();
    if let Some(every) = given.iter().rev().find(|g| g.name == "*") {
        for name in coordinate_names(mechanism) {
            if !named.iter().any(|g| g.name == name) {
                all.push(Given {
                    name,
                    value: every.value.clone(),
                });
            }
        }
    }
    all
}

/// `mechanism` with the `given` coordinates held at their values by the assembly.
fn holding(mechanism: &Mechanism, given: &[Given]) -> Result<Mechanism, String> {
    let mut held = mechanism.clone();
    for g in given {
        let found = (0..mechanism.joins.len()).find_map(|index| {
            let join = JoinId(index as u32);
            let name = mechanism.join_name(join);
            let link = mechanism.link(mechanism.join(join).link);
            let coordinate = link
                .coordinates
                .iter()
                .position(|c| format!("{name}.{}", &**c) == g.name)?;
            Some((join, coordinate))
        });
        let Some((join, coordinate)) = found else {
            return Err(format!(
                "`--at {}`: no join coordinate of that name",
                g.name
            ));
        };
        let value = num(g.approximate());
        match (held.initial.iter_mut())
            .find(|i| i.join == join && i.coordinate == coordinate && i.order == 0)
        {
            Some(initial) => {
                initial.value = value;
                initial.fixed = true;
                initial.guess = false;
            }
            None => {
                let span = mechanism.join(join).span;
                held.initial.push(InitialValue {
                    join,
                    coordinate,
                    order: 0,
                    value,
                    fixed: true,
                    guess: false,
                    span,
                });
            }
        }
    }
    Ok(held)
}

/// The exact mobility at the configuration of `given` values, the other coordinates assembled
/// and read exactly.
pub fn exact_tree(mechanism: &Mechanism, given: &[Given]) -> Result<ExactReport, Vec<Diagnostic>> {
    let topology = topology::build(mechanism)?;
    let unavailable = |message: String| ExactReport {
        exact: Err(message.clone()),
        numeric_rank: Err(message),
        tolerance: RANK_TOLERANCE,
    };
    let given = &expanded(mechanism, given);
    let held = match holding(mechanism, given) {
        Ok(held) => held,
        Err(message) => return Ok(unavailable(message)),
    };
    let assembled = assembled_model(&held, topology.clone(), &AssemblyOptions::default());
    let (model, report) = match assembled {
        Ok((model, report, _)) => (model, report),
        Err(diagnostics) => {
            let messages: Vec<String> = diagnostics.iter().map(|d| d.message.clone()).collect();
            return Ok(unavailable(format!(
                "the configuration could not be assembled: {}",
                messages.join("; ")
            )));
        }
    };
    let numeric: HashMap<String, f64> = report
        .coordinates
        .iter()
        .map(|c| (c.name.clone(), c.value))
        .collect();
    let q: Vec<f64> = report.coordinates.iter().map(|c| c.value).collect();
    let numeric_rank = constraint_rank(&model, &q)
        .map(|(rank, _)| rank)
        .map_err(|e| crate::kinematics::eval::describe(&e, mechanism));
    let exact = exact_mobility(&held, &topology, given, &numeric).map_err(|e| e.to_string());
    Ok(ExactReport {
        exact,
        numeric_rank,
        tolerance: RANK_TOLERANCE,
    })
}
