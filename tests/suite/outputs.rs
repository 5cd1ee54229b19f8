//! Named outputs (`output name = value;`) against independent oracles: a pendulum's tip from its
//! angle in closed form, an energy output against the run's own energies, the frames of
//! `--output-frame` (outputs of the same tape) against the frames' states that the kinematic
//! model computes (another forward kinematics than the run's), a distance output against the
//! frames' positions, outputs in arrays of packages named by instance, and `lsdc test` and
//! `lsdc precision` reading outputs.

use crate::common::lsdc;
use crate::common::programs::{example_text, simulated};

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::Simulation;

fn prepared_text(text: &str) -> Result<Prepared, Vec<String>> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text(
        "program.lsd",
        text,
        Some(std::path::Path::new("examples")),
        &options,
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).map_err(|d| {
        d.iter()
            .map(|d| format!("{}: {}", d.code, d.message))
            .collect()
    })
}

fn output(simulation: &Simulation, name: &str) -> usize {
    (simulation.output_names.iter())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no output {name} in {:?}", simulation.output_names))
}

/// The pendulum of `examples/pendulum.lsd` (a revolute about x, the rod along −z, l = 1 to its
/// tip) with outputs of its tip.
fn pendulum_with(outputs: &str) -> Simulation {
    let text = example_text("pendulum", &[]) + "let tip = [0, 0, -1] ++ 1 @ rod ;\n" + outputs;
    simulated(&prepared_text(&text).expect("prepares"))
}

#[test]
fn a_pendulum_tip_is_at_its_closed_form_position_and_velocity() {
    let simulation = pendulum_with(
        "output tip = position(tip) ; output v = velocity(tip) ; output angle = swing.q ;",
    );
    let (p, v, angle) = (
        output(&simulation, "tip.x"),
        output(&simulation, "v.x"),
        output(&simulation, "angle"),
    );
    assert_eq!(simulation.samples.len(), 101);
    for sample in &simulation.samples {
        let (q, rate) = (sample.coordinates[0], sample.rates[0]);
        let o = &sample.outputs;
        // A turn q about x takes −z to (0, sin q, −cos q).
        let expected = [0.0, q.sin(), -q.cos(), 0.0, rate * q.cos(), rate * q.sin()];
        let actual = [o[p], o[p + 1], o[p + 2], o[v], o[v + 1], o[v + 2]];
        for (a, e) in actual.iter().zip(expected) {
            assert!(
                (a - e).abs() < 1e-14,
                "t = {}: {actual:?} ≠ {expected:?}",
                sample.time
            );
        }
        assert_eq!(o[angle], q);
    }
}

#[test]
fn an_energy_output_is_the_runs_energy() {
    // The rod: mass 1.2, centre 0.5 below the axis, inertia 0.1 about x at its centre.
    let simulation = pendulum_with(
        "output e = 0.5 * (0.1 + 1.2 * 0.5 ^ 2) * swing.q' ^ 2 + 9.81 * 1.2 * dot(position(rod.iframe), [0, 0, 1]) ;",
    );
    let e = output(&simulation, "e");
    for sample in &simulation.samples {
        let run = sample.kinetic_energy + sample.potential_energy.expect("conservative");
        assert!(
            (sample.outputs[e] - run).abs() < 1e-12,
            "t = {}",
            sample.time
        );
    }
}

#[test]
fn a_frame_output_has_the_columns_and_values_of_output_frame() {
    let program = std::env::temp_dir().join(format!("lsdc-outputs-{}.lsd", std::process::id()));
    let text = example_text("four_bar", &[("duration = 10", "duration = 1")])
        + "output coupler = coupler_point ;\noutput gap = distance(bar1, coupler_point) ;\n";
    std::fs::write(&program, text).expect("written");
    let path = program.to_str().expect("a path");
    let library = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let (code, csv, stderr) = lsdc(&[
        "simulate",
        path,
        "-L",
        library,
        "--output-frame",
        "coupler_point",
        "--output-frame",
        "bar1",
    ]);
    std::fs::remove_file(&program).ok();
    assert_eq!(code, 0, "{stderr}");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let mut rows = 0;
    for line in lines.filter(|l| !l.starts_with('#')) {
        let row: Vec<f64> = line
            .split(',')
            .map(|c| c.parse().expect("a number"))
            .collect();
        for part in lsdc::kinematics::frames::STATE_COMPONENTS {
            let (ours, theirs) = (
                row[column(&format!("coupler.{part}"))],
                row[column(&format!("coupler_point.{part}"))],
            );
            assert!((ours - theirs).abs() < 1e-12, "{part}: {ours} ≠ {theirs}");
        }
        let difference: f64 = ["x", "y", "z"]
            .iter()
            .map(|a| row[column(&format!("coupler_point.{a}"))] - row[column(&format!("bar1.{a}"))])
            .map(|d| d * d)
            .sum::<f64>()
            .sqrt();
        assert!((row[column("gap")] - difference).abs() < 1e-12);
        rows += 1;
    }
    assert_eq!(rows, 21);
}

