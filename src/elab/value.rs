//! Values of LSD programs: symbolic scalars (numbers, unknowns, joint coordinates and the
//! operations between them), vectors, matrices, rotations, displacements, and references to the
//! mechanical objects of the [`Mechanism`](super::mechanism::Mechanism).

use std::fmt;
use std::sync::{Arc, LazyLock};

use crate::check::types::DefId;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct UnknownId(pub u32);
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(pub u32);
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LinkId(pub u32);
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EffortId(pub u32);
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JoinId(pub u32);
/// A state of the program (`state(x0)`), by its index among the mechanism's states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StateId(pub u32);

pub type Scalar = Arc<SExpr>;

/// A function applied to arguments: `sin(x)` (`F` its name) or `?fs(x, x')` (`F` the unknown).
/// Boxed in [`SExpr`], so that every other node is not as large as a call.
#[derive(Clone, Debug, PartialEq)]
pub struct Applied<F> {
    pub function: F,
    pub args: Vec<Scalar>,
}

/// A symbolic scalar expression. Its variants hold at most 16 bytes, so that a node with its
/// `Arc` counts is 40 bytes (a 48-byte block of glibc's malloc, where 56 bytes took 64): an
/// elaborated mechanism holds several per body.
#[derive(Clone, Debug, PartialEq)]
pub enum SExpr {
    Num(f64),
    /// The time `t` of a simulation (`time` in programs).
    Time,
    /// `?s`, or a `let` name bound to one.
    Unknown(UnknownId),
    /// `?fs(x, x')`
    UnknownFunction(Box<Applied<UnknownId>>),
    /// The `index`-th coordinate of the enclosing link, differentiated `order` times.
    Coordinate {
        index: u32,
        order: u32,
    },
    /// A coordinate of a join (`crank.q`, `crank.q'`), usable anywhere after the join.
    JoinCoordinate {
        join: JoinId,
        index: u32,
        order: u32,
    },
    Neg(Scalar),
    Add(Scalar, Scalar),
    Sub(Scalar, Scalar),
    Mul(Scalar, Scalar),
    Div(Scalar, Scalar),
    Pow(Scalar, Scalar),
    Call(Box<Applied<&'static str>>),
    /// One component of the state of a frame at the current instant, in the fixed axes
    /// (`position(F)`, `velocity(F)`, …): only efforts may depend on it.
    FrameState(Arc<Frame>, FrameQuantity),
    /// The value of a state (`let integral = state(0);`) at the current instant: a variable
    /// with its own differential equation (`rate integral = ...;`), integrated with the motion.
    State(StateId),
}

/// A component of a frame's state, in the fixed axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameQuantity {
    /// Component i of its origin's position.
    Position(u8),
    /// Component i of its origin's velocity.
    Velocity(u8),
    /// Component i of its angular velocity.
    AngularVelocity(u8),
    /// Entry (i, j) of its rotation matrix (columns: the frame's axes).
    Orientation(u8, u8),
}

/// A number as a scalar. Zero and one, which fill most vectors and axes, are shared rather than
/// allocated at each use (a chain of 100,000 bodies has about twenty per body).
pub fn num(value: f64) -> Scalar {
    static ZERO: LazyLock<Scalar> = LazyLock::new(|| Arc::new(SExpr::Num(0.0)));
    static ONE: LazyLock<Scalar> = LazyLock::new(|| Arc::new(SExpr::Num(1.0)));
    // Bit patterns, not `==`: −0.0 keeps its own node.
    if value.to_bits() == 0.0f64.to_bits() {
        ZERO.clone()
    } else if value.to_bits() == 1.0f64.to_bits() {
        ONE.clone()
    } else {
        Arc::new(SExpr::Num(value))
    }
}

pub fn constant(s: &Scalar) -> Option<f64> {
    match **s {
        SExpr::Num(v) => Some(v),
        _ => None,
    }
}

