//! What force elements cost beside the dynamics: per right-hand side, the efforts (forward
//! kinematics, declared coordinates, every effort's value) and the whole derivative, against the
//! same law written by hand in joint coordinates and against the mechanism without its elements.
//! Run with `cargo bench --bench efforts`. Times are CPU times of the timing thread (on a shared
//! virtual machine the wall clock also counts the time given to others): the best over rounds
//! of 7 batches, and the median of the last round. The ratios are the result.

mod common;
use common::cpu_time_per_call;
use std::hint::black_box;

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::system::MechanicalSystem;

fn prepared(text: &str) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text(
        "bench.lsd",
        text,
        Some(std::path::Path::new("examples")),
        &options,
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).expect("prepares")
}

/// A prepared case, ready to be timed at its initial state.
struct Case<'p> {
    name: &'static str,
    system: MechanicalSystem<'p>,
    q: Vec<f64>,
    v: Vec<f64>,
    y: Vec<f64>,
    size: usize,
    /// Best microseconds of CPU per call so far: efforts, whole right-hand side; and the
    /// medians of the last round.
    best: (f64, f64),
    median: (f64, f64),
}

impl<'p> Case<'p> {
    fn new(name: &'static str, prepared: &'p Prepared) -> Case<'p> {
        let model = &prepared.model;
        let (q, v) = model
            .state_from_declared(&prepared.coordinates, &prepared.rates)
            .expect("initial state");
        let mut y = q.clone();
        y.extend_from_slice(&v);
        let reference = prepared.coordinates.clone();
        let system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        let size = model.effort_tape.as_ref().map_or(0, |t| t.size());
        Case {
            name,
            system,
            q,
            v,
            y,
            size,
            best: (f64::INFINITY, f64::INFINITY),
            median: (0.0, 0.0),
        }
    }

    /// One more timing of each; the best is kept.
    fn time(&mut self) {
        let (system, q, v) = (&mut self.system, &self.q, &self.v);
        let efforts = cpu_time_per_call(|| {
            black_box(
                system
                    .efforts(0.1, black_box(q), black_box(v))
                    .expect("efforts"),
            );
        });
        let mut dydt = vec![0.0; self.y.len()];
        let y = &self.y;
        let derivative = cpu_time_per_call(|| {
            system
                .derivative(0.1, black_box(y), &mut dydt)
                .expect("evaluates");
        });
        self.best.0 = self.best.0.min(efforts.0 * 1e6);
        self.best.1 = self.best.1.min(derivative.0 * 1e6);
        self.median = (efforts.1 * 1e6, derivative.1 * 1e6);
    }
}

/// Rounds of timings, every case once per round, so that a slow spell of the machine falls on
/// all of them alike.
const ROUNDS: usize = 7;

/// Two bodies of 2 and 3 kg on parallel slides 1 m apart, joined by `elements`.
fn two_bodies(elements: &str) -> String {
    format!(
        "import forces ;
        let k = 150 ; let l0 = 0.8 ; let c = 4 ;
        let b1 = body mass = 2, iframe = 0, inertia = [1, 1, 1] end ;
        let b2 = body mass = 3, iframe = 0, inertia = [1, 1, 1] end ;
        join earth and b1.frame with link(x) dof = [x, 0, 0] end as s1 ;
        join [1, 0, 0] ++ 1 @ earth and b2.frame with link(x) dof = [x, 0, 0] end as s2 ;
        {elements}
        initial s1.x = 0, s2.x = 0.1, s1.x' = 0.3 ;"
    )
}

const HAND_SPRING: &str = "
    apply force value = [k * (l0 - (1 + s2.x - s1.x)), 0, 0], body = earth end on b2.frame ;
    apply force value = [-k * (l0 - (1 + s2.x - s1.x)), 0, 0], body = earth end on b1.frame ;";
const HAND_SPRING_DAMPER: &str = "
    apply force value = [k * (l0 - (1 + s2.x - s1.x)) - c * (s2.x' - s1.x'), 0, 0], body = earth end on b2.frame ;
    apply force value = [-k * (l0 - (1 + s2.x - s1.x)) + c * (s2.x' - s1.x'), 0, 0], body = earth end on b1.frame ;";
const STDLIB_SPRING: &str = "apply spring(b1, b2, k, l0) between b1 and b2 ;";
const STDLIB_SPRING_DAMPER: &str =
    "apply spring(b1, b2, k, l0) between b1 and b2 ; apply damper(b1, b2, c) between b1 and b2 ;";

