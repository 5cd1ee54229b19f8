//! Position drives (`drive position(nacelle) = [x(time), y(time), z(time)]`): the origin of a
//! frame imposed in the fixed axes as three laws of time, each lowered and differentiated twice
//! on the expression graph as a coordinate's drive is (`drives`), so that the path's rate and
//! acceleration are exact. The frame must be carried by a body at a constant place on it; the
//! laws are checked as a drive's are (E0483 not a law of time, E0484 not twice differentiable).
//! How the path moves the mechanism is decided where it is used: `lsdc inverse` follows it
//! through the inverse geometric model of the actuated coordinates
//! (`studies::trajectory`). Refused before a run: a path that asks more of the mechanism than
//! it can move (E0494), a path that starts out of reach (E0499).

use nalgebra::{DMatrix, Vector3};

use super::closure::closure;
use super::drag::{drag, DragOptions};
use super::drives::{law, resolve as resolve_coordinates, DriveLaw, LawAt};
use super::eval::describe;
use super::frames::FramePoint;
use super::mobility::rank;
use super::model::{constant_pose, KinematicModel};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Mechanism, PositionDrive};
use crate::source::Span;
use crate::spatial::{self, Twist};

/// The fixed axes' names, in the order of a path's components.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// A position drive resolved on the numbered mechanism.
#[derive(Clone, Debug)]
pub struct ResolvedPositionDrive {
    /// The frame as written (`nacelle`), on its body.
    pub frame: FramePoint,
    /// The laws of x, y and z.
    pub laws: [DriveLaw; 3],
    /// The driven frame as the program writes it.
    pub span: Span,
}

impl ResolvedPositionDrive {
    /// The three laws at time `t`.
    pub fn at(&self, t: f64) -> [LawAt; 3] {
        let mut values = Vec::new();
        [0, 1, 2].map(|k| self.laws[k].evaluate(t, &mut values))
    }

    /// The path's columns as `simulate --output-frame` names them: `nacelle.x`, `.y`, `.z`.
    pub fn component_names(&self) -> [String; 3] {
        AXES.map(|axis| format!("{}.{axis}", self.frame.name))
    }
}

/// The program's position drives, each checked (see the module's documentation); every
/// refusal is reported.
pub fn resolve(
    mechanism: &Mechanism,
    model: &KinematicModel,
) -> Result<Vec<ResolvedPositionDrive>, Vec<Diagnostic>> {
    let mut errors = Vec::new();
    let mut resolved = Vec::new();
    for drive in &mechanism.position_drives {
        match resolve_one(mechanism, model, drive) {
            Ok(drive) => resolved.push(drive),
            Err(refused) => errors.push(refused),
        }
    }
    match errors.is_empty() {
        true => Ok(resolved),
        false => Err(errors),
    }
}

fn resolve_one(
    mechanism: &Mechanism,
    model: &KinematicModel,
    drive: &PositionDrive,
) -> Result<ResolvedPositionDrive, Diagnostic> {
    let offset = constant_pose(&drive.frame.displacement, &model.unknowns).map_err(|e| {
        Diagnostic::error(
            "E0492",
            format!(
                "`drive position(...)` imposes the position of a frame at a constant place on its body, and `{}` is not: {}",
                drive.name,
                describe(&e, mechanism)
            ),
        )
        .primary(drive.span, "not a constant frame")
        .help("name a body or a frame fixed on one (`let tip = [0.3, 0, 0] ++ 1 @ arm;`)")
    })?;
    let subject = format!("the position drive of `{}`", drive.name);
    let mut laws = Vec::with_capacity(3);
    for component in &drive.law {
        laws.push(law(
            mechanism,
            component,
            drive.law_span,
            &subject,
            &model.unknowns,
        )?);
    }
    let laws: [DriveLaw; 3] = laws.try_into().expect("three components");
    Ok(ResolvedPositionDrive {
        frame: FramePoint {
            name: drive.name.clone(),
            body: model.topology.number(drive.frame.body),
            offset,
        },
        laws,
        span: drive.span,
    })
}

