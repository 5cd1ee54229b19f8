//! Prescribed motions (`drive crank.q = 2 * pi * time`): a coordinate of a join of the tree
//! imposed as a law of time. The law is lowered into the expression pool with the time as its
//! one symbol and differentiated there twice (`Pool::derivative`), so that its rate and its
//! acceleration are exact, not differences; one tape evaluates the three.
//!
//! What a drive may impose is decided here, for every phase that reads the drives (the starting
//! configuration, the dynamics): one coordinate of a revolute or prismatic join of the tree that
//! no other declaration imposes (not a mimic, not closing a loop, not driven twice: E0482,
//! E0485), by a law of the time and numbers only (E0483) that is twice differentiable
//! (E0484: `floor` and `abs` are not).

use std::collections::HashMap;

use super::eval::{describe, EvalError, Geometric, UnknownValues};
use super::model::KinematicModel;
use super::tabulated_law::TabulatedLaw;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Drive, Mechanism};
use crate::elab::value::SExpr;
use crate::symbolic::expr::{ExprId, Function, Node, Pool, Tape};
use crate::symbolic::program::Lower;

/// A law of time with its first two derivatives: the program's expression as one tape, or
/// knots read from a file (`lsdc inverse --motion`).
#[derive(Clone, Debug)]
pub enum DriveLaw {
    Expression(Tape),
    Tabulated(TabulatedLaw),
}

/// A law's value and its first two time derivatives at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawAt {
    pub position: f64,
    pub rate: f64,
    pub acceleration: f64,
}

impl DriveLaw {
    /// The law, its rate and its acceleration at time `t`.
    pub fn at(&self, t: f64) -> LawAt {
        self.evaluate(t, &mut Vec::new())
    }

    /// As `at`, the tape's nodes evaluated in `values` (which keeps its storage: a run's
    /// evaluations allocate nothing).
    pub fn evaluate(&self, t: f64, values: &mut Vec<f64>) -> LawAt {
        let [position, rate, acceleration] = match self {
            DriveLaw::Expression(tape) => {
                tape.eval_into(&[t], values);
                [0, 1, 2].map(|k| values[tape.roots[k]])
            }
            DriveLaw::Tabulated(law) => law.at(t),
        };
        LawAt {
            position,
            rate,
            acceleration,
        }
    }
}

/// A drive resolved against the kinematic model: which declared coordinate it imposes.
#[derive(Clone, Debug)]
pub struct ResolvedDrive {
    /// The index of the driven coordinate among the declared coordinates.
    pub coordinate: usize,
    /// `crank.q`, as outputs name it.
    pub name: String,
    pub law: DriveLaw,
    /// Where the program drives it.
    pub span: crate::source::Span,
}

/// The program's drives, each checked (see the module's documentation); every refusal is
/// reported.
pub fn resolve(
    mechanism: &Mechanism,
    model: &KinematicModel,
) -> Result<Vec<ResolvedDrive>, Vec<Diagnostic>> {
    let mut errors = Vec::new();
    let mut resolved: Vec<ResolvedDrive> = Vec::new();
    let mut first_span = HashMap::new();
    for drive in &mechanism.drives {
        let target = driven_coordinate(mechanism, model, drive);
        let law = law(mechanism, drive, &model.unknowns);
        match (target, law) {
            (Ok((coordinate, name)), Ok(law)) => {
                if let Some(&first) = first_span.get(&coordinate) {
                    errors.push(
                        Diagnostic::error("E0485", format!("`{name}` is driven twice"))
                            .primary(drive.span, "driven again here")
                            .secondary(first, "first driven here")
                            .help("keep one law per coordinate (a sum of motions is one law)"),
                    );
                    continue;
                }
                first_span.insert(coordinate, drive.span);
                resolved.push(ResolvedDrive {
                    coordinate,
                    name,
                    law,
                    span: drive.span,
                });
            }
            (target, law) => errors.extend(target.err().into_iter().chain(law.err())),
        }
    }
    match errors.is_empty() {
        true => Ok(resolved),
        false => Err(errors),
    }
}

