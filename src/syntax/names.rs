//! The names the language predefines: constants and functions every program can use without
//! declaring them. The checker gives them types (`check::types`) and the elaborator values; the
//! URDF import avoids them when it names bodies and joints.

pub const BUILTIN_NAMES: &[&str] = &[
    "pi",
    "time",
    "earth",
    "sin",
    "cos",
    "tan",
    "asin",
    "acos",
    "atan",
    "sqrt",
    "exp",
    "log",
    "abs",
    "atan2",
    "floor",
    "mod",
    "norm",
    "dot",
    "cross",
    "position",
    "velocity",
    "angular_velocity",
    "orientation",
    "distance",
    "rolling",
    "sliding",
    "rolling_disc",
    "sliding_disc",
];
