//! The report of a run: the integrator's work, the energy and momentum the outputs saw, the
//! loops' findings, the events, why it stopped early if it did, and the warnings it gives.

use serde::Serialize;

use super::branch;
use super::constraints::ConstraintReport;
use super::sample::{MomentumDrift, Sample};
use super::sampling::SamplingReport;
use super::stiffness::{self, StiffnessReport};
use super::summary::Summary;
use super::system::MechanicalSystem;
use crate::diag::Diagnostic;
use crate::dynamics::friction::Switch;
use crate::dynamics::stops::Impact;
use crate::integrate::{Failure, IntegrationError, Stats};
use crate::prepare::{Integrator, Prepared};

#[derive(Clone, Debug, Serialize)]
pub struct RunFailure {
    pub time: f64,
    pub message: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub integrator: String,
    /// Whether the right-hand side took the model's planar form (`dynamics::planar`).
    pub planar: bool,
    pub duration: f64,
    pub steps: usize,
    pub rejected_steps: usize,
    pub function_evaluations: usize,
    /// With the implicit integrator: the accepted steps its Rosenbrock method took (the others
    /// are Dormand–Prince's, where the motion is not stiff), and how often it changed method.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiff_steps: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method_switches: Option<usize>,
    /// The CPU time of the run (integration and sampling, on the thread that ran it), when the
    /// thread's CPU clock can be read; and the wall-clock time it took, longer when the machine
    /// gave time to other work.
    pub cpu_seconds: Option<f64>,
    pub wall_seconds: f64,
    /// Largest |E(t) − E(0)| over the outputs, relative to the larger of |E(0)| and the largest
    /// kinetic energy, when the system is conservative.
    pub energy_drift: Option<f64>,
    /// For a mechanism with non-conservative efforts: the largest change of kinetic + potential
    /// − work since the start, over the largest of those energies (the energy balance).
    pub energy_balance: Option<f64>,
    /// Kinetic energy, potential energy (of the conservative efforts) and work of the others at
    /// the end of the run, when the work is integrated.
    pub final_energies: Option<[f64; 3]>,
    /// Largest change of a component of the total momentum, when nothing outside acts on the
    /// mechanism (its root joints are free and no effort is applied).
    pub momentum_drift: Option<MomentumDrift>,
    /// The loops: redundancy, residuals, singular configurations (mechanisms with loops).
    pub constraints: Option<ConstraintReport>,
    /// A fixed-step method's largest local error estimate over its steps (RK4, symplectic).
    pub step_error: Option<StepErrorReport>,
    /// The impacts on the stops (links' `lower` and `upper`), in time order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub impacts: Vec<Impact>,
    /// The joints' friction switching between slipping and sticking, in time order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub friction_switches: Vec<Switch>,
    /// The sampling instants of the program's sampled states (`sample`), in time order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<SamplingReport>,
    /// Where an explicit integrator's steps were found held by its stability region (W0901).
    pub stiffness: Option<StiffnessReport>,
    pub failure: Option<RunFailure>,
    /// The scene run and what its model holds: bodies and loops kept, parts left out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<crate::elab::scene_model::SceneModel>,
    /// When the run was stopped from outside (`RunOptions::interrupt`): not a failure, but the
    /// outputs end there.
    pub interrupted: Option<Interruption>,
}

/// When a run was stopped from outside, and the value the interrupt was set to (the signal's
/// number for `lsdc simulate`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Interruption {
    pub time: f64,
    pub signal: usize,
}

/// Why an integration stopped, in a run's words.
pub(super) fn failure_message(failure: &Failure, max_steps: usize) -> String {
    match failure {
        Failure::TooManySteps => format!(
            "the run reached its limit of {max_steps} steps (rejected ones included); raise it with `--max-steps`"
        ),
        other => other.to_string(),
    }
}

/// The largest local error estimate of a fixed-step run, in the norm of the tolerances (at most
/// 1 meets them), the time at the end of that step, and the tolerances it was measured against.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StepErrorReport {
    pub largest: f64,
    pub time: f64,
    pub rtol: f64,
    pub atol: f64,
}