/// A flyball governor: a spindle turning about z, two arms hinged on it carrying their balls, a
/// sleeve sliding on the spindle, each arm held to the sleeve by a stiff spring and a damper
/// (K = 8e5 N/m, C = 4e4 N s/m), under gravity. With `elements` false, the same mechanism
/// without its four force elements.
fn governor(elements: bool) -> String {
    let forces = if elements {
        "apply spring(ball1, sleeve, 8e5, 0.25) between ball1 and sleeve ;
        apply damper(ball1, sleeve, 4e4) between ball1 and sleeve ;
        apply spring(ball2, sleeve, 8e5, 0.25) between ball2 and sleeve ;
        apply damper(ball2, sleeve, 4e4) between ball2 and sleeve ;"
    } else {
        ""
    };
    format!(
        "import joints ; import forces ; import gravity ;
        let spindle = body mass = 2, iframe = 0, inertia = [0.02, 0.02, 0.01] end ;
        let arm1 = body mass = 1, iframe = [0, 0, -0.3] ++ 1, inertia = [0.01, 0.01, 0.001] end ;
        let arm2 = body mass = 1, iframe = [0, 0, -0.3] ++ 1, inertia = [0.01, 0.01, 0.001] end ;
        let sleeve = body mass = 0.5, iframe = 0, inertia = [0.002, 0.002, 0.002] end ;
        let ball1 = [0, 0, -0.3] ++ 1 @ arm1 ;
        let ball2 = [0, 0, -0.3] ++ 1 @ arm2 ;
        join earth and spindle with revolute([0, 0, 1]) as spin ;
        join [0.05, 0, 0.6] ++ 1 @ spindle and arm1 with revolute([0, 1, 0]) as hinge1 ;
        join [-0.05, 0, 0.6] ++ 1 @ spindle and arm2 with revolute([0, 1, 0]) as hinge2 ;
        join spindle and sleeve with prismatic([0, 0, 1]) as collar ;
        {forces}
        apply gravity_field ;
        initial spin.q' = 10, hinge1.q = -0.5, hinge2.q = 0.5, collar.q = 0.2 ;"
    )
}

/// The elastic pendulum example, or the same mechanism without its spring-damper and torsion
/// spring-damper (its weight kept).
fn elastic_pendulum(elements: bool) -> String {
    let text = std::fs::read_to_string("examples/elastic_pendulum.lsd").expect("example");
    if elements {
        return text;
    }
    text.lines()
        .filter(|l| !l.starts_with("apply force value = (k") && !l.starts_with("apply torque"))
        .collect::<Vec<_>>()
        .join("\n")
}

fn main() {
    let texts = [
        ("two bodies: spring by hand", two_bodies(HAND_SPRING)),
        ("two bodies: stdlib spring", two_bodies(STDLIB_SPRING)),
        (
            "two bodies: spring + damper by hand",
            two_bodies(HAND_SPRING_DAMPER),
        ),
        (
            "two bodies: stdlib spring + damper",
            two_bodies(STDLIB_SPRING_DAMPER),
        ),
        ("elastic pendulum", elastic_pendulum(true)),
        (
            "elastic pendulum without its elements",
            elastic_pendulum(false),
        ),
        ("governor, 2 springs + 2 dampers", governor(true)),
        ("governor without its elements", governor(false)),
    ];
    let prepared: Vec<(&'static str, Prepared)> = texts
        .iter()
        .map(|(name, text)| (*name, self::prepared(text)))
        .collect();
    let mut cases: Vec<Case> = prepared
        .iter()
        .map(|(name, p)| Case::new(name, p))
        .collect();
    for _ in 0..ROUNDS {
        cases.iter_mut().for_each(Case::time);
    }
    println!(
        "{:<40} {:>11} {:>11} {:>7}  (CPU time; best, median of the last round)",
        "case", "efforts µs", "RHS µs", "nodes"
    );
    for case in &cases {
        println!(
            "{:<40} {:>11.3} {:>11.3} {:>7}  ({:.3}, {:.3})",
            case.name, case.best.0, case.best.1, case.size, case.median.0, case.median.1
        );
    }
    let best = |k: usize| cases[k].best;
    println!("\nratios (best of {ROUNDS} rounds each):");
    // (label, case, baseline, whether the whole RHS or the efforts alone are compared)
    let ratios = [
        ("stdlib spring / by hand, efforts", 1, 0, false),
        ("stdlib spring + damper / by hand, efforts", 3, 2, false),
        ("elastic pendulum / without elements, RHS", 4, 5, true),
        ("governor / without elements, RHS", 6, 7, true),
    ];
    for (label, case, baseline, whole) in ratios {
        let pick = |k: usize| if whole { best(k).1 } else { best(k).0 };
        println!(
            "  {:<44} {:.2}",
            format!("{label}:"),
            pick(case) / pick(baseline)
        );
    }
}
