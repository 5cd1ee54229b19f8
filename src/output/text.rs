//! Text renderings of the reports, as the command line prints them.

use crate::elab::Summary;
use crate::studies::analysis::{AssemblyReport, LinkReport, TreeReport};

pub fn summary(file: &std::path::Path, s: &Summary) -> String {
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    let mut out = format!("{}: ok\n", file.display());
    out += &format!("  bodies    {}", s.bodies);
    if !s.body_names.is_empty() {
        out += &format!(" ({})", s.body_names.join(", "));
    }
    out += &format!("\n  links     {}\n  joins     {}\n", s.links, s.joins);
    out += &format!(
        "  applied   {}, {}\n",
        plural(s.applied_forces, "force"),
        plural(s.applied_torques, "torque")
    );
    out += &format!(
        "  unknowns  {} (?s), {} (?v), {} (?f)\n",
        plural(s.unknown_scalars, "scalar"),
        plural(s.unknown_vectors, "vector"),
        plural(s.unknown_functions, "function")
    );
    out
}

fn joint_text(link: &LinkReport) -> String {
    match &link.joint {
        Some(j) => format!("{:?}, {} dof", j.kind, j.dof).to_lowercase(),
        None => "not analysed".to_string(),
    }
}

pub fn tree(report: &TreeReport) -> String {
    let name_of = |n: usize| {
        if n == 0 {
            "earth".to_string()
        } else {
            report.bodies[n - 1].name.clone()
        }
    };
    let mut out = match &report.model {
        Some(model) => format!("{}\n", model.describe()),
        None => String::new(),
    };
    out += "bodies (breadth-first from earth)\n";
    for body in &report.bodies {
        out += &format!(
            "  {:>3}  {:<20} parent {:<20} link {:>3}  {} ({})\n",
            body.number,
            body.name,
            name_of(body.parent),
            body.link.number,
            body.link.join,
            joint_text(&body.link)
        );
    }
    if report.complementary.is_empty() {
        out += "complementary links: none\n";
    } else {
        out += "complementary links\n";
        for link in &report.complementary {
            out += &format!(
                "  {:>3}  {:<20} {} – {} ({}, constraint {})\n",
                link.number,
                link.join,
                name_of(link.first_body),
                name_of(link.second_body),
                joint_text(link),
                link.joint
                    .as_ref()
                    .map_or("?".to_string(), |j| j.constraint.to_string())
            );
        }
    }
    match (&report.mobility, &report.mobility_unavailable) {
        (Some(m), _) => {
            out += &format!(
                "{} {} = tree dof {} - rank {} ({} constraint rows, {} redundant; rank tolerance {:e})\n",
                if m.mobility == m.first_order_mobility { "mobility" } else { "first-order mobility" },
                m.first_order_mobility,
                m.tree_dof,
                m.rank,
                m.constraint_rows,
                m.redundant,
                m.tolerance
            );
            if m.mobility != m.first_order_mobility {
                out += &format!(
                    "mobility {}: the closed configurations nearby form a {}-dimensional set; {} constraint{} only at second order\n",
                    m.mobility,
                    m.mobility,
                    m.first_order_mobility.abs_diff(m.mobility),
                    if m.first_order_mobility.abs_diff(m.mobility) == 1 { " acts" } else { "s act" }
                );
            }
            if m.singular {
                out += &format!(
                    "singular configuration: the rank is {} here and {} at other closed configurations\n",
                    m.rank, m.generic_rank
                );
            }
            for (body, count) in &m.internal {
                out += &format!(
                    "internal mobility: {} can move alone ({count} way{})\n",
                    name_of(*body),
                    if *count == 1 { "" } else { "s" }
                );
            }
        }
        (None, Some(reason)) => out += &format!("mobility not computed: {reason}\n"),
        (None, None) => {}
    }
    if let Some(c) = &report.contacts {
        out += &contact_text(c, report.mobility.as_ref().map_or(0, |m| m.tree_dof));
    }
    out
}

/// The degrees of freedom left by contacts: in position (the normal rows are holonomic) and
/// in velocity (the rolling rows are not).
fn contact_text(c: &crate::kinematics::contacts::ContactMobility, tree_dof: usize) -> String {
    let tree = match c.couplings {
        0 => format!("tree dof {tree_dof}"),
        n => format!("tree dof {tree_dof} - {n} mimic couplings"),
    };
    format!(
        "contacts {}: position dof {} = {tree} - {} holonomic rows; velocity dof {} = {tree} - {} independent rows ({} non-holonomic)\n",
        c.contacts,
        c.position_dof,
        c.holonomic_rank,
        c.velocity_dof,
        c.velocity_rank,
        c.velocity_rank - c.holonomic_rank
    )
}

