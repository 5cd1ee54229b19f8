//! Prescribed motions (`drive crank.q = 2 * pi * time`): a coordinate of a join of the tree
//! imposed as a law of time. The law is lowered into the expression pool with the time as its
//! one symbol and differentiated there twice (`Pool::derivative`), so that its rate and its
//! acceleration are exact, not differences; one tape evaluates the three.
//!
//! What a drive may impose is decided here, for every phase that reads the drives (the starting
//! configuration, the dynamics): one coordinate of a revolute or prismatic join of the tree that
//! no other declaration imposes (not a mimic, not closing a loop, not driven twice: E0482,
//! E0485), by a law of the time and numbers only (E0483) that is twice differentiable
//! (E0484: `floor` and `abs` are not). The hidden coordinates of rheonomic joints (`time` in a
//! dof chain, `rheonomic`) are driven alike, by the time's part of their parameters, on joins of
//! the tree only (E0489).

use std::collections::HashMap;

use super::eval::{describe, EvalError, Geometric, UnknownValues};
use super::mobility::rank;
use super::model::{JointModel, KinematicModel};
use super::tabulated_law::TabulatedLaw;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Drive, Mechanism};
use crate::elab::value::{SExpr, Scalar};
use crate::source::Span;
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
    /// Where the program drives it (for a rheonomic joint's hidden coordinate: its link).
    pub span: crate::source::Span,
    /// The name of its effort among the outputs: `crank.drive_effort`; for a rheonomic joint's
    /// hidden coordinate, `spin.motion1_effort` (a force or torque along its parameter) or
    /// `spin.motion1_power` (the time itself, see `rheonomic`).
    pub effort: String,
}

