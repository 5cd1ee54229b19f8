//! Why `kinematics::exact` computed no rank.

/// Why no exact rank was computed.
#[derive(Debug)]
pub enum ExactFailure {
    /// The program's mechanism or the command line's values are wrong.
    Input(String),
    /// A number is not exact: a constant, a coordinate, or an expression of them.
    NotExact(String),
    /// The exact configuration does not close a loop: the rank there would be off the
    /// configuration set.
    NotClosed { join: String, residual: f64 },
}

impl std::fmt::Display for ExactFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExactFailure::Input(m) | ExactFailure::NotExact(m) => write!(f, "{m}"),
            ExactFailure::NotClosed { join, residual } => write!(
                f,
                "the exact configuration does not close the loop of `{join}` (its two frames differ by {residual:.1e}); give every coordinate of the loop exactly with `--at`"
            ),
        }
    }
}
