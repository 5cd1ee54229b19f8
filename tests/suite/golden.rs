//! Golden tests for diagnostics: each `tests/golden/NAME.lsd` is checked (then numbered, assembled,
//! prepared for a simulation, and its equations written, while it stays clean) and its rendered
//! diagnostics are compared with `tests/golden/NAME.stderr`. The error text is reviewed like code.
//! Set `UPDATE_GOLDEN=1` to rewrite the expected files after an intended change.

use std::path::{Path, PathBuf};

use lsdc::diag::render;
use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;

fn golden_inputs() -> Vec<PathBuf> {
    let mut inputs: Vec<PathBuf> = std::fs::read_dir("tests/golden")
        .expect("tests/golden exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    inputs.sort();
    inputs
}

/// The diagnostics of the front end, then of the topology and assembly when it is clean.
fn render_diagnostics(input: &Path) -> String {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[input.to_path_buf()], &options).expect("input readable");
    let mut diagnostics = compilation.diagnostics.clone();
    if let (false, Some(mechanism)) = (compilation.has_errors(), &compilation.mechanism) {
        match lsdc::topology::build(mechanism) {
            Err(errors) => diagnostics.extend(errors),
            Ok(topology) => {
                match lsdc::studies::analysis::assembled_model(
                    mechanism,
                    topology.clone(),
                    &Default::default(),
                ) {
                    Err(errors) => diagnostics.extend(errors),
                    // A program that asks for a simulation (`simulate`) is prepared for it,
                    // then every program's equations are written, for what only they reject;
                    // a clean program without `simulate` is prepared last (values of `given`,
                    // outputs).
                    Ok((_, _, warnings)) => {
                        let settings = lsdc::prepare::Settings::default();
                        let prepare = || {
                            lsdc::prepare::prepare(mechanism, &[], &settings)
                                .err()
                                .unwrap_or_default()
                        };
                        let refused = match &mechanism.scenario {
                            Some(_) => prepare(),
                            None => Vec::new(),
                        };
                        let later = match refused.is_empty() {
                            true => lsdc::symbolic::generate(mechanism, &topology)
                                .err()
                                .unwrap_or_default(),
                            false => refused,
                        };
                        let later = match (later.is_empty(), &mechanism.scenario) {
                            (true, None) => prepare(),
                            _ => later,
                        };
                        diagnostics.extend(warnings.into_iter().chain(later))
                    }
                }
            }
        }
    }
    // A golden file shows an error, or a warning of a clean program.
    assert!(
        !diagnostics.is_empty(),
        "{} should not check clean",
        input.display()
    );
    render::to_text(&compilation.workspace.sources, &diagnostics)
}

#[test]
fn diagnostics_match_golden_files() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    let mut failures = Vec::new();
    let inputs = golden_inputs();
    assert!(inputs.len() >= 11, "the golden suite lost files");
    for input in inputs {
        let actual = render_diagnostics(&input);
        let expected_path = input.with_extension("stderr");
        if update {
            std::fs::write(&expected_path, &actual).expect("writable golden file");
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if actual != expected {
            failures.push(format!("--- {}\n{actual}", expected_path.display()));
        }
    }
    assert!(
        failures.is_empty(),
        "diagnostics differ from golden files:\n{}",
        failures.join("\n")
    );
}

#[test]
fn json_diagnostics_carry_positions_and_labels() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[PathBuf::from("tests/golden/library_error.lsd")], &options)
        .expect("readable");
    let json = render::to_json_value(&compilation.workspace.sources, &compilation.diagnostics);
    let first = &json[0];
    assert_eq!(first["code"], "E0401");
    assert_eq!(first["file"], "tests/golden/lib/broken.lsd");
    assert_eq!(first["line"], 3);
    assert_eq!(first["column"], 32);
    let labels = first["labels"].as_array().expect("labels");
    assert!(labels
        .iter()
        .any(|l| l["file"] == "tests/golden/library_error.lsd" && l["primary"] == false));
}

/// The notation table of `examples/NAME.lsd` is compared with `tests/notation/NAME.txt`.
#[test]
fn notation_tables_match_golden_files() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    for name in ["satellite", "delta_isir88"] {
        let options = LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        };
        let compilation = compile_files(&[PathBuf::from(format!("examples/{name}.lsd"))], &options)
            .expect("readable");
        let mechanism = compilation.mechanism.expect("elaborates");
        let topology = lsdc::topology::build(&mechanism).expect("connected");
        let actual = lsdc::topology::notation::notation(&mechanism, &topology);
        let path = format!("tests/notation/{name}.txt");
        if update {
            std::fs::write(&path, &actual).expect("writable");
            continue;
        }
        let expected = std::fs::read_to_string(&path).unwrap_or_default();
        assert_eq!(
            actual, expected,
            "notation table of {name} differs from {path}"
        );
    }
}