/// E0710: a coordinate both locked (`lock`, in a scene) and driven, or locked twice; the
/// labels say which is which.
fn lock_on_driven(name: &str, second: (Span, bool), first: (Span, bool)) -> Diagnostic {
    let what = |locked: bool| if locked { "locked here" } else { "driven here" };
    Diagnostic::error("E0710", format!("`{name}` is locked and driven: a lock holds a coordinate nothing else imposes"))
        .primary(second.0, what(second.1))
        .secondary(first.0, what(first.1))
        .help("keep the lock or the drive: a scene locks a coordinate the program leaves free, or drives it with its own `drive` instead")
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
        let law = law(
            mechanism,
            &drive.law,
            drive.law_span,
            "a drive",
            &model.unknowns,
        );
        match (target, law) {
            (Ok((coordinate, name)), Ok(law)) => {
                if let Some(&(first, first_locked)) = first_span.get(&coordinate) {
                    errors.push(if drive.locked || first_locked {
                        lock_on_driven(&name, (drive.span, drive.locked), (first, first_locked))
                    } else {
                        Diagnostic::error("E0485", format!("`{name}` is driven twice"))
                            .primary(drive.span, "driven again here")
                            .secondary(first, "first driven here")
                            .help("keep one law per coordinate (a sum of motions is one law)")
                    });
                    continue;
                }
                first_span.insert(coordinate, (drive.span, drive.locked));
                let join = mechanism.join_name(drive.join);
                resolved.push(ResolvedDrive {
                    coordinate,
                    name,
                    law,
                    span: drive.span,
                    effort: drive_effort_name(join),
                });
            }
            (target, law) => errors.extend(target.err().into_iter().chain(law.err())),
        }
    }
    for joint in &model.joints {
        match prescribed_motions(mechanism, model, joint) {
            Ok(motions) => resolved.extend(motions),
            Err(refused) => errors.push(refused),
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
    if joint.declared_count() != 1 {
        return Err(refuse(
            format!(
                "`{name}` is one of {} coordinates of its join: a drive imposes the coordinate of a join with one",
                joint.declared_count()
            ),
            "a coordinate of a join with several",
            "drive a revolute or prismatic join (split the join into single joints to drive one of its motions)",
        ));
    }
    Ok((joint.offset + drive.coordinate, name))
}

/// The drives of the hidden coordinates of `joint`'s rheonomic chain (`rheonomic`): none for a
/// chain without `time`; refused (E0489) on a join that closes a loop, whose coordinates the
/// closure decides.
fn prescribed_motions(
    mechanism: &Mechanism,
    model: &KinematicModel,
    joint: &JointModel,
) -> Result<Vec<ResolvedDrive>, Diagnostic> {
    if joint.prescribed.is_empty() {
        return Ok(Vec::new());
    }
    let join = mechanism.join(joint.join);
    let link_span = mechanism.link(join.link).span;
    if model.complementary().iter().any(|j| j.join == joint.join) {
        return Err(Diagnostic::error(
            "E0489",
            format!("the dof chain of `{}` depends on the time, and its join closes a loop", joint.name),
        )
        .primary(link_span, "a motion imposed in time")
        .secondary(join.span, "this join closes a loop")
        .note("the closure of a loop decides the coordinates of the join that closes it, and it cannot impose a motion")
        .help("join the moving part by a join of the tree (`lsdc tree` lists the joins that close loops), or declare the joins in another order"));
    }
    if let Some(refused) = not_independent(joint, link_span, join.span) {
        return Err(refused);
    }
    let subject = format!("the motion in time of `{}`", joint.name);
    let declared = joint.declared_count();
    let mut motions = Vec::new();
    for motion in &joint.prescribed {
        let coordinate = &joint.coordinate_names[motion.coordinate];
        if let Some(function) = rough(&motion.written, declared, &model.unknowns) {
            return Err(not_smooth_error(&subject, function, link_span));
        }
        motions.push(ResolvedDrive {
            coordinate: joint.offset + motion.coordinate,
            name: format!("{}.{coordinate}", joint.name),
            law: law(mechanism, &motion.law, link_span, &subject, &model.unknowns)?,
            span: link_span,
            effort: format!(
                "{}.{coordinate}_{}",
                joint.name,
                if motion.clock { "power" } else { "effort" }
            ),
        });
    }
    Ok(motions)
}

/// E0490 when the motions the time imposes on `joint` are not independent of the motions of
/// its declared coordinates (at a generic configuration and instant), as in `rz(q + w * time)`
/// or `[q * cos(time), 0, 0]`: a hidden coordinate is a coordinate of the state held by its row,
/// and two coordinates along one motion make the mass matrix singular. `None` when they are,
/// or when the chain cannot be evaluated (reported where it is evaluated).
fn not_independent(joint: &JointModel, link_span: Span, join_span: Span) -> Option<Diagnostic> {
    let generic = super::joint::generic_coordinates(joint.coordinate_count());
    let (_, subspace) = joint.chain(&generic).ok()?;
    let declared = subspace.columns(0, joint.declared_count()).into_owned();
    let independent = rank(&subspace) == rank(&declared) + joint.prescribed.len();
    let names = &joint.coordinate_names[..joint.declared_count()];
    (!independent).then(|| {
        Diagnostic::error(
            "E0490",
            format!(
                "the motion in time of `{}` moves along its coordinates ({}): lsdc imposes a motion in time only along directions its coordinates do not move",
                joint.name,
                names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
            ),
        )
        .primary(link_span, "the time and a coordinate move the same way")
        .secondary(join_span, "the join")
        .note("the time and the coordinates would be two coordinates of one motion, and the mass matrix singular")
        .help("the time only changes how the coordinates measure a motion they already make: declare the coordinate of that motion (`link(theta) dof = theta || axis end`) and read `theta - w * time` where the old coordinate was read; a motion in time along another direction is its own step (`dof1 = w * time || axis, dof2 = q || other axis`)")
    })
}

/// The law of time `written` (of `subject`, "a drive"), differentiated twice.
pub(super) fn law(
    mechanism: &Mechanism,
    written: &Scalar,
    span: Span,
    subject: &str,
    unknowns: &UnknownValues,
) -> Result<DriveLaw, Diagnostic> {
    let mut lowering = LawLowering::new(unknowns, 0);
    let position = lowering.lower(written).map_err(|e| {
        Diagnostic::error("E0483", format!("the law of {subject} is a function of the time: {}", describe(&e, mechanism)))
            .primary(span, "not a law of time")
            .help("write the law with `time`, numbers and the program's constants (`drive crank.q = 2 * pi * time`)")
    })?;
    let time = lowering.time;
    let pool = &mut lowering.geometric.pool;
    if let Some(function) = not_smooth(pool, position, time) {
        return Err(not_smooth_error(
            &format!("the law of {subject}"),
            function,
            span,
        ));
    }
    let rate = pool.derivative(position, time, &mut HashMap::new());
    let acceleration = pool.derivative(rate, time, &mut HashMap::new());
    Ok(DriveLaw::Expression(Tape::new(
        pool,
        &[position, rate, acceleration],
    )))
}

/// The output that carries the effort imposing join `join`'s driven coordinate
/// (`crank.drive_effort`).
pub fn drive_effort_name(join: impl std::fmt::Display) -> String {
    format!("{join}.drive_effort")
}

/// E0484: `subject` (a law of time) uses `function`, whose derivatives jump.
fn not_smooth_error(subject: &str, function: Function, span: Span) -> Diagnostic {
    let why = match function {
        Function::Floor => "it jumps at every integer",
        _ => "its slope jumps at zero",
    };
    Diagnostic::error(
        "E0484",
        format!("{subject} must be twice differentiable, and `{}` is not: {why}", function.name()),
    )
    .primary(span, format!("uses `{}`", function.name()))
    .help("impose a smooth law (a polynomial, sines, the seed's trajectory laws): the effort that imposes it needs its second derivative")
}

/// A function of the time in `parameter` (of `coordinates` coordinates and the time) whose
/// derivatives jump; `None` when it is smooth in time or cannot be lowered (reported where
/// the chain is evaluated).
fn rough(parameter: &Scalar, coordinates: usize, unknowns: &UnknownValues) -> Option<Function> {
    let mut lowering = LawLowering::new(unknowns, coordinates);
    let root = lowering.lower(parameter).ok()?;
    not_smooth(&lowering.geometric.pool, root, lowering.time)
}

/// A function applied to something that depends on `symbol` whose derivatives jump (`floor`)
/// or do not exist somewhere (`abs`).
fn not_smooth(pool: &Pool, root: ExprId, symbol: ExprId) -> Option<Function> {
    let mut stack = vec![root];
    while let Some(e) = stack.pop() {
        if let Node::Apply(f @ (Function::Floor | Function::Abs), argument) = pool.node(e) {
            if depends_on(pool, argument, symbol) {
                return Some(f);
            }
        }
        stack.extend(pool.operands(e));
    }
    None
}

/// Whether the expression `root` contains `symbol`.
fn depends_on(pool: &Pool, root: ExprId, symbol: ExprId) -> bool {
    let mut stack = vec![root];
    while let Some(e) = stack.pop() {
        if e == symbol {
            return true;
        }
        stack.extend(pool.operands(e));
    }
    false
}

/// The leaves of a law: the time is the pool's symbol `t`; the rest as in geometry (numbers,
/// unknowns with values and the link's first `coordinates` coordinates as symbols), other
/// coordinates refused.
struct LawLowering<'a> {
    geometric: Geometric<'a>,
    time: ExprId,
}

impl<'a> LawLowering<'a> {
    fn new(unknowns: &'a UnknownValues, coordinates: usize) -> LawLowering<'a> {
        let mut pool = Pool::new();
        let time = pool.symbol("t");
        let coordinates = (0..coordinates)
            .map(|k| pool.symbol(&format!("q{k}")))
            .collect();
        LawLowering {
            geometric: Geometric {
                pool,
                unknowns,
                coordinates,
            },
            time,
        }
    }
}

impl Lower for LawLowering<'_> {
    type Error = EvalError;

    fn pool(&mut self) -> &mut Pool {
        &mut self.geometric.pool
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        match s {
            SExpr::Time => Ok(self.time),
            _ => self.geometric.leaf(s),
        }
    }
}