/// E0494 when the program's drives ask for more motions than the mechanism can make at the
/// configuration `q`: the rows they add to the constraint stack (three per position drive, the
/// velocity of its frame's origin; one per driven coordinate, the time's hidden ones among
/// them) are dependent on the motions the loops allow, rank([Δ; R]) − rank(Δ) < rows, so no
/// motion keeps them all. `None` when they are independent, or when the geometry cannot be
/// evaluated (reported where it is used).
pub fn over_constrained(
    mechanism: &Mechanism,
    model: &KinematicModel,
    drives: &[ResolvedPositionDrive],
    q: &[f64],
) -> Option<Diagnostic> {
    let first = drives.first()?;
    let driven = resolve_coordinates(mechanism, model).ok()?;
    let closure = closure(model, q).ok()?;
    let loops = closure.jacobian.nrows();
    let imposed = 3 * drives.len() + driven.len();
    let mut stacked = DMatrix::zeros(loops + imposed, model.coordinate_count);
    stacked
        .rows_mut(0, loops)
        .copy_from(&closure.jacobian.dense());
    for (k, drive) in drives.iter().enumerate() {
        let configuration = &closure.configuration;
        let origin = drive.frame.pose(configuration).translation.vector;
        let twists = &configuration.jacobian(drive.frame.body);
        for column in 0..model.coordinate_count {
            let twist = Twist::from_column_slice(twists.column(column).as_slice());
            let velocity = spatial::point_velocity(&twist, &origin);
            for axis in 0..3 {
                stacked[(loops + 3 * k + axis, column)] = velocity[axis];
            }
        }
    }
    for (k, drive) in driven.iter().enumerate() {
        stacked[(loops + 3 * drives.len() + k, drive.coordinate)] = 1.0;
    }
    let allowed = rank(&stacked) - rank(&closure.jacobian.dense());
    (allowed < imposed).then(|| {
        let mut refused = Diagnostic::error(
            "E0494",
            format!(
                "the drives impose {imposed} motions and the mechanism can make {allowed} of them where the path starts: no motion keeps them all"
            ),
        )
        .primary(first.span, "imposes the three coordinates of this frame's position");
        for drive in &mechanism.drives {
            refused = refused.secondary(drive.span, "and this coordinate");
        }
        refused
            .note("their rows in the constraint stack are dependent (rank-deficient)")
            .help("impose as many motions as the mechanism has degrees of freedom (`lsdc tree` gives the mobility), along directions it can move: drive fewer coordinates, or a frame the mechanism can move in three directions")
    })
}

/// The declared coordinates `q` (closed) moved so that each position drive's frame starts on
/// its path, at p(0): its origin dragged there with the loops kept closed (`drag`, to its
/// reach tolerance; the run's start closes the rows to round-off). E0499 when a path starts
/// out of reach.
pub fn start_on_paths(
    model: &KinematicModel,
    drives: &[ResolvedPositionDrive],
    q: Vec<f64>,
) -> Result<Vec<f64>, Diagnostic> {
    let options = DragOptions::default();
    let mut q = q;
    for drive in drives {
        let start = drive.at(0.0).map(|law| law.position);
        let target = Vector3::from(start);
        let out_of_reach = |left: String| {
            Diagnostic::error(
                "E0499",
                format!(
                    "the path of `{}` starts at [{}, {}, {}], where the mechanism cannot bring it: {left}",
                    drive.frame.name, start[0], start[1], start[2]
                ),
            )
            .primary(drive.span, "the path starts out of reach")
            .help("start the path where the frame can be (`lsdc drag` and `lsdc workspace` show where it can go)")
        };
        let dragged = drag(model, &drive.frame, &q, &target, &options)
            .map_err(|_| out_of_reach("the loops cannot be closed on the way".to_string()))?;
        if !dragged.reached(&options) {
            return Err(out_of_reach(format!(
                "it stops {:.3e} m away",
                dragged.distance
            )));
        }
        q = dragged.q;
    }
    Ok(q)
}
