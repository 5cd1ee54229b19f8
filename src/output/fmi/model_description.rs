//! `modelDescription.xml` of an FMI unit for co-simulation, model exchange or both, in FMI 3.0
//! (the standard's §2.4, schema `fmi3ModelDescription.xsd`) or FMI 2.0 (§2.2,
//! `fmi2ModelDescription.xsd`): the unit's identity, its interfaces' capabilities, the units,
//! the variables and the model structure (every output; for model exchange the derivatives of
//! the continuous states, the coordinates and their rates; and as initial unknowns every
//! output and derivative: all are computed at initialisation).

use std::collections::BTreeSet;
use std::fmt::Write;

use super::variables::{Role, Unit, Variable};
use crate::output::xml::escape;

/// The FMI version a unit is written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    Fmi2,
    Fmi3,
}

impl Version {
    /// The folder of `binaries/` a 64-bit Linux shared library goes in (FMI 3.0 §2.5.1.1: the
    /// platform tuple; FMI 2.0 §2.3: `linux64`).
    pub fn platform_folder(self, arch: &str, os: &str) -> String {
        match self {
            Version::Fmi3 => format!("{arch}-{os}"),
            Version::Fmi2 => match (arch, os) {
                ("x86_64", "linux") => "linux64".to_string(),
                ("x86_64", "windows") => "win64".to_string(),
                ("x86_64" | "aarch64", "macos") => "darwin64".to_string(),
                _ => format!("{arch}-{os}"),
            },
        }
    }
}

/// The interfaces a unit provides (`lsdc export-fmu --kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    CoSimulation,
    ModelExchange,
    Both,
}

impl Kind {
    pub fn co_simulation(self) -> bool {
        self != Kind::ModelExchange
    }

    pub fn model_exchange(self) -> bool {
        self != Kind::CoSimulation
    }

    /// How the command line and the summary name it.
    pub fn name(self) -> &'static str {
        match self {
            Kind::CoSimulation => "co-simulation",
            Kind::ModelExchange => "model exchange",
            Kind::Both => "model exchange and co-simulation",
        }
    }
}

/// What the model description says about the unit besides its variables.
pub struct Identity<'a> {
    pub model_name: &'a str,
    /// The shared library's name without its extension (a C identifier).
    pub model_identifier: &'a str,
    /// The instantiation token (FMI 3.0) or GUID (FMI 2.0) the library checks.
    pub token: &'a str,
    pub description: &'a str,
    pub kind: Kind,
    pub generation_tool: &'a str,
    /// The program's `simulate` settings: duration, tolerance, output interval.
    pub stop_time: f64,
    pub tolerance: f64,
    pub step_size: f64,
}

/// A number as XML Schema's `xs:double` reads it back exactly (Rust's shortest round trip;
/// `INF`, `-INF`, `NaN` for the others).
fn number(x: f64) -> String {
    if x.is_nan() {
        "NaN".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "INF" } else { "-INF" }.to_string()
    } else {
        format!("{x:?}")
    }
}

/// The unit definitions of the units the written variables use.
fn unit_definitions(out: &mut String, variables: &[&Variable]) {
    let units: BTreeSet<Unit> = variables.iter().filter_map(|v| v.unit).collect();
    if units.is_empty() {
        return;
    }
    out.push_str("  <UnitDefinitions>\n");
    for unit in units {
        let exponents: String = (unit.base().iter())
            .filter(|(_, e)| *e != 0)
            .map(|(base, e)| format!(" {base}=\"{e}\""))
            .collect();
        let _ = writeln!(
            out,
            "    <Unit name=\"{}\">\n      <BaseUnit{exponents}/>\n    </Unit>",
            escape(unit.name())
        );
    }
    out.push_str("  </UnitDefinitions>\n");
}

/// The causality, variability and `initial` attributes of a variable's role (`initial`
/// omitted where the standard allows one value only), the same in FMI 3.0 and 2.0.
fn attributes(role: Role) -> &'static str {
    match role {
        Role::Time => "causality=\"independent\" variability=\"continuous\"",
        Role::Parameter => "causality=\"parameter\" variability=\"fixed\"",
        Role::Input | Role::ValueInput => "causality=\"input\" variability=\"continuous\"",
        Role::Acceleration => {
            "causality=\"local\" variability=\"continuous\" initial=\"calculated\""
        }
        _ => "causality=\"output\" variability=\"continuous\" initial=\"calculated\"",
    }
}

fn is_output(role: Role) -> bool {
    !matches!(
        role,
        Role::Time | Role::Parameter | Role::Input | Role::ValueInput | Role::Acceleration
    )
}

/// The derivatives of the continuous states, in the states' order (the coordinates, then
/// their rates): the rates, then the accelerations; with the index of the variable each is the
/// derivative of, among `written`.
fn derivatives<'v>(written: &[&'v Variable]) -> Vec<(usize, &'v Variable)> {
    let place = |role, index| {
        written
            .iter()
            .position(|v| v.role == role && v.index == index)
    };
    let mut found = Vec::new();
    for (of, role) in [
        (Role::Coordinate, Role::Rate),
        (Role::Rate, Role::Acceleration),
    ] {
        for variable in written.iter().filter(|v| v.role == role) {
            if let Some(state) = place(of, variable.index) {
                found.push((state, *variable));
            }
        }
    }
    found
}

