//! Piecewise scalars: `select(test, a, b)`, the one piecewise operation (a where test ≥ 0, else
//! b), and the built-in functions written with it, `saturate(x, lo, hi)` and
//! `dead_zone(x, width)`. Each piece is differentiated on its own (`Pool::derivative`), so the
//! derivatives are exact inside every piece; at a boundary they are the pieces' on the side a
//! rising test enters (the right-hand derivatives of a law of time).

use std::sync::Arc;

use super::value::{arith, constant, num, SExpr, Scalar};
use crate::diag::Diagnostic;
use crate::source::Span;

type Result<T> = std::result::Result<T, Diagnostic>;

/// `when_nonnegative` where `test ≥ 0`, else `otherwise`: decided now for a number test, and
/// either branch when both are the same.
pub(super) fn select(test: &Scalar, when_nonnegative: &Scalar, otherwise: &Scalar) -> Scalar {
    let same = Arc::ptr_eq(when_nonnegative, otherwise)
        || matches!((constant(when_nonnegative), constant(otherwise)), (Some(a), Some(b)) if a.to_bits() == b.to_bits());
    match constant(test) {
        Some(c) if c >= 0.0 => when_nonnegative.clone(),
        Some(_) => otherwise.clone(),
        None if same => otherwise.clone(),
        None => Arc::new(SExpr::call(
            "select",
            vec![test.clone(), when_nonnegative.clone(), otherwise.clone()],
        )),
    }
}

/// `saturate(x, lo, hi)`: x bounded to [lo, hi]. Its derivative is x' strictly inside, 0
/// outside; at x = lo it is x', at x = hi 0 (the side a rising x goes to). Bounds written as
/// numbers must be ordered (E0650).
pub(super) fn saturate(args: &[Scalar], spans: &[Span]) -> Result<Scalar> {
    let [x, lo, hi] = args else {
        return Err(super::elaborator::internal("`saturate` takes 3 arguments"));
    };
    if let (Some(low), Some(high)) = (constant(lo), constant(hi)) {
        if low > high {
            return Err(Diagnostic::error(
                "E0650",
                format!(
                    "`saturate` between {} and {}: its lower bound is above its upper bound",
                    shown(low),
                    shown(high)
                ),
            )
            .primary(spans[1], "the lower bound")
            .secondary(spans[2], "the upper bound")
            .help("write `saturate(x, lo, hi)` with lo ≤ hi"));
        }
    }
    let inside_or_low = select(&arith('-', x, lo), x, lo);
    Ok(select(&arith('-', x, hi), hi, &inside_or_low))
}

/// `dead_zone(x, width)`: 0 where |x| ≤ width/2, and x moved toward 0 by width/2 beyond, so
/// that it is continuous: x − width/2 above, x + width/2 below. Its derivative is 0 inside the
/// zone and x' beyond; at x = width/2 it is x', at x = −width/2 it is 0. A width written as a
/// number must not be negative (E0650).
pub(super) fn dead_zone(args: &[Scalar], spans: &[Span]) -> Result<Scalar> {
    let [x, width] = args else {
        return Err(super::elaborator::internal("`dead_zone` takes 2 arguments"));
    };
    if let Some(w) = constant(width).filter(|w| *w < 0.0) {
        return Err(Diagnostic::error(
            "E0650",
            format!("`dead_zone` of width {}: a width is not negative", shown(w)),
        )
        .primary(spans[1], "a negative width")
        .help("`dead_zone(x, width)` is 0 on [-width/2, width/2]: give a width ≥ 0"));
    }
    let half = arith('/', width, &num(2.0));
    let (above, below) = (arith('-', x, &half), arith('+', x, &half));
    let zone_or_below = select(&below, &num(0.0), &below);
    Ok(select(&above, &above, &zone_or_below))
}

/// A number as the diagnostics write it.
pub(super) fn shown(x: f64) -> String {
    crate::diag::number::shortest(x)
}
