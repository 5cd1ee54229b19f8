//! The integrators a run can use, by name: one registry that the checker (`simulate
//! integrator = ...`), the settings, the command line (`--integrator`, its help listing) and the
//! test manifests read, and from which a run's refusals say what an integrator does not handle
//! and which ones do. The methods themselves are in `integrate`; what each name runs is in
//! `simulate::run`.

use std::fmt;

use crate::diag::suggest::did_you_mean;

/// An integrator of the equations of motion, as `simulate` and `--integrator` name it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Integrator {
    Rk4,
    DormandPrince,
    Dop853,
    Implicit,
    Symplectic,
}

/// What a mechanism may have that an integrator may not handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// `rolling` and `sliding` joins.
    Contacts,
    /// Links' `lower` and `upper` bounds, with impacts.
    Stops,
    GearedRotors,
    Mimics,
    /// Joints' dry and viscous friction.
    Friction,
    /// Coordinates imposed as laws of time (`drive`).
    Drives,
    /// The program's states (`state(x0)` and `rate`).
    States,
    /// The program's sampled states (`sample(period, x0)` and `update`).
    Sampled,
    /// Efforts along coordinates whose laws may read the model (`actuate`).
    Actuators,
}

impl Feature {
    /// How a refusal names it.
    pub fn description(self) -> &'static str {
        match self {
            Feature::Stops => "stops (links' `lower` and `upper`)",
            Feature::Contacts => "contacts (`rolling`, `sliding`)",
            Feature::GearedRotors => "geared rotors",
            Feature::Mimics => "mimic joints",
            Feature::Friction => "joint friction",
            Feature::Drives => "drives (`drive`)",
            Feature::States => "states (`state` and `rate`)",
            Feature::Sampled => "sampled states (`sample` and `update`)",
            Feature::Actuators => "actuators (`actuate`)",
        }
    }
}

/// One integrator of the registry.
#[derive(Debug)]
pub struct IntegratorEntry {
    pub integrator: Integrator,
    /// Its name in programs, on the command line and in test manifests.
    pub name: &'static str,
    /// One line for the command line's help and the documentation.
    pub description: &'static str,
    /// A fixed step (`step`) rather than steps chosen by the tolerances.
    pub fixed_step: bool,
    /// The features of a mechanism it refuses to run.
    pub unsupported: &'static [Feature],
}

/// Every integrator, the default (`dopri5`) second, in the order the documentation lists them.
/// All of them run closed loops; native code (`simulate --compiled`) serves every one but
/// `symplectic`, whose steps evaluate the model themselves.
pub const INTEGRATORS: &[IntegratorEntry] = &[
    IntegratorEntry {
        integrator: Integrator::Rk4,
        name: "rk4",
        description: "classic Runge–Kutta of order 4, fixed step",
        fixed_step: true,
        unsupported: &[],
    },
    IntegratorEntry {
        integrator: Integrator::DormandPrince,
        name: "dopri5",
        description: "Dormand–Prince 5(4), adaptive (the default)",
        fixed_step: false,
        unsupported: &[],
    },
    IntegratorEntry {
        integrator: Integrator::Dop853,
        name: "dop853",
        description: "Dormand–Prince 8(5,3), adaptive, for tight tolerances",
        fixed_step: false,
        unsupported: &[],
    },
    IntegratorEntry {
        integrator: Integrator::Implicit,
        name: "implicit",
        description: "Dormand–Prince, and Radau IIA where the motion is stiff, adaptive",
        fixed_step: false,
        unsupported: &[],
    },
    IntegratorEntry {
        integrator: Integrator::Symplectic,
        name: "symplectic",
        description: "variational midpoint integrator for long conservative runs, fixed step",
        fixed_step: true,
        unsupported: &[
            Feature::Contacts,
            Feature::Stops,
            Feature::GearedRotors,
            Feature::Mimics,
            Feature::Friction,
            Feature::Drives,
            Feature::States,
            Feature::Sampled,
            Feature::Actuators,
        ],
    },
];

impl Integrator {
    /// The integrator of that name, or why there is none (naming the known ones).
    pub fn from_name(name: &str) -> Result<Integrator, UnknownIntegrator> {
        INTEGRATORS
            .iter()
            .find(|entry| entry.name == name)
            .map(|entry| entry.integrator.clone())
            .ok_or_else(|| UnknownIntegrator(name.to_string()))
    }

    pub fn entry(&self) -> &'static IntegratorEntry {
        INTEGRATORS
            .iter()
            .find(|entry| entry.integrator == *self)
            .expect("every integrator is in the registry")
    }

    pub fn name(&self) -> &'static str {
        self.entry().name
    }

    /// Whether it takes a fixed step rather than tolerances.
    pub fn fixed_step(&self) -> bool {
        self.entry().fixed_step
    }

    /// Why it cannot run a mechanism that has the features `present`, or `None` if it can: the
    /// features it does not handle, and the integrators that handle them all.
    pub fn refusal(&self, present: &[Feature]) -> Option<String> {
        let entry = self.entry();
        let lacking: Vec<&str> = (present.iter())
            .filter(|f| entry.unsupported.contains(f))
            .map(|f| f.description())
            .collect();
        if lacking.is_empty() {
            return None;
        }
        let able: Vec<String> = (INTEGRATORS.iter())
            .filter(|other| present.iter().all(|f| !other.unsupported.contains(f)))
            .map(|other| format!("`{}`", other.name))
            .collect();
        Some(format!(
            "the {} integrator does not handle {}: use {}",
            entry.name,
            listed(&lacking, "nor"),
            listed(&able, "or")
        ))
    }
}

/// The registry's names, in order.
pub fn names() -> impl Iterator<Item = &'static str> {
    INTEGRATORS.iter().map(|entry| entry.name)
}

/// "a", "a and b", "a, b and c" with `last` for the last joint.
fn listed<S: AsRef<str>>(items: &[S], last: &str) -> String {
    match items {
        [] => String::new(),
        [one] => one.as_ref().to_string(),
        [rest @ .., final_item] => {
            let rest: Vec<&str> = rest.iter().map(|s| s.as_ref()).collect();
            format!("{} {last} {}", rest.join(", "), final_item.as_ref())
        }
    }
}

/// A name that is not in the registry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownIntegrator(pub String);

impl UnknownIntegrator {
    /// The known name it is likely a misspelling of.
    pub fn suggestion(&self) -> Option<&'static str> {
        did_you_mean(&self.0, names())
    }
}

impl fmt::Display for UnknownIntegrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown integrator `{}`", self.0)?;
        if let Some(name) = self.suggestion() {
            write!(f, ": did you mean `{name}`?")?;
        }
        let known: Vec<&str> = names().collect();
        write!(f, " (the integrators are: {})", known.join(", "))
    }
}

impl std::error::Error for UnknownIntegrator {}
