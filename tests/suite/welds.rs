//! Welded bodies merged into their anchor (`lsdc::dynamics::welds`) against the same mechanism
//! where nothing is merged: a zero force applied on each welded body keeps it a body of its own
//! in the recursions. Motions, energies and every join's reaction must agree.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run, Simulation};

/// An arm on a revolute shoulder: a heavy sensor welded off its axis, a tool welded to the
/// sensor, and a forearm on a revolute elbow hanging from the tool. Gravity on every body.
fn arm(keep_welds: bool) -> String {
    let pin = if keep_welds {
        "apply force value = [0, 0, 0] end on sensor ;\napply force value = [0, 0, 0] end on tool ;\n"
    } else {
        ""
    };
    format!(
        "import joints ; import gravity ;
let upper = body mass = 2, iframe = [0.2, 0, 0] ++ 1, inertia = [0.01, 0.05, 0.05] end ;
let sensor = body mass = 0.7, iframe = [0.01, 0.02, -0.03] ++ (0.4 || [1, 2, 3]), inertia = [0.002, 0.003, 0.004] end ;
let tool = body mass = 0.3, iframe = [0, 0.05, 0] ++ 1, inertia = [0.001, 0.001, 0.002] end ;
let fore = body mass = 1, iframe = [0.15, 0, 0] ++ 1, inertia = [0.005, 0.02, 0.02] end ;
join earth and upper with revolute([0, 1, 0]) as shoulder ;
join [0.4, 0.1, 0] ++ (0.3 || [0, 0, 1]) @ upper and sensor with weld as mount ;
join [0, 0, 0.1] ++ (-1.1 || [1, 0, 0]) @ sensor and tool with weld as flange ;
join [0.05, 0, 0] ++ 1 @ tool and fore with revolute([0, 0, 1]) as elbow ;
apply weight(upper) on upper.iframe ; apply weight(sensor) on sensor.iframe ;
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
        "the two welds are merged"
    );
    assert_eq!(
        kept.model.dynamic_joints.len(),
        4,
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
    }
    // The weld carrying the tool and the forearm holds at least their weight.
    let last = with_merging.samples.last().expect("samples");
    let flange = 6 * 2;
    let force = (3..6)
        .map(|i| last.reactions[flange + i].powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(force > 0.5 * 1.3 * 9.80665, "{force}");
}