/// The thesis's notation (Papegay 1992, §3.2.4 and §3.3.2; notes §6.1, §9.3) at the scalar
/// level with its own indices, and the equations at the level of vectors, for the satellite and
/// the robot: `tests/notation/NAME_thesis.txt` and `tests/notation/NAME_vector.txt`. The
/// satellite's lines the thesis prints are all there, as it prints them (but for `M1T_1_15`,
/// its slip for `M1R_1_15`, and the spaces after commas).
#[test]
fn thesis_notation_tables_match_golden_files() {
    use lsdc::topology::notation::{notation_with, vector_equations, Level, Options};
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    let options = Options {
        level: Level::Scalar,
        thesis_indices: true,
    };
    for name in ["satellite", "robot"] {
        let compilation = compile_files(
            &[PathBuf::from(format!("examples/{name}.lsd"))],
            &LoadOptions::default(),
        )
        .expect("readable");
        let mechanism = compilation.mechanism.expect("elaborates");
        let topology = lsdc::topology::build(&mechanism).expect("connected");
        for (suffix, actual) in [
            ("thesis", notation_with(&mechanism, &topology, options)),
            ("vector", vector_equations(&mechanism, &topology, options)),
        ] {
            let path = format!("tests/notation/{name}_{suffix}.txt");
            if update {
                std::fs::write(&path, &actual).expect("writable");
                continue;
            }
            let expected = std::fs::read_to_string(&path).unwrap_or_default();
            assert_eq!(actual, expected, "{path} differs");
        }
    }
    let satellite = std::fs::read_to_string("tests/notation/satellite_thesis.txt").expect("golden");
    for line in [
        "V1T_1_15 := 0 ;",
        "M1R_1_15 := Id ;",
        "mu_2 := 0 ;",
        "mu_3 := 0 ;",
        "MIg_2 := 0 ;",
        "MIg_3 := 0 ;",
        "V4T_4_45 := [0, 0, v4T_4_45_z] ;",
        "MIg_4 := 0 ;",
        "VOT_1_15 = 0 ;",
        "MOIo_2 := 0 ;",
        "MOIo_3 := 0 ;",
        "MOIo_1 = MOIg_1 ;",
        "VOT_4_45 = MOR_0_4 &* V4T_4_45 ;",
        "MMassMax = BlockDiagonal(MMassMax_1, MMassMax_2, MMassMax_3, MMassMax_4) ;",
        "MMassMax_1 = [[mu_1 &s Id, 0], [0, MOIo_1]] ;",
        "MMassMax_2 = 0 ;",
        "MMassMax_3 = 0 ;",
        "MMassMax_4 = [[mu_4 &s Id, - mu_4 &s ~VOT_4_45], [mu_4 &s ~VOT_4_45, MOIo_4]] ;",
        "MOR_0_4 := [[cos(p4[5](t)) cos(p4[6](t)), - cos(p4[5](t)) sin(p4[6](t)), sin(p4[5](t))], \
         [sin(p4[4](t)) sin(p4[5](t)) cos(p4[6](t)) + cos(p4[4](t)) sin(p4[6](t)), \
         - sin(p4[4](t)) sin(p4[5](t)) sin(p4[6](t)) + cos(p4[4](t)) cos(p4[6](t)), \
         - sin(p4[4](t)) cos(p4[5](t))], \
         [- cos(p4[4](t)) sin(p4[5](t)) cos(p4[6](t)) + sin(p4[4](t)) sin(p4[6](t)), \
         cos(p4[4](t)) sin(p4[5](t)) sin(p4[6](t)) + sin(p4[4](t)) cos(p4[6](t)), \
         cos(p4[4](t)) cos(p4[5](t))]] ;",
        "MIg_1 := matrix([[MIg_1_xx, 0, 0], [0, MIg_1_yy, 0], [0, 0, MIg_1_zz]]) ;",
    ] {
        assert!(
            satellite.lines().any(|l| l == line),
            "the thesis's `{line}` is missing"
        );
    }
}

/// The fixes offered for the newcomers' slips are right: applied to the golden file, every one
/// of them at once, they leave a program that checks clean.
#[test]
fn applying_the_offered_fixes_makes_the_program_check_clean() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    for name in [
        "stdlib_name_not_imported",
        "missing_comma",
        "slash_comment",
        "leading_dot",
        "quoted_integrator",
        "number_with_unit",
        "rotation_precedence",
    ] {
        let path = PathBuf::from(format!("tests/golden/{name}.lsd"));
        let compilation = compile_files(std::slice::from_ref(&path), &options).expect("readable");
        let mut fixes: Vec<_> = compilation
            .diagnostics
            .iter()
            .filter_map(|d| d.fix.as_deref().cloned())
            .collect();
        assert!(!fixes.is_empty(), "{name}: no fix offered");
        assert!(
            compilation.diagnostics.iter().all(|d| d.fix.is_some()),
            "{name}: a diagnostic without a fix"
        );
        // From the end of the file, so the earlier offsets stay valid.
        fixes.sort_by_key(|f| std::cmp::Reverse(f.span.start()));
        let mut text = std::fs::read_to_string(&path).expect("readable");
        for fix in fixes {
            text.replace_range(fix.span.range(), &fix.replacement);
        }
        let fixed = lsdc::driver::compile_text("fixed.lsd", &text, None, &options);
        assert!(
            !fixed.has_errors(),
            "{name} after its fixes:\n{text}\n{:?}",
            fixed.diagnostics
        );
    }
}
