//! The program's `output` declarations compiled for a run: every output's expression lowered
//! into one tape (the machinery of the compiled efforts), evaluated at each output time from the
//! sample's forward kinematics, declared coordinates, rates and time. Frames asked for by name
//! (`--output-frame`) are frame outputs added after the program's own, in the same tape: they
//! cost one evaluation of their part of the tape per sample, and nothing when none is asked for.

use std::sync::Arc;

use nalgebra::{Matrix3, Rotation3, UnitQuaternion};

use crate::diag::Diagnostic;
use crate::dynamics::actuators::refuse_unactuated;
use crate::dynamics::compiled::{EffortScratch, EffortState, EffortTape, Link, TapeBuilder};
use crate::dynamics::model::{EffortFrame, Model};
use crate::elab::mechanism::{Mechanism, NamedOutput, OutputValue};
use crate::elab::value::{BodyRef, Frame, FrameQuantity, SExpr, Scalar};
use crate::kinematics::eval::{unknown_label, EvalError};
use crate::kinematics::frames::{self, quaternion, STATE_COMPONENTS};
use crate::kinematics::model::{constant_pose, KinematicModel};
use crate::source::{FileId, Span};

/// The axes' letters, for the columns of vectors (`tip.x`) and matrices (`r.xy`).
const AXES: [&str; 3] = ["x", "y", "z"];

/// Where one output's values lie among the tape's roots.
#[derive(Clone, Debug)]
enum Layout {
    /// One root per column, in column order (scalars, vectors, matrices by rows).
    Plain(Vec<usize>),
    /// A frame: position (3), rotation matrix by rows (9), velocity (3), angular velocity (3);
    /// written as the 13 columns of `--output-frame`, the matrix as a quaternion.
    Frame([usize; 18]),
}

/// The compiled outputs of a program (none when it declares none).
#[derive(Clone, Debug, Default)]
pub struct Outputs {
    /// The columns, in order: `e`, `tip.x`, `tip.y`, …, then the 13 of each frame asked for.
    pub names: Vec<String>,
    /// The frames asked for by name ([`Outputs::with_frames`]), in order: the last 13 columns
    /// each, after the program's outputs.
    pub frame_names: Vec<String>,
    layouts: Vec<Layout>,
    tape: Option<EffortTape>,
    frames: Vec<EffortFrame>,
    /// Whether an output reads the model in the actuated coordinates (`mass_matrix`, …): the
    /// sample then comes from an evaluation, which computes it.
    pub reads_model: bool,
}

/// The state an output is evaluated at: the forward kinematics of the dynamic model (each
/// body's pose and velocity) and the declared coordinates and rates.
pub type OutputState<'a> = EffortState<'a>;

impl Outputs {
    /// Compiles the mechanism's outputs on the dynamic model; every value the outputs need
    /// must be known (E0840), and their frames constant on bodies of the mechanism (E0841).
    pub fn compile(mechanism: &Mechanism, model: &Model) -> Result<Outputs, Vec<Diagnostic>> {
        compile_list(mechanism, model, &mechanism.outputs)
    }

    /// The program's outputs, then the state of each named frame (a frame the program names, a
    /// body's name or `earth`): 13 columns `NAME.x` … `NAME.wz` each, as a frame output. The
    /// error names a frame that cannot be found (with the closest name) or placed.
    pub fn with_frames(
        mechanism: &Mechanism,
        model: &Model,
        kinematics: &KinematicModel,
        names: &[String],
    ) -> Result<Outputs, String> {
        let mut list = mechanism.outputs.clone();
        for name in names {
            // Resolved first for its messages: an unknown name, a frame not constant on its body.
            frames::resolve(mechanism, kinematics, name)?;
            let frame = mechanism.frame_named(name).ok_or("resolved above")?;
            list.push(NamedOutput {
                name: name.as_str().into(),
                value: OutputValue::Frame(frame),
                // Asked for from outside the program: no place in it (errors go by message).
                span: Span::new(FileId(0), 0, 0),
            });
        }
        let mut outputs = compile_list(mechanism, model, &list).map_err(|errors| {
            let messages: Vec<String> = errors.iter().map(|e| e.message.clone()).collect();
            messages.join("; ")
        })?;
        outputs.frame_names = names.to_vec();
        Ok(outputs)
    }

