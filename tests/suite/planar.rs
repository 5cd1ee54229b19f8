//! The planar form of planar mechanisms (`dynamics::planar`, `simulate --planar`): the
//! right-hand side in planar vectors and planar loop rows gives the spatial form's results to
//! round-off (the spatial form, the default, is the independent algorithm it is checked
//! against), on loops, trees with prismatic joints, efforts in the plane, planes normal to each
//! fixed axis, and states next to the singular configurations of loops; mechanisms that are not
//! planar keep the spatial form, with the reason.

use lsdc::prepare::{Integrator, Prepared};
use lsdc::simulate::run::run;
use lsdc::simulate::system::MechanicalSystem;

use crate::common::lsdc;
use crate::common::programs::{prepared, prepared_text};

/// Relative agreement asked of the two forms.
const AGREEMENT: f64 = 1e-12;

/// The step of the motion along which the two forms are compared: short enough that forward
/// Euler's steps stay bounded over 0.2 s on every case (the values, not only their
/// differences, would grow otherwise).
const STEP: f64 = 2e-3;

/// A planar tree: a cart on a track, an arm on the cart (its joint frame off the plane, along
/// the normal), a slider along the arm and a hand on the slider whose principal axes are tilted
/// out of the plane (products of inertia with the normal, which only the joints' reactions
/// feel); efforts in the plane that read the state: a force in the fixed basis, a damping
/// torque along the normal, a force written in the arm's basis.
const PRISMATIC_TREE: &str = "import joints ;
let cart = body mass = 2, iframe = 0, inertia = [0.1, 0.2, 0.3] end ;
let arm = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.01, 0.08, 0.08] end ;
let slider = body mass = 0.3, iframe = [0, 0.1, 0] ++ 1, inertia = [0.001, 0.002, 0.003] end ;
let hand = body mass = 0.5, iframe = [0.2, 0, 0.05] ++ (0.3 || [1, 0, 0]), inertia = [0.01, 0.02, 0.03] end ;
join earth and cart with prismatic([1, 0, 0]) as track ;
join [0, 0, 0.2] ++ 1 @ cart and arm with revolute([0, 0, 1]) as shoulder ;
join arm and slider with prismatic([1, 0, 0]) as slide ;
join [0.3, 0, 0] ++ (0.4 || [0, 0, 1]) @ slider and hand with revolute([0, 0, -1]) as wrist ;
apply force value = [0, -9.81 * cart.mass, 0], body = earth end on cart.iframe ;
apply force value = [0, -9.81 * arm.mass, 0], body = earth end on arm.iframe ;
apply force value = [0, -9.81 * slider.mass, 0], body = earth end on slider.iframe ;
apply force value = [0, -9.81 * hand.mass, 0], body = earth end on hand.iframe ;
apply force value = [-3 * track.q - 0.5 * track.q', 2 * sin(shoulder.q), 0], body = earth end on arm.iframe ;
apply torque value = [0, 0, -0.4 * wrist.q'], body = hand end on hand ;
apply force value = [-20 * slide.q, 0, 0], body = arm end on slider.iframe ;
initial track.q = 0.1, shoulder.q = 0.7, slide.q = 0.2, wrist.q = -0.5, shoulder.q' = 2, slide.q' = -1, wrist.q' = 3 ;
";

/// The planar twin of a prepared program: the same program, its run taking the planar form.
fn planar(mut prepared: Prepared) -> Prepared {
    prepared.take_planar().expect("planar");
    prepared
}

/// A system evaluating in the form its model has, its loops closed at the initial state.
fn started(prepared: &Prepared) -> (MechanicalSystem<'_>, Vec<f64>) {
    let model = &prepared.model;
    let (mut y, v) =
        (model.state_from_declared(&prepared.coordinates, &prepared.rates)).expect("initial state");
    y.extend_from_slice(&v);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.use_planar(prepared.planar_form());
    system.start_loops(&mut y).expect("starts");
    (system, y)
}

/// A planar mechanism's systems in both forms, and their rates at the last state compared.
struct Twins<'p> {
    planar: MechanicalSystem<'p>,
    spatial: MechanicalSystem<'p>,
    planar_rates: Vec<f64>,
    spatial_rates: Vec<f64>,
}

impl<'p> Twins<'p> {
    /// Both forms' systems started (their loops closed at the initial state), and the spatial
    /// one's initial state.
    fn started(planar: &'p Prepared, spatial: &'p Prepared) -> (Twins<'p>, Vec<f64>) {
        let (planar, _) = started(planar);
        let (spatial, y) = started(spatial);
        assert!(planar.uses_planar(), "the planar form is taken");
        assert!(!spatial.uses_planar());
        let (planar_rates, spatial_rates) = (vec![0.0; y.len()], vec![0.0; y.len()]);
        let twins = Twins {
            planar,
            spatial,
            planar_rates,
            spatial_rates,
        };
        (twins, y)
    }

    /// The difference of the two forms' right-hand sides at (t, y), relative to the largest
    /// rate.
    fn difference(&mut self, t: f64, y: &[f64]) -> f64 {
        (self.planar.derivative(t, y, &mut self.planar_rates)).expect("planar");
        (self.spatial.derivative(t, y, &mut self.spatial_rates)).expect("spatial");
        let scale = (self.spatial_rates.iter()).fold(0.0f64, |m, x| m.max(x.abs()));
        let difference = (self.planar_rates.iter().zip(&self.spatial_rates))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        difference / scale
    }
}

/// The largest difference of the two forms' right-hand sides over states along a motion (forward
/// Euler steps of 2 ms of the spatial form, kept on the loops), relative to the largest rate.
fn largest_difference(planar: &Prepared, spatial: &Prepared, steps: usize) -> f64 {
    let (mut twins, mut y) = Twins::started(planar, spatial);
    let mut largest = 0.0f64;
    for step in 0..steps {
        let t = STEP * step as f64;
        largest = largest.max(twins.difference(t, &y));
        y.iter_mut()
            .zip(&twins.spatial_rates)
            .for_each(|(y, rate)| *y += STEP * rate);
        twins.spatial.keep_closed(t, &mut y).expect("closes");
    }
    largest
}

fn assert_forms_agree(name: &str, planar: Prepared, spatial: Prepared) {
    assert!(planar.planar_form().is_some(), "{name}: planar");
    let difference = largest_difference(&planar, &spatial, 100);
    assert!(
        difference <= AGREEMENT,
        "{name}: the planar and spatial right-hand sides differ by {difference:e}"
    );
}

#[test]
fn planar_and_spatial_right_hand_sides_agree_on_loops() {
    let loops = [
        "four_bar",
        "slider_crank",
        "hard/four_bar_row_10",
        "hard/watt_six_bar",
    ];
    // Joint friction, a mimic coupling and stops: rows of the stack beyond the loops.
    let stacked = ["four_bar_friction", "four_bar_mimic", "limited_four_bar"];
    for name in loops.into_iter().chain(stacked) {
        let spatial = prepared(name, &[]);
        assert_forms_agree(name, planar(prepared(name, &[])), spatial);
    }
}

#[test]
fn planar_and_spatial_right_hand_sides_agree_on_trees() {
    // The double pendulum turns about x (its plane is normal to the fixed x axis); the meshed
    // gears' mimic coupling takes the tree through its mass matrix, the elliptic pendulum
    // hangs from a slider, the limited pendulum has stops.
    let trees = [
        "double_pendulum",
        "pendulum",
        "meshed_gears",
        "elliptic_pendulum",
    ];
    for name in trees.into_iter().chain(["limited_pendulum"]) {
        let spatial = prepared(name, &[]);
        assert_forms_agree(name, planar(prepared(name, &[])), spatial);
    }
    assert_forms_agree(
        "prismatic tree",
        planar(prepared_text(PRISMATIC_TREE)),
        prepared_text(PRISMATIC_TREE),
    );
}

#[test]
fn planar_and_spatial_right_hand_sides_agree_with_efforts_in_the_plane() {
    // A four-bar in the plane normal to y, a spring torque on its crank and a force on its
    // coupler, with joint friction (the slipping joints' forces act with the efforts).
    let replacements = [
        (
            "revolute([0, 0, 1]) as crank",
            "revolute([0, -1, 0]) as crank",
        ),
        (
            "revolute([0, 0, 1]) as coupler",
            "revolute([0, 1, 0]) as coupler",
        ),
        ("revolute([0, 0, 1]) as c ;", "revolute([0, 1, 0]) as c ;"),
        (
            "revolute([0, 0, 1]) as rocker",
            "revolute([0, 1, 0]) as rocker",
        ),
        (
            "let down = [0, -9.81, 0] ;",
            "let down = [0, 0, -9.81] ;
apply torque value = [0, -2 * crank.q - 0.3 * crank.q', 0], body = earth end on bar1 ;
apply force value = [1.5 * cos(rocker.q), 0, 0.5], body = bar2 end on coupler_point ;",
        ),
    ];
    let in_plane = planar(prepared("four_bar", &replacements));
    let twin = prepared("four_bar", &replacements);
    assert_forms_agree("four_bar in the plane normal to y", in_plane, twin);
    // A plane normal to none of the fixed axes: its rows mix the fixed axes' six.
    let tilted = [
        ("revolute([0, 0, 1])", "revolute([0, 0.6, 0.8])"),
        (
            "let down = [0, -9.81, 0] ;",
            "let down = [0, -9.81 * 0.8, 9.81 * 0.6] ;",
        ),
    ];
    let in_plane = planar(prepared("four_bar", &tilted));
    assert!(in_plane.planar_form().is_some_and(|p| p.rows.is_none()));
    assert_forms_agree("tilted four_bar", in_plane, prepared("four_bar", &tilted));
}

#[test]
fn planar_and_spatial_runs_agree() {
    // Whole runs: the same steps, the same outputs to round-off (RK4's fixed steps).
    for name in ["four_bar", "slider_crank", "hard/four_bar_row_2"] {
        let with_rk4 = |mut prepared: Prepared| {
            let settings = &mut prepared.settings;
            (settings.integrator, settings.step) = (Integrator::Rk4, Some(1e-3));
            (settings.duration, settings.output) = (0.5, 0.01);
            prepared
        };
        let in_plane = with_rk4(planar(prepared(name, &[])));
        let twin = with_rk4(prepared(name, &[]));
        let (planar_run, spatial_run) = (run(&in_plane, &mut |_| {}), run(&twin, &mut |_| {}));
        assert!(planar_run.report.planar && !spatial_run.report.planar);
        assert_eq!(planar_run.report.steps, spatial_run.report.steps, "{name}");
        let scale = (spatial_run.samples.iter().flat_map(|s| &s.coordinates))
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let difference = (planar_run.samples.iter().zip(&spatial_run.samples))
            .flat_map(|(p, s)| p.coordinates.iter().zip(&s.coordinates))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            difference <= AGREEMENT * scale,
            "{name}: runs differ by {difference:e} (scale {scale})"
        );
    }
}

/// Why the model of a program keeps the spatial form.
fn refusal(prepared: &Prepared) -> String {
    prepared.planar.clone().expect_err("not planar")
}

#[test]
fn mechanisms_that_are_not_planar_keep_the_spatial_form() {
    // A spatial loop.
    let bennett = prepared("hard/bennett", &[]);
    assert!(
        refusal(&bennett).contains("out of the plane"),
        "{}",
        refusal(&bennett)
    );
    // An effort with a component along the normal.
    let pushed = prepared(
        "four_bar",
        &[(
            "let down = [0, -9.81, 0] ;",
            "let down = [0, -9.81, 0] ;\napply force value = [0, 0, 0.1 * crank.q], body = earth end on bar2 ;",
        )],
    );
    assert!(
        refusal(&pushed).contains("not written in the plane"),
        "{}",
        refusal(&pushed)
    );
    // A tilted axis.
    let tilted = prepared_text(&PRISMATIC_TREE.replace(
        "revolute([0, 0, -1]) as wrist",
        "revolute([0, 0.01, -1]) as wrist",
    ));
    assert!(refusal(&tilted).contains("`wrist`"), "{}", refusal(&tilted));
    // A gravity field out of the plane.
    let tipped = prepared(
        "four_bar",
        &[("let down = [0, -9.81, 0] ;", "let down = [0, -9.81, 0.1] ;")],
    );
    assert!(refusal(&tipped).contains("gravity"), "{}", refusal(&tipped));
    // Each runs in the spatial form when the planar form is asked for, and says why.
    for mut prepared in [bennett, pushed] {
        let why = prepared.take_planar().expect_err("not planar");
        assert_eq!(why, refusal(&prepared));
        let (system, _) = started(&prepared);
        assert!(!system.uses_planar());
    }
}

#[test]
fn the_spatial_form_is_the_default_and_simulate_planar_takes_the_planar_form() {
    // Planar, and run in spatial form unless asked.
    let four_bar = prepared("four_bar", &[]);
    assert!(four_bar.planar.is_ok() && four_bar.planar_form().is_none());
    let (system, _) = started(&four_bar);
    assert!(!system.uses_planar());
    let asked = planar(prepared("four_bar", &[]));
    let (system, _) = started(&asked);
    assert!(system.uses_planar());
    let said = |args: &[&str]| {
        // The samples on standard output, the report on standard error.
        let (code, _, stderr) = lsdc(args);
        assert_eq!(code, 0, "{stderr}");
        let report: serde_json::Value = serde_json::from_str(&stderr).expect("a JSON report");
        report["planar"].clone()
    };
    let base = [
        "simulate",
        "examples/four_bar.lsd",
        "--report",
        "json",
        "--duration",
        "0.01",
    ];
    assert_eq!(said(&base), serde_json::json!(false));
    assert_eq!(
        said(&[&base[..], &["--planar"]].concat()),
        serde_json::json!(true)
    );
    // Asked of a spatial loop: the spatial form, and the warning says why.
    let bennett = [
        "simulate",
        "examples/hard/bennett.lsd",
        "--report",
        "json",
        "--duration",
        "0.01",
        "--planar",
    ];
    let (code, _, stderr) = lsdc(&bennett);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("W0906") && stderr.contains("out of the plane"),
        "{stderr}"
    );
    // The option of the spatial form is gone with its default.
    let (code, _, stderr) = lsdc(&[&base[..], &["--spatial"]].concat());
    assert_ne!(code, 0, "{stderr}");
}

