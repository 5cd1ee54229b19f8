//! The types of LSD and the rules that relate them: which type fits where (the overloading of `0`
//! and `1`, translations and rotations as displacements, a body as its reference frame), the
//! fields of each kind of object, and the built-in constants and functions.

use std::fmt;

/// A scope: a file, a package or the standard library (see `check::scope`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ScopeId(pub u32);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DefId(pub u32);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Ty {
    Scalar,
    Vector,
    Matrix,
    Rotation,
    Displacement,
    Frame,
    Body,
    Link,
    Force,
    Torque,
    /// A named join: its fields are its joint coordinates (`crank.q`).
    Join,
    /// The literal `0`: zero scalar, vector, matrix or displacement, resolved by context.
    Zero,
    /// The literal `1`: one, identity rotation, identity displacement or identity matrix.
    One,
    Package(ScopeId),
    Definition(DefId),
    /// The type of an expression that already produced an error: it fits everywhere, so one
    /// mistake gives one message.
    Error,
}

impl Ty {
    /// The type named in a parameter annotation `a : vector`.
    pub fn from_annotation(name: &str) -> Option<Ty> {
        Some(match name {
            "scalar" => Ty::Scalar,
            "vector" => Ty::Vector,
            "matrix" => Ty::Matrix,
            "rotation" => Ty::Rotation,
            "displacement" => Ty::Displacement,
            "frame" => Ty::Frame,
            "body" => Ty::Body,
            "link" => Ty::Link,
            "force" => Ty::Force,
            "torque" => Ty::Torque,
            _ => return None,
        })
    }

    pub const ANNOTATIONS: [&'static str; 10] = [
        "scalar",
        "vector",
        "matrix",
        "rotation",
        "displacement",
        "frame",
        "body",
        "link",
        "force",
        "torque",
    ];

    /// Whether a value of type `self` can be used where `expected` is required.
    pub fn fits(self, expected: Ty) -> bool {
        use Ty::*;
        match (self, expected) {
            (Error, _) | (_, Error) => true,
            (a, b) if a == b => true,
            (Zero, Scalar | Vector | Matrix | Displacement) => true,
            (One, Scalar | Rotation | Displacement | Matrix) => true,
            // A translation and a rotation are displacements (subgroups of the displacements).
            (Vector | Rotation, Displacement) => true,
            // A body stands for its reference frame (`join satellite and earth`).
            (Body, Frame) => true,
            _ => false,
        }
    }

    /// `0` and `1` in arithmetic are numbers.
    pub fn numeric(self) -> Ty {
        match self {
            Ty::Zero | Ty::One => Ty::Scalar,
            other => other,
        }
    }

    /// The type's name with an article, for messages ("a vector", "an error").
    pub fn with_article(self) -> String {
        let name = self.to_string();
        let article = if name.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        };
        match self {
            Ty::Zero => "the literal `0`".to_string(),
            Ty::One => "the literal `1`".to_string(),
            _ => format!("{article} {name}"),
        }
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = match self {
            Ty::Scalar => "scalar",
            Ty::Vector => "vector",
            Ty::Matrix => "matrix",
            Ty::Rotation => "rotation",
            Ty::Displacement => "displacement",
            Ty::Frame => "frame",
            Ty::Body => "body",
            Ty::Link => "link",
            Ty::Force => "force",
            Ty::Torque => "torque",
            Ty::Join => "join",
            Ty::Zero => "zero",
            Ty::One => "one",
            Ty::Package(_) => "package",
            Ty::Definition(_) => "parameterised definition",
            Ty::Error => "error",
        };
        f.write_str(name)
    }
}

/// Fields that can be read with `x.field`, by kind of object.
pub fn field_type(target: Ty, field: &str) -> Option<Ty> {
    Some(match (target, field) {
        (Ty::Body, "frame" | "iframe") => Ty::Frame,
        (Ty::Body, "mass") => Ty::Scalar,
        (Ty::Body, "inertia") => Ty::Vector,
        (Ty::Link, f) if is_numbered(f, "dof") => Ty::Displacement,
        (Ty::Link, f) if is_numbered(f, "force") || is_numbered(f, "torque") => Ty::Vector,
        (Ty::Force | Ty::Torque, "value") => Ty::Vector,
        (Ty::Force | Ty::Torque, "body") => Ty::Body,
        (Ty::Frame, "body") => Ty::Body,
        (Ty::Frame, "displ") => Ty::Displacement,
        // Coordinate names depend on the link's value: checked during elaboration.
        (Ty::Join, _) => Ty::Scalar,
        _ => return None,
    })
}

