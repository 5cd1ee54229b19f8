//! Everything a simulation needs before it starts: values for every unknown the motion depends
//! on (from `given` and `--set`), the dynamic model, the initial state from `initial`, and the
//! settings from `simulate` and the command line. Every missing value is reported at once.

pub mod consistent;
pub mod kinematic_scene;
pub mod native;
pub mod outputs;
pub mod settings;

use std::collections::{BTreeSet, HashMap};

use crate::diag::Diagnostic;
use crate::dynamics::driven_subtrees::DrivenSubtrees;
use crate::dynamics::model::{self as dynamic_model, Model};
use crate::dynamics::planar::{self, PlanarModel};
use crate::elab::mechanism::{Mechanism, Origin, UnknownKind};
use crate::elab::value::{BodyRef, Displacement, Elementary, SExpr, UnknownId, Vector};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model as kinematic_model;
use crate::kinematics::position_drives;
use crate::kinematics::sphere_on_disc::sphere_contacts_on_discs;
pub use crate::kinematics::unknowns::Override;
use crate::kinematics::unknowns::{constant, names_of, unknown_values};
use crate::topology::{self, notation, Topology};

use self::settings::program_settings;
pub use self::settings::{Integrator, Settings};

pub struct Prepared {
    pub model: Model,
    pub topology: Topology,
    /// The kinematic model of the declared coordinates: the poses of the bodies and frames.
    pub kinematics: kinematic_model::KinematicModel,
    /// Declared coordinates and rates at t = 0 (in the model's joint order).
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    pub settings: Settings,
    /// `join.coordinate` for every declared coordinate.
    pub coordinate_names: Vec<String>,
    /// What preparing found worth saying without stopping: given values assembly moved (W0801),
    /// rates the loops made far larger than those given (W0802).
    pub warnings: Vec<Diagnostic>,
    /// The forward dynamics as native code, when asked for and able to serve
    /// (`compiled::attach`).
    pub native: Option<self::native::NativeDynamics>,
    /// The program's `output` declarations, compiled.
    pub outputs: self::outputs::Outputs,
    /// The scene prepared and what its model holds (`elab::scene`); `None` without scenes.
    pub scene: Option<crate::elab::scene_model::SceneModel>,
    /// The model's planar form when the mechanism is planar (`dynamics::planar::decide`);
    /// otherwise why not.
    pub planar: Result<Box<PlanarModel>, String>,
    /// Whether the run's right-hand side takes the planar form (`simulate --planar`). Not by
    /// default: through singular configurations of its loops, runs in either form differ at
    /// round-off and the passages amplify that (docs/guarantees.md).
    pub takes_planar: bool,
    /// The method the run's loops are solved by, when forced (`dynamics::loops::Method`), to
    /// compare the two on one mechanism; `None`, the default, takes the cheaper by the rule of
    /// `loops::range_space::method_for`.
    pub loop_method: Option<crate::dynamics::loops::Method>,
    /// Whether the run follows the drives by assembly at each output instead of integrating
    /// the dynamics: a scene that asks only for kinematics (`kinematic_scene`).
    pub kinematics_only: bool,
    /// The fully driven subtrees, whose drives the run takes by hybrid dynamics rather than
    /// as rows of the constraint stack (`dynamics::driven_subtrees`); otherwise why not.
    pub driven_subtrees: Result<DrivenSubtrees, String>,
}

impl Prepared {
    /// Has the run's right-hand side take the planar form of a planar mechanism (`simulate
    /// --planar`); why it cannot, when the mechanism is not planar (it keeps the spatial form).
    pub fn take_planar(&mut self) -> Result<(), String> {
        self.takes_planar = true;
        self.planar.as_ref().map(|_| ()).map_err(Clone::clone)
    }

    /// Runs the drives as rows of the constraint stack, as a model without fully driven
    /// subtrees does: the full model, for comparisons.
    pub fn keep_drive_rows(&mut self) {
        self.driven_subtrees = Err("the drives kept as rows".to_string());
        if let Some(scene) = &mut self.scene {
            scene.driven_kinematics = 0;
        }
    }

