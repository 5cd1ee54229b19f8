//! Welded bodies merged into their anchor (`lsdc::dynamics::welds`) against the same mechanism
//! where nothing is merged: a zero force applied on each welded body keeps it a body of its own
//! in the recursions. Motions, energies and every join's reaction must agree, a base welded to
//! earth (merged into earth: its inertia counts nowhere) included.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run, Simulation};

/// An arm on a revolute shoulder of a base bolted to earth off its origin: a heavy sensor welded
/// off the shoulder's axis, a tool welded to the sensor, and a forearm on a revolute elbow
/// hanging from the tool. Gravity on every body.
fn arm(keep_welds: bool) -> String {
    let pin = if keep_welds {
        "apply force value = [0, 0, 0] end on base ;\napply force value = [0, 0, 0] end on sensor ;\napply force value = [0, 0, 0] end on tool ;\n"
    } else {
        ""
    };
    format!(
        "import joints ; import gravity ;
let base = body mass = 5, iframe = [0, 0, 0.05] ++ 1, inertia = [0.02, 0.02, 0.03] end ;
let upper = body mass = 2, iframe = [0.2, 0, 0] ++ 1, inertia = [0.01, 0.05, 0.05] end ;
let sensor = body mass = 0.7, iframe = [0.01, 0.02, -0.03] ++ (0.4 || [1, 2, 3]), inertia = [0.002, 0.003, 0.004] end ;
let tool = body mass = 0.3, iframe = [0, 0.05, 0] ++ 1, inertia = [0.001, 0.001, 0.002] end ;
let fore = body mass = 1, iframe = [0.15, 0, 0] ++ 1, inertia = [0.005, 0.02, 0.02] end ;
join [0.2, -0.1, 0.3] ++ (0.5 || [1, 1, 0]) @ earth and base with weld as bolt ;
join [0, 0, 0.1] ++ (-0.5 || [1, 1, 0]) @ base and upper with revolute([0, 1, 0]) as shoulder ;
join [0.4, 0.1, 0] ++ (0.3 || [0, 0, 1]) @ upper and sensor with weld as mount ;
join [0, 0, 0.1] ++ (-1.1 || [1, 0, 0]) @ sensor and tool with weld as flange ;
join [0.05, 0, 0] ++ 1 @ tool and fore with revolute([0, 0, 1]) as elbow ;
apply weight(base) on base.iframe ; apply weight(upper) on upper.iframe ; apply weight(sensor) on sensor.iframe ;
apply weight(tool) on tool.iframe ; apply weight(fore) on fore.iframe ;
{pin}initial shoulder.q = 0.3, elbow.q = -0.8, shoulder.q' = 1.5 ;
simulate duration = 1, output = 0.05, tolerance = 1e-12 end ;
"
    )
}

fn prepared(keep_welds: bool) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("arm.lsd", &arm(keep_welds), None, &options);
    let mechanism = compilation
        .mechanism
        .unwrap_or_else(|| panic!("{:?}", compilation.diagnostics));
    let mut prepared = prepare(&mechanism, &[], &Settings::default())
        .unwrap_or_else(|d| panic!("{:?}", d[0].message));
    prepared.settings.reactions = true;
    prepared
}

fn simulate(keep_welds: bool) -> (Prepared, Simulation) {
    let p = prepared(keep_welds);
    let simulation = run(&p, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    (p, simulation)
}

#[test]
fn merged_welds_move_and_react_as_bodies_of_their_own() {
    let (merged, with_merging) = simulate(false);
    let (kept, without) = simulate(true);
    assert_eq!(
        merged.model.dynamic_joints.len(),
        2,
        "the three welds are merged, the bolt into earth"
    );
    assert_eq!(
        kept.model.dynamic_joints.len(),
        5,
        "efforts on the welded bodies keep them"
    );
    assert_eq!(with_merging.samples.len(), without.samples.len());
    for (a, b) in with_merging.samples.iter().zip(&without.samples) {
        let close = |x: &[f64], y: &[f64], what: &str| {
            for (k, (u, w)) in x.iter().zip(y).enumerate() {
                assert!(
                    (u - w).abs() <= 1e-9 * (1.0 + w.abs()),
                    "t = {}: {what}[{k}]: {u} vs {w}",
                    a.time
                );
            }
        };
        close(&a.coordinates, &b.coordinates, "coordinates");
        close(&a.rates, &b.rates, "rates");
        close(&a.reactions, &b.reactions, "reactions");
        assert!((a.kinetic_energy - b.kinetic_energy).abs() < 1e-9);
        let (u, w) = (a.potential_energy, b.potential_energy);
        assert!(
            (u.expect("potential") - w.expect("potential")).abs() < 1e-9,
            "{u:?} vs {w:?}"
        );
    }
    // The weld carrying the tool and the forearm holds at least their weight.
    let last = with_merging.samples.last().expect("samples");
    let flange = 6 * 3;
    let force = (3..6)
        .map(|i| last.reactions[flange + i].powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(force > 0.5 * 1.3 * 9.80665, "{force}");
}

/// A geared rotor carried by a base bolted to earth: the base is kept (earth carries no rotor)
/// and the arm moves as the example's, whose shoulder motor sits on earth itself.
#[test]
fn a_rotor_on_a_base_bolted_to_earth_keeps_the_base() {
    let example = include_str!("../../examples/geared_arm.lsd");
    let shoulder = "join [0, 0, 0.3] ++ 1 @ earth and upper with geared_revolute";
    assert!(example.contains(shoulder), "the example's shoulder");
    let bolted = example.replace(
        shoulder,
        "let base = body mass = 4, iframe = 1, inertia = [0.1, 0.1, 0.1] end ;
join [0, 0, 0.1] ++ 1 @ earth and base with weld as bolt ;
join [0, 0, 0.2] ++ 1 @ base and upper with geared_revolute",
    );
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let simulate = |text: &str| {
        let compilation = compile_text("geared_arm.lsd", text, None, &options);
        let mechanism =
            (compilation.mechanism).unwrap_or_else(|| panic!("{:?}", compilation.diagnostics));
        let prepared = prepare(&mechanism, &[], &Settings::default())
            .unwrap_or_else(|d| panic!("{:?}", d[0].message));
        let simulation = run(&prepared, &mut |_| {});
        assert!(simulation.report.failure.is_none());
        (prepared.model.dynamic_joints.len(), simulation)
    };
    let (on_earth_joints, on_earth) = simulate(example);
    let (bolted_joints, on_base) = simulate(&bolted);
    assert_eq!((on_earth_joints, bolted_joints), (2, 3), "the base is kept");
    assert_eq!(on_earth.samples.len(), on_base.samples.len());
    for (a, b) in on_earth.samples.iter().zip(&on_base.samples) {
        for (u, w) in a.coordinates.iter().zip(&b.coordinates) {
            assert!((u - w).abs() <= 1e-9, "t = {}: {u} vs {w}", a.time);
        }
    }
}
