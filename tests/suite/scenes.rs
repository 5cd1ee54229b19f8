//! Scenes (`scene NAME = ... end`): selection, locks, and the smallest model that serves a
//! scene. Each reduction is checked twice: the reduced scene's outputs equal the full model's
//! (the same declarations outside any scene: a program without scenes is never reduced) at the
//! same fixed steps, and the report's counts show that the reduction happened.

use lsdc::api::{Program, SettingsChanges, Simulation};
use lsdc::load::LoadOptions;
use lsdc::prepare::Integrator;

use lsdc::simulate::run::run;

use crate::common::programs::simulated;

const CELL: &str = "examples/robot_cell.lsd";

fn options(scene: Option<&str>) -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: scene.map(str::to_string),
    }
}

fn program(text: &str, scene: Option<&str>) -> Program {
    let dir = std::path::Path::new("examples");
    let program = Program::from_text("cell.lsd", text, Some(dir), &options(scene));
    assert!(!program.has_errors(), "{}", program.render());
    program
}

/// The cell's own declarations (its scenes are at its end) followed by `added`: the full
/// model of a scene whose declarations are `added`.
fn cell_without_scenes(added: &str) -> String {
    let text = std::fs::read_to_string(CELL).expect("the example is readable");
    let end = text
        .find("scene left_trajectory")
        .expect("the cell's first scene");
    format!("{}\n{added}\n", &text[..end])
}

/// A run with RK4 at a fixed step: the reduced and the full model take the same steps.
fn run_fixed(program: &Program, duration: f64) -> Simulation {
    let changes = SettingsChanges {
        integrator: Some(Integrator::Rk4),
        step: Some(1e-3),
        duration: Some(duration),
        output: Some(0.01),
        ..Default::default()
    };
    simulated(&program.prepare(&[], &changes).expect("the scene prepares"))
}

/// The column `name` (a coordinate or an output) of every sample.
fn column(simulation: &Simulation, name: &str) -> Vec<f64> {
    let coordinate = simulation.coordinate_names.iter().position(|n| n == name);
    let output = simulation.output_names.iter().position(|n| n == name);
    simulation
        .samples
        .iter()
        .map(|s| match (coordinate, output) {
            (Some(i), _) => s.coordinates[i],
            (None, Some(i)) => s.outputs[i],
            (None, None) => panic!("no column `{name}` in {:?}", simulation.output_names),
        })
        .collect()
}

/// The largest difference of two runs' columns relative to the column's largest magnitude.
fn relative_difference(reduced: &Simulation, full: &Simulation, name: &str) -> f64 {
    let (a, b) = (column(reduced, name), column(full, name));
    assert_eq!(a.len(), b.len(), "{name}: as many samples");
    let scale = (a.iter().chain(&b))
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    let worst = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    worst / scale
}

fn scene_model(program: &Program) -> lsdc::elab::scene_model::SceneModel {
    let mechanism = program.mechanism().expect("a mechanism");
    mechanism.scene.clone().expect("a scene's model")
}