#[test]
fn planar_and_spatial_right_hand_sides_agree_next_to_singular_configurations() {
    // The states of a run of a parallelogram through its flat configurations, every
    // millisecond over 1.5 s (RK4 at 1 ms), four flat configurations among them (and the one
    // near 0.139 s that the steps jumped across unseen before they were cut short of it,
    // `singular_passages.rs`): the two forms'
    // right-hand sides at those states, whose kept rows come within 3.2e-4 of dependent
    // (conditioning), where a difference in the rows is amplified most.
    let with_rk4 = |mut prepared: Prepared| {
        let settings = &mut prepared.settings;
        (settings.integrator, settings.step) = (Integrator::Rk4, Some(1e-3));
        (settings.duration, settings.output) = (1.5, 1e-3);
        prepared
    };
    let twin = with_rk4(prepared("hard/four_bar_row_1", &[]));
    let motion = run(&twin, &mut |_| {});
    let loops = motion.report.constraints.as_ref().expect("loops");
    let closest = loops.closest.as_ref().expect("a closest approach").ratio;
    assert!(
        closest < 5e-4 && loops.singular.len() >= 4,
        "{closest}, {:?}",
        loops.singular
    );
    let in_plane = planar(prepared("hard/four_bar_row_1", &[]));
    let (mut twins, _) = Twins::started(&in_plane, &twin);
    let mut largest = (0.0f64, 0.0);
    for sample in &motion.samples {
        let (mut y, v) = (twin.model)
            .state_from_declared(&sample.coordinates, &sample.rates)
            .expect("state");
        y.extend_from_slice(&v);
        let difference = twins.difference(sample.time, &y);
        if difference > largest.0 {
            largest = (difference, sample.time);
        }
    }
    assert!(largest.0 <= AGREEMENT, "{largest:?}");
}

