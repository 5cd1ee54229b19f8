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
