//! A study that asks only for kinematics (`lsdc kinematics`, `lsdc workspace`) builds no
//! dynamics (`prepare::prepare_kinematics`): its model has no inertia, effort, rotor, friction
//! or state, and it finds what the full model finds. The oracle of the reduction is the full
//! model's workspace of the Delta (masses, weights and shorted motors built), sampled on the
//! same grid; the proof that nothing of the dynamics is built is a program whose masses have
//! no value, which the full preparation refuses (E0813) and the kinematic one accepts.

use lsdc::prepare::{prepare, prepare_kinematics, Prepared, Settings};
use lsdc::studies::kinematic_models::{actuation, Output, OutputKind, SINGULAR_TOLERANCE};
use lsdc::studies::workspace::{sample, Range, Workspace};

use crate::common::lsdc;
use crate::common::programs::{example_text, mechanism};

/// The Delta's nacelle over the arms' box [0.5, 1.3]³ rad on a grid of `n`³ cells.
fn delta_workspace(prepared: &Prepared, n: usize) -> Workspace {
    let mechanism = mechanism("delta_isir88", &[]);
    let frame = lsdc::kinematics::frames::resolve(&mechanism, &prepared.kinematics, "nacelle")
        .expect("the nacelle is a body");
    let names = ["A1.q", "A2.q", "A3.q"].map(String::from);
    let actuation = actuation(prepared, &names).expect("the arms' coordinates");
    let output = Output {
        frame,
        kind: OutputKind::Point,
    };
    let ranges: Vec<Range> = (names.iter())
        .map(|name| Range {
            name: name.clone(),
            low: 0.5,
            high: 1.3,
        })
        .collect();
    sample(
        prepared,
        &actuation,
        &output,
        &ranges,
        n,
        SINGULAR_TOLERANCE,
    )
    .expect("sampled")
}

/// |a − b| relative to the larger, zero for two zeros.
fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

#[test]
fn kinematic_studies_find_the_full_models_workspace_without_building_dynamics() {
    let mechanism = mechanism("delta_isir88", &[]);
    let full = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    let kinematic = prepare_kinematics(&mechanism, &[]).expect("prepares");
    // The reduction happened: the full model has the Delta's masses and efforts, the
    // kinematic one none of them.
    assert!(full.model.dynamics && !kinematic.model.dynamics);
    assert!(full.model.bodies.iter().any(|b| !b.massless));
    assert!(!full.model.applied.is_empty() || full.model.gravity.norm() > 0.0);
    assert!(kinematic.model.bodies.iter().all(|b| b.massless));
    assert!(kinematic.model.applied.is_empty() && kinematic.model.gravity.norm() == 0.0);
    assert!(kinematic.model.link_efforts.is_empty() && kinematic.model.states.is_empty());
    assert!(kinematic.model.effort_tape.is_err() && kinematic.model.actuation.is_none());
    assert!(kinematic.planar.is_err() && kinematic.outputs.is_empty());
    // The same assembled start, and the same workspace sample by sample.
    assert_eq!(full.coordinates, kinematic.coordinates);
    let (a, b) = (delta_workspace(&full, 4), delta_workspace(&kinematic, 4));
    assert_eq!((a.reachable, a.boundary), (b.reachable, b.boundary));
    assert!(a.reachable > 0, "the box reaches the workspace");
    assert!(
        relative(a.volume, b.volume) <= 1e-12,
        "{} {}",
        a.volume,
        b.volume
    );
    for (x, y) in a.samples.iter().zip(&b.samples) {
        assert_eq!((x.reachable, x.singular), (y.reachable, y.singular));
        if let (Some(p), Some(r)) = (x.point, y.point) {
            (0..3).for_each(|k| assert!(relative(p[k], r[k]) <= 1e-12, "{p:?} {r:?}"));
        }
        let measures = |s: &lsdc::studies::workspace::WorkspaceSample| {
            [
                s.dexterity,
                s.type1_measure,
                s.type2_measure,
                s.jacobian_measure,
            ]
        };
        for (m, n) in measures(x).into_iter().zip(measures(y)) {
            match (m, n) {
                (Some(m), Some(n)) => assert!(relative(m, n) <= 1e-12, "{m} {n}"),
                (m, n) => assert_eq!(m.is_some(), n.is_some()),
            }
        }
    }
}

/// The four-bar with its bars' masses written as unknowns without a value.
fn four_bar_without_masses() -> String {
    example_text("four_bar", &[("body mass = l,", "body mass = ?m,")])
}

#[test]
fn kinematic_studies_need_no_mass_where_a_simulation_does() {
    let folder = std::env::temp_dir().join(format!("lsdc-kinematic-{}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("a scratch folder");
    let path = folder.join("four_bar_without_masses.lsd");
    std::fs::write(&path, four_bar_without_masses()).expect("written");
    let file = path.to_str().expect("a UTF-8 path");
    let (code, _, stderr) = lsdc(&["simulate", file]);
    assert_ne!(code, 0);
    assert!(stderr.contains("E0813"), "{stderr}");
    // Both studies run without the masses, and write what they write for the four-bar with
    // its masses (the example itself).
    let studies: [&[&str]; 2] = [
        &[
            "workspace",
            "--point",
            "coupler_point",
            "--actuate",
            "crank.q",
            "--range",
            "crank.q=0:3",
            "--samples",
            "8",
        ],
        &[
            "kinematics",
            "--point",
            "coupler_point",
            "--actuate",
            "crank.q",
        ],
    ];
    for study in studies {
        let with = |program: &str| {
            let mut args = vec![study[0], program];
            args.extend_from_slice(&study[1..]);
            lsdc(&args)
        };
        let (code, without_masses, stderr) = with(file);
        assert_eq!(code, 0, "{stderr}");
        let (code, with_masses, stderr) = with("examples/four_bar.lsd");
        assert_eq!(code, 0, "{stderr}");
        assert!(without_masses.lines().count() > 2, "{without_masses}");
        assert_eq!(without_masses, with_masses, "{}", study[0]);
    }
    std::fs::remove_dir_all(&folder).ok();
}
