//! `lsdc export-fmu`: its diagnostics, its model descriptions (golden files, FMI 3.0 and 2.0)
//! and the ZIP container read back by its central directory. FMPy's checks of the units
//! (validation against the standard's schema, simulations, a co-simulated controller) are in
//! tools/fmi/check_units.py, which `.ci/run` runs through tools/fmi-tests.

use std::path::Path;

use crate::common::lsdc;

/// The model description of the pendulum with an input along `swing.q`, against its golden
/// file (`UPDATE_GOLDEN=1` rewrites it after an intended change).
fn golden_model_description(version: &str, golden: &str) {
    let (code, stdout, stderr) = lsdc(&[
        "export-fmu",
        "examples/pendulum.lsd",
        "--input",
        "swing.q",
        "--fmi",
        version,
        "--model-description",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let path = Path::new("tests/golden/fmi").join(golden);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, &stdout).expect("golden file written");
    }
    let expected = std::fs::read_to_string(&path).expect("golden file");
    assert_eq!(
        stdout,
        expected,
        "the model description changed ({})",
        path.display()
    );
}

#[test]
fn the_model_descriptions_of_the_pendulum_are_the_golden_ones() {
    golden_model_description("3", "pendulum_input.fmi3.xml");
    golden_model_description("2", "pendulum_input.fmi2.xml");
}