    /// No output: what a study of kinematics alone prepares (`prepare_kinematics`).
    pub fn none() -> Outputs {
        Outputs {
            names: Vec::new(),
            frame_names: Vec::new(),
            layouts: Vec::new(),
            tape: None,
            frames: Vec::new(),
            reads_model: false,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The outputs' values at `state`, in column order.
    pub fn values(&self, state: &OutputState<'_>, scratch: &mut EffortScratch) -> Vec<f64> {
        let Some(tape) = &self.tape else {
            return Vec::new();
        };
        tape.eval(&self.frames, state, true, scratch);
        let root = |k: usize| tape.root(scratch, k) + 0.0;
        let mut values = Vec::with_capacity(self.names.len());
        for layout in &self.layouts {
            match layout {
                Layout::Plain(roots) => values.extend(roots.iter().map(|&k| root(k))),
                Layout::Frame(roots) => {
                    let all = roots.map(root);
                    values.extend(frame_columns(&all));
                }
            }
        }
        values
    }
}

/// Compiles `list`, outputs of the mechanism, on the dynamic model (see [`Outputs::compile`]).
fn compile_list(
    mechanism: &Mechanism,
    model: &Model,
    list: &[NamedOutput],
) -> Result<Outputs, Vec<Diagnostic>> {
    if list.is_empty() {
        return Ok(Outputs::default());
    }
    let frames = place_frames(mechanism, model, list)?;
    // Made before the builder and kept until the tape is built: the builder recognises
    // subexpressions it has lowered by their address.
    let components: Vec<Vec<Scalar>> = list.iter().map(components).collect();
    let declared_offset = |join| model.declared_offset(join);
    let actuated: Vec<usize> = model
        .actuation
        .iter()
        .flat_map(|a| a.coordinates.iter().map(|c| c.declared))
        .collect();
    let mut errors = Vec::new();
    let compiling = model.actuators_compiling(mechanism);
    for (output, components) in list.iter().zip(&components) {
        for component in components {
            refuse_unactuated(&compiling, &actuated, component, output.span, &mut errors);
        }
    }
    if !errors.is_empty() {
        errors.dedup_by(|a, b| a.message == b.message);
        return Err(errors);
    }
    let mut builder = TapeBuilder::new(&model.unknowns, &frames, &declared_offset)
        .reading_model(actuated.clone());
    let mut outputs = Outputs::default();
    for (output, components) in list.iter().zip(&components) {
        let roots: Result<Vec<usize>, EvalError> = components
            .iter()
            .map(|s| builder.scalar(s, Link(None)))
            .collect();
        match roots {
            Ok(roots) => {
                outputs.names.extend(column_names(output));
                outputs.layouts.push(layout(output, roots));
            }
            Err(error) => errors.push(lowering_error(mechanism, output, error)),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let tape = builder.build();
    outputs.reads_model = tape.model_reads(actuated.len()).any();
    outputs.tape = Some(tape);
    outputs.frames = frames;
    Ok(outputs)
}

/// Position, quaternion `[w, x, y, z]`, velocity, angular velocity from the 18 evaluated roots.
fn frame_columns(all: &[f64; 18]) -> impl Iterator<Item = f64> {
    let matrix = Matrix3::from_row_slice(&all[3..12]);
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(matrix));
    let position = [all[0], all[1], all[2]];
    let rest: Vec<f64> = all[12..].to_vec();
    position
        .into_iter()
        .chain(quaternion(&rotation))
        .chain(rest)
}

/// An output's scalar components: a scalar's, a vector's, a matrix's by rows, or the 18
/// components of a frame's state (`Layout::Frame`).
fn components(output: &NamedOutput) -> Vec<Scalar> {
    match &output.value {
        OutputValue::Scalar(s) => vec![s.clone()],
        OutputValue::Vector(v) => v.to_vec(),
        OutputValue::Matrix(m) => m.iter().flatten().cloned().collect(),
        OutputValue::Frame(frame) => {
            let frame = Arc::new(frame.clone());
            frame_quantities()
                .map(|quantity| Arc::new(SExpr::FrameState(frame.clone(), quantity)))
                .collect()
        }
    }
}

/// Where the output's components lie among the tape's roots.
fn layout(output: &NamedOutput, roots: Vec<usize>) -> Layout {
    match (&output.value, <[usize; 18]>::try_from(roots.as_slice())) {
        (OutputValue::Frame(_), Ok(frame)) => Layout::Frame(frame),
        _ => Layout::Plain(roots),
    }
}

/// The 18 components of a frame's state, in `Layout::Frame` order.
fn frame_quantities() -> impl Iterator<Item = FrameQuantity> {
    let position = (0..3).map(FrameQuantity::Position);
    let orientation = (0..9).map(|k| FrameQuantity::Orientation(k / 3, k % 3));
    let velocity = (0..3).map(FrameQuantity::Velocity);
    let angular = (0..3).map(FrameQuantity::AngularVelocity);
    position.chain(orientation).chain(velocity).chain(angular)
}

/// An output's columns: its name for a scalar, `name.x` … for a vector, `name.xx` … for a
/// matrix, the 13 components of `--output-frame` for a frame.
fn column_names(output: &NamedOutput) -> Vec<String> {
    let name = &output.name;
    match &output.value {
        OutputValue::Scalar(_) => vec![name.to_string()],
        OutputValue::Vector(_) => AXES.iter().map(|a| format!("{name}.{a}")).collect(),
        OutputValue::Matrix(_) => AXES
            .iter()
            .flat_map(|r| AXES.iter().map(move |c| format!("{name}.{r}{c}")))
            .collect(),
        OutputValue::Frame(_) => STATE_COMPONENTS
            .iter()
            .map(|c| format!("{name}.{c}"))
            .collect(),
    }
}

/// Every frame the outputs read, placed on its body of the dynamic model.
fn place_frames<'a>(
    mechanism: &Mechanism,
    model: &Model,
    list: &'a [NamedOutput],
) -> Result<Vec<EffortFrame>, Vec<Diagnostic>> {
    let mut used: Vec<(Arc<Frame>, &'a NamedOutput)> = Vec::new();
    for output in list {
        let mut frames = Vec::new();
        match &output.value {
            OutputValue::Scalar(s) => s.frames_used(&mut frames),
            OutputValue::Vector(v) => v.iter().for_each(|s| s.frames_used(&mut frames)),
            OutputValue::Matrix(m) => m.iter().flatten().for_each(|s| s.frames_used(&mut frames)),
            OutputValue::Frame(f) => frames.push(Arc::new(f.clone())),
        }
        for frame in frames {
            if !used.iter().any(|(f, _)| *f == frame) {
                used.push((frame, output));
            }
        }
    }
    let mut placed = Vec::new();
    let mut errors = Vec::new();
    for (frame, output) in used {
        match place(mechanism, model, &frame, output) {
            Ok((body, offset)) => placed.push(EffortFrame {
                frame,
                body,
                offset,
            }),
            Err(error) => errors.push(error),
        }
    }
    match errors.is_empty() {
        true => Ok(placed),
        false => Err(errors),
    }
}

/// A frame's body number and its constant pose on the body.
fn place(
    mechanism: &Mechanism,
    model: &Model,
    frame: &Frame,
    output: &NamedOutput,
) -> Result<(usize, crate::spatial::Pose), Diagnostic> {
    let body = match frame.body {
        BodyRef::Earth => 0,
        BodyRef::Body(id) => *model.body_numbers.get(&id).ok_or_else(|| {
            let name = mechanism.body_name(frame.body);
            Diagnostic::error(
                "E0841",
                format!("the output `{}` reads a frame of `{name}`, a body outside the mechanism", output.name),
            )
            .primary(output.span, "this output")
            .help(format!("`{name}` is joined to nothing: join it to the mechanism, or output a frame of a body that moves with it"))
        })?,
    };
    let offset = constant_pose(&frame.displacement, &model.unknowns)
        .map_err(|error| lowering_error(mechanism, output, error))?;
    Ok((body, offset))
}

/// Why an output cannot be computed: a value it needs is missing, or it reads what a run
/// cannot give it (a second derivative, a link's own coordinate).
fn lowering_error(mechanism: &Mechanism, output: &NamedOutput, error: EvalError) -> Diagnostic {
    match error {
        EvalError::Missing(id) => {
            let label = unknown_label(mechanism, id);
            Diagnostic::error(
                "E0840",
                format!("the output `{}` needs a value for {label}", output.name),
            )
            .primary(output.span, "this output")
            .secondary(mechanism.unknowns[id.0 as usize].span, "no value given")
            .help("give it with `given` in the program or `--set NAME=VALUE`")
        }
        EvalError::NotGeometric(_) | EvalError::NotFinite => Diagnostic::error(
            "E0842",
            format!(
                "the output `{}` cannot be computed: {}",
                output.name,
                crate::kinematics::eval::describe(&error, mechanism)
            ),
        )
        .primary(output.span, "this output")
        .help("an output is an expression of the coordinates, rates, time and frames' state (`position`, `velocity`, …), without second derivatives"),
    }
}
