//! Rheonomic joints: `time` in a dof chain (`rz(2 * pi * time) * tx(q)`, a pivot shaken by
//! `[0, 0, 0.01 * sin(50 * time)]`). Each parameter of the chain (a translation's component, a
//! rotation's angle) that uses the time gets a hidden coordinate of its join, appended after the
//! declared ones and imposed by a law of time as a drive imposes a coordinate
//! (`kinematics::drives`): the rest of lsdc sees a chain of coordinates, with the exact partials
//! and second derivatives of `chain`, and a driven coordinate, with the drive's exact law
//! derivatives, its row of the constraint stack, its effort and its work.
//!
//! Which hidden coordinate, decided from the parameter's terms p = Σ ±termᵢ:
//! - every term uses either the time or coordinates, never both (`tz(a * sin(w * time))`,
//!   `rz(q + w * time)`): the hidden coordinate h is the sum g(t) of the time's terms and the
//!   parameter becomes f(q) + h. h is a length or an angle along the step, and its effort is
//!   the force along the translation's component or the torque about the rotation's axis;
//! - a term mixes them (`tx(q * sin(time))`): the hidden coordinate is the time itself, τ = t,
//!   substituted in the parameter; its effort is the generalised force conjugate to the time,
//!   the power that imposes the motion (W).

use std::sync::Arc;

use crate::elab::value::{arith, negate, num, Applied, SExpr, Scalar};

/// A hidden coordinate of a rheonomic joint and the law that imposes it.
#[derive(Clone, Debug)]
pub struct PrescribedMotion {
    /// Its index among the joint's coordinates (after the declared ones).
    pub coordinate: usize,
    /// Its law of time: the time's terms of the parameter, or `time` itself.
    pub law: Scalar,
    /// Whether it is the time itself (its effort is then a power).
    pub clock: bool,
    /// The parameter as written, whose smoothness in time the law's derivatives need.
    pub written: Scalar,
}

/// The name of a join's k-th hidden coordinate (from 1): `motion1`, unless the link declares a
/// coordinate of that name (then `motion1_`, …).
pub fn hidden_name(declared: &[String], k: usize) -> String {
    let mut name = format!("motion{k}");
    while declared.contains(&name) {
        name.push('_');
    }
    name
}

/// Rewrites every parameter of a chain (`parameters`, in the chain's order) that uses the time
/// on a hidden coordinate, the hidden coordinates numbered from `declared` (the count of the
/// link's own coordinates).
pub fn rewrite<'a>(
    parameters: impl Iterator<Item = &'a mut Scalar>,
    declared: usize,
) -> Vec<PrescribedMotion> {
    let mut prescribed = Vec::new();
    for parameter in parameters.filter(|p| p.uses_time()) {
        let written = parameter.clone();
        let coordinate = declared + prescribed.len();
        let hidden = Arc::new(SExpr::Coordinate {
            index: coordinate as u32,
            order: 0,
        });
        let (rewritten, motion) = match split(parameter) {
            Some((rest, law)) => (
                arith('+', &rest, &hidden),
                PrescribedMotion {
                    coordinate,
                    law,
                    clock: false,
                    written,
                },
            ),
            None => (
                time_replaced(parameter, &hidden),
                PrescribedMotion {
                    coordinate,
                    law: Arc::new(SExpr::Time),
                    clock: true,
                    written,
                },
            ),
        };
        *parameter = rewritten;
        prescribed.push(motion);
    }
    prescribed
}

/// `p` as f + g with f the terms without the time and g those of the time alone, when no term
/// uses both.
fn split(p: &Scalar) -> Option<(Scalar, Scalar)> {
    let mut terms = Vec::new();
    additive_terms(p, true, &mut terms);
    let (mut rest, mut law) = (num(0.0), num(0.0));
    for (positive, term) in terms {
        let sum = match (term.uses_time(), term.uses_state()) {
            (true, true) => return None,
            (true, false) => &mut law,
            (false, _) => &mut rest,
        };
        *sum = arith(if positive { '+' } else { '-' }, sum, &term);
    }
    Some((rest, law))
}

/// The terms of the sums and differences at the top of `p`, each with its sign.
fn additive_terms(p: &Scalar, positive: bool, into: &mut Vec<(bool, Scalar)>) {
    match &**p {
        SExpr::Add(a, b) => {
            additive_terms(a, positive, into);
            additive_terms(b, positive, into);
        }
        SExpr::Sub(a, b) => {
            additive_terms(a, positive, into);
            additive_terms(b, !positive, into);
        }
        SExpr::Neg(a) => additive_terms(a, !positive, into),
        _ => into.push((positive, p.clone())),
    }
}

/// `p` with every `time` replaced by `by`.
fn time_replaced(p: &Scalar, by: &Scalar) -> Scalar {
    let replaced = |s: &Scalar| time_replaced(s, by);
    let call = |args: &[Scalar]| args.iter().map(replaced).collect::<Vec<_>>();
    match &**p {
        SExpr::Time => by.clone(),
        _ if !p.uses_time() => p.clone(),
        SExpr::Neg(a) => negate(&replaced(a)),
        SExpr::Add(a, b) => arith('+', &replaced(a), &replaced(b)),
        SExpr::Sub(a, b) => arith('-', &replaced(a), &replaced(b)),
        SExpr::Mul(a, b) => arith('*', &replaced(a), &replaced(b)),
        SExpr::Div(a, b) => arith('/', &replaced(a), &replaced(b)),
        SExpr::Pow(a, b) => arith('^', &replaced(a), &replaced(b)),
        SExpr::Call(applied) => Arc::new(SExpr::Call(Box::new(Applied {
            function: applied.function,
            args: call(&applied.args),
        }))),
        SExpr::UnknownFunction(applied) => Arc::new(SExpr::UnknownFunction(Box::new(Applied {
            function: applied.function,
            args: call(&applied.args),
        }))),
        _ => p.clone(),
    }
}