/// Builds `a op b`, folding numbers and the neutral elements 0 and 1.
// The guards compare floats on purpose: a literal pattern would hide that −0.0 matches too.
#[allow(clippy::redundant_guards)]
pub fn arith(op: char, a: &Scalar, b: &Scalar) -> Scalar {
    let (ca, cb) = (constant(a), constant(b));
    if let (Some(x), Some(y)) = (ca, cb) {
        let folded = match op {
            '+' => x + y,
            '-' => x - y,
            '*' => x * y,
            '/' => x / y,
            _ => x.powf(y),
        };
        if folded.is_finite() {
            return num(folded);
        }
    }
    match (op, ca, cb) {
        ('+', Some(z), _) if z == 0.0 => return b.clone(),
        ('+' | '-', _, Some(z)) if z == 0.0 => return a.clone(),
        // 0 · x is 0 only for a finite x: 0 · ∞ and 0 · NaN are NaN (IEEE 754).
        ('*', Some(z), _) if z == 0.0 && surely_finite(b, FINITENESS_DEPTH) => return num(0.0),
        ('*', _, Some(z)) if z == 0.0 && surely_finite(a, FINITENESS_DEPTH) => return num(0.0),
        ('*', Some(o), _) if o == 1.0 => return b.clone(),
        ('*' | '/', _, Some(o)) if o == 1.0 => return a.clone(),
        ('-', Some(z), _) if z == 0.0 => return negate(b),
        _ => {}
    }
    let (a, b) = (a.clone(), b.clone());
    Arc::new(match op {
        '+' => SExpr::Add(a, b),
        '-' => SExpr::Sub(a, b),
        '*' => SExpr::Mul(a, b),
        '/' => SExpr::Div(a, b),
        _ => SExpr::Pow(a, b),
    })
}

/// How deep `surely_finite` looks before it answers "maybe not": a bound that keeps the folding
/// of long expressions linear, on the safe side (an unproven product is kept, not folded).
const FINITENESS_DEPTH: u32 = 32;

/// Whether `s` is finite at every instant and state: numbers that are, the time, coordinates,
/// rates, unknowns and unknown functions (their values are finite numbers), and sums,
/// differences, products and negations of finite values, sines, cosines, arctangents, absolute
/// values and floors of them. Overflow of a sum or product of finite values is not considered.
/// A quotient, a root, a power, a logarithm or an exponential may be infinite or NaN. The same
/// rule as `symbolic::expr::Pool::surely_finite`, on the elaborated values.
fn surely_finite(s: &Scalar, depth: u32) -> bool {
    if depth == 0 {
        return false;
    }
    let finite = |s: &Scalar| surely_finite(s, depth - 1);
    match &**s {
        SExpr::Num(v) => v.is_finite(),
        SExpr::Time
        | SExpr::Unknown(_)
        | SExpr::Coordinate { .. }
        | SExpr::JoinCoordinate { .. }
        | SExpr::UnknownFunction(_)
        | SExpr::FrameState(..)
        | SExpr::State(_) => true,
        SExpr::Neg(a) => finite(a),
        SExpr::Add(a, b) | SExpr::Sub(a, b) | SExpr::Mul(a, b) => finite(a) && finite(b),
        // A piecewise value is one of its branches, whatever its test.
        SExpr::Call(call) if call.function == "select" => call.args[1..].iter().all(finite),
        SExpr::Call(call) => {
            matches!(
                call.function,
                "sin" | "cos" | "atan" | "abs" | "atan2" | "floor"
            ) && call.args.iter().all(finite)
        }
        _ => false,
    }
}

pub fn negate(a: &Scalar) -> Scalar {
    match constant(a) {
        Some(v) => num(-v),
        None => Arc::new(SExpr::Neg(a.clone())),
    }
}

pub type Vector = [Scalar; 3];
pub type Matrix = [Vector; 3];

pub fn zero_vector() -> Vector {
    [num(0.0), num(0.0), num(0.0)]
}

/// One step of a displacement chain.
#[derive(Clone, Debug, PartialEq)]
pub enum Elementary {
    Translation(Vector),
    Rotation { angle: Scalar, axis: Vector },
}

/// A displacement as a chain of translations and rotations, each expressed in the frame the
/// previous ones produce (the thesis's `dof1`, `dof2`, … convention). The empty chain is the
/// identity.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Displacement(pub Vec<Elementary>);