    /// The fully driven subtrees the run takes by hybrid dynamics, if any.
    pub fn driven_subtrees(&self) -> Option<&DrivenSubtrees> {
        self.driven_subtrees.as_ref().ok()
    }

    /// The planar form, when the run takes one.
    pub fn planar_form(&self) -> Option<&PlanarModel> {
        self.planar.as_deref().ok().filter(|_| self.takes_planar)
    }
}

fn collect(s: &SExpr, into: &mut BTreeSet<UnknownId>) {
    s.collect_unknowns(into);
}

fn collect_vector(v: &Vector, into: &mut BTreeSet<UnknownId>) {
    v.iter().for_each(|s| collect(s, into));
}

fn collect_displacement(d: &Displacement, into: &mut BTreeSet<UnknownId>) {
    for step in &d.0 {
        match step {
            Elementary::Translation(t) => collect_vector(t, into),
            Elementary::Rotation { angle, axis } => {
                collect(angle, into);
                collect_vector(axis, into);
            }
        }
    }
}

/// The unknowns the motion depends on: geometry, and `with_dynamics` the inertia of massive
/// bodies (a body declared without mass and inertia needs no inertia frame) and the efforts.
fn required_unknowns(
    mechanism: &Mechanism,
    topology: &Topology,
    with_dynamics: bool,
) -> BTreeSet<UnknownId> {
    let mut required = BTreeSet::new();
    for join in &mechanism.joins {
        collect_displacement(&join.first.displacement, &mut required);
        collect_displacement(&join.second.displacement, &mut required);
        let link = mechanism.link(join.link);
        link.dofs
            .iter()
            .for_each(|d| collect_displacement(d, &mut required));
        if with_dynamics {
            link.forces
                .iter()
                .chain(&link.torques)
                .for_each(|(_, v)| collect_vector(v, &mut required));
        }
    }
    if !with_dynamics {
        return required;
    }
    for &id in &topology.bodies {
        let body = mechanism.body(id);
        let mut inertia = BTreeSet::new();
        collect(body.mass.value(), &mut inertia);
        collect_vector(body.inertia.value(), &mut inertia);
        let declared_massless = body.mass.is_declared()
            && body.inertia.is_declared()
            && eval(body.mass.value(), &UnknownValues::new()) == Ok(0.0)
            && body
                .inertia
                .value()
                .iter()
                .all(|s| eval(s, &UnknownValues::new()) == Ok(0.0));
        if !declared_massless {
            required.extend(inertia);
            collect_displacement(body.iframe.value(), &mut required);
        }
    }
    for application in &mechanism.applications {
        collect_displacement(&application.target.displacement, &mut required);
        collect_vector(
            mechanism.effort(application.effort).value.value(),
            &mut required,
        );
    }
    required
}

