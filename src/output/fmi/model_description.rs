//! `modelDescription.xml` of an FMI unit for co-simulation, in FMI 3.0 (the standard's §2.4,
//! schema `fmi3ModelDescription.xsd`) or FMI 2.0 (§2.2, `fmi2ModelDescription.xsd`): the unit's
//! identity, its co-simulation capabilities, the units, the variables and the model structure
//! (every output, and every output as an initial unknown: all are computed at initialisation).

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

/// What the model description says about the unit besides its variables.
pub struct Identity<'a> {
    pub model_name: &'a str,
    /// The shared library's name without its extension (a C identifier).
    pub model_identifier: &'a str,
    /// The instantiation token (FMI 3.0) or GUID (FMI 2.0) the library checks.
    pub token: &'a str,
    pub description: &'a str,
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
        Role::Input => "causality=\"input\" variability=\"continuous\"",
        _ => "causality=\"output\" variability=\"continuous\" initial=\"calculated\"",
    }
}

fn is_output(role: Role) -> bool {
    !matches!(role, Role::Time | Role::Parameter | Role::Input)
}

/// The model description's text.
pub fn model_description(version: Version, identity: &Identity<'_>, variables: &[Variable]) -> String {
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
    // Steps of any length; no state saved and restored, no early return.
    let _ = writeln!(
        out,
        "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" canBeInstantiatedOnlyOncePerProcess=\"false\"/>",
        escape(identity.model_identifier)
    );
    // FMI 2.0 has no time variable.
    let written: Vec<&Variable> = variables
        .iter()
        .filter(|v| version == Version::Fmi3 || v.role != Role::Time)
        .collect();
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
        match version {
            Version::Fmi3 => {
                let _ = writeln!(out, "    <Float64 {common}{unit}{start}/>");
            }
            Version::Fmi2 => {
                let _ = writeln!(
                    out,
                    "    <ScalarVariable {common}>\n      <Real{unit}{start}/>\n    </ScalarVariable>"
                );
            }
        }
    }
    out.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    match version {
        Version::Fmi3 => {
            for tag in ["Output", "InitialUnknown"] {
                for variable in written.iter().filter(|v| is_output(v.role)) {
                    let _ = writeln!(
                        out,
                        "    <{tag} valueReference=\"{}\"/>",
                        variable.value_reference
                    );
                }
            }
        }
        Version::Fmi2 => {
            // FMI 2.0 names a variable by its place among ModelVariables, from 1.
            let places: Vec<usize> = (written.iter().enumerate())
                .filter(|(_, v)| is_output(v.role))
                .map(|(k, _)| k + 1)
                .collect();
            for tag in ["Outputs", "InitialUnknowns"] {
                let _ = writeln!(out, "    <{tag}>");
                for place in &places {
                    let _ = writeln!(out, "      <Unknown index=\"{place}\"/>");
                }
                let _ = writeln!(out, "    </{tag}>");
            }
        }
    }
    out.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    out
}
