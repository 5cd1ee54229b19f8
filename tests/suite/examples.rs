//! The front end on the thesis's programs: the satellite, its library form, the five link forms.

use std::path::PathBuf;

use lsdc::driver::{compile_files, compile_text, Compilation};
use lsdc::elab::Summary;
use lsdc::load::LoadOptions;

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

fn compile(path: &str) -> Compilation {
    let compilation = compile_files(&[PathBuf::from(path)], &options()).expect("example readable");
    let text =
        lsdc::diag::render::to_text(&compilation.workspace.sources, &compilation.diagnostics);
    assert!(
        compilation.diagnostics.is_empty(),
        "{path} should check clean:\n{text}"
    );
    compilation
}

fn summary(path: &str) -> Summary {
    compile(path)
        .mechanism
        .expect("clean programs elaborate")
        .summary()
}

#[test]
fn satellite_checks_clean_with_the_expected_summary() {
    let s = summary("examples/satellite.lsd");
    assert_eq!(s.bodies, 4);
    assert_eq!(s.joins, 4);
    assert_eq!(s.applied_forces, 2);
    assert_eq!(s.applied_torques, 0);
    assert_eq!(
        s.unknown_scalars, 2,
        "the two `?s` are independent (z12 and z34)"
    );
    assert_eq!(s.unknown_functions, 3);
    assert_eq!(
        s.body_names,
        [
            "satellite",
            "bras_primaire",
            "bras_secondaire",
            "reflecteur"
        ]
    );
}

#[test]
fn library_form_elaborates_to_the_same_mechanism() {
    let inline = compile("examples/satellite.lsd")
        .mechanism
        .expect("elaborates");
    let library = compile("examples/satellite_library.lsd")
        .mechanism
        .expect("elaborates");
    assert_eq!(inline.summary(), library.summary());
    assert_eq!(inline.dump(), library.dump());
}

#[test]
fn the_five_link_forms_check_clean() {
    let compilation = compile("examples/link_forms.lsd");
    let mechanism = compilation.mechanism.expect("elaborates");
    let dof_counts: Vec<usize> = mechanism
        .links
        .iter()
        .map(|l| l.coordinates.len())
        .collect();
    assert_eq!(dof_counts, [1, 2, 2, 2, 6]);
    let chain_lengths: Vec<usize> = mechanism.links.iter().map(|l| l.dofs.len()).collect();
    assert_eq!(chain_lengths, [1, 1, 2, 2, 4]);
}

#[test]
fn every_example_checks_clean() {
    for dir in ["examples", "examples/hard"] {
        for entry in std::fs::read_dir(dir).expect("examples directory") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "lsd") {
                compile(path.to_str().expect("utf-8 path"));
            }
        }
    }
}

#[test]
fn the_standard_library_checks_clean_and_provides_every_joint() {
    let text = "import joints;\nlet a = body end;\nlet b = body end;\n\
        join earth and a with weld;\n\
        join a and b with revolute([0,0,1]);\n\
        join a and b with prismatic(axis = [1,0,0]);\n\
        join a and b with helical([0,0,1], 0.01);\n\
        join a and b with cylindrical([0,0,1]);\n\
        join a and b with universal([1,0,0], [0,1,0]);\n\
        join a and b with spherical;\n\
        join a and b with planar;\n\
        join a and b with joints:free;\n\
        join a and b with rotoïde([1,0,0]);\n";
    let compilation = compile_text("joints_test.lsd", text, None, &options());
    assert!(
        compilation.diagnostics.is_empty(),
        "{:?}",
        compilation.diagnostics
    );
    let mechanism = compilation.mechanism.expect("elaborates");
    let coordinates: Vec<usize> = mechanism
        .joins
        .iter()
        .map(|j| mechanism.link(j.link).coordinates.len())
        .collect();
    assert_eq!(coordinates, [0, 1, 1, 1, 2, 2, 3, 3, 6, 1]);
}

#[test]
fn shared_unknowns_are_named_and_occurrences_are_fresh() {
    let text = "let L = ?s;\nlet a = body iframe = [0,0,L] ++ 1 end;\nlet b = body iframe = [0,0,L] ++ 1 end;\n\
        join earth and a with link(x) dof = x || [0,0,1] end;\n\
        join a and [0,?s,?s] ++ 1 @ b with link(x) dof = [x,0,0] end;\n";
    let compilation = compile_text("unknowns.lsd", text, None, &options());
    let s = compilation.mechanism.expect("elaborates").summary();
    assert_eq!(s.unknown_scalars, 3, "L once, then two fresh `?s`");
}

#[test]
fn zero_and_one_take_the_type_their_context_requires() {
    let text = "let a = body mass = 0, iframe = 0, inertia = 0 end;\n\
        join earth and 0 @ a with link(x) dof = [0,0,x] ++ 1 end;\n\
        let f = force value = 0, body = earth end;\n\
        apply f on 1 @ a;\n";
    let compilation = compile_text("overloading.lsd", text, None, &options());
    assert!(
        compilation.diagnostics.is_empty(),
        "{:?}",
        compilation.diagnostics
    );
}

#[test]
fn packages_and_local_bindings_resolve() {
    let text = "package P = let arm = body mass = 2 end; let hinge(axis) = link(q) dof = q || axis end; end;\n\
        let z = local h = 0.5 and w = 2 in [0, 0, h * w] end;\n\
        join earth and z ++ 1 @ P:arm with P:hinge([0,0,1]);\n\
        apply force value = [0,0,-9.81 * P:arm.mass], body = earth end on P:arm.iframe;\n";
    let compilation = compile_text("packages.lsd", text, None, &options());
    assert!(
        compilation.diagnostics.is_empty(),
        "{:?}",
        compilation.diagnostics
    );
    let s = compilation.mechanism.expect("elaborates").summary();
    assert_eq!((s.bodies, s.joins, s.applied_forces), (1, 1, 1));
}