/// `lsdc tree` asks only for kinematics, and builds no dynamics: the four-bar with inertias
/// that have no values (the dynamic model cannot be built, `prepare` says which value it
/// lacks) is still numbered, assembled, given its mobility and said planar; a spatial loop is
/// still said not planar, with the joint that leaves the plane.
#[test]
fn tree_decides_planarity_without_building_the_dynamics() {
    use lsdc::studies::analysis;
    let unknown_inertia = [(
        "let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;",
        "let bar(l) = body mass = ?s, iframe = [l / 2, 0, 0] ++ 1, inertia = [?s, ?s, ?s] end ;",
    )];
    let mechanism = crate::common::programs::mechanism("four_bar", &unknown_inertia);
    let missing = lsdc::prepare::prepare(&mechanism, &[], &Default::default()).err();
    assert!(
        missing.is_some_and(|d| d.iter().any(|d| d.message.contains("no value"))),
        "the dynamic model needs the inertias' values"
    );
    let report = analysis::tree(&mechanism).expect("tree");
    assert!(report.planar, "{:?}", report.not_planar);
    assert_eq!(report.mobility.expect("mobility").mobility, 1);
    let bennett = analysis::tree(&crate::common::programs::mechanism("hard/bennett", &[]));
    let why = bennett.expect("tree").not_planar.expect("not planar");
    assert!(why.contains("out of the plane"), "{why}");
}

/// The factor by blocks of three rows is chosen from the kept rows alone (every loop keeping
/// exactly three rows, contiguous in the kept order), whatever form made them.
#[test]
fn the_factor_by_threes_follows_the_kept_rows() {
    use lsdc::dynamics::loops::triples::kept_by_threes;
    // Two loops, three rows each (indices among 6 per loop), as a planar loop keeps them.
    assert!(kept_by_threes(&[0, 1, 5, 6, 7, 11], 2));
    assert!(kept_by_threes(&[6, 7, 11, 0, 1, 5], 2));
    // One loop keeping six rows, or two loops' rows mixed in one three: row by row.
    assert!(!kept_by_threes(&[0, 1, 2, 3, 4, 5], 1));
    assert!(!kept_by_threes(&[0, 1, 6, 2, 7, 8], 2));
    // A loop keeping two rows, or none kept at all.
    assert!(!kept_by_threes(&[0, 1, 6, 7, 8], 2));
    assert!(!kept_by_threes(&[], 0));
}
