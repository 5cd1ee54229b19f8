//! The variables of an FMI unit made from a program: what an importer reads and sets, with the
//! value reference that names each in the model description and in the unit's own description
//! of its variables (`unit.json`, read by the shared library, `fmi/`).
//!
//! Value references are numbered in the order below, from 0: `time` (FMI 3.0 declares it; FMI
//! 2.0 does not), the parameters (the program's unknowns that have a value: `given` or
//! `--set`), the inputs (efforts along the velocities the program's `input` declarations and
//! `--input` name), then the outputs:
//! the declared coordinates (`swing.q`), their rates (`swing.q'`), the kinetic and potential
//! energies and the program's `output`s, the columns of `lsdc simulate`'s CSV; and in a unit for
//! model exchange, the coordinates' accelerations (`swing.q''`), the derivatives of the
//! continuous states (the coordinates and their rates).

use serde::Serialize;

use crate::elab::mechanism::{Mechanism, UnknownKind};
use crate::elab::value::UnknownId;
use crate::kinematics::model::{KinematicModel, Step};
use crate::kinematics::unknowns::{names_of, unknown_values, Override};
use crate::prepare::Prepared;

/// What a variable is in the run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The independent variable (FMI 3.0 only).
    Time,
    /// A value of the program, set before initialisation (`index` into the parameters).
    Parameter,
    /// An effort along a velocity, held over each communication step.
    Input,
    /// A value input of the program (`input voltage = 0;`, `index` among its value inputs),
    /// held over each communication step.
    ValueInput,
    /// A declared coordinate (`index` among `Prepared::coordinate_names`).
    Coordinate,
    /// A declared coordinate's rate.
    Rate,
    KineticEnergy,
    /// NaN where the program's efforts derive from no potential.
    PotentialEnergy,
    /// An `output` of the program (`index` among its outputs' columns).
    Output,
    /// A declared coordinate's acceleration, the derivative of its rate (units for model
    /// exchange only).
    Acceleration,
}

/// One variable of the unit.
#[derive(Clone, Debug, Serialize)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub role: Role,
    /// Its place among the variables of its role.
    pub index: usize,
    /// The unit's name in the model description's unit definitions, if known.
    #[serde(skip)]
    pub unit: Option<Unit>,
    #[serde(skip)]
    pub description: String,
    /// The start value of a parameter (its value at export) or of an input (its declared start
    /// value, or 0).
    pub start: Option<f64>,
}

/// The units the variables use, with their SI base-unit exponents (FMI 3.0 §2.4.3, FMI 2.0
/// §2.2.2: `BaseUnit` kg, m, s, rad).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Unit {
    Second,
    Radian,
    Metre,
    RadianPerSecond,
    MetrePerSecond,
    RadianPerSecondSquared,
    MetrePerSecondSquared,
    NewtonMetre,
    Newton,
    Joule,
}

impl Unit {
    /// Its name in the model description.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Second => "s",
            Unit::Radian => "rad",
            Unit::Metre => "m",
            Unit::RadianPerSecond => "rad/s",
            Unit::MetrePerSecond => "m/s",
            Unit::RadianPerSecondSquared => "rad/s2",
            Unit::MetrePerSecondSquared => "m/s2",
            Unit::NewtonMetre => "N.m",
            Unit::Newton => "N",
            Unit::Joule => "J",
        }
    }

    /// The exponents of kg, m, s and rad.
    pub fn base(self) -> [(&'static str, i32); 4] {
        let [kg, m, s, rad] = match self {
            Unit::Second => [0, 0, 1, 0],
            Unit::Radian => [0, 0, 0, 1],
            Unit::Metre => [0, 1, 0, 0],
            Unit::RadianPerSecond => [0, 0, -1, 1],
            Unit::MetrePerSecond => [0, 1, -1, 0],
            Unit::RadianPerSecondSquared => [0, 0, -2, 1],
            Unit::MetrePerSecondSquared => [0, 1, -2, 0],
            // A torque: N.m, not J, though their base units agree.
            Unit::NewtonMetre | Unit::Joule => [1, 2, -2, 0],
            Unit::Newton => [1, 1, -2, 0],
        };
        [("kg", kg), ("m", m), ("s", s), ("rad", rad)]
    }
}

/// Whether a declared coordinate is an angle or a length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dimension {
    Angle,
    Length,
}

impl Dimension {
    /// The unit of the coordinate (order 0), of its rate (1), of its acceleration (2), of the
    /// effort along it (`None`).
    fn of(self, order: Option<usize>) -> Unit {
        match (self, order) {
            (Dimension::Angle, Some(0)) => Unit::Radian,
            (Dimension::Angle, Some(1)) => Unit::RadianPerSecond,
            (Dimension::Angle, Some(_)) => Unit::RadianPerSecondSquared,
            (Dimension::Angle, None) => Unit::NewtonMetre,
            (Dimension::Length, Some(0)) => Unit::Metre,
            (Dimension::Length, Some(1)) => Unit::MetrePerSecond,
            (Dimension::Length, Some(_)) => Unit::MetrePerSecondSquared,
            (Dimension::Length, None) => Unit::Newton,
        }
    }
}