#[test]
fn dump_shows_the_satellite_structure() {
    let dump = compile("examples/satellite.lsd")
        .mechanism
        .expect("elaborates")
        .dump();
    assert!(
        dump.contains("join T[0, 0, ?s1] @ satellite and 1 @ bras_primaire with link(x)"),
        "{dump}"
    );
    assert!(dump.contains("torque = [?f2(q0, q0'), 0, 0]"), "{dump}");
    assert!(
        dump.contains(
            "body reflecteur: mass mass(reflecteur), iframe T[0, 0, ?s5], inertia [0, 0, 0]"
        ),
        "{dump}"
    );
    assert!(
        dump.contains(
            "body satellite: mass mass(satellite), iframe 1, inertia [inertia_x(satellite), "
        ),
        "{dump}"
    );
}

#[test]
fn generic_quantities_can_be_read_and_are_not_counted_as_written_unknowns() {
    let text = "let a = body end;\nlet f = force end;\n\
        join earth and a with link(x) dof = x || [0,0,1], torque = [0, 0, -a.mass * x] end;\n\
        apply force value = 2 * f.value + a.inertia, body = f.body end on a.iframe;\n";
    let compilation = compile_text("generic.lsd", text, None, &options());
    assert!(
        compilation.diagnostics.is_empty(),
        "{:?}",
        compilation.diagnostics
    );
    let mechanism = compilation.mechanism.expect("elaborates");
    let s = mechanism.summary();
    assert_eq!((s.unknown_scalars, s.unknown_functions), (0, 0));
    assert!(mechanism.dump().contains("mass(a)"), "{}", mechanism.dump());
}

#[test]
fn rotation_applied_to_a_vector_rotates_it() {
    let text = "let v = (pi/2 || [0,0,2]) * [1,0,0];\nlet a = body mass = v.x end;\n";
    // `v.x` is not a field: the checker must say so instead of evaluating.
    let compilation = compile_text("rotate.lsd", text, None, &options());
    assert!(compilation.has_errors());
    let text = "let v = (pi/2 || [0,0,2]) * [1,0,0];\n\
        let a = body iframe = v ++ 1 end;\n\
        join earth and a with link(x) dof = x || [0,0,1] end;\n";
    let compilation = compile_text("rotate.lsd", text, None, &options());
    let mechanism = compilation.mechanism.expect("elaborates");
    let lsdc::elab::mechanism::Quantity::Declared(iframe) = &mechanism.bodies[0].iframe else {
        panic!("declared")
    };
    let lsdc::elab::value::Elementary::Translation(t) = &iframe.0[0] else {
        panic!("translation")
    };
    let numbers: Vec<f64> = t
        .iter()
        .map(|s| lsdc::elab::value::constant(s).expect("a number"))
        .collect();
    assert!(
        (numbers[0]).abs() < 1e-15 && (numbers[1] - 1.0).abs() < 1e-15 && numbers[2].abs() < 1e-15,
        "{numbers:?}"
    );
}

#[test]
fn any_unknown_name_is_a_fresh_scalar() {
    let text =
        "let a = body mass = ?k_2 + ?mass end;\njoin earth and a with link(x) dof = [0,0,x] end;\n";
    let s = compile_text("unknowns.lsd", text, None, &options())
        .mechanism
        .expect("elaborates")
        .summary();
    assert_eq!(s.unknown_scalars, 2);
}

#[test]
fn an_import_opens_its_names_to_the_declarations_after_it() {
    let text = "let joints = 1;\nimport joints;\nlet a = body end;\njoin earth and a with revolute([0,0,1]);\n";
    let compilation = compile_text("open.lsd", text, None, &options());
    assert!(
        compilation.diagnostics.is_empty(),
        "{:?}",
        compilation.diagnostics
    );
}

/// The `.lsd` files of a folder and its subfolders.
fn programs_in(folder: &str, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(folder).expect("folder exists") {
        let path = entry.expect("readable entry").path();
        if path.is_dir() {
            programs_in(path.to_str().expect("a UTF-8 path"), found);
        } else if path.extension().is_some_and(|e| e == "lsd") {
            found.push(path);
        }
    }
}

/// `compile_files_lean` frees each declaration of the root file once it is elaborated: the
/// diagnostics and the mechanism must be those of the compilation that keeps the tree, on
/// every example and on every golden input (clean programs, and the checker's and the
/// elaborator's errors).
#[test]
fn freeing_the_tree_while_elaborating_changes_nothing() {
    let mut programs = Vec::new();
    programs_in("examples", &mut programs);
    programs_in("tests/golden", &mut programs);
    programs.sort();
    assert!(programs.len() > 100, "{} programs", programs.len());
    let mut elaborated = 0;
    for path in programs {
        let kept = compile_files(std::slice::from_ref(&path), &options()).expect("readable");
        let lean = lsdc::driver::compile_files_lean(std::slice::from_ref(&path), &options())
            .expect("readable");
        let render =
            |c: &Compilation| lsdc::diag::render::to_text(&c.workspace.sources, &c.diagnostics);
        assert_eq!(render(&kept), render(&lean), "{}", path.display());
        let debug = |c: &Compilation| format!("{:?}", c.mechanism);
        assert_eq!(debug(&kept), debug(&lean), "{}", path.display());
        elaborated += usize::from(lean.mechanism.is_some());
        if lean.mechanism.is_some() {
            let root = lean.workspace.roots[0];
            assert!(lean.workspace.module(root).program.decls.is_empty());
        }
    }
    assert!(elaborated > 40, "{elaborated} programs elaborated");
}
