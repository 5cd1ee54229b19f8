//! Fully driven subtrees run as kinematics (`dynamics::driven_subtrees`): their drives are no
//! rows of the constraint stack, the free part's accelerations come from hybrid dynamics and the
//! drives' efforts from the subtrees' inverse dynamics. Each case is run twice, with the
//! reduction and with the drives kept as rows (the full model, `Prepared::keep_drive_rows`):
//! the samples (coordinates, rates, energies, drives' efforts, outputs) agree to 1e-12 relative
//! at the same steps, and the report's model says what was run as kinematics. The oracle is the
//! rows' solve on the mass matrix, an algorithm the hybrid dynamics shares nothing with but the
//! kinematics.

use lsdc::api::{Program, SettingsChanges, Simulation};
use lsdc::load::LoadOptions;
use lsdc::prepare::{Integrator, Prepared};

use crate::common::programs::simulated;

/// A cart on a sprung slide carrying a three-joint arm whose joints all follow drives, the
/// elbow with its own spring and damper (a link effort on a driven joint), under gravity.
const CART_ARM: &str = r#"
import joints ;
import forces ;
import gravity ;

let rod(m, l) = body mass = m, iframe = [0, 0, l / 2] ++ 1, inertia = [m * l * l / 12, m * l * l / 12, 1e-3 * m] end ;
let sprung_slider(axis, k, c) = link(x) dof = x * axis, force = (-k * x - c * x') * axis end ;
let cart = body mass = 5, iframe = 0, inertia = [0.1, 0.2, 0.2] end ;
let column = rod(3, 0.4) and upper = rod(2, 0.5) and fore = rod(1, 0.4) ;
join earth and cart with sprung_slider([1, 0, 0], 40, 0.5) as slide ;
join [0, 0, 0.1] ++ 1 @ cart and column with revolute([0, 0, 1]) as yaw ;
join [0, 0, 0.4] ++ 1 @ column and upper with revolute([0, 1, 0]) as shoulder ;
join [0, 0, 0.5] ++ 1 @ upper and fore with revolute_spring_damper([0, 1, 0], 5, 0.2, 0.3) as elbow ;
apply weight(cart) on cart.iframe ;
apply weight(column) on column.iframe ;
apply weight(upper) on upper.iframe ;
apply weight(fore) on fore.iframe ;
drive yaw.q = 0.8 * sin(2 * time) ;
drive shoulder.q = 0.3 + 0.5 * sin(3 * time) ;
drive elbow.q = quintic(time, 0, 0.2, 1, 1.2) ;
initial slide.x = 0.05 ;
scene swing =
  output tip = position([0, 0, 0.4] ++ 1 @ fore) ;
  simulate duration = 1, output = 0.05, integrator = dopri5, tolerance = 1e-10 end ;
end ;
"#;

/// A robot on a fixed base whose two-joint wrist is driven, its arm free on spring-dampers:
/// a program without scenes (reduced as well).
const WRIST: &str = r#"
import joints ;
import forces ;
import gravity ;

let rod(m, l) = body mass = m, iframe = [0, 0, l / 2] ++ 1, inertia = [m * l * l / 12, m * l * l / 12, m * l * l / 24] end ;
let column = rod(6, 0.4) and upper = rod(3, 0.5) and fore = rod(2, 0.4) and hand = rod(0.8, 0.1) and tool = rod(0.5, 0.15) ;
join earth and column with revolute_spring_damper([0, 0, 1], 8, 1, 0.2) as yaw ;
join [0, 0, 0.4] ++ 1 @ column and upper with revolute_spring_damper([0, 1, 0], 200, 5, 0.4) as shoulder ;
join [0, 0, 0.5] ++ 1 @ upper and fore with revolute_spring_damper([0, 1, 0], 60, 2, 0.6) as elbow ;
join [0, 0, 0.4] ++ 1 @ fore and hand with revolute([0, 1, 0]) as pitch ;
join [0, 0, 0.1] ++ 1 @ hand and tool with revolute([0, 0, 1]) as roll ;
apply weight(column) on column.iframe ;
apply weight(upper) on upper.iframe ;
apply weight(fore) on fore.iframe ;
apply weight(hand) on hand.iframe ;
apply weight(tool) on tool.iframe ;
drive pitch.q = 0.4 * sin(5 * time) ;
drive roll.q = 3 * time + 0.2 * cos(4 * time) ;
"#;

/// A free-floating base (a quaternion joint) carrying a two-joint arm along drives, no
/// gravity: the base's motion answers the arm's.
const FLOATING: &str = r#"
import joints ;

let base = body mass = 20, iframe = 0, inertia = [1, 1.5, 2] end ;
let link_body(m, l) = body mass = m, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-2 * m, m * l * l / 12, m * l * l / 12] end ;
let first = link_body(2, 0.6) and second = link_body(1, 0.5) ;
join earth and base with free as drift ;
join [0.3, 0, 0] ++ 1 @ base and first with revolute([0, 0, 1]) as j1 ;
join [0.6, 0, 0] ++ 1 @ first and second with revolute([0, 1, 0]) as j2 ;
drive j1.q = 1.2 * sin(2 * time) ;
drive j2.q = 0.5 - 0.7 * cos(3 * time) ;
initial drift.b' = 0.1 ;
"#;