impl StepErrorReport {
    /// Whether the steps were too long for the tolerances (a non-finite estimate is kept as
    /// infinite, `StepError::keep_largest`).
    pub fn exceeds_tolerances(&self) -> bool {
        self.largest > 1.0
    }
}

/// The warning for an explicit run whose steps were held by stability (W0901).
pub fn stiffness_warning(report: &Report) -> Option<Diagnostic> {
    stiffness::warning(report.stiffness.as_ref()?, &report.integrator)
}

/// The warning for a fixed-step run whose steps were too long for its tolerances (W0902): its
/// results may be far from the motion, and nothing else would say so.
pub fn step_error_warning(report: &Report) -> Option<Diagnostic> {
    let error = report
        .step_error
        .filter(StepErrorReport::exceeds_tolerances)?;
    let message = format!(
        "the steps of `{}` are too long for the tolerances: a step's local error estimate reaches {:.1e} times them (rtol {:e}, atol {:e}) at t = {}",
        report.integrator, error.largest, error.rtol, error.atol, error.time
    );
    Some(
        Diagnostic::warning("W0902", message)
            .note(match report.integrator.as_str() {
                "symplectic" => "its energy stays bounded, but its positions and phase are only as accurate as its step: the outputs may be far from the motion",
                _ => "the outputs may be far from the motion; the estimate bounds the error a step adds, and errors grow along the run",
            })
            .help("shorten the step (`--step`), or let `dopri5` choose it to the tolerances (`--integrator dopri5`)"),
    )
}

/// The warning for outputs inside a singular passage that the run ended in (W0903): they come
/// from the motion with rows set aside, only projected, and may be off the branch.
pub fn passage_output_warning(report: &Report) -> Option<Diagnostic> {
    let times = &report.constraints.as_ref()?.outputs_off_branch;
    let (first, last) = (times.first()?, times.last()?);
    let message = format!(
        "{} output{} from t = {first} to t = {last} fell inside a singular passage that the run ended in: {} not be interpolated between states on the branch, and may be off it",
        times.len(),
        if times.len() > 1 { "s" } else { "" },
        if times.len() > 1 { "they could" } else { "it could" },
    );
    Some(
        Diagnostic::warning("W0903", message)
            .note("inside a passage the rows losing their independence are set aside; outputs there are interpolated between the states before and after it, which a run that ends inside it does not reach")
            .help("end the run (`duration`) or the outputs away from the singular configuration"),
    )
}

/// Where a failing run was heading: the coordinate moving fastest at the last output.
pub(super) fn fastest_coordinate(names: &[String], last: Option<&Sample>) -> String {
    let Some(last) = last else {
        return String::new();
    };
    let fastest = last.rates.iter().enumerate().max_by(|a, b| {
        a.1.abs()
            .total_cmp(&b.1.abs())
            .then(a.1.is_nan().cmp(&b.1.is_nan()))
    });
    match fastest {
        Some((i, rate)) if i < names.len() && *rate != 0.0 => {
            format!(
                " (at t = {}, the fastest coordinate was `{}`, moving at {rate:.3e})",
                last.time, names[i]
            )
        }
        _ => String::new(),
    }
}

impl Report {
    /// The report of a run of `duration` that took no step and found nothing yet: what a run
    /// that failed before its first step reports, and the start of the report of a run without
    /// an integrator (a kinematic scene's assembly at each output).
    pub fn empty(integrator: &str, duration: f64) -> Report {
        Report {
            integrator: integrator.to_string(),
            planar: false,
            duration,
            steps: 0,
            rejected_steps: 0,
            function_evaluations: 0,
            stiff_steps: None,
            method_switches: None,
            cpu_seconds: Some(0.0),
            wall_seconds: 0.0,
            energy_drift: None,
            energy_balance: None,
            final_energies: None,
            momentum_drift: None,
            constraints: None,
            step_error: None,
            stiffness: None,
            impacts: Vec::new(),
            friction_switches: Vec::new(),
            sampling: None,
            failure: None,
            model: None,
            interrupted: None,
        }
    }

