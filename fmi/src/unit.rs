//! The unit's description of its program and variables, `resources/lsdc/unit.json`, as
//! `lsdc export-fmu` writes it (src/cli/export_fmu.rs, src/output/fmi/variables.rs).

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// What a variable is in the run (`lsdc::output::fmi::variables::Role`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    Time,
    Parameter,
    Input,
    /// A value input of the program (`input voltage = 0;`), set by its name.
    ValueInput,
    Coordinate,
    Rate,
    KineticEnergy,
    PotentialEnergy,
    Output,
    Acceleration,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub role: Role,
    pub index: usize,
    pub start: Option<f64>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Unit {
    pub token: String,
    pub program: String,
    pub library_dirs: Vec<String>,
    pub scene: Option<String>,
    /// Whether the unit provides model exchange (units written before it was provided do
    /// not say, and do not).
    #[serde(default)]
    pub model_exchange: bool,
    pub inputs: Vec<String>,
    pub variables: Vec<Variable>,
}

impl Unit {
    /// Reads `lsdc/unit.json` in the unit's resources folder.
    pub fn read(resources: &Path) -> Result<Unit, String> {
        let path = resources.join("lsdc").join("unit.json");
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        serde_json::from_str(&text).map_err(|e| format!("cannot read {}: {e}", path.display()))
    }

    /// The folder the program's files are in.
    pub fn program_folder(resources: &Path) -> PathBuf {
        resources.join("lsdc").join("program")
    }

    /// The number of continuous states in model exchange: the declared coordinates and their
    /// rates.
    pub fn state_count(&self) -> usize {
        2 * self
            .variables
            .iter()
            .filter(|v| v.role == Role::Coordinate)
            .count()
    }

    /// The variable of a value reference.
    pub fn variable(&self, value_reference: u32) -> Option<&Variable> {
        // Value references are numbered from 0 in the list's order.
        (self.variables.get(value_reference as usize))
            .filter(|v| v.value_reference == value_reference)
    }
}