#[test]
fn frames_asked_by_name_are_the_states_the_kinematic_model_computes() {
    use lsdc::api::{run, Program, SettingsChanges};
    use lsdc::kinematics::frames::{self, STATE_COMPONENTS};
    let text = example_text("four_bar", &[]);
    let examples = std::path::Path::new("examples");
    let program = Program::from_text("four_bar.lsd", &text, Some(examples), &Default::default());
    let changes = SettingsChanges {
        duration: Some(1.0),
        ..Default::default()
    };
    let mut prepared = program.prepare(&[], &changes).expect("prepares");
    let names = [
        "coupler_point".to_string(),
        "bar1".to_string(),
        "earth".to_string(),
    ];
    program
        .output_frames(&mut prepared, &names)
        .expect("frames found");
    let mechanism = program.mechanism().expect("a mechanism");
    let points: Vec<_> = (names.iter())
        .map(|name| frames::resolve(mechanism, &prepared.kinematics, name).expect("resolved"))
        .collect();
    let simulation = run(&prepared, &mut |_| {});
    assert_eq!(simulation.output_names.len(), 13 * names.len());
    assert_eq!(simulation.output_names[13], "bar1.x");
    assert_eq!(simulation.samples.len(), 21);
    for sample in &simulation.samples {
        let states = frames::states(
            &prepared.kinematics,
            &points,
            &sample.coordinates,
            &sample.rates,
        )
        .expect("evaluated");
        let expected: Vec<f64> = states.iter().flat_map(|s| s.values()).collect();
        for (k, (ours, theirs)) in sample.outputs.iter().zip(&expected).enumerate() {
            let column = &simulation.output_names[k];
            assert!(
                (ours - theirs).abs() < 1e-12,
                "t = {}, {column}: {ours} ≠ {theirs}",
                sample.time
            );
            assert!(column.ends_with(STATE_COMPONENTS[k % 13]));
        }
    }
    let unknown = program.output_frames(&mut prepared, &["coupler_pont".to_string()]);
    let message = unknown.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(
        message.contains("did you mean `coupler_point`"),
        "{message}"
    );
}

#[test]
fn json_samples_keep_the_program_outputs_apart_from_the_frames_asked_by_name() {
    let program = std::env::temp_dir().join(format!("lsdc-json-frames-{}.lsd", std::process::id()));
    let text = example_text("four_bar", &[]) + "output gap = distance(bar1, coupler_point) ;\n";
    std::fs::write(&program, text).expect("written");
    let path = program.to_str().expect("a path");
    let library = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let run = |format: &str| {
        let arguments = ["simulate", path, "-L", library, "--duration", "0.2"];
        let frames = ["--output-frame", "coupler_point", "--format", format];
        let (code, out, err) = lsdc(&[&arguments[..], &frames[..]].concat());
        assert_eq!(code, 0, "{err}");
        out
    };
    let (json, csv) = (run("json"), run("csv"));
    std::fs::remove_file(&program).ok();
    let document: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(document["output_names"], serde_json::json!(["gap"]));
    let samples = document["samples"].as_array().expect("samples");
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(samples.len(), rows.len());
    let header: Vec<&str> = csv.lines().next().expect("a header").split(',').collect();
    let x = header
        .iter()
        .position(|c| *c == "coupler_point.x")
        .expect("x");
    for (sample, row) in samples.iter().zip(rows) {
        assert_eq!(sample["outputs"].as_array().map(Vec::len), Some(1));
        let frame = &sample["frames"]["coupler_point"];
        let columns: Vec<f64> = row
            .split(',')
            .map(|c| c.parse().expect("a number"))
            .collect();
        let parts = ["position", "orientation", "velocity", "angular_velocity"];
        let values: Vec<f64> = (parts.iter())
            .flat_map(|part| frame[part].as_array().expect(part).clone())
            .map(|v| v.as_f64().expect("a number"))
            .collect();
        // The same numbers: serde_json reads decimals back to within an ulp, not exactly.
        for (json, csv) in values.iter().zip(&columns[x..x + 13]) {
            assert!(
                (json - csv).abs() <= 1e-15 * csv.abs().max(1.0),
                "t = {}: {json} ≠ {csv}",
                columns[0]
            );
        }
    }
}

#[test]
fn outputs_in_an_array_of_packages_are_named_by_instance() {
    let text = "import joints ;
let z = [0, 0, 1] ;
package leg[i in 1 .. 2] =
  let b = body mass = 1, iframe = [1, 0, 0] ++ 1, inertia = [0.1, 0.1, 0.1] end ;
  join [0, i, 0] ++ 1 @ earth and b with revolute(z) as hip ;
  initial hip.q' = i ;
  output tip = position([1, 0, 0] ++ 1 @ b) ;
end ;
output first = leg[1]:hip.q ;
simulate duration = 0.5, output = 0.25 end ;";
    let simulation = simulated(&prepared_text(text).expect("prepares"));
    let names = &simulation.output_names;
    assert_eq!(names[..3], ["leg[1]:tip.x", "leg[1]:tip.y", "leg[1]:tip.z"]);
    assert_eq!(
        names[3..6],
        ["leg[2]:tip.x", "leg[2]:tip.y", "leg[2]:tip.z"]
    );
    let last = simulation.samples.last().expect("samples");
    for (k, i) in [(0, 1.0), (3, 2.0)] {
        // Free turns at rate i: the tip at angle i t on a unit circle about (0, i).
        let angle = i * last.time;
        assert!((last.outputs[k] - angle.cos()).abs() < 1e-9);
        assert!((last.outputs[k + 1] - (i + angle.sin())).abs() < 1e-9);
    }
    assert_eq!(last.outputs[6], last.coordinates[0]);
}