pub fn assembly(report: &AssemblyReport) -> String {
    let mut out = String::new();
    for c in &report.coordinates {
        let held = if c.fixed { "  (fixed)" } else { "" };
        let moved = match report.moved.iter().find(|m| m.name == c.name) {
            Some(m) => format!("  (moved from {})", m.given),
            None => String::new(),
        };
        out += &format!("{:<24} {:>22.15e}{held}{moved}\n", c.name, c.value);
    }
    out += &format!(
        "assembled in {} iterations, largest residual {:.1e}\n",
        report.iterations, report.residual
    );
    out
}

/// One impact on a stop: when, which, the rate and kinetic energy before and after.
fn impact_line(impact: &crate::dynamics::stops::Impact) -> String {
    let side = match impact.side {
        crate::dynamics::stops::Side::Lower => "lower",
        crate::dynamics::stops::Side::Upper => "upper",
    };
    format!(
        "impact at t = {:.12}: `{}` on its {side} stop {} (e = {}), rate {:.9e} -> {:.9e}, kinetic energy {:.9e} -> {:.9e}\n",
        impact.time,
        impact.coordinate,
        impact.bound,
        impact.restitution,
        impact.rate_before,
        impact.rate_after,
        impact.kinetic_before,
        impact.kinetic_after
    )
}

/// The run report of a simulation, for people.
pub fn run_report(report: &crate::simulate::run::Report) -> String {
    let cpu = report
        .cpu_seconds
        .map_or("unknown".to_string(), |s| format!("{s:.3} s"));
    let mut out = format!(
        "{}: {} steps ({} rejected), {} function evaluations to simulate {} s; CPU time {cpu}, wall time {:.3} s\n",
        report.integrator,
        report.steps,
        report.rejected_steps,
        report.function_evaluations,
        report.duration,
        report.wall_seconds,
    );
    if let Some(model) = &report.model {
        out += &format!("{}\n", model.describe());
    }
    if report.planar {
        out += "planar: the recursions in planar vectors (3 per body), 3 rows per loop\n";
    }
    if let (Some(stiff), Some(switches)) = (report.stiff_steps, report.method_switches) {
        out += &format!(
            "stiff steps (implicit): {stiff} of {}, {switches} changes of method\n",
            report.steps
        );
    }
    if let Some(drift) = report.energy_drift {
        out += &format!("energy drift (relative): {drift:.3e}\n");
    }
    if let Some([kinetic, potential, work]) = report.final_energies {
        out += &format!("energy at the end: kinetic {kinetic:.6e}, potential {potential:.6e}, work of non-conservative efforts {work:.6e}\n");
    }
    if let Some(balance) = report.energy_balance {
        out += &format!("energy balance (kinetic + potential - work, relative): {balance:.3e}\n");
    }
    if let Some(drift) = report.momentum_drift {
        out += &format!(
            "momentum drift: linear {:.3e}, angular {:.3e}\n",
            drift.linear, drift.angular
        );
    }
    if let Some(c) = &report.constraints {
        out += &constraint_report(c);
    }
    for impact in &report.impacts {
        out += &impact_line(impact);
    }
    if let Some(sampling) = &report.sampling {
        out += &sampling_line(sampling);
    }
    for switch in &report.friction_switches {
        out += &format!(
            "friction at t = {:.12}: `{}` {} at {:.9e}\n",
            switch.time,
            switch.coordinate,
            switch.phase.describe(),
            switch.position
        );
    }
    if let Some(e) = &report.step_error {
        out += &format!(
            "largest local error estimate of a step: {:.1e} of the tolerances (rtol {:e}, atol {:e}), at t = {}\n",
            e.largest, e.rtol, e.atol, e.time
        );
    }
    if let Some(s) = &report.stiffness {
        out += &format!(
            "stiffness: at t = {}, steps of {:.1e} s held by stability (fastest mode {:.1e} /s, stable step {:.1e} s){}\n",
            s.time,
            s.step,
            s.rate,
            s.stable_step,
            s.element
                .as_ref()
                .map_or(String::new(), |e| format!(", made fast by {e}"))
        );
    }
    if let Some(failure) = &report.failure {
        out += &format!(
            "the run FAILED at t = {}: {}\n",
            failure.time, failure.message
        );
    }
    if let Some(stop) = &report.interrupted {
        out += &format!(
            "the run was INTERRUPTED at t = {} ({}): the outputs end there\n",
            stop.time,
            signal_name(stop.signal)
        );
    }
    out
}

/// How a run's report names the signal that interrupted it.
pub fn signal_name(signal: usize) -> String {
    match signal as i32 {
        libc::SIGINT => "SIGINT".to_string(),
        libc::SIGTERM => "SIGTERM".to_string(),
        other => format!("signal {other}"),
    }
}