/// Field names readable on a kind of object (for did-you-mean).
pub fn field_names(target: Ty) -> Vec<String> {
    let fixed: &[&str] = match target {
        Ty::Body => &["frame", "iframe", "mass", "inertia"],
        Ty::Force | Ty::Torque => &["value", "body"],
        Ty::Frame => &["body", "displ"],
        Ty::Link => &[],
        _ => &[],
    };
    let mut names: Vec<String> = fixed.iter().map(|s| s.to_string()).collect();
    if target == Ty::Link {
        for base in ["dof", "force", "torque"] {
            names.push(base.to_string());
            names.extend((1..=6).map(|i| format!("{base}{i}")));
        }
    }
    names
}

/// A link's scalar fields besides its efforts: its potential, the limits of its coordinate and
/// the restitution of its stops, the geared rotor that drives it, the coupling of a mimic's
/// coordinate to its leader's, and the friction in its coordinate.
const LINK_SCALAR_FIELDS: [&str; 10] = [
    "potential",
    "lower",
    "upper",
    "restitution",
    "rotor_inertia",
    "gear_ratio",
    "mimic_multiplier",
    "mimic_offset",
    "friction",
    "damping",
];

/// Fields a constructor accepts, with the type of their value.
pub fn constructor_field_type(kind: crate::syntax::ast::ConstructKind, field: &str) -> Option<Ty> {
    use crate::syntax::ast::ConstructKind::*;
    Some(match (kind, field) {
        (Body, "mass") => Ty::Scalar,
        (Body, "iframe") => Ty::Displacement,
        (Body, "inertia") => Ty::Vector,
        (Link, f) if is_numbered(f, "dof") => Ty::Displacement,
        (Link, f) if is_numbered(f, "force") || is_numbered(f, "torque") => Ty::Vector,
        (Force | Torque, "value") => Ty::Vector,
        (Force | Torque, "body") => Ty::Body,
        (Force | Torque | Link, "potential") => Ty::Scalar,
        (Link, f) if LINK_SCALAR_FIELDS.contains(&f) => Ty::Scalar,
        (Link, "rotor_axis") => Ty::Vector,
        (Link, "mimic") => Ty::Join,
        (Force, "field") => Ty::Vector,
        _ => return None,
    })
}