fn missing_value(
    mechanism: &Mechanism,
    generated: &HashMap<UnknownId, String>,
    id: UnknownId,
) -> Diagnostic {
    let unknown = &mechanism.unknowns[id.0 as usize];
    let names = names_of(mechanism, generated, id);
    let shown = names
        .first()
        .cloned()
        .unwrap_or_else(|| "an unknown".to_string());
    if unknown.kind == UnknownKind::Function {
        return Diagnostic::error(
            "E0812",
            format!("the unknown function `{shown}` has no law to simulate"),
        )
        .primary(unknown.span, "an unknown function of the coordinates")
        .help("replace it with the law, for example `-k * x - c * x'`");
    }
    let also = if names.len() > 1 {
        format!(
            " (also called {})",
            names[1..]
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    } else {
        String::new()
    };
    let setter = names.last().cloned().unwrap_or_default();
    let given_target =
        unknown
            .name
            .as_ref()
            .map(|n| n.to_string())
            .or_else(|| match unknown.origin {
                Origin::Mass(b) => Some(format!("{}.mass", mechanism.body_name(BodyRef::Body(b)))),
                Origin::Inertia(b, _) => {
                    Some(format!("{}.inertia", mechanism.body_name(BodyRef::Body(b))))
                }
                _ => None,
            });
    let help = match given_target {
        Some(target) => {
            format!("write `given {target} = ...;` in the program, or pass `--set {setter}=VALUE`")
        }
        None => format!("pass `--set {setter}=VALUE`, or write the number in the program"),
    };
    Diagnostic::error("E0813", format!("no value for `{shown}`{also}"))
        .primary(unknown.span, "needed to simulate; it comes from here")
        .help(help)
}

fn missing_inertia_frame(mechanism: &Mechanism, body: crate::elab::value::BodyId) -> Diagnostic {
    let name = mechanism.body_name(BodyRef::Body(body));
    Diagnostic::error("E0813", format!("no inertia frame for `{name}`"))
        .primary(mechanism.body(body).span, "a body with mass needs its centre of mass and principal axes")
        .help(format!(
            "declare `iframe = ...` in the body (`iframe = 0` when its reference frame is its principal inertia frame), or pass `--set iframe_x({name})=VALUE` … `--set iframe_rz({name})=VALUE`"
        ))
}

/// Builds the model and initial state. `overrides` come from `--set`; `settings` from the
/// program's `simulate` declaration completed by `defaults`.
/// Gives the declared inputs named by `--set` (`voltage`, `swing.q`) their start values.
fn set_input_starts(model: &mut Model, starts: &[Override]) {
    for start in starts {
        let states = model.states.iter_mut().filter(|state| state.input);
        for state in states.filter(|state| state.name == start.name) {
            state.initial = start.value;
        }
        let efforts = model.effort_inputs.iter_mut();
        for (_, value) in efforts.filter(|(name, _)| *name == start.name) {
            *value = start.value;
        }
    }
}

pub fn prepare(
    mechanism: &Mechanism,
    overrides: &[Override],
    defaults: &Settings,
) -> Result<Prepared, Vec<Diagnostic>> {
    prepare_parts(mechanism, overrides, defaults, true)
}

/// Builds what a study that asks only for kinematics reads (`lsdc kinematics`, `lsdc
/// workspace`): the model without the dynamics (`dynamic_model::build_kinematic`: no inertia,
/// effort, rotor, friction or state, so that none needs a value), the initial state closed on
/// the loops, no outputs and no planar form.
pub fn prepare_kinematics(
    mechanism: &Mechanism,
    overrides: &[Override],
) -> Result<Prepared, Vec<Diagnostic>> {
    prepare_parts(mechanism, overrides, &Settings::default(), false)
}

pub(crate) fn prepare_parts(
    mechanism: &Mechanism,
    overrides: &[Override],
    defaults: &Settings,
    with_dynamics: bool,
) -> Result<Prepared, Vec<Diagnostic>> {
    let topology = topology::build(mechanism)?;
    let generated = notation::unknown_names(mechanism, &topology);
    // `--set voltage=5`, `--set swing.q=0.5`: the start values of declared inputs, not
    // unknowns.
    let inputs: Vec<String> = (mechanism.declared_inputs().into_iter())
        .chain(mechanism.declared_value_inputs())
        .map(|(name, _)| name)
        .collect();
    let (input_starts, overrides): (Vec<Override>, Vec<Override>) =
        (overrides.iter().cloned()).partition(|o| inputs.contains(&o.name));
    let overrides = &overrides[..];
    let values = unknown_values(mechanism, &generated, overrides)?;
    let mut missing = Vec::new();
    let mut frames_reported = BTreeSet::new();
    for id in required_unknowns(mechanism, &topology, with_dynamics)
        .into_iter()
        .filter(|id| !values.contains_key(id))
    {
        // The six generic values of an inertia frame are one thing to declare.
        if let Origin::InertiaFrame(body, _) = mechanism.unknowns[id.0 as usize].origin {
            if frames_reported.insert(body) {
                missing.push(missing_inertia_frame(mechanism, body));
            }
            continue;
        }
        missing.push(missing_value(mechanism, &generated, id));
    }
    if !missing.is_empty() {
        return Err(missing);
    }
    let kinematics = kinematic_model::build(mechanism, topology.clone(), values)?;
    let mut model = match with_dynamics {
        true => dynamic_model::build(mechanism, &kinematics)?,
        false => dynamic_model::build_kinematic(mechanism, &kinematics)?,
    };
    set_input_starts(&mut model, &input_starts);
    let (mut coordinates, mut rates) = initial_state(mechanism, &model)?;
    let mut warnings = Vec::new();
    if model.has_loops() {
        let consistent = self::consistent::initial_state(mechanism, &kinematics, &model, &rates)?;
        (coordinates, rates, warnings) = (
            consistent.coordinates,
            consistent.rates,
            consistent.warnings,
        );
    }
    warnings.extend(sphere_contacts_on_discs(
        mechanism,
        &kinematics,
        &coordinates,
    ));
    let settings = program_settings(mechanism, &model, defaults)?;
    if settings.integrator == Integrator::Symplectic {
        let help = "choose `rk4`, `dopri5`, `dop853` or `implicit`: their steps land on every sampling instant";
        let refused = crate::dynamics::sampled::refusal(&model, "the symplectic integrator", help);
        refused.map_or(Ok(()), |error| Err(vec![error]))?;
    }
    let outputs = match with_dynamics {
        true => self::outputs::Outputs::compile(mechanism, &model)?,
        false => self::outputs::Outputs::none(),
    };
    let coordinate_names = kinematics.coordinate_names();
    if !model.position_drives.is_empty() {
        let paths = &model.position_drives;
        coordinates = position_drives::start_on_paths(&kinematics, paths, coordinates)
            .map_err(|refused| vec![refused])?;
        if let Some(over) =
            position_drives::over_constrained(mechanism, &kinematics, paths, &coordinates)
        {
            return Err(vec![over]);
        }
    }
    let driven_subtrees = match with_dynamics {
        true => DrivenSubtrees::find(&model),
        false => Err("a study of kinematics alone builds no dynamics".to_string()),
    };
    let mut scene = mechanism.scene.clone();
    if let (Some(scene), Ok(subtrees)) = (&mut scene, &driven_subtrees) {
        scene.driven_kinematics = subtrees.bodies;
    }
    Ok(Prepared {
        driven_subtrees,
        planar: match with_dynamics {
            true => planar::decide(&kinematics, &model).map(Box::new),
            false => Err("a study of kinematics alone builds no dynamics".to_string()),
        },
        takes_planar: false,
        loop_method: None,
        kinematics_only: false,
        model,
        topology,
        kinematics,
        coordinates,
        rates,
        settings,
        coordinate_names,
        warnings,
        native: None,
        outputs,
        scene,
    })
}

fn initial_state(
    mechanism: &Mechanism,
    model: &Model,
) -> Result<(Vec<f64>, Vec<f64>), Vec<Diagnostic>> {
    let mut coordinates = vec![0.0; model.declared_count];
    let mut rates = vec![0.0; model.declared_count];
    for initial in &mechanism.initial {
        let Some(offset) = model.declared_offset(initial.join) else {
            continue;
        };
        let value = constant(&initial.value, &model.unknowns).ok_or_else(|| {
            vec![
                Diagnostic::error("E0803", "an initial value must be a number")
                    .primary(initial.span, "here"),
            ]
        })?;
        let index = offset + initial.coordinate;
        if initial.order == 0 {
            coordinates[index] = value;
        } else {
            rates[index] = value;
        }
    }
    // A driven coordinate starts on its law, whatever `initial` gives it: then the start's
    // projection onto the held rows has nothing to change, and leaves the other rates alone.
    for drive in &model.drives {
        let law = drive.at(0.0);
        (coordinates[drive.declared], rates[drive.declared]) = (law.position, law.rate);
    }
    Ok((coordinates, rates))
}