fn constraint_report(c: &crate::simulate::constraints::ConstraintReport) -> String {
    let mut out = format!(
        "loops: {} constraint rows, rank {} at the start; stabilisation: {}\n",
        c.rows, c.rank, c.stabilisation
    );
    if !c.redundant.is_empty() {
        out += &format!(
            "  {} redundant (implied by the others): {}\n",
            c.redundant.len(),
            c.redundant.join(", ")
        );
    }
    out += &format!(
        "  largest residuals: position {:.3e}, velocity {:.3e} (before projection: {:.3e}, {:.3e})\n",
        c.position_residual, c.velocity_residual, c.position_residual_before_projection, c.velocity_residual_before_projection
    );
    for passage in &c.singular {
        let end = passage
            .end
            .map_or("the end of the run".to_string(), |t| format!("t = {t}"));
        out += &format!(
            "  near a singular configuration from t = {} to {}: the loop closed by `{}` loses a constraint direction (conditioning down to {:.1e}); the run went on\n",
            passage.start, end, passage.loop_name, passage.smallest_ratio
        );
    }
    if let Some(closest) = &c.closest {
        out += &format!(
            "  closest to a singular configuration at t = {}: conditioning {:.1e}, loop `{}`\n",
            closest.time, closest.ratio, closest.loop_name
        );
    }
    out
}

/// Holding efforts, one coordinate per line.
pub fn holding(h: &crate::studies::statics::Holding) -> String {
    let width = h.efforts.iter().map(|e| e.name.len()).max().unwrap_or(0);
    let mut out =
        String::from("efforts that hold the mechanism at rest (along each coordinate):\n");
    for e in &h.efforts {
        out += &format!("  {:width$}  {:.6e}\n", e.name, e.effort);
    }
    if h.unbalanced > 1e-9 {
        out += &format!("these actuators cannot hold it: {:.3e} of generalised force is left unbalanced on a motion they do not drive\n", h.unbalanced);
    }
    out
}

/// A work-precision table (`lsdc precision`) as a Markdown table, with the reference and the
/// recommendation: readable in a terminal, and pasted as it is into a document.
pub fn precision(table: &crate::studies::precision::Table) -> String {
    use crate::studies::precision::ReferenceSource;
    let reference = match &table.reference {
        ReferenceSource::Computed {
            integrator,
            tolerance,
            self_difference,
        } => format!(
            "{integrator} at tolerance {tolerance:e} (differs from a run at ten times that by {self_difference:.1e} in positions)"
        ),
        ReferenceSource::File { path } => format!("`{path}`"),
    };
    let mut out = format!(
        "{} s, outputs every {} s; reference: {reference}\n\n",
        table.duration, table.output_interval
    );
    // The outputs' column only for a program that declares outputs the reference has.
    let outputs = table
        .measurements
        .iter()
        .any(|m| m.errors.outputs.is_some());
    let (output_head, output_rule) = match outputs {
        true => (" output error |", "---|"),
        false => ("", ""),
    };
    out += &format!("| method | setting | position error | velocity error |{output_head} closure | energy drift | steps | rejected | evaluations | CPU min (ms) | CPU median (ms) | outcome |\n");
    out += &format!("|---|---|---|---|{output_rule}---|---|---|---|---|---|---|---|\n");
    let optional = |value: Option<f64>| value.map_or("–".to_string(), |v| format!("{v:.1e}"));
    for m in &table.measurements {
        let output_cell = match outputs {
            true => format!(" {} |", optional(m.errors.outputs)),
            false => String::new(),
        };
        out += &format!(
            "| {} | {} | {:.1e} | {:.1e} |{output_cell} {} | {} | {} | {} | {} | {:.3} | {:.3} | {} |\n",
            m.integrator,
            m.setting,
            m.errors.position,
            m.errors.velocity,
            optional(m.closure_residual),
            optional(m.energy_drift),
            m.steps,
            m.rejected_steps,
            m.function_evaluations,
            m.cpu_seconds_min * 1e3,
            m.cpu_seconds_median * 1e3,
            m.failure.as_deref().unwrap_or("ok"),
        );
    }
    if let Some(recommendation) = &table.recommendation {
        out += &format!("\nRecommended {}\n", recommendation.message);
    }
    out
}

/// The sampling instants of a run: how many, of which states at which periods, the first and
/// the last (the JSON report lists each with the values it set).
fn sampling_line(sampling: &crate::simulate::sampling::SamplingReport) -> String {
    let states: Vec<String> = (sampling.states.iter().zip(&sampling.periods))
        .map(|(name, period)| format!("`{name}` every {period} s"))
        .collect();
    let instants = &sampling.instants;
    let span = match (instants.first(), instants.last()) {
        (Some(first), Some(last)) => format!(", from t = {} to t = {}", first.time, last.time),
        _ => String::new(),
    };
    format!(
        "sampling: {} instant{} ({}){span}\n",
        instants.len(),
        if instants.len() == 1 { "" } else { "s" },
        states.join(", ")
    )
}