pub fn constructor_field_names(kind: crate::syntax::ast::ConstructKind) -> Vec<String> {
    use crate::syntax::ast::ConstructKind::*;
    match kind {
        Body => ["mass", "iframe", "inertia"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        Link => field_names(Ty::Link)
            .into_iter()
            .chain(LINK_SCALAR_FIELDS.iter().map(|s| s.to_string()))
            .chain(["rotor_axis".to_string(), "mimic".to_string()])
            .collect(),
        Force => ["value", "body", "potential", "field"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        Torque => ["value", "body", "potential"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
    }
}

/// `dof`, `dof1` … `dof6` (likewise `force`, `torque`).
pub fn is_numbered(field: &str, base: &str) -> bool {
    match field.strip_prefix(base) {
        Some("") => true,
        Some(digit) => matches!(digit, "1" | "2" | "3" | "4" | "5" | "6"),
        None => false,
    }
}

/// Built-in constants.
pub fn builtin_constant(name: &str) -> Option<Ty> {
    match name {
        "pi" | "time" => Some(Ty::Scalar),
        "earth" => Some(Ty::Body),
        _ => None,
    }
}

/// Built-in functions: parameter types and result type.
pub fn builtin_function(name: &str) -> Option<(&'static [Ty], Ty)> {
    use Ty::*;
    const S1: &[Ty] = &[Scalar];
    const S2: &[Ty] = &[Scalar, Scalar];
    const S3: &[Ty] = &[Scalar, Scalar, Scalar];
    const V1: &[Ty] = &[Vector];
    const V2: &[Ty] = &[Vector, Vector];
    const F1: &[Ty] = &[Frame];
    const F2: &[Ty] = &[Frame, Frame];
    Some(match name {
        "sin" | "cos" | "tan" | "asin" | "acos" | "atan" | "sqrt" | "exp" | "log" | "abs"
        | "floor" => (S1, Scalar),
        "atan2" | "mod" => (S2, Scalar),
        // Piecewise functions of a signal (`x` bounded to [lo, hi], or 0 within a width).
        "saturate" => (S3, Scalar),
        "dead_zone" => (S2, Scalar),
        // The model at the current state, along actuated coordinates (see `check::model_laws`).
        "mass_matrix" => (S2, Scalar),
        "bias" | "gravity_effort" => (S1, Scalar),
        "norm" => (V1, Scalar),
        "dot" => (V2, Scalar),
        "cross" => (V2, Vector),
        // A rotation aiming a frame's z axis along u (and its x axis toward v): `aim(u[, v])`.
        "aim" => (V2, Rotation),
        // The state of a frame at the current instant, in the fixed axes (efforts only).
        "position" | "velocity" | "angular_velocity" => (F1, Vector),
        "orientation" => (F1, Matrix),
        "distance" => (F2, Scalar),
        // A new state starting at its argument (`let integral = state(0);`).
        "state" => (S1, Scalar),
        // A sampled state: its period and its value before the first instant
        // (`let u = sample(0.01, 0);`).
        "sample" => (S2, Scalar),
        // Contacts of a sphere or a disc on a plane, as links (`join plane and ball with rolling(r)`).
        "rolling" | "rolling_disc" => (S1, Link),
        "sliding" | "sliding_disc" => (S2, Link),
        _ => return None,
    })
}

/// The arguments of a reference law of time after its first, the time (see `check::laws`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LawArguments {
    /// From a start to an end at rest, `(t, t0, q0, t1, q1, extra...)`: the names of the
    /// scalar parameters that follow the ends.
    Between(&'static [&'static str]),
    /// Through via points `(t, t0, q0, t1, q1, ..., tn, qn)`, two at least.
    Through,
}

impl LawArguments {
    /// Whether argument `k` of a call is a position (the time is argument 0).
    pub fn is_position(self, k: usize) -> bool {
        match self {
            LawArguments::Between(_) => k == 2 || k == 4,
            LawArguments::Through => k >= 2 && k.is_multiple_of(2),
        }
    }
}

/// The reference laws of time (`quintic(time, 0, 0, 2, pi)`): the positions `q` are scalars
/// (a joint's law) or vectors (a point's law), the rest scalars.
pub fn reference_law(name: &str) -> Option<LawArguments> {
    use LawArguments::*;
    Some(match name {
        "linear" | "parabolic" | "cubic" | "quintic" | "harmonic" | "cycloidal" => Between(&[]),
        "trapezoidal" => Between(&["ramp"]),
        "exponential" => Between(&["sigma", "lambda"]),
        "spline" => Through,
        _ => return None,
    })
}

/// Whether `name` is a built-in function of any shape: a fixed signature, a reference law, or
/// `derivative` (a scalar's or a vector's time derivative), or `inverse_dynamics` (a coordinate,
/// then pairs of a coordinate and its acceleration).
pub fn is_builtin_function(name: &str) -> bool {
    builtin_function(name).is_some()
        || reference_law(name).is_some()
        || name == "derivative"
        || name == "inverse_dynamics"
}

/// How many of a built-in function's last parameters may be left out: `aim(u)` is `aim(u, v)`
/// without its second direction.
pub fn builtin_optional_parameters(name: &str) -> usize {
    match name {
        "aim" => 1,
        _ => 0,
    }
}

/// The numeric fields of `simulate`.
pub const SIMULATE_FIELDS: &[&str] = &[
    "duration",
    "output",
    "step",
    "max_step",
    "tolerance",
    "rtol",
    "atol",
];