#[test]
fn the_model_description_lists_parameters_units_and_outputs() {
    let (code, xml, stderr) = lsdc(&[
        "export-fmu",
        "examples/four_bar_grashof.lsd",
        "--set",
        "l1=1.5",
        "--model-description",
    ]);
    assert_eq!(code, 0, "{stderr}");
    // `given l1 = 1.0, l3 = 3.0`: parameters, l1 with the value set at export.
    assert!(xml.contains(r#"name="l1" valueReference="1""#), "{xml}");
    assert!(
        xml.contains(r#"causality="parameter" variability="fixed" start="1.5""#),
        "{xml}"
    );
    assert!(
        xml.contains(r#"name="l3""#) && xml.contains(r#"start="3.0""#),
        "{xml}"
    );
    assert!(
        xml.contains(r#"<Unit name="rad">"#) && xml.contains(r#"unit="rad/s""#),
        "{xml}"
    );
    assert!(
        !xml.contains("causality=\"input\""),
        "no input asked: {xml}"
    );
}

#[test]
fn an_input_that_is_no_velocity_is_refused_with_the_nearest() {
    let (code, _, stderr) = lsdc(&[
        "export-fmu",
        "examples/pendulum.lsd",
        "--input",
        "swing.qq",
        "--model-description",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("no velocity `swing.qq`"), "{stderr}");
    assert!(stderr.contains("did you mean `swing.q`?"), "{stderr}");
}

#[test]
fn a_program_with_errors_gets_its_diagnostics_and_no_unit() {
    let dir = std::env::temp_dir().join(format!("lsdc-export-fmu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("folder");
    let program = dir.join("typo.lsd");
    std::fs::write(
        &program,
        "let b = body mass = 1 end;\njoin earth and c with 1;\n",
    )
    .expect("program");
    let unit = dir.join("typo.fmu");
    let (code, _, stderr) = lsdc(&[
        "export-fmu",
        program.to_str().expect("utf-8"),
        "-o",
        unit.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("typo.lsd:2:"), "{stderr}");
    assert!(!unit.exists());
    let (code, _, stderr) = lsdc(&["export-fmu", "examples/pendulum.lsd"]);
    assert_eq!(code, 2, "-o or --model-description is required: {stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The names and contents of a stored ZIP archive's entries, read from its central directory
/// (APPNOTE.TXT §4.3.12, §4.3.16), each checked against its CRC-32.
fn entries(archive: &[u8]) -> Vec<(String, Vec<u8>)> {
    let u16_at = |at: usize| u16::from_le_bytes([archive[at], archive[at + 1]]) as usize;
    let u32_at = |at: usize| {
        u32::from_le_bytes([
            archive[at],
            archive[at + 1],
            archive[at + 2],
            archive[at + 3],
        ])
    };
    let end = archive.len() - 22;
    assert_eq!(u32_at(end), 0x0605_4b50, "end of central directory");
    let (count, mut at) = (u16_at(end + 10), u32_at(end + 16) as usize);
    let mut found = Vec::new();
    for _ in 0..count {
        assert_eq!(u32_at(at), 0x0201_4b50, "central directory header");
        assert_eq!(u16_at(at + 10), 0, "stored");
        let (crc, size) = (u32_at(at + 16), u32_at(at + 24) as usize);
        let name_length = u16_at(at + 28);
        let name = String::from_utf8(archive[at + 46..at + 46 + name_length].to_vec()).unwrap();
        let local = u32_at(at + 42) as usize;
        assert_eq!(u32_at(local), 0x0403_4b50, "local header of {name}");
        let data = local + 30 + u16_at(local + 26) + u16_at(local + 28);
        let contents = archive[data..data + size].to_vec();
        assert_eq!(crc32fast::hash(&contents), crc, "CRC-32 of {name}");
        found.push((name, contents));
        at += 46 + name_length + u16_at(at + 30) + u16_at(at + 32);
    }
    found
}

#[test]
fn the_unit_holds_the_description_the_library_and_the_program_with_its_imports() {
    let dir = std::env::temp_dir().join(format!("lsdc-export-fmu-zip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("folder");
    // Any file stands for the shared library here: the unit carries its bytes.
    let library = dir.join("library.so");
    std::fs::write(&library, b"not a library").expect("library");
    let unit = dir.join("delta.fmu");
    let (code, _, stderr) = lsdc(&[
        "export-fmu",
        "examples/delta_isir88.lsd",
        "--fmi",
        "2",
        "--library",
        library.to_str().expect("utf-8"),
        "-o",
        unit.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let archive = std::fs::read(&unit).expect("unit");
    let entries = entries(&archive);
    let names: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "modelDescription.xml",
            "binaries/linux64/delta_isir88.so",
            "resources/lsdc/unit.json",
            "resources/lsdc/program/delta_isir88.lsd",
            "resources/lsdc/program/lib/delta_masses.lsd",
        ]
    );
    assert_eq!(entries[1].1, b"not a library");
    let program = std::fs::read("examples/lib/delta_masses.lsd").expect("import");
    assert_eq!(entries[4].1, program);
    let description = String::from_utf8(entries[0].1.clone()).expect("utf-8");
    assert!(description.contains(r#"fmiVersion="2.0""#), "{description}");
    let unit_json: serde_json::Value = serde_json::from_slice(&entries[2].1).expect("json");
    assert_eq!(unit_json["program"], "delta_isir88.lsd");
    std::fs::remove_dir_all(&dir).ok();
}

/// The model description of `args`' unit, which must be written.
fn description_of(args: &[&str]) -> String {
    let mut all = vec!["export-fmu"];
    all.extend_from_slice(args);
    all.push("--model-description");
    let (code, xml, stderr) = lsdc(&all);
    assert_eq!(code, 0, "{stderr}");
    xml
}

#[test]
fn a_tree_without_events_is_exported_for_model_exchange_and_co_simulation() {
    let xml = description_of(&["examples/double_pendulum.lsd", "--fmi", "3"]);
    assert!(
        xml.contains("<ModelExchange modelIdentifier=\"double_pendulum\""),
        "{xml}"
    );
    assert!(
        xml.contains("<CoSimulation modelIdentifier=\"double_pendulum\""),
        "{xml}"
    );
    // The states are the coordinates then the rates; their derivatives the rates then the
    // accelerations, each naming its state.
    let reference = |name: &str| {
        let name = name.replace('\'', "&apos;");
        let prefix = format!("name=\"{name}\" valueReference=\"");
        let at = xml.find(&prefix).expect("the variable");
        let rest = &xml[at + prefix.len()..];
        rest[..rest.find('"').expect("quote")].to_string()
    };
    for coordinate in ["shoulder.q", "elbow.q"] {
        let (q, rate, acceleration) = (
            reference(coordinate),
            reference(&format!("{coordinate}'")),
            reference(&format!("{coordinate}''")),
        );
        let rate_line = xml
            .lines()
            .find(|l| l.contains(&format!("valueReference=\"{rate}\"")));
        assert!(
            rate_line
                .expect("rate")
                .contains(&format!("derivative=\"{q}\"")),
            "{xml}"
        );
        let line = xml
            .lines()
            .find(|l| l.contains(&format!("valueReference=\"{acceleration}\"")));
        let line = line.expect("acceleration");
        assert!(line.contains(&format!("derivative=\"{rate}\"")), "{line}");
        assert!(
            line.contains("causality=\"local\"") && line.contains("unit=\"rad/s2\""),
            "{line}"
        );
        assert!(xml.contains(&format!(
            "<ContinuousStateDerivative valueReference=\"{rate}\"/>"
        )));
        assert!(xml.contains(&format!(
            "<InitialUnknown valueReference=\"{acceleration}\"/>"
        )));
    }
    let derivatives: Vec<&str> = (xml.lines())
        .filter(|l| l.contains("<ContinuousStateDerivative"))
        .collect();
    assert_eq!(derivatives.len(), 4, "{xml}");
    // FMI 2.0: the derivatives by their places among the variables, from 1.
    let xml = description_of(&["examples/double_pendulum.lsd", "--fmi", "2"]);
    assert!(
        xml.contains("completedIntegratorStepNotNeeded=\"true\""),
        "{xml}"
    );
    assert!(xml.contains("<Derivatives>"), "{xml}");
    // Co-simulation only when asked: no accelerations.
    let xml = description_of(&["examples/double_pendulum.lsd", "--kind", "co-simulation"]);
    assert!(
        !xml.contains("<ModelExchange") && !xml.contains("q''"),
        "{xml}"
    );
}

#[test]
fn a_mechanism_with_loops_is_for_co_simulation_only_and_says_why() {
    let xml = description_of(&["examples/four_bar.lsd"]);
    assert!(
        !xml.contains("<ModelExchange") && xml.contains("<CoSimulation"),
        "{xml}"
    );
    assert!(
        xml.contains("co-simulation only: its closed loops"),
        "{xml}"
    );
    for kind in ["model-exchange", "both"] {
        let (code, _, stderr) = lsdc(&[
            "export-fmu",
            "examples/four_bar.lsd",
            "--kind",
            kind,
            "--model-description",
        ]);
        assert_eq!(code, 2, "{stderr}");
        assert!(
            stderr.contains("cannot be exported for model exchange: its closed loops"),
            "{stderr}"
        );
        assert!(stderr.contains("`--kind co-simulation`"), "{stderr}");
    }
    // Stops are events.
    let (code, _, stderr) = lsdc(&[
        "export-fmu",
        "examples/limited_pendulum.lsd",
        "--kind",
        "model-exchange",
        "--model-description",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("stops"), "{stderr}");
}

/// The derivatives the model-exchange equations give at a state, an input's effort set, are
/// the rates and `lsdc eval`'s forward dynamics (ABA) with that effort: the run's evaluation
/// and the batch's, two paths to the same equations.
#[test]
fn the_equations_for_model_exchange_are_the_forward_dynamics() {
    use lsdc::api::{evaluate, parse_states, Equations, Program};
    let program =
        Program::from_file("examples/double_pendulum.lsd", &Default::default()).expect("program");
    let prepared = program.prepare(&[], &Default::default()).expect("prepared");
    let mut equations = Equations::new(&prepared, &["elbow.q"]).expect("a tree without events");
    assert_eq!(equations.state_count(), 4);
    assert_eq!(equations.start(), [2.0, -1.0, 0.5, 1.0]);
    equations.set_inputs(&[0.7]).expect("one input");
    let state = [0.3, -1.2, 0.7, 2.5];
    let mut derivatives = [0.0; 4];
    equations
        .derivatives(0.0, &state, &mut derivatives)
        .expect("derivatives");
    let states =
        parse_states(r#"[{"q": [0.3, -1.2], "v": [0.7, 2.5], "tau": [0, 0.7]}]"#).expect("states");
    let evaluation = evaluate(&prepared, &states).expect("evaluated");
    assert_eq!(evaluation.positions, ["shoulder.q", "elbow.q"]);
    let aba = evaluation.states[0].aba.as_ref().expect("aba");
    assert_eq!(derivatives[..2], state[2..]);
    for k in 0..2 {
        assert!(
            (derivatives[2 + k] - aba[k]).abs() <= 1e-13,
            "{derivatives:?} {aba:?}"
        );
    }
    let sample = equations.sample(0.0, &state).expect("sample");
    assert_eq!(sample.coordinates, state[..2]);
    assert!(sample.kinetic_energy > 0.0);
}

/// `input swing.q = 0.25;`: the unit's input with that start value, once even when
/// `--input` names it too; `lsdc linearize`'s input without `--input`; and `lsdc simulate`
/// holds it at its start value, or at the value `--set` gives it, which the unit starts it at too.
#[test]
fn a_declared_input_is_the_units_and_the_linear_models() {
    let program = "tests/fixtures/input_pendulum.lsd";
    for extra in [&[][..], &["--input", "swing.q"][..]] {
        let mut args = vec![program];
        args.extend_from_slice(extra);
        let xml = description_of(&args);
        let inputs: Vec<&str> = (xml.lines())
            .filter(|l| l.contains("causality=\"input\""))
            .collect();
        assert_eq!(inputs.len(), 1, "{xml}");
        assert!(inputs[0].contains("name=\"swing.q.effort\""), "{xml}");
        assert!(inputs[0].contains("start=\"0.25\""), "{xml}");
    }
    // `--set` starts the unit's input where every run starts it.
    let xml = description_of(&[program, "--set", "swing.q=0.5"]);
    let input = (xml.lines()).find(|l| l.contains("name=\"swing.q.effort\""));
    assert!(input.is_some_and(|l| l.contains("start=\"0.5\"")), "{xml}");
    let xml = description_of(&["examples/control/dc_motor.lsd", "--set", "voltage=6"]);
    let input = (xml.lines()).find(|l| l.contains("name=\"voltage\""));
    assert!(input.is_some_and(|l| l.contains("start=\"6.0\"")), "{xml}");
    let (code, json, stderr) = lsdc(&["linearize", program, "--format", "json"]);
    assert_eq!(code, 0, "{stderr}");
    let linear: serde_json::Value = serde_json::from_str(&json).expect("json");
    assert_eq!(linear["inputs"], serde_json::json!(["swing.q"]), "{json}");
    // B's row of the rate: 1 / I about the axis (0.1 + 1.2 × 0.5², the rod's inertia moved
    // to the axis).
    let b = linear["B"][1][0].as_f64().expect("B");
    assert!((b - 1.0 / (0.1 + 1.2 * 0.25)).abs() < 1e-12, "{json}");
    // `lsdc simulate` holds the input at its start value: the pendulum moves otherwise than
    // without the declaration, and as without it when `--set` starts the input at 0.
    let simulate = |file, set: &[&str]| {
        let mut args = vec!["simulate", file, "--duration", "0.3", "--every", "0.1"];
        args.extend_from_slice(set);
        lsdc(&args)
    };
    let declared = simulate(program, &[]);
    let at_zero = simulate(program, &["--set", "swing.q=0"]);
    let plain = simulate("examples/pendulum.lsd", &[]);
    assert_eq!(
        (declared.0, at_zero.0, plain.0),
        (0, 0, 0),
        "{}",
        declared.2
    );
    assert_ne!(declared.1, plain.1);
    assert_eq!(at_zero.1, plain.1);
}