/// The declared coordinate a drive imposes and its name, if the drive may impose it.
fn driven_coordinate(
    mechanism: &Mechanism,
    model: &KinematicModel,
    drive: &Drive,
) -> Result<(usize, String), Diagnostic> {
    let join_name = mechanism.join_name(drive.join);
    let refuse = |why: String, label: &str, help: &str| {
        Diagnostic::error("E0482", why)
            .primary(drive.span, label.to_string())
            .secondary(mechanism.join(drive.join).span, "the join")
            .help(help.to_string())
    };
    let Some(joint) = model.joint_of_join(drive.join) else {
        return Err(refuse(
            format!("`{join_name}` has no coordinate a drive can impose"),
            "not a joint coordinate",
            "drive a revolute or prismatic join of the tree",
        ));
    };
    let name = format!(
        "{}.{}",
        joint.name, joint.coordinate_names[drive.coordinate]
    );
    let closes_loop = model.complementary().iter().any(|j| j.join == drive.join);
    let link = mechanism.link(mechanism.join(drive.join).link);
    if closes_loop {
        return Err(refuse(
            format!("`{name}` is not free: its join closes a loop, and the loop's closure decides its coordinates"),
            "a coordinate of a loop-closing join",
            "drive a join of the tree (`lsdc tree` lists them); the loop then follows",
        ));
    }
    if link.mimic().is_declared() {
        return Err(refuse(
            format!("`{name}` is not free: it follows its `mimic` leader"),
            "a mimic's coordinate",
            "drive the leader instead: the follower follows it",
        ));
    }
    if joint.coordinate_count() != 1 {
        return Err(refuse(
            format!(
                "`{name}` is one of {} coordinates of its join: a drive imposes the coordinate of a join with one",
                joint.coordinate_count()
            ),
            "a coordinate of a join with several",
            "drive a revolute or prismatic join (split the join into single joints to drive one of its motions)",
        ));
    }
    Ok((joint.offset + drive.coordinate, name))
}

/// The law of time of a drive, differentiated twice.
fn law(
    mechanism: &Mechanism,
    drive: &Drive,
    unknowns: &UnknownValues,
) -> Result<DriveLaw, Diagnostic> {
    let mut lowering = LawLowering {
        geometric: Geometric {
            pool: Pool::new(),
            unknowns,
            coordinates: Vec::new(),
        },
        time: None,
    };
    let time = lowering.geometric.pool.symbol("t");
    lowering.time = Some(time);
    let position = lowering.lower(&drive.law).map_err(|e| {
        Diagnostic::error("E0483", format!("the law of a drive is a function of the time: {}", describe(&e, mechanism)))
            .primary(drive.law_span, "not a law of time")
            .help("write the law with `time`, numbers and the program's constants (`drive crank.q = 2 * pi * time`)")
    })?;
    let pool = &mut lowering.geometric.pool;
    if let Some(function) = not_smooth(pool, position) {
        let why = match function {
            Function::Floor => "it jumps at every integer",
            _ => "its slope jumps at zero",
        };
        return Err(Diagnostic::error(
            "E0484",
            format!("the law of a drive must be twice differentiable, and `{}` is not: {why}", function.name()),
        )
        .primary(drive.law_span, format!("uses `{}`", function.name()))
        .help("impose a smooth law (a polynomial, sines, the seed's trajectory laws): the drive's effort needs its second derivative"));
    }
    let rate = pool.derivative(position, time, &mut HashMap::new());
    let acceleration = pool.derivative(rate, time, &mut HashMap::new());
    Ok(DriveLaw::Expression(Tape::new(
        pool,
        &[position, rate, acceleration],
    )))
}

/// A function in the law whose derivatives jump (`floor`) or do not exist somewhere (`abs`).
fn not_smooth(pool: &Pool, root: ExprId) -> Option<Function> {
    let mut stack = vec![root];
    while let Some(e) = stack.pop() {
        if let Node::Apply(f @ (Function::Floor | Function::Abs), _) = pool.node(e) {
            return Some(f);
        }
        stack.extend(pool.operands(e));
    }
    None
}

/// The leaves of a law: the time is the pool's symbol `t`; the rest as in geometry (numbers and
/// unknowns with values), coordinates refused.
struct LawLowering<'a> {
    geometric: Geometric<'a>,
    time: Option<ExprId>,
}

impl Lower for LawLowering<'_> {
    type Error = EvalError;

    fn pool(&mut self) -> &mut Pool {
        &mut self.geometric.pool
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        match (s, self.time) {
            (SExpr::Time, Some(time)) => Ok(time),
            _ => self.geometric.leaf(s),
        }
    }
}