#[test]
fn a_scene_reading_one_arm_leaves_out_the_other_arm_and_the_linkage() {
    let text = std::fs::read_to_string(CELL).expect("readable");
    let reduced = program(&text, Some("left_trajectory"));
    let model = scene_model(&reduced);
    assert_eq!((model.bodies, model.bodies_total), (3, 9));
    assert_eq!((model.loops, model.loops_total), (0, 1));
    let left_out: Vec<_> = model.left_out.iter().map(|p| p.bodies.clone()).collect();
    assert_eq!(
        left_out,
        [
            vec!["arm[2]:column", "arm[2]:upper", "arm[2]:fore"],
            vec!["crank_bar", "coupler_bar", "rocker_bar"]
        ]
    );
    assert!(model.describe().starts_with(
        "model of scene `left_trajectory`: 3 of 9 bodies, 0 of 1 loops; left out: arm[2]:column, arm[2]:upper and arm[2]:fore; crank_bar"
    ));
    let full = program(
        &cell_without_scenes("output tip = position(arm[1]:tip) ;"),
        None,
    );
    assert!(scene_model(&reduced).left_out.len() == 2 && full.mechanism().unwrap().scene.is_none());
    let (reduced, full) = (run_fixed(&reduced, 1.0), run_fixed(&full, 1.0));
    assert_eq!(reduced.coordinate_names.len(), 3);
    assert_eq!(full.coordinate_names.len(), 10);
    for name in [
        "tip.x",
        "tip.y",
        "tip.z",
        "arm[1]:yaw.q",
        "arm[1]:shoulder.q",
        "arm[1]:elbow.q",
    ] {
        let difference = relative_difference(&reduced, &full, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
    assert_eq!(reduced.report.model.as_ref().map(|m| m.bodies), Some(3));
}

#[test]
fn a_scene_reading_the_linkage_keeps_its_loop_and_matches_the_full_model() {
    let text = std::fs::read_to_string(CELL).expect("readable");
    let reduced = program(&text, Some("linkage_check"));
    let model = scene_model(&reduced);
    assert_eq!((model.bodies, model.loops), (3, 1));
    assert_eq!(model.left_out.len(), 2);
    let full = program(
        &cell_without_scenes(
            "output coupler_point = position([l2 / 2, 0, 0] ++ 1 @ coupler_bar) ;\noutput rocker_angle = rocker.q ;",
        ),
        None,
    );
    let (reduced, full) = (run_fixed(&reduced, 0.5), run_fixed(&full, 0.5));
    for name in [
        "coupler_point.x",
        "coupler_point.z",
        "rocker_angle",
        "coupler.q",
        "c.q",
    ] {
        let difference = relative_difference(&reduced, &full, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
}

#[test]
fn a_scene_without_outputs_models_everything() {
    let text = std::fs::read_to_string(CELL).expect("readable");
    let model = scene_model(&program(&text, Some("cell")));
    assert_eq!((model.bodies, model.bodies_total, model.loops), (9, 9, 1));
    assert!(model.left_out.is_empty());
}

#[test]
fn parts_coupled_by_an_effort_or_an_output_stay() {
    // A spring between the arms' tips couples them: only the linkage is left out.
    let spring = "scene tied =\n  apply spring(arm[1]:tip, arm[2]:tip, 50, 2) between arm[1]:tip and arm[2]:tip ;\n  output tip = position(arm[1]:tip) ;\nend ;";
    let model = scene_model(&program(&cell_without_scenes(spring), None));
    assert_eq!((model.bodies, model.loops), (6, 0));
    // An output that reads both arms keeps both.
    let both = "scene both =\n  output gap = distance(arm[1]:tip, arm[2]:tip) ;\nend ;";
    let model = scene_model(&program(&cell_without_scenes(both), None));
    assert_eq!((model.bodies, model.loops), (6, 0));
    // A law of one arm that reads the linkage's coordinate couples them.
    let law = "scene follows =\n  apply torque value = [0, 0, 0.1 * rocker.q], body = earth end on arm[1]:column ;\n  output yaw = arm[1]:yaw.q ;\nend ;";
    let model = scene_model(&program(&cell_without_scenes(law), None));
    assert_eq!((model.bodies, model.loops), (6, 1));
}

#[test]
fn the_first_scene_is_the_default_and_the_scene_replaces_the_programs_settings() {
    let text = "import joints ;\nlet rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and rod with revolute([1, 0, 0]) as swing ;\nsimulate duration = 1 end ;\nscene long =\n  simulate duration = 3 end ;\nend ;\nscene short =\n  initial swing.q = 0.5 ;\nend ;";
    let default = program(text, None);
    assert_eq!(default.scene(), Some("long"));
    assert_eq!(default.scene_names(), ["long", "short"]);
    let duration = |p: &Program| {
        p.mechanism()
            .unwrap()
            .scenario
            .as_ref()
            .unwrap()
            .setting("duration")
            .map(|s| lsdc::elab::value::constant(&s.1))
    };
    assert_eq!(duration(&default), Some(Some(3.0)));
    let short = program(text, Some("short"));
    assert_eq!(duration(&short), Some(Some(1.0)));
    assert_eq!(short.mechanism().unwrap().initial.len(), 1);
    assert!(default.mechanism().unwrap().initial.is_empty());
}

#[test]
fn a_lock_welds_the_joint_and_moves_as_a_drive_at_that_value() {
    let base = "import joints ;\nimport gravity ;\nlet a = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\nlet b = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and a with revolute([1, 0, 0]) as shoulder ;\njoin [0, 0, -1] ++ 1 @ a and b with revolute([1, 0, 0]) as elbow ;\napply weight(a) on a.iframe ;\napply weight(b) on b.iframe ;\ninitial shoulder.q = 0.3 ;\noutput tip = position([0, 0, -1] ++ 1 @ b) ;\n";
    let locked = program(
        &format!("{base}scene rigid =\n  lock elbow.q = 0.4 ;\nend ;"),
        None,
    );
    let driven = program(&format!("{base}drive elbow.q = 0.4 ;"), None);
    let mechanism = locked.mechanism().unwrap();
    assert!(mechanism.drives.is_empty());
    assert!(mechanism
        .link(mechanism.joins[1].link)
        .coordinates
        .is_empty());
    let model = scene_model(&locked);
    assert_eq!(model.welded, 1);
    assert!(
        model.describe().ends_with("; 1 locked coordinate welded"),
        "{}",
        model.describe()
    );
    let (locked, driven) = (run_fixed(&locked, 1.0), run_fixed(&driven, 1.0));
    assert_eq!(locked.coordinate_names, ["shoulder.q"]);
    for name in ["shoulder.q", "tip.x", "tip.y", "tip.z"] {
        let difference = relative_difference(&locked, &driven, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
    // A lock on a coordinate that is also driven is not welded: E0710 says so.
    let both = program(
        &format!("{base}drive elbow.q = time ;\nscene rigid =\n  lock elbow.q = 0.4 ;\nend ;"),
        None,
    );
    assert_eq!(scene_model(&both).welded, 0);
    let refused = both
        .prepare(&[], &Default::default())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        refused.contains("E0710") || refused.contains("locked and driven"),
        "{refused}"
    );
}

#[test]
fn an_unknown_scene_is_an_error_that_names_the_scenes() {
    let text = std::fs::read_to_string(CELL).expect("readable");
    let program = Program::from_text(
        "cell.lsd",
        &text,
        Some(std::path::Path::new("examples")),
        &options(Some("left_trajectry")),
    );
    let rendered = program.render();
    assert!(
        rendered.contains("E0714") && rendered.contains("did you mean `left_trajectory`?"),
        "{rendered}"
    );
}

/// A run of a file's scene with the given changes.
fn run_file(path: &str, scene: Option<&str>, changes: &SettingsChanges) -> Simulation {
    let program = Program::from_file(path, &options(scene)).expect("readable");
    assert!(!program.has_errors(), "{}", program.render());
    simulated(&program.prepare(&[], changes).expect("prepares"))
}

#[test]
fn the_delta_passive_scene_is_the_delta_legs_example() {
    let changes = SettingsChanges {
        duration: Some(0.5),
        output: Some(0.05),
        ..Default::default()
    };
    let scene = run_file("examples/delta_scenes.lsd", Some("passive"), &changes);
    let example = run_file("examples/delta_legs.lsd", None, &changes);
    for name in ["leg[1]:A.q", "leg[2]:A.q", "leg[3]:A.q", "leg[1]:Pp.b"] {
        let difference = relative_difference(&scene, &example, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
}

#[test]
fn the_delta_controlled_scene_tracks_with_the_closed_form_error() {
    // e'' + 40 e' + 400 e = 0 from e(0) = -0.02, e'(0) = 0: e = -0.02 (1 + 20 t) exp(-20 t).
    let run = run_file(
        "examples/delta_scenes.lsd",
        Some("controlled"),
        &Default::default(),
    );
    let worst = (run.samples.iter())
        .map(|s| {
            let exact = -0.02 * (1.0 + 20.0 * s.time) * (-20.0 * s.time).exp();
            s.outputs
                .iter()
                .map(|e| (e - exact).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-8, "{worst:e}");
}

#[test]
fn the_delta_kinematics_scene_follows_its_drives() {
    let run = run_file(
        "examples/delta_scenes.lsd",
        Some("kinematics"),
        &Default::default(),
    );
    let start = 40f64.to_radians();
    let last = run.samples.last().expect("samples");
    assert!((last.time - 1.0).abs() < 1e-12);
    let arm = |name: &str| column(&run, name).last().copied().expect("a value");
    for (name, end) in [
        ("leg[1]:A.q", start + 0.3),
        ("leg[2]:A.q", start - 0.1),
        ("leg[3]:A.q", start + 0.2),
    ] {
        assert!((arm(name) - end).abs() < 1e-12, "{name}: {}", arm(name));
    }
}

#[test]
fn efforts_identically_zero_are_left_out_and_change_nothing() {
    let base = "import joints ;\nimport gravity ;\nlet a = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and a with revolute([1, 0, 0]) as swing ;\napply weight(a) on a.iframe ;\napply force value = [0, 0, 0], body = a end on a.iframe ;\napply torque value = 0 * [1, 2, 3] end on a ;\ninitial swing.q = 1 ;\noutput angle = swing.q ;\n";
    let reduced = program(&format!("{base}scene swinging =\nend ;"), None);
    let model = scene_model(&reduced);
    assert_eq!(model.zero_efforts, 2);
    assert!(
        model
            .describe()
            .ends_with("left out: 2 applied efforts identically zero"),
        "{}",
        model.describe()
    );
    assert_eq!(reduced.mechanism().unwrap().applications.len(), 1);
    let full = program(base, None);
    assert_eq!(full.mechanism().unwrap().applications.len(), 3);
    let (reduced, full) = (run_fixed(&reduced, 1.0), run_fixed(&full, 1.0));
    for name in ["angle", "swing.q"] {
        let difference = relative_difference(&reduced, &full, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
}

/// Two links under gravity, a push and a damping torque declared in a group (`package`): the
/// efforts a scene's `apply only` and `apply without` choose among.
const CHOSEN_BASE: &str = "import joints ;\nimport gravity ;\nlet a = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\nlet b = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and a with revolute([1, 0, 0]) as shoulder ;\njoin [0, 0, -1] ++ 1 @ a and b with revolute([1, 0, 0]) as elbow ;\ninitial shoulder.q = 0.3 ;\noutput tip = position([0, 0, -1] ++ 1 @ b) ;\n";
const WEIGHTS: &str = "apply weight(a) on a.iframe ;\napply weight(b) on b.iframe ;\n";
const PUSH: &str =
    "let push = force value = [0, 0.5, 0.2 * elbow.q] end ;\napply push on b.iframe ;\n";
const DAMPING: &str = "package damping =\n  apply torque value = [-0.2 * shoulder.q', 0, 0] end on a ;\n  apply torque value = [-0.1 * elbow.q', 0, 0] end between a and b ;\nend ;\n";

#[test]
fn a_scene_applies_the_efforts_it_chooses_by_name_definition_or_group() {
    let all = format!("{CHOSEN_BASE}{WEIGHTS}{PUSH}{DAMPING}");
    // Each choice, the `apply` declarations it leaves out, and the program that declares only
    // the efforts chosen.
    for (choice, left_out, declared) in [
        ("apply without push, damping ;", 3, WEIGHTS.to_string()),
        ("apply only weight ;", 3, WEIGHTS.to_string()),
        ("apply only push, damping ;", 2, format!("{PUSH}{DAMPING}")),
        (
            "apply only weight, damping ;\n  apply without damping ;",
            3,
            WEIGHTS.to_string(),
        ),
        ("apply without weight ;", 2, format!("{PUSH}{DAMPING}")),
    ] {
        let chosen = program(&format!("{all}scene chosen =\n  {choice}\nend ;"), None);
        let model = scene_model(&chosen);
        assert_eq!(model.efforts_not_chosen, left_out, "{choice}");
        let plural = if left_out == 1 { "" } else { "s" };
        let text = model.describe();
        let said = format!("left out: {left_out} applied effort{plural} (not chosen by the scene)");
        assert!(text.ends_with(&said), "{text}");
        let full = program(&format!("{CHOSEN_BASE}{declared}"), None);
        assert_eq!(
            chosen.mechanism().unwrap().applications.len(),
            full.mechanism().unwrap().applications.len(),
            "{choice}"
        );
        let (chosen_run, full_run) = (run_fixed(&chosen, 1.0), run_fixed(&full, 1.0));
        let json = serde_json::to_value(&chosen_run.report).expect("the report as JSON");
        assert_eq!(json["model"]["efforts_not_chosen"], left_out, "{json}");
        for name in ["tip.x", "tip.y", "tip.z", "shoulder.q", "elbow.q"] {
            let difference = relative_difference(&chosen_run, &full_run, name);
            assert!(difference <= 1e-12, "{choice} {name}: {difference:e}");
        }
    }
}

#[test]
fn a_scene_chooses_the_efforts_of_an_instance_or_of_an_array() {
    let text = std::fs::read_to_string(CELL).expect("readable");
    // Each arm applies three weights, the linkage three.
    for (choice, left_out) in [
        ("apply only arm[1] ;", 6),
        ("apply without arm ;", 6),
        ("apply without arm[2] ;", 3),
        ("apply only arm[2]:weight ;", 6),
        ("apply without arm:weight ;", 6),
    ] {
        let scene = format!("{text}\nscene chosen =\n  {choice}\nend ;");
        let model = scene_model(&program(&scene, Some("chosen")));
        assert_eq!(model.efforts_not_chosen, left_out, "{choice}");
    }
}

/// A double pendulum carrying at its first link a massless subtree: a turntable `s` and a slide
/// `t` on it, of zero mass and inertia.
const MASSLESS_BASE: &str = "import joints ;\nimport gravity ;\nlet a = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\nlet b = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and a with revolute([1, 0, 0]) as shoulder ;\njoin [0, 0, -1] ++ 1 @ a and b with revolute([1, 0, 0]) as elbow ;\napply weight(a) on a.iframe ;\napply weight(b) on b.iframe ;\ninitial shoulder.q = 0.5 ;\noutput tip = position([0, 0, -1] ++ 1 @ b) ;\n";
const MASSLESS_TREE: &str = "let s = body mass = 0, iframe = 0, inertia = [0, 0, 0] end ;\nlet t = body mass = 0, iframe = 0, inertia = [0, 0, 0] end ;\njoin [0, 0, -1] ++ 1 @ a and s with revolute([0, 0, 1]) as spin ;\njoin [0, 0, 0.2] ++ 1 @ s and t with prismatic([1, 0, 0]) as slide ;\napply weight(s) on s.iframe ;\n";

#[test]
fn a_massless_subtree_nothing_reads_is_left_out_and_changes_nothing() {
    // Free, the subtree's coordinates carry no inertia: the full model's mass matrix is
    // singular. Driven, the full model runs the subtree as kinematics (its drives need no
    // inertia then) and moves as the program written without it. The scene runs as that
    // program.
    let drives = "drive spin.q = 2 * time ;\ndrive slide.q = 0.1 * sin(3 * time) ;\n";
    let without = run_fixed(&program(MASSLESS_BASE, None), 1.0);
    for added in ["", drives] {
        let text = format!("{MASSLESS_BASE}{MASSLESS_TREE}{added}");
        let full = program(&text, None);
        if added.is_empty() {
            let failure = (full.prepare(&[], &Default::default()).ok())
                .and_then(|prepared| run(&prepared, &mut |_| {}).report.failure)
                .map(|f| f.message);
            let failure = failure.unwrap_or_default();
            assert!(
                failure.starts_with("the mass matrix is singular"),
                "{failure}"
            );
        } else {
            let full_run = run_fixed(&full, 1.0);
            for name in ["tip.x", "tip.y", "tip.z", "shoulder.q", "elbow.q"] {
                let difference = relative_difference(&full_run, &without, name);
                assert!(difference <= 1e-12, "{name}: {difference:e}");
            }
        }
        let reduced = program(&format!("{text}scene arm =\nend ;"), None);
        let model = scene_model(&reduced);
        assert_eq!((model.bodies, model.bodies_total), (2, 4));
        let said = model.describe();
        assert!(
            said.contains("left out: s and t (massless, nothing the scene reads moves with them)"),
            "{said}"
        );
        let reduced_run = run_fixed(&reduced, 1.0);
        assert_eq!(reduced_run.coordinate_names, ["shoulder.q", "elbow.q"]);
        for name in ["tip.x", "tip.y", "tip.z", "shoulder.q", "elbow.q"] {
            let difference = relative_difference(&reduced_run, &without, name);
            assert!(difference <= 1e-12, "{name}: {difference:e}");
        }
        let json = serde_json::to_value(&reduced_run.report).expect("the report as JSON");
        assert_eq!(json["model"]["bodies"], 2, "{json}");
        assert_eq!(json["model"]["left_out"][0]["bodies"][1], "t", "{json}");
    }
}

#[test]
fn a_massless_subtree_read_loaded_or_closed_stays() {
    let drives = "drive spin.q = 2 * time ;\ndrive slide.q = 0.1 * sin(3 * time) ;\n";
    let text = format!("{MASSLESS_BASE}{MASSLESS_TREE}{drives}");
    for (scene, bodies) in [
        // The turntable's angle is read: the slide on it is not, and goes.
        ("output turn = spin.q ;", 3),
        ("output where = position(t) ;", 4),
        ("output rate = slide.q' ;", 4),
        ("apply force value = [0, 0, 1] end on t ;", 4),
        // The slide only is read: the turntable carries it and stays.
        ("output along = slide.q ;", 4),
        // A loop through the turntable keeps it; the slide on it goes.
        ("join s and b with spherical as closing ;", 3),
        ("output far = elbow.q ;", 2),
    ] {
        let reduced = program(&format!("{text}scene arm =\n  {scene}\nend ;"), None);
        assert_eq!(scene_model(&reduced).bodies, bodies, "{scene}");
    }
}

/// The largest difference of two runs' rates of `name` relative to their largest magnitude.
fn relative_rate_difference(reduced: &Simulation, full: &Simulation, name: &str) -> f64 {
    let rates = |run: &Simulation| -> Vec<f64> {
        let i = (run.coordinate_names.iter().position(|n| n == name)).expect("a coordinate");
        run.samples.iter().map(|s| s.rates[i]).collect()
    };
    let (a, b) = (rates(reduced), rates(full));
    assert_eq!(a.len(), b.len(), "{name}': as many samples");
    let scale = (a.iter().chain(&b)).fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = (a.iter().zip(&b)).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    worst / scale
}

#[test]
fn a_scene_that_asks_only_for_kinematics_builds_no_dynamics_and_matches_the_full_model() {
    // The linkage's crank is driven and its loop fixes the three other coordinates; the scene
    // reads a point and a coordinate: its run assembles the linkage at each output.
    let text = std::fs::read_to_string(CELL).expect("readable");
    let scene = program(&text, Some("linkage_check"));
    let changes = SettingsChanges {
        integrator: Some(Integrator::Rk4),
        step: Some(1e-3),
        duration: Some(0.5),
        output: Some(0.01),
        ..Default::default()
    };
    let prepared = scene.prepare_run(&[], &changes).expect("prepares");
    assert!(prepared.kinematics_only && !prepared.model.dynamics);
    let model = prepared.scene.clone().expect("a scene's model");
    assert!(model.kinematics_only && (model.bodies, model.loops) == (3, 1));
    assert!(
        model.describe().ends_with(
            "kinematics only (every coordinate driven or closed by the loops): no dynamics built"
        ),
        "{}",
        model.describe()
    );
    let kinematic = simulated(&prepared);
    assert_eq!(kinematic.report.integrator, "assembly");
    assert_eq!(kinematic.samples.len(), 51);
    assert!(kinematic
        .output_names
        .iter()
        .all(|n| !n.ends_with("drive_effort")));
    assert!(lsdc::output::csv::to_csv(&kinematic).contains(",,1.9"));
    // `lsdc simulate` of the scene asked for its reactions, or of the same declarations
    // outside any scene, integrates the dynamics.
    let reactions = SettingsChanges {
        reactions: true,
        ..changes.clone()
    };
    let with_reactions = scene.prepare_run(&[], &reactions).expect("prepares");
    assert!(!with_reactions.kinematics_only && with_reactions.model.dynamics);
    let full = program(
        &cell_without_scenes(
            "output coupler_point = position([l2 / 2, 0, 0] ++ 1 @ coupler_bar) ;\noutput rocker_angle = rocker.q ;",
        ),
        None,
    );
    let full = full.prepare_run(&[], &changes).expect("prepares");
    assert!(!full.kinematics_only && full.model.dynamics);
    let full = simulated(&full);
    assert_eq!(full.report.integrator, "rk4");
    for name in [
        "coupler_point.x",
        "coupler_point.z",
        "rocker_angle",
        "crank.q",
        "coupler.q",
        "c.q",
    ] {
        let difference = relative_difference(&kinematic, &full, name);
        assert!(difference <= 1e-12, "{name}: {difference:e}");
    }
    for name in ["crank.q", "coupler.q", "c.q", "rocker.q"] {
        let difference = relative_rate_difference(&kinematic, &full, name);
        assert!(difference <= 1e-12, "{name}': {difference:e}");
    }
}

#[test]
fn the_delta_kinematics_scene_keeps_its_dynamics_for_its_spinning_rods() {
    // Each rod turns freely about its axis between its two ball joints: the drives do not
    // determine that motion, the dynamics do.
    let program = Program::from_file("examples/delta_scenes.lsd", &options(Some("kinematics")))
        .expect("readable");
    let prepared = program
        .prepare_run(&[], &Default::default())
        .expect("prepares");
    assert!(!prepared.kinematics_only && prepared.model.dynamics);
    assert!(!prepared.scene.expect("a scene").kinematics_only);
}