/// The model description's text.
pub fn model_description(
    version: Version,
    identity: &Identity<'_>,
    variables: &[Variable],
) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let (version_attribute, token_attribute) = match version {
        Version::Fmi3 => ("3.0", "instantiationToken"),
        Version::Fmi2 => ("2.0", "guid"),
    };
    let _ = writeln!(
        out,
        "<fmiModelDescription fmiVersion=\"{version_attribute}\" modelName=\"{}\" {token_attribute}=\"{}\" description=\"{}\" generationTool=\"{}\" variableNamingConvention=\"flat\"{}>",
        escape(identity.model_name),
        escape(identity.token),
        escape(identity.description),
        escape(identity.generation_tool),
        if version == Version::Fmi2 { " numberOfEventIndicators=\"0\"" } else { "" },
    );
    let identifier = escape(identity.model_identifier);
    if identity.kind.model_exchange() {
        // No event: no completed integrator step needed, nothing saved and restored.
        let flag = match version {
            Version::Fmi3 => "needsCompletedIntegratorStep=\"false\"",
            Version::Fmi2 => "completedIntegratorStepNotNeeded=\"true\"",
        };
        let _ = writeln!(
            out,
            "  <ModelExchange modelIdentifier=\"{identifier}\" {flag} canBeInstantiatedOnlyOncePerProcess=\"false\"/>"
        );
    }
    if identity.kind.co_simulation() {
        // Steps of any length; no state saved and restored, no early return.
        let _ = writeln!(
            out,
            "  <CoSimulation modelIdentifier=\"{identifier}\" canHandleVariableCommunicationStepSize=\"true\" canBeInstantiatedOnlyOncePerProcess=\"false\"/>"
        );
    }
    // FMI 2.0 has no time variable.
    let written: Vec<&Variable> = variables
        .iter()
        .filter(|v| version == Version::Fmi3 || v.role != Role::Time)
        .collect();
    let derivatives = if identity.kind.model_exchange() {
        derivatives(&written)
    } else {
        Vec::new()
    };
    let derivative_of = |variable: &Variable| {
        let found = derivatives.iter().find(|(_, d)| std::ptr::eq(*d, variable));
        found.map(|(state, _)| match version {
            Version::Fmi3 => format!(" derivative=\"{}\"", written[*state].value_reference),
            // FMI 2.0 names a variable by its place among ModelVariables, from 1.
            Version::Fmi2 => format!(" derivative=\"{}\"", state + 1),
        })
    };
    unit_definitions(&mut out, &written);
    let _ = writeln!(
        out,
        "  <DefaultExperiment startTime=\"0\" stopTime=\"{}\" tolerance=\"{}\" stepSize=\"{}\"/>",
        number(identity.stop_time),
        number(identity.tolerance),
        number(identity.step_size)
    );
    out.push_str("  <ModelVariables>\n");
    for variable in &written {
        let unit = variable
            .unit
            .map(|u| format!(" unit=\"{}\"", escape(u.name())))
            .unwrap_or_default();
        let start = variable
            .start
            .map(|s| format!(" start=\"{}\"", number(s)))
            .unwrap_or_default();
        let common = format!(
            "name=\"{}\" valueReference=\"{}\" description=\"{}\" {}",
            escape(&variable.name),
            variable.value_reference,
            escape(&variable.description),
            attributes(variable.role)
        );
        let derivative = derivative_of(variable).unwrap_or_default();
        match version {
            Version::Fmi3 => {
                let _ = writeln!(out, "    <Float64 {common}{unit}{start}{derivative}/>");
            }
            Version::Fmi2 => {
                let _ = writeln!(
                    out,
                    "    <ScalarVariable {common}>\n      <Real{unit}{start}{derivative}/>\n    </ScalarVariable>"
                );
            }
        }
    }
    out.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    match version {
        Version::Fmi3 => {
            let outputs = written.iter().filter(|v| is_output(v.role));
            for variable in outputs.clone() {
                let reference = variable.value_reference;
                let _ = writeln!(out, "    <Output valueReference=\"{reference}\"/>");
            }
            for (_, variable) in &derivatives {
                let reference = variable.value_reference;
                let _ = writeln!(
                    out,
                    "    <ContinuousStateDerivative valueReference=\"{reference}\"/>"
                );
            }
            let accelerations = derivatives.iter().map(|(_, v)| *v);
            let accelerations = accelerations.filter(|v| v.role == Role::Acceleration);
            for variable in outputs.copied().chain(accelerations) {
                let reference = variable.value_reference;
                let _ = writeln!(out, "    <InitialUnknown valueReference=\"{reference}\"/>");
            }
        }
        Version::Fmi2 => {
            // FMI 2.0 names a variable by its place among ModelVariables, from 1.
            let place = |variable: &Variable| {
                1 + (written.iter())
                    .position(|v| std::ptr::eq(*v, variable))
                    .expect("a written variable")
            };
            let outputs: Vec<usize> = (written.iter().copied())
                .filter(|v| is_output(v.role))
                .map(place)
                .collect();
            let states: Vec<usize> = derivatives.iter().map(|(_, v)| place(v)).collect();
            let mut initial: Vec<usize> = outputs.iter().chain(&states).copied().collect();
            // Listed once each, in the variables' order (FMI 2.0 §2.2.8).
            initial.sort_unstable();
            initial.dedup();
            for (tag, places) in [
                ("Outputs", &outputs),
                ("Derivatives", &states),
                ("InitialUnknowns", &initial),
            ] {
                if places.is_empty() && tag == "Derivatives" {
                    continue;
                }
                let _ = writeln!(out, "    <{tag}>");
                for place in places {
                    let _ = writeln!(out, "      <Unknown index=\"{place}\"/>");
                }
                let _ = writeln!(out, "    </{tag}>");
            }
        }
    }
    out.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    out
}