impl Displacement {
    pub fn then(mut self, other: &Displacement) -> Displacement {
        // At the exact length: a frame `t ++ r @ b` is kept per join and per body, and a chain
        // grown by doubling kept room for four steps.
        self.0.reserve_exact(other.0.len());
        self.0.extend(other.0.iter().cloned());
        self
    }

    pub fn is_identity(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether the displacement moves with coordinate `index` of its link: a translation or an
    /// angle that uses it (an axis that does is refused later, E0802).
    pub fn uses_coordinate(&self, index: u32) -> bool {
        self.0.iter().any(|step| match step {
            Elementary::Translation(t) => t.iter().any(|s| s.uses_coordinate(index)),
            Elementary::Rotation { angle, axis } => {
                angle.uses_coordinate(index) || axis.iter().any(|s| s.uses_coordinate(index))
            }
        })
    }

    /// Adds every unknown the displacement's parameters mention to `into`.
    pub fn collect_unknowns(&self, into: &mut std::collections::BTreeSet<UnknownId>) {
        for step in &self.0 {
            match step {
                Elementary::Translation(t) => t.iter().for_each(|s| s.collect_unknowns(into)),
                Elementary::Rotation { angle, axis } => {
                    angle.collect_unknowns(into);
                    axis.iter().for_each(|s| s.collect_unknowns(into));
                }
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyRef {
    Earth,
    Body(BodyId),
}

/// A frame: a body's reference frame moved by a displacement.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub body: BodyRef,
    pub displacement: Displacement,
}

#[derive(Clone, Debug)]
pub enum Value {
    Scalar(Scalar),
    Vector(Vector),
    /// Boxed: nine scalars would make every value (and the elaborator's table of the program's
    /// names) three times larger.
    Matrix(Box<Matrix>),
    /// Rotations are displacement chains made of rotations only.
    Rotation(Displacement),
    Displacement(Displacement),
    Frame(Frame),
    Body(BodyRef),
    Link(LinkId),
    Force(EffortId),
    Torque(EffortId),
    Join(JoinId),
    /// The literal `0`, until its context says what it is.
    Zero,
    /// The literal `1`, until its context says what it is.
    One,
    Package,
    Definition(DefId),
}

impl SExpr {
    /// `function(args)`: a call of a function of the standard library.
    pub fn call(function: &'static str, args: Vec<Scalar>) -> SExpr {
        SExpr::Call(Box::new(Applied { function, args }))
    }

    /// `?fs(args)`: a call of an unknown function.
    pub fn unknown_function(function: UnknownId, args: Vec<Scalar>) -> SExpr {
        SExpr::UnknownFunction(Box::new(Applied { function, args }))
    }

    /// The expression with each operand `a` replaced by `f(a)` (the arguments of calls
    /// included), for the rewritings of expressions; `None` for a node without operands (a
    /// number, `time`, an unknown, a coordinate, a state, the state of a frame).
    pub fn with_operands(&self, f: &mut dyn FnMut(&Scalar) -> Scalar) -> Option<SExpr> {
        Some(match self {
            SExpr::Neg(a) => SExpr::Neg(f(a)),
            SExpr::Add(a, b) => SExpr::Add(f(a), f(b)),
            SExpr::Sub(a, b) => SExpr::Sub(f(a), f(b)),
            SExpr::Mul(a, b) => SExpr::Mul(f(a), f(b)),
            SExpr::Div(a, b) => SExpr::Div(f(a), f(b)),
            SExpr::Pow(a, b) => SExpr::Pow(f(a), f(b)),
            SExpr::Call(call) => {
                SExpr::call(call.function, call.args.iter().map(&mut *f).collect())
            }
            SExpr::UnknownFunction(call) => {
                SExpr::unknown_function(call.function, call.args.iter().map(f).collect())
            }
            SExpr::Num(_)
            | SExpr::Time
            | SExpr::Unknown(_)
            | SExpr::Coordinate { .. }
            | SExpr::JoinCoordinate { .. }
            | SExpr::State(_)
            | SExpr::FrameState(..) => return None,
        })
    }

    /// The arguments of a call, known or unknown; none for any other node.
    pub fn arguments(&self) -> &[Scalar] {
        match self {
            SExpr::Call(call) => &call.args,
            SExpr::UnknownFunction(call) => &call.args,
            _ => &[],
        }
    }

    /// Adds every unknown (scalar or function) the expression mentions to `into`.
    pub fn collect_unknowns(&self, into: &mut std::collections::BTreeSet<UnknownId>) {
        match self {
            SExpr::Num(_)
            | SExpr::Time
            | SExpr::Coordinate { .. }
            | SExpr::JoinCoordinate { .. }
            | SExpr::State(_) => {}
            SExpr::Unknown(id) => {
                into.insert(*id);
            }
            SExpr::UnknownFunction(call) => {
                into.insert(call.function);
                call.args.iter().for_each(|a| a.collect_unknowns(into));
            }
            SExpr::Neg(a) => a.collect_unknowns(into),
            SExpr::Add(a, b)
            | SExpr::Sub(a, b)
            | SExpr::Mul(a, b)
            | SExpr::Div(a, b)
            | SExpr::Pow(a, b) => {
                a.collect_unknowns(into);
                b.collect_unknowns(into);
            }
            SExpr::Call(call) => call.args.iter().for_each(|a| a.collect_unknowns(into)),
            SExpr::FrameState(frame, _) => frame.displacement.collect_unknowns(into),
        }
    }

    /// Every frame whose state the expression uses, once each.
    pub fn frames_used(&self, into: &mut Vec<Arc<Frame>>) {
        match self {
            SExpr::FrameState(frame, _) => {
                if !into.iter().any(|f| f == frame) {
                    into.push(frame.clone());
                }
            }
            SExpr::Neg(a) => a.frames_used(into),
            SExpr::Add(a, b)
            | SExpr::Sub(a, b)
            | SExpr::Mul(a, b)
            | SExpr::Div(a, b)
            | SExpr::Pow(a, b) => {
                a.frames_used(into);
                b.frames_used(into);
            }
            SExpr::Call(_) | SExpr::UnknownFunction(_) => {
                self.arguments().iter().for_each(|a| a.frames_used(into))
            }
            SExpr::Num(_)
            | SExpr::Time
            | SExpr::Unknown(_)
            | SExpr::Coordinate { .. }
            | SExpr::JoinCoordinate { .. }
            | SExpr::State(_) => {}
        }
    }

    /// Whether the expression uses the state of a frame (`position(F)`, …).
    pub fn uses_frame_state(&self) -> bool {
        self.any(&|e| matches!(e, SExpr::FrameState(..)))
    }

    /// Whether the expression may change during a motion: it uses a coordinate (of its link or
    /// of a join), `time` or the state of a frame. Numbers and unknowns do not.
    pub fn varies_with_motion(&self) -> bool {
        self.any(&|e| {
            matches!(
                e,
                SExpr::Time
                    | SExpr::Coordinate { .. }
                    | SExpr::JoinCoordinate { .. }
                    | SExpr::FrameState(..)
                    | SExpr::State(_)
            )
        })
    }

    /// Whether the expression reads the mechanism's state: a coordinate or a rate (of its link
    /// or of a join), or the state of a frame. Numbers, unknowns and `time` do not.
    pub fn reads_state(&self) -> bool {
        self.any(&|e| {
            matches!(
                e,
                SExpr::Coordinate { .. } | SExpr::JoinCoordinate { .. } | SExpr::FrameState(..)
            )
        })
    }

    /// Whether the expression uses `time`.
    pub fn uses_time(&self) -> bool {
        self.any(&|e| matches!(e, SExpr::Time))
    }

    /// Whether the expression uses a coordinate (of its link or of a join) or the state of a
    /// frame: what varies with a motion apart from the time.
    pub fn uses_state(&self) -> bool {
        self.any(&|e| {
            matches!(
                e,
                SExpr::Coordinate { .. } | SExpr::JoinCoordinate { .. } | SExpr::FrameState(..)
            )
        })
    }

    /// Whether the expression uses coordinate `index` of its link (or its rates).
    pub fn uses_coordinate(&self, index: u32) -> bool {
        self.any(&|e| matches!(e, SExpr::Coordinate { index: i, .. } if *i == index))
    }

    /// Whether `test` holds for the expression or one of its subexpressions (the arguments of
    /// calls included, the displacement of a frame whose state is read not).
    pub(crate) fn any(&self, test: &dyn Fn(&SExpr) -> bool) -> bool {
        if test(self) {
            return true;
        }
        match self {
            SExpr::Neg(a) => a.any(test),
            SExpr::Add(a, b)
            | SExpr::Sub(a, b)
            | SExpr::Mul(a, b)
            | SExpr::Div(a, b)
            | SExpr::Pow(a, b) => a.any(test) || b.any(test),
            SExpr::Call(_) | SExpr::UnknownFunction(_) => {
                self.arguments().iter().any(|a| a.any(test))
            }
            SExpr::FrameState(..)
            | SExpr::Num(_)
            | SExpr::Time
            | SExpr::Unknown(_)
            | SExpr::Coordinate { .. }
            | SExpr::JoinCoordinate { .. }
            | SExpr::State(_) => false,
        }
    }

    /// Text of the expression; `unknown` writes the name of each unknown.
    pub fn render(&self, unknown: &mut dyn FnMut(UnknownId) -> String) -> String {
        self.render_with(unknown, &|join, index, order| {
            let primes = "'".repeat(order as usize);
            match join {
                Some(join) => format!("join{}.q{index}{primes}", join.0 + 1),
                None => format!("q{index}{primes}"),
            }
        })
    }

    /// Text of the expression, with `coordinate(join, index, order)` naming coordinates: those
    /// of the enclosing link (`join` is `None`) and those of named joins.
    pub fn render_with(
        &self,
        unknown: &mut dyn FnMut(UnknownId) -> String,
        coordinate: &dyn Fn(Option<JoinId>, u32, u32) -> String,
    ) -> String {
        let list = |args: &[Scalar], unknown: &mut dyn FnMut(UnknownId) -> String| {
            args.iter()
                .map(|a| a.render_with(unknown, coordinate))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match self {
            SExpr::Num(v) => crate::diag::number::shortest(*v),
            SExpr::Time => "t".to_string(),
            SExpr::Unknown(id) => unknown(*id),
            SExpr::UnknownFunction(call) => {
                let name = unknown(call.function);
                format!("{name}({})", list(&call.args, unknown))
            }
            SExpr::Coordinate { index, order } => coordinate(None, *index, *order),
            SExpr::JoinCoordinate { join, index, order } => coordinate(Some(*join), *index, *order),
            SExpr::Neg(a) => format!("-({})", a.render_with(unknown, coordinate)),
            SExpr::Add(a, b) => format!(
                "({} + {})",
                a.render_with(unknown, coordinate),
                b.render_with(unknown, coordinate)
            ),
            SExpr::Sub(a, b) => format!(
                "({} - {})",
                a.render_with(unknown, coordinate),
                b.render_with(unknown, coordinate)
            ),
            SExpr::Mul(a, b) => format!(
                "({} * {})",
                a.render_with(unknown, coordinate),
                b.render_with(unknown, coordinate)
            ),
            SExpr::Div(a, b) => format!(
                "({} / {})",
                a.render_with(unknown, coordinate),
                b.render_with(unknown, coordinate)
            ),
            SExpr::Pow(a, b) => format!(
                "({} ^ {})",
                a.render_with(unknown, coordinate),
                b.render_with(unknown, coordinate)
            ),
            SExpr::Call(call) => format!("{}({})", call.function, list(&call.args, unknown)),
            SExpr::FrameState(_, quantity) => match quantity {
                FrameQuantity::Position(i) => format!("position(frame)[{i}]"),
                FrameQuantity::Velocity(i) => format!("velocity(frame)[{i}]"),
                FrameQuantity::AngularVelocity(i) => format!("angular_velocity(frame)[{i}]"),
                FrameQuantity::Orientation(i, j) => format!("orientation(frame)[{i}][{j}]"),
            },
            SExpr::State(id) => format!("state#{}", id.0 + 1),
        }
    }
}

impl fmt::Display for SExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render(&mut |id| format!("?{}", id.0)))
    }
}
