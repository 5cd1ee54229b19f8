//! A simulation's settings: the integrator, duration, outputs, steps and tolerances, from the
//! program's `simulate` declaration, then changed by the command line (or a library caller).

use std::fmt;

use crate::diag::Diagnostic;
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::model::Model;
use crate::elab::mechanism::Mechanism;
use crate::kinematics::unknowns::constant;

/// The output times are listed before the run (8 bytes each): more than this many are refused
/// up front, with a message that says so.
const MAX_OUTPUTS: f64 = 1e7;

/// Most steps of a run unless `--max-steps` says otherwise (attempts, rejected ones included).
pub const DEFAULT_MAX_STEPS: usize = 1_000_000;

pub use crate::integrators::Integrator;

#[derive(Clone, Debug)]
pub struct Settings {
    pub integrator: Integrator,
    pub duration: f64,
    /// Time between outputs.
    pub output: f64,
    /// Fixed step (RK4, symplectic) or initial step (adaptive methods).
    pub step: Option<f64>,
    pub max_step: f64,
    pub rtol: f64,
    pub atol: f64,
    /// How loops are kept closed.
    pub stabilisation: Stabilisation,
    /// Output the reactions in every join.
    pub reactions: bool,
    /// Most steps (attempts, rejected ones included) before the run stops with a failure.
    pub max_steps: usize,
    /// Whether an explicit integrator checks during the run whether its steps are held by
    /// its stability region (W0901).
    pub stiffness_check: bool,
}

/// Changes to the settings of a program's `simulate` declaration; `None` keeps the program's.
#[derive(Clone, Debug, Default)]
pub struct SettingsChanges {
    pub integrator: Option<Integrator>,
    pub duration: Option<f64>,
    /// Time between outputs.
    pub output: Option<f64>,
    /// Relative and absolute tolerance at once.
    pub tolerance: Option<f64>,
    pub step: Option<f64>,
    pub stabilisation: Option<Stabilisation>,
    /// Also output the reactions in every join.
    pub reactions: bool,
    pub max_steps: Option<usize>,
    /// Turn the stiffness check off (`--no-stiffness-check`).
    pub no_stiffness_check: bool,
}

/// Settings that cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub enum SettingsError {
    /// An option that must be a positive number is not (named as the command line names it).
    NotPositive { option: &'static str },
    /// `--max-steps 0`.
    NoSteps,
    /// More outputs than can be kept in memory.
    TooManyOutputs { duration: f64, output: f64 },
}

impl fmt::Display for SettingsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SettingsError::NotPositive { option } => {
                write!(f, "`--{option}` must be a positive number")
            }
            SettingsError::NoSteps => write!(f, "`--max-steps` must be at least 1"),
            SettingsError::TooManyOutputs { duration, output } => write!(
                f,
                "{duration} s of simulation with an output every {output} s makes more than {MAX_OUTPUTS:e} outputs: raise the output interval"
            ),
        }
    }
}

impl std::error::Error for SettingsError {}

fn positive(value: f64) -> bool {
    value.is_finite() && value > 0.0
}

impl Settings {
    /// The output times are listed before the run: refuses more than `MAX_OUTPUTS`.
    pub fn check_outputs(&self) -> Result<(), SettingsError> {
        if self.duration / self.output > MAX_OUTPUTS {
            return Err(SettingsError::TooManyOutputs {
                duration: self.duration,
                output: self.output,
            });
        }
        Ok(())
    }

    /// Applies changes asked for on top of the program's `simulate` declaration (the command
    /// line's options), after checking them.
    pub fn apply(&mut self, changes: &SettingsChanges) -> Result<(), SettingsError> {
        for (option, value) in [
            ("duration", changes.duration),
            ("every", changes.output),
            ("tolerance", changes.tolerance),
            ("step", changes.step),
        ] {
            if value.is_some_and(|v| !positive(v)) {
                return Err(SettingsError::NotPositive { option });
            }
        }
        if let Some(Stabilisation::Baumgarte(rate)) = changes.stabilisation {
            if !positive(rate) {
                return Err(SettingsError::NotPositive {
                    option: "baumgarte-rate",
                });
            }
        }
        if changes.max_steps == Some(0) {
            return Err(SettingsError::NoSteps);
        }
        self.max_steps = changes.max_steps.unwrap_or(self.max_steps);
        self.stiffness_check &= !changes.no_stiffness_check;
        if let Some(integrator) = &changes.integrator {
            self.integrator = integrator.clone();
        }
        if let Some(stabilisation) = changes.stabilisation {
            self.stabilisation = stabilisation;
        }
        self.reactions |= changes.reactions;
        self.duration = changes.duration.unwrap_or(self.duration);
        self.output = changes.output.unwrap_or(self.output);
        self.step = changes.step.or(self.step);
        if let Some(t) = changes.tolerance {
            (self.rtol, self.atol) = (t, t);
        }
        self.check_outputs()
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            integrator: Integrator::DormandPrince,
            duration: 1.0,
            output: 0.01,
            step: None,
            max_step: f64::INFINITY,
            rtol: 1e-8,
            atol: 1e-10,
            stabilisation: Stabilisation::Projection,
            reactions: false,
            max_steps: DEFAULT_MAX_STEPS,
            stiffness_check: true,
        }
    }
}

pub(super) fn program_settings(
    mechanism: &Mechanism,
    model: &Model,
    defaults: &Settings,
) -> Result<Settings, Vec<Diagnostic>> {
    let mut settings = defaults.clone();
    let Some(scenario) = &mechanism.scenario else {
        return Ok(settings);
    };
    let mut errors = Vec::new();
    let mut number = |name: &str| -> Option<f64> {
        let (_, value, span) = scenario.setting(name)?;
        match constant(value, &model.unknowns).filter(|v| v.is_finite() && *v > 0.0) {
            Some(v) => Some(v),
            None => {
                errors.push(
                    Diagnostic::error("E0814", format!("`{name}` must be a positive number"))
                        .primary(*span, "here"),
                );
                None
            }
        }
    };
    if let Some(v) = number("duration") {
        settings.duration = v;
    }
    if let Some(v) = number("output") {
        settings.output = v;
    }
    if let Some(v) = number("step") {
        settings.step = Some(v);
    }
    if let Some(v) = number("max_step") {
        settings.max_step = v;
    }
    if let Some(v) = number("tolerance") {
        settings.rtol = v;
        settings.atol = v;
    }
    if let Some(v) = number("rtol") {
        settings.rtol = v;
    }
    if let Some(v) = number("atol") {
        settings.atol = v;
    }
    if let Some((name, span)) = &scenario.integrator {
        // The checker reports an unknown name first (E0420); none is taken for another here.
        match Integrator::from_name(name) {
            Ok(integrator) => settings.integrator = integrator,
            Err(unknown) => errors.push(
                Diagnostic::error("E0420", unknown.to_string()).primary(*span, "not an integrator"),
            ),
        }
    }
    if let (Err(error), Some(span)) = (settings.check_outputs(), scenario.span) {
        errors.push(
            Diagnostic::error("E0814", error.to_string()).primary(span, "in this `simulate`"),
        );
    }
    if errors.is_empty() {
        Ok(settings)
    } else {
        Err(errors)
    }
}
