//! The cost of a sensitivity run against the plain run of the same program
//! (`cargo bench --bench sensitivity`): for each case, the thread CPU time of `lsdc simulate`'s
//! run (`api::run`) and of `lsdc sensitivity`'s augmented run (the state and m sensitivities
//! under one error control), at the program's tolerance, in 7 interleaved rounds (each round
//! times a batch of the run, then a batch of the study, so that the machine's load falls on
//! both alike), best and median, their ratio, and the steps and right-hand-side evaluations of each. Prints one line per case:
//! `NAME m run_ms sensitivity_ms ratio run_steps sensitivity_steps run_evaluations
//! sensitivity_evaluations` (best times; the medians after them).

mod common;
use common::interleaved;

use lsdc::driver::compile_text;
use lsdc::elab::Mechanism;
use lsdc::prepare::settings::SettingsChanges;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::run::run;
use lsdc::studies::sensitivity::sensitivities;

/// A case: its name, the program's text, its parameters.
struct Case {
    name: &'static str,
    text: String,
    parameters: &'static [&'static str],
}

fn example(name: &str, replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(format!("examples/{name}.lsd")).expect("example");
    for (from, to) in replacements {
        text = text.replace(from, to);
    }
    text
}

fn mechanism(case: &Case) -> Mechanism {
    let folder = std::path::Path::new("examples/control");
    let compilation = compile_text(case.name, &case.text, Some(folder), &Default::default());
    compilation.mechanism.expect("elaborates")
}

fn main() {
    let pendulum = example(
        "pendulum",
        &[(
            "let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1,",
            "let L = ?s ; given L = 0.5 ; let rod = body mass = 1.2, iframe = [0, 0, -L] ++ 1,",
        )],
    );
    let flywheel = example(
        "control/pi_flywheel",
        &[("let k_p = 1 ;", "let k_p = ?s ; given k_p = 1 ;")],
    );
    let cases = [
        Case {
            name: "pendulum",
            text: pendulum.clone(),
            parameters: &["swing.q"],
        },
        Case {
            name: "pendulum",
            text: pendulum,
            parameters: &["L", "swing.q", "swing.q'"],
        },
        Case {
            name: "double_pendulum",
            text: example("double_pendulum", &[]),
            parameters: &["shoulder.q", "elbow.q'"],
        },
        Case {
            name: "pi_flywheel",
            text: flywheel,
            parameters: &["k_p", "spin.q'"],
        },
    ];
    let changes = SettingsChanges {
        duration: Some(2.0),
        ..Default::default()
    };
    for case in &cases {
        let mechanism = mechanism(case);
        let mut prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
        prepared.settings.apply(&changes).expect("settings");
        let names: Vec<String> = case.parameters.iter().map(|s| s.to_string()).collect();
        let plain = run(&prepared, &mut |_| {});
        let study = sensitivities(&mechanism, &[], &changes, &names).expect("computes");
        let [run_time, study_time] = interleaved(
            [
                &mut || {
                    std::hint::black_box(run(&prepared, &mut |_| {}));
                },
                &mut || {
                    let study = sensitivities(&mechanism, &[], &changes, &names);
                    std::hint::black_box(study.expect("computes"));
                },
            ],
            0.02,
            7,
        );
        println!(
            "{} {} {:.3} {:.3} {:.1} {} {} {} {}   (medians {:.3} {:.3} {:.1})",
            case.name,
            names.len(),
            run_time.0 * 1e3,
            study_time.0 * 1e3,
            study_time.0 / run_time.0,
            plain.report.steps,
            study.report.steps,
            plain.report.function_evaluations,
            study.report.function_evaluations,
            run_time.1 * 1e3,
            study_time.1 * 1e3,
            study_time.1 / run_time.1,
        );
    }
}