/// A planar chain of three rods about parallel axes, its last joint driven, no gravity: the
/// planar form applies to the whole chain, but the driven tip runs by hybrid dynamics.
const PLANAR_TIP: &str = r#"
import joints ;

let rod(m, l) = body mass = m, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-3 * m, m * l * l / 12, m * l * l / 12] end ;
let a = rod(2, 0.6) and b = rod(1, 0.5) and c = rod(0.5, 0.3) ;
join earth and a with revolute([0, 0, 1]) as j1 ;
join [0.6, 0, 0] ++ 1 @ a and b with revolute([0, 0, 1]) as j2 ;
join [0.5, 0, 0] ++ 1 @ b and c with revolute([0, 0, 1]) as j3 ;
drive j3.q = 0.5 * sin(3 * time) ;
initial j1.q' = 1 ;
"#;

fn program(text: &str) -> Program {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let program = Program::from_text("driven.lsd", text, None, &options);
    assert!(!program.has_errors(), "{}", program.render());
    program
}

fn prepared(text: &str, changes: &SettingsChanges) -> Prepared {
    program(text).prepare(&[], changes).expect("prepares")
}

/// RK4 at 2 ms over 0.5 s, outputs every 50 ms: the runs compared at the same steps.
fn rk4_half_second() -> SettingsChanges {
    SettingsChanges {
        integrator: Some(Integrator::Rk4),
        step: Some(2e-3),
        duration: Some(0.5),
        output: Some(0.05),
        ..Default::default()
    }
}

/// The run with the reduction and the run with the drives' rows.
fn both(text: &str, changes: &SettingsChanges) -> (Simulation, Simulation) {
    let reduced = prepared(text, changes);
    assert!(
        reduced.driven_subtrees().is_some(),
        "{:?}",
        reduced.driven_subtrees
    );
    let mut full = prepared(text, changes);
    full.keep_drive_rows();
    (simulated(&reduced), simulated(&full))
}

/// The largest difference of two series relative to their largest magnitude.
fn relative(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = (a.iter().chain(b))
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(1e-300);
    let worst = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    worst / scale
}

/// Every column of the samples agrees to `tolerance` relative, at the same steps; the worst
/// difference.
fn agree(reduced: &Simulation, full: &Simulation, tolerance: f64) -> f64 {
    assert_eq!(reduced.report.steps, full.report.steps, "the same steps");
    assert_eq!(reduced.report.rejected_steps, full.report.rejected_steps);
    assert_eq!(reduced.output_names, full.output_names);
    assert_eq!(reduced.samples.len(), full.samples.len());
    let mut worst = 0.0f64;
    let series = |s: &Simulation, pick: &dyn Fn(&lsdc::simulate::run::Sample) -> f64| {
        s.samples.iter().map(pick).collect::<Vec<f64>>()
    };
    let mut check = |name: String, pick: &dyn Fn(&lsdc::simulate::run::Sample) -> f64| {
        let difference = relative(&series(reduced, pick), &series(full, pick));
        assert!(difference <= tolerance, "{name}: {difference:e}");
        worst = worst.max(difference);
    };
    for (i, name) in reduced.coordinate_names.iter().enumerate() {
        check(name.clone(), &|s| s.coordinates[i]);
        check(format!("{name}'"), &|s| s.rates[i]);
    }
    for (i, name) in reduced.output_names.iter().enumerate() {
        check(name.clone(), &|s| s.outputs[i]);
    }
    check("kinetic_energy".into(), &|s| s.kinetic_energy);
    check("work".into(), &|s| s.work.unwrap_or(0.0));
    worst
}

