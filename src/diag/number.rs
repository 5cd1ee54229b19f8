//! Numbers written for people and for programs that read them back.

/// The shortest text that reads back as the same `f64` (in LSD, URDF and messages alike):
/// positional for usual magnitudes, with an exponent outside [1e-5, 1e16) so that round-off such
/// as 6e-17 does not spell out its zeros; −0 is written 0.
pub fn shortest(x: f64) -> String {
    let x = x + 0.0;
    if x == 0.0 || (1e-5..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