#[test]
fn an_output_needs_its_values_and_reads_no_second_derivative() {
    let errors = prepared_text(
        "import joints ; let k = ?s ; let b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end ;
        join earth and b with revolute([0, 0, 1]) as hinge ;
        output spring = 0.5 * k * hinge.q ^ 2 ;
        output accel = hinge.q'' ;",
    )
    .err()
    .expect("refused");
    assert!(
        errors[0].starts_with("E0840: the output `spring` needs a value for `k`"),
        "{errors:?}"
    );
    assert!(
        errors[1].starts_with("E0842: the output `accel` cannot be computed"),
        "{errors:?}"
    );
}

#[test]
fn lsdc_test_compares_outputs_and_precision_measures_them() {
    let folder = std::env::temp_dir().join(format!("lsdc-outputs-test-{}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("folder");
    let text = example_text("pendulum", &[("duration = 5", "duration = 1")])
        + "output tip = position([0, 0, -1] ++ 1 @ rod) ;\n";
    std::fs::write(folder.join("p.lsd"), text).expect("program");
    let manifest = "[[case]]\nname = \"p\"\nprogram = \"p.lsd\"\nreference = \"p.csv\"\nabsolute = 1e-9\noutputs = [\"swing.q\", \"tip.y\"]\n";
    std::fs::write(folder.join("lsdtest.toml"), manifest).expect("manifest");
    let dir = folder.to_str().expect("a path");
    let (code, _, stderr) = lsdc(&["test", "--update", dir]);
    assert_eq!(code, 0, "{stderr}");
    let reference = std::fs::read_to_string(folder.join("p.csv")).expect("recorded");
    let header = reference
        .lines()
        .find(|l| l.starts_with("time"))
        .expect("a header");
    assert_eq!(header, "time,swing.q,tip.y");
    let (code, out, _) = lsdc(&["test", dir]);
    assert_eq!(code, 0, "{out}");
    // The output's column moved by 1e-6 in the reference: the case fails on it.
    let moved: String = reference
        .lines()
        .map(|line| match line.starts_with(['#', 't']) {
            true => format!("{line}\n"),
            false => {
                let mut cells: Vec<String> = line.split(',').map(String::from).collect();
                let y = cells.len() - 1;
                cells[y] = (cells[y].parse::<f64>().expect("number") + 1e-6).to_string();
                cells.join(",") + "\n"
            }
        })
        .collect();
    std::fs::write(folder.join("p.csv"), moved).expect("moved");
    let (code, out, _) = lsdc(&["test", dir]);
    assert_ne!(code, 0);
    assert!(out.contains("tip.y"), "{out}");
    let (code, table, stderr) = lsdc(&[
        "precision",
        &format!("{dir}/p.lsd"),
        "--integrators",
        "dopri5",
        "--tolerances",
        "1e-4,1e-8",
        "--repeats",
        "1",
        "--format",
        "json",
    ]);
    std::fs::remove_dir_all(&folder).ok();
    assert_eq!(code, 0, "{stderr}");
    let table: serde_json::Value = serde_json::from_str(&table).expect("json");
    let errors: Vec<f64> = (table["measurements"]
        .as_array()
        .expect("measurements")
        .iter())
    .map(|m| m["errors"]["outputs"].as_f64().expect("an output error"))
    .collect();
    assert!(
        errors[1] < errors[0] / 100.0 && errors[1] > 0.0,
        "{errors:?}"
    );
}

#[test]
fn the_viewer_plots_every_output_column() {
    let text = example_text("pendulum", &[])
        + "output tip = position([0, 0, -1] ++ 1 @ rod) ; output angle = swing.q ;";
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let mechanism = compile_text("pendulum.lsd", &text, None, &options)
        .mechanism
        .expect("elaborates");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    let mut viewer = lsdc::view::Viewer::new(mechanism, prepared, "pendulum").expect("a scene");
    let animation = viewer.simulate(Some(0.5)).expect("runs");
    let series = |name: &str| {
        (animation.series.iter())
            .find(|s| s.name == name)
            .unwrap_or_else(|| panic!("no series {name}"))
    };
    assert_eq!(series("angle").values, series("swing.q").values);
    for (y, q) in series("tip.y").values.iter().zip(&series("swing.q").values) {
        assert!((y - q.sin()).abs() < 1e-14);
    }
}
