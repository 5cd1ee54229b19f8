//! The settings' keyword arguments (`duration`, `every`, `integrator`, …) as changes to the
//! program's `simulate` declaration, and `{name: value}` mappings as the library's overrides:
//! the options of `lsdc simulate` and `lsdc sweep`, under the same names.

use std::collections::BTreeMap;

use lsdc::api::{Integrator, Override, SettingsChanges, Stabilisation};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The run settings a method takes as keyword arguments (`None`: the program's).
#[derive(Clone, Default)]
pub struct RunSettings {
    pub integrator: Option<String>,
    pub duration: Option<f64>,
    pub every: Option<f64>,
    pub tolerance: Option<f64>,
    pub step: Option<f64>,
    pub max_steps: Option<usize>,
}

impl RunSettings {
    /// The changes as `lsdc sweep`'s options make them (`RunSettingsArgs::changes`).
    pub fn changes(&self) -> PyResult<SettingsChanges> {
        let integrator = match &self.integrator {
            Some(name) => Some(
                Integrator::from_name(name).map_err(|e| PyValueError::new_err(e.to_string()))?,
            ),
            None => None,
        };
        Ok(SettingsChanges {
            integrator,
            duration: self.duration,
            output: self.every,
            tolerance: self.tolerance,
            step: self.step,
            max_steps: self.max_steps,
            ..Default::default()
        })
    }

    /// The changes as `lsdc simulate` makes them: with the loops' stabilisation it names
    /// (`"projection"`, its default, `"baumgarte"` at `baumgarte_rate`, or `"none"`) and the
    /// reactions asked for.
    pub fn simulate_changes(
        &self,
        stabilisation: &str,
        baumgarte_rate: f64,
        reactions: bool,
    ) -> PyResult<SettingsChanges> {
        let stabilisation = match stabilisation {
            "projection" => Stabilisation::Projection,
            "baumgarte" => Stabilisation::Baumgarte(baumgarte_rate),
            "none" => Stabilisation::None,
            other => {
                return Err(PyValueError::new_err(format!(
                    "stabilisation `{other}`: choose \"projection\", \"baumgarte\" or \"none\""
                )))
            }
        };
        Ok(SettingsChanges {
            stabilisation: Some(stabilisation),
            reactions,
            ..self.changes()?
        })
    }
}

/// `{name: value}` as overrides (`--set NAME=VALUE`), in the names' order.
pub fn overrides(values: Option<BTreeMap<String, f64>>) -> Vec<Override> {
    (values.unwrap_or_default().into_iter())
        .map(|(name, value)| Override { name, value })
        .collect()
}