/// The dimension of each declared coordinate, by name: an angle when its chain uses it as the
/// whole angle of its rotations (`JointModel::turns`), a length when only its translations use
/// it; neither (no unit given) otherwise.
fn dimensions(kinematics: &KinematicModel) -> Vec<(String, Dimension)> {
    let mut found = Vec::new();
    for joint in &kinematics.joints {
        for (k, name) in joint.coordinate_names.iter().enumerate() {
            let full = format!("{}.{name}", joint.name);
            let index = k as u32;
            let in_translation = joint.steps.iter().any(|s| match s {
                Step::Translation(t) => t.iter().any(|e| e.uses_coordinate(index)),
                Step::Rotation { .. } => false,
            });
            let in_rotation = joint.steps.iter().any(|s| match s {
                Step::Rotation { angle, .. } => angle.uses_coordinate(index),
                Step::Translation(_) => false,
            });
            if joint.turns(k) && !in_translation {
                found.push((full, Dimension::Angle));
            } else if in_translation && !in_rotation {
                found.push((full, Dimension::Length));
            }
        }
    }
    found
}

/// A program's parameters: every scalar unknown with a value (from `given` or `values`), under
/// its first name, with that value.
pub fn parameters(mechanism: &Mechanism, values: &[Override]) -> Vec<(String, f64, String)> {
    let Ok(known) = unknown_values(mechanism, &Default::default(), values) else {
        return Vec::new();
    };
    let mut parameters = Vec::new();
    for (index, unknown) in mechanism.unknowns.iter().enumerate() {
        let id = UnknownId(index as u32);
        if !matches!(unknown.kind, UnknownKind::Scalar | UnknownKind::Generic) {
            continue;
        }
        let (Some(value), Some(name)) = (
            known.get(&id),
            names_of(mechanism, &Default::default(), id)
                .into_iter()
                .next(),
        ) else {
            continue;
        };
        let set = values.iter().any(|o| o.name == name);
        let source = if set { "--set" } else { "`given`" };
        parameters.push((
            name.clone(),
            *value,
            format!("the program's value `{name}` (from {source} at export)"),
        ));
    }
    parameters
}

/// The unit's variables, in the order of their value references (see the module's comment);
/// with `accelerations` (a unit for model exchange), the declared coordinates' accelerations
/// last, the derivatives of their rates.
pub fn variables(
    prepared: &Prepared,
    parameters: &[(String, f64, String)],
    inputs: &[(String, f64)],
    value_inputs: &[(String, f64)],
    output_names: &[String],
    accelerations: bool,
) -> Vec<Variable> {
    let dimensions = dimensions(&prepared.kinematics);
    let dimension = |name: &str| dimensions.iter().find(|(n, _)| n == name).map(|(_, d)| *d);
    let mut list = Vec::new();
    let mut push = |name: String, role, index, unit, description: String, start| {
        let value_reference = list.len() as u32;
        list.push(Variable {
            name,
            value_reference,
            role,
            index,
            unit,
            description,
            start,
        });
    };
    push(
        "time".to_string(),
        Role::Time,
        0,
        Some(Unit::Second),
        "the program's time".to_string(),
        None,
    );
    for (k, (name, value, description)) in parameters.iter().enumerate() {
        let description = description.clone();
        push(
            name.clone(),
            Role::Parameter,
            k,
            None,
            description,
            Some(*value),
        );
    }
    for (k, (name, start)) in inputs.iter().enumerate() {
        let unit = match name.rsplit_once('.').map(|(_, last)| last) {
            Some("ω_x" | "ω_y" | "ω_z") => Some(Unit::NewtonMetre),
            Some("v_x" | "v_y" | "v_z") => Some(Unit::Newton),
            _ => dimension(name).map(|d| d.of(None)),
        };
        let description =
            format!("generalised effort along `{name}`, held over each communication step");
        push(
            format!("{name}.effort"),
            Role::Input,
            k,
            unit,
            description,
            Some(*start),
        );
    }
    for (k, (name, start)) in value_inputs.iter().enumerate() {
        let description =
            format!("the program's input `{name}`, held over each communication step");
        push(
            name.clone(),
            Role::ValueInput,
            k,
            None,
            description,
            Some(*start),
        );
    }
    for (k, name) in prepared.coordinate_names.iter().enumerate() {
        let unit = dimension(name).map(|d| d.of(Some(0)));
        let description = format!("coordinate `{name}`");
        push(name.clone(), Role::Coordinate, k, unit, description, None);
    }
    for (k, name) in prepared.coordinate_names.iter().enumerate() {
        let unit = dimension(name).map(|d| d.of(Some(1)));
        let description = format!("rate of `{name}`");
        push(format!("{name}'"), Role::Rate, k, unit, description, None);
    }
    push(
        "kinetic_energy".to_string(),
        Role::KineticEnergy,
        0,
        Some(Unit::Joule),
        "kinetic energy of the mechanism".to_string(),
        None,
    );
    push(
        "potential_energy".to_string(),
        Role::PotentialEnergy,
        0,
        Some(Unit::Joule),
        "potential energy of the program's conservative efforts (NaN where they have none)"
            .to_string(),
        None,
    );
    // A value input is a column of the run (a state) but an input of the unit.
    let is_input = |name: &String| value_inputs.iter().any(|(n, _)| n == name);
    for (k, name) in output_names
        .iter()
        .enumerate()
        .filter(|(_, n)| !is_input(n))
    {
        let description = format!("the program's output `{name}`");
        push(name.clone(), Role::Output, k, None, description, None);
    }
    if accelerations {
        for (k, name) in prepared.coordinate_names.iter().enumerate() {
            let unit = dimension(name).map(|d| d.of(Some(2)));
            let description = format!("acceleration of `{name}`");
            push(
                format!("{name}''"),
                Role::Acceleration,
                k,
                unit,
                description,
                None,
            );
        }
    }
    list
}
