//! The text of `lsdc tree --exact`: the exact configuration, rank(Δ) beside the numeric rank,
//! the kernel Ψ as the velocities in the independent ones, and the reduced equations at rest.

use crate::kinematics::exact::evaluate::SymbolValue;
use crate::kinematics::exact::Number;
use crate::studies::exact_mobility::ExactReport;

/// `a·x + b·y` with exact coefficients; `0` when every coefficient is.
fn combination(coefficients: &[Number], names: &[String]) -> String {
    let mut out = String::new();
    for (c, name) in coefficients.iter().zip(names) {
        if c.is_zero() {
            continue;
        }
        let text = c.to_string();
        let (negative, magnitude) = match text.strip_prefix('-') {
            Some(rest) if c.is_rational() || c.rational.is_zero() => (true, rest.to_string()),
            _ => (false, text),
        };
        let factor = if magnitude == "1" {
            String::new()
        } else if magnitude.contains(' ') {
            format!("({magnitude})·")
        } else {
            format!("{magnitude}·")
        };
        out += &match (out.is_empty(), negative) {
            (true, false) => format!("{factor}{name}"),
            (true, true) => format!("-{factor}{name}"),
            (false, false) => format!(" + {factor}{name}"),
            (false, true) => format!(" - {factor}{name}"),
        };
    }
    if out.is_empty() {
        "0".to_string()
    } else {
        out
    }
}

pub fn exact_tree(report: &ExactReport) -> String {
    let exact = match &report.exact {
        Ok(exact) => exact,
        Err(reason) => {
            let mut out = format!("exact mobility not computed: {reason}\n");
            if let Ok(rank) = report.numeric_rank {
                out += &format!(
                    "numeric rank(Δ) {rank} (relative tolerance {:e})\n",
                    report.tolerance
                );
            }
            return out;
        }
    };
    let field = match exact.radicand {
        1 => "ℚ".to_string(),
        d => format!("ℚ(√{d})"),
    };
    let mut out =
        format!("exact configuration (numbers of {field}; t = tan(θ/2) for an angle θ)\n");
    for c in &exact.configuration {
        let kind = match c.value {
            SymbolValue::Angle { .. } => "angle",
            SymbolValue::Number(_) => "length",
        };
        out += &format!(
            "  {:<20} {:<6} {:<28} {}\n",
            c.name,
            kind,
            c.describe(),
            if c.given {
                "given"
            } else {
                "read from the assembly"
            }
        );
    }
    out += "the loops close exactly there\n";
    out += &format!(
        "exact rank(Δ) {} = closure Jacobian rank {} - complementary links' own rank {} ({} constraint rows, {} redundant)\n",
        exact.rank,
        exact.closure_rank,
        exact.cut_rank,
        exact.constraint_rows,
        exact.constraint_rows - exact.rank
    );
    out += &format!(
        "exact first-order mobility {} = tree dof {} - rank {}\n",
        exact.first_order_mobility(),
        exact.tree_dof,
        exact.rank
    );
    match &report.numeric_rank {
        Ok(rank) if *rank == exact.rank => {
            out += &format!(
                "numeric rank(Δ) {rank} at the same configuration (SVD, relative tolerance {:e}): agrees\n",
                report.tolerance
            )
        }
        Ok(rank) => {
            out += &format!(
                "numeric rank(Δ) {rank} at the same configuration (SVD, relative tolerance {:e}): WRONG, the threshold {} ({} exactly)\n",
                report.tolerance,
                if *rank < exact.rank {
                    "took small singular values for zeros"
                } else {
                    "took round-off for independent rows"
                },
                exact.rank
            )
        }
        Err(reason) => out += &format!("numeric rank(Δ) not computed: {reason}\n"),
    }
    let names: Vec<String> = exact.independent.iter().map(|n| format!("{n}'")).collect();
    out += &format!(
        "independent velocities ({}): {}\n",
        names.len(),
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    );
    out += "kernel Ψ (every rate in the independent ones, Δ Ψ = 0)\n";
    for (c, row) in exact.configuration.iter().zip(&exact.kernel) {
        out += &format!(
            "  {:<20} = {}\n",
            format!("{}'", c.name),
            combination(row, &names)
        );
    }
    match &exact.reduced {
        Ok(reduced) => {
            out += "reduced equations at rest, M𝒫'' = F with M = Ψᵀ M Ψ, F = Ψᵀ F (velocity terms vanish at rest)\n";
            let accelerations: Vec<String> =
                exact.independent.iter().map(|n| format!("{n}''")).collect();
            for (row, force) in reduced.mass.iter().zip(&reduced.forces) {
                out += &format!("  {} = {}\n", combination(row, &accelerations), force);
            }
        }
        Err(reason) => out += &format!("reduced equations not computed: {reason}\n"),
    }
    out
}