#[test]
fn a_cart_carrying_a_driven_arm_runs_the_arm_as_kinematics_with_the_full_models_results() {
    let (reduced, full) = both(CART_ARM, &SettingsChanges::default());
    let worst = agree(&reduced, &full, 1e-12);
    eprintln!("cart and driven arm, dopri5: worst relative difference {worst:e}");
    let names = &reduced.output_names;
    assert_eq!(
        names[..3],
        [
            "yaw.drive_effort",
            "shoulder.drive_effort",
            "elbow.drive_effort"
        ]
    );
    // The efforts are not zero: the comparison weighs something.
    let shoulder = reduced.samples.iter().map(|s| s.outputs[1].abs());
    assert!(shoulder.fold(0.0, f64::max) > 1.0);
    let model = reduced.report.model.as_ref().expect("a scene's model");
    assert_eq!(model.driven_kinematics, 3);
    assert!(
        model
            .describe()
            .ends_with("; 3 driven bodies as kinematics"),
        "{}",
        model.describe()
    );
    let json = serde_json::to_value(model).expect("serialises");
    assert_eq!(json["driven_kinematics"], 3);
    let kept = full.report.model.as_ref().expect("a scene's model");
    assert_eq!(kept.driven_kinematics, 0);
    assert!(!kept.describe().contains("as kinematics"));
}

#[test]
fn a_robot_whose_wrist_is_driven_matches_its_full_model_at_fixed_steps() {
    let changes = rk4_half_second();
    let (reduced, full) = both(WRIST, &changes);
    let subtrees = prepared(WRIST, &changes);
    assert_eq!(subtrees.driven_subtrees().map(|s| s.bodies), Some(2));
    let worst = agree(&reduced, &full, 1e-12);
    eprintln!("robot with a driven wrist, rk4: worst relative difference {worst:e}");
}

#[test]
fn a_floating_base_answers_its_driven_arm_as_in_the_full_model() {
    let changes = SettingsChanges {
        duration: Some(0.5),
        output: Some(0.05),
        integrator: Some(Integrator::DormandPrince),
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let (reduced, full) = both(FLOATING, &changes);
    let worst = agree(&reduced, &full, 1e-12);
    eprintln!("floating base and driven arm, dopri5: worst relative difference {worst:e}");
}

#[test]
fn a_driven_joint_with_a_free_joint_below_or_in_a_loop_keeps_its_row() {
    // The wrist's pitch driven, its roll free: the pitch carries a free joint.
    let free_below = WRIST.replace("drive roll.q = 3 * time + 0.2 * cos(4 * time) ;", "");
    let kept = prepared(&free_below, &SettingsChanges::default());
    let why = kept.driven_subtrees.as_ref().expect_err("no reduction");
    assert!(why.contains("free joint below"), "{why}");
    let text = std::fs::read_to_string("examples/four_bar_driven.lsd").expect("readable");
    let dir = std::path::Path::new("examples");
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let looped = Program::from_text("four_bar_driven.lsd", &text, Some(dir), &options);
    let prepared = looped
        .prepare(&[], &SettingsChanges::default())
        .expect("prepares");
    let why = prepared.driven_subtrees.as_ref().expect_err("no reduction");
    assert!(why.contains("closed loops"), "{why}");
}

#[test]
fn a_planar_chain_whose_tip_is_driven_reports_the_form_its_run_took() {
    // Asked for the planar form, the reduced run takes hybrid dynamics (in spatial algebra):
    // its report says so, while the full model's rows run on the planar mass matrix.
    let changes = rk4_half_second();
    let mut reduced = prepared(PLANAR_TIP, &changes);
    reduced.take_planar().expect("a planar chain");
    let mut full = prepared(PLANAR_TIP, &changes);
    full.keep_drive_rows();
    full.take_planar().expect("a planar chain");
    let (reduced, full) = (simulated(&reduced), simulated(&full));
    assert!(!reduced.report.planar, "the hybrid run is spatial");
    assert!(full.report.planar, "the rows' run is planar");
    let worst = agree(&reduced, &full, 1e-12);
    eprintln!("planar chain with a driven tip, rk4: worst relative difference {worst:e}");
}