    /// The warnings the run found, in this order: steps held by stability (W0901), fixed steps
    /// too long for their tolerances (W0902), outputs inside a singular passage (W0903).
    pub fn warnings(&self) -> Vec<Diagnostic> {
        let found = [
            stiffness_warning(self),
            step_error_warning(self),
            passage_output_warning(self),
        ];
        found.into_iter().flatten().collect()
    }
}

/// How an integration ended, with what the outputs saw of it.
pub(super) struct Ended<'s> {
    pub(super) result: Result<(Vec<f64>, Stats), IntegrationError>,
    pub(super) summary: &'s Summary,
    /// The outputs inside a passage the run ended in (`Sampler::unsettled`).
    pub(super) outputs_off_branch: Vec<f64>,
    pub(super) cpu_seconds: Option<f64>,
    pub(super) wall_seconds: f64,
    /// The sampling instants passed, with a program's sampled states.
    pub(super) sampling: Option<SamplingReport>,
}

/// The report of an ended run: the integrator's work, the energy and momentum the outputs saw,
/// the loops' findings, the events, and why it stopped early if it did.
pub(super) fn report(
    prepared: &Prepared,
    system: &mut MechanicalSystem<'_>,
    ended: Ended<'_>,
) -> Report {
    let model = &prepared.model;
    let settings = &prepared.settings;
    let summary = ended.summary;
    let (stats, stopped) = match ended.result {
        Ok((_, stats)) => (stats, None),
        Err(e) => (*e.stats, Some((e.time, e.failure))),
    };
    let interrupted = match stopped {
        Some((time, Failure::Interrupted(signal))) => Some(Interruption { time, signal }),
        _ => None,
    };
    let failure = stopped
        .filter(|(_, failure)| !matches!(failure, Failure::Interrupted(_)))
        .map(|(time, failure)| RunFailure {
            time,
            message: format!(
                "{}{}",
                failure_message(&failure, settings.max_steps),
                fastest_coordinate(&prepared.coordinate_names, summary.last())
            ),
        });
    let constraints = model.has_loops().then(|| {
        let mut report = system.scratch.loops.report(&system.state.loops);
        report.outputs_off_branch = ended.outputs_off_branch;
        report
    });
    let left_branch = constraints
        .as_ref()
        .filter(|c| !c.singular.is_empty())
        .and_then(|c| branch::left_branch(summary.branch_outputs(), &c.singular))
        .map(|left| RunFailure {
            time: left.time,
            message: left.message,
        });
    let failure = match (failure, left_branch) {
        (Some(stopped), Some(left)) if left.time < stopped.time => Some(left),
        (None, left) => left,
        (stopped, _) => stopped,
    };
    Report {
        integrator: settings.integrator.name().to_string(),
        planar: system.uses_planar(),
        duration: settings.duration,
        steps: stats.steps,
        rejected_steps: stats.rejected,
        function_evaluations: stats.rhs_evaluations,
        stiff_steps: (settings.integrator == Integrator::Implicit).then_some(stats.stiff_steps),
        method_switches: (settings.integrator == Integrator::Implicit)
            .then_some(stats.method_switches),
        cpu_seconds: ended.cpu_seconds,
        wall_seconds: ended.wall_seconds,
        energy_drift: summary.energy_drift(),
        energy_balance: summary.energy_balance(),
        final_energies: summary.final_energies(),
        momentum_drift: summary.momentum_drift(),
        constraints,
        step_error: stats.largest_step_error.map(|e| StepErrorReport {
            largest: e.norm,
            time: e.time,
            rtol: settings.rtol,
            atol: settings.atol,
        }),
        stiffness: stats
            .stability_bound
            .as_ref()
            .and_then(|bound| stiffness::describe(prepared, bound)),
        impacts: std::mem::take(&mut system.state.impacts),
        friction_switches: std::mem::take(&mut system.state.switches),
        sampling: ended.sampling,
        failure,
        model: prepared.scene.clone(),
        interrupted,
    }
}
