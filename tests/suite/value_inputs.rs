//! Inputs that every run applies: a value input (`input voltage = 12;`, the DC motor of
//! `examples/control/dc_motor.lsd`) gives the motion the same voltage written as a number
//! gives; set between steps of a `Simulator`, the motion of the same voltage as a sampled law
//! of time with the same switching instants; its column of `lsdc linearize`'s B is the closed
//! form b3 = 1/L; `--set` gives it its start value. A declared effort input's start value moves
//! the pendulum as the same torque applied by the program does. An unknown name is refused
//! with the run's inputs.

use lsdc::api::{
    run, Integrator, LinearizeRequest, OperatingPoint, Override, Prepared, Program, Sample,
    SettingsChanges, Simulator,
};

/// The motor's inductance, H (`examples/control/dc_motor.lsd`).
const INDUCTANCE: f64 = 1.2e-3;

/// A fixed-step run, short: the electrical transient and the start of the mechanical one.
fn fixed_step(duration: f64) -> SettingsChanges {
    SettingsChanges {
        integrator: Some(Integrator::Rk4),
        duration: Some(duration),
        output: Some(0.01),
        step: Some(1e-4),
        ..Default::default()
    }
}

fn dc_motor(replacements: &[(&str, &str)], values: &[Override], duration: f64) -> Prepared {
    let mut text = std::fs::read_to_string("examples/control/dc_motor.lsd").expect("example");
    for (from, to) in replacements {
        assert!(text.contains(from), "`{from}` not found");
        text = text.replace(from, to);
    }
    let program = Program::from_text("dc_motor.lsd", &text, None, &Default::default());
    assert!(!program.has_errors(), "{}", program.render());
    let prepared = program.prepare(values, &fixed_step(duration));
    prepared.expect("prepares")
}

/// The largest difference of the coordinates and rates of two runs' samples, relative to the
/// largest rate.
fn largest_difference(a: &[Sample], b: &[Sample]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = (a.iter().flat_map(|s| s.rates.iter())).fold(1.0f64, |m, r| m.max(r.abs()));
    let differences = a.iter().zip(b).flat_map(|(x, y)| {
        assert_eq!(x.time, y.time);
        let q = x.coordinates.iter().zip(&y.coordinates);
        let v = x.rates.iter().zip(&y.rates);
        q.chain(v).map(|(p, r)| (p - r).abs())
    });
    differences.fold(0.0, f64::max) / scale
}

#[test]
fn a_value_input_moves_the_motor_as_its_value_written_as_a_number() {
    let as_input = dc_motor(&[], &[], 0.1);
    let as_number = dc_motor(&[("input voltage = 12 ;", "let voltage = 12 ;")], &[], 0.1);
    let (with_input, with_number) = (run(&as_input, &mut |_| {}), run(&as_number, &mut |_| {}));
    assert!(with_input.report.failure.is_none());
    let difference = largest_difference(&with_input.samples, &with_number.samples);
    assert!(difference < 1e-13, "{difference:e}");
    // The arm moved: the motor's torque reached it.
    assert!(with_input.samples.last().expect("samples").rates[0] > 1.0);
    // `--set voltage=6` gives the input its start value, as `let voltage = 6` would.
    let set = Override {
        name: "voltage".to_string(),
        value: 6.0,
    };
    let six = run(&dc_motor(&[], &[set], 0.1), &mut |_| {});
    let six_written = dc_motor(&[("input voltage = 12 ;", "let voltage = 6 ;")], &[], 0.1);
    let difference = largest_difference(&six.samples, &run(&six_written, &mut |_| {}).samples);
    assert!(difference < 1e-13, "{difference:e}");
}

/// The voltage set at instants t_k = k h between the steps of a fixed-step run equals the
/// program whose voltage is a sampled state updated by the same law of time at the same
/// instants (`sample`, `update`): a zero-order hold of 12 cos(50 t_k) V, switching on the
/// steps' boundaries.
#[test]
fn a_value_input_set_between_steps_is_the_same_law_of_time_sampled_in_the_program() {
    let (period, duration) = (0.02, 0.1);
    let law = |t: f64| 12.0 * (50.0 * t).cos();
    let prepared = dc_motor(&[], &[], duration);
    let mut simulator = Simulator::new(&prepared, &[]).expect("starts");
    assert_eq!(simulator.value_input_names(), ["voltage"]);
    let mut stepped = Vec::new();
    for k in 1..=5 {
        simulator.advance_to(k as f64 * period).expect("advances");
        stepped.extend(simulator.take_samples());
        let t = simulator.time();
        simulator.set_input("voltage", law(t)).expect("an input");
        assert_eq!(simulator.value_inputs(), [law(t)]);
    }
    let (rest, report) = simulator.finish();
    assert!(report.failure.is_none(), "{:?}", report.failure);
    stepped.extend(rest);
    let sampled = dc_motor(
        &[(
            "input voltage = 12 ; (* U, V *)",
            "let voltage = sample(0.02, 12) ; update voltage = 12 * cos(50 * time) ;",
        )],
        &[],
        duration,
    );
    let in_lsd = run(&sampled, &mut |_| {});
    assert!(in_lsd.report.failure.is_none());
    let difference = largest_difference(&stepped, &in_lsd.samples);
    assert!(difference < 1e-12, "{difference:e}");
    // The law changed the motion: the run at a held 12 V differs.
    let held = run(&prepared, &mut |_| {});
    assert!(largest_difference(&held.samples, &in_lsd.samples) > 1e-3);
}

/// İ = b2 N ω + b1 I + b3 U: the voltage's column of B is b3 = 1/L in the current's row and 0
/// in the arm's, by the differences `linearize` takes of the states' rates.
#[test]
fn a_value_inputs_column_of_b_is_the_closed_form() {
    let prepared = dc_motor(&[], &[], 0.1);
    let program = Program::from_file("examples/control/dc_motor.lsd", &Default::default());
    let request = LinearizeRequest {
        point: OperatingPoint::Initial,
        inputs: Vec::new(),
        coordinates: Vec::new(),
    };
    let linear = program.expect("loads").linearize(&prepared, &request);
    let linear = linear.expect("linearises");
    assert_eq!(linear.inputs, ["voltage"]);
    assert_eq!(linear.input, [12.0]);
    let row = |name: &str| linear.states.iter().position(|s| s == name).expect(name);
    let b3 = linear.b[(row("current"), 0)];
    assert!((b3 * INDUCTANCE - 1.0).abs() < 1e-9, "{b3}");
    assert_eq!(linear.b[(row("shoulder.q'"), 0)], 0.0);
}

const PENDULUM: &str = "
    import joints;
    let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
    join earth and rod with revolute([1, 0, 0]) as swing;
    apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;
    initial swing.q = 0.3;
    simulate duration = 1, output = 0.05, integrator = dopri5, tolerance = 1e-10 end;";

fn pendulum_with(declaration: &str) -> Prepared {
    let text = format!("{PENDULUM}\n{declaration}");
    let program = Program::from_text("pendulum.lsd", &text, None, &Default::default());
    assert!(!program.has_errors(), "{}", program.render());
    program.prepare(&[], &Default::default()).expect("prepares")
}

/// `input swing.q = 0.7;`: every run holds the torque at its start value until set, the
/// motion of `apply torque value = [0.7, 0, 0]` about the joint's axis.
#[test]
fn an_effort_inputs_start_value_moves_the_pendulum_as_the_same_torque_applied() {
    let input = run(&pendulum_with("input swing.q = 0.7;"), &mut |_| {});
    let applied = pendulum_with("apply torque value = [0.7, 0, 0], body = earth end on rod;");
    let applied = run(&applied, &mut |_| {});
    let free = run(&pendulum_with(""), &mut |_| {});
    assert!(input.report.failure.is_none());
    let difference = largest_difference(&input.samples, &applied.samples);
    assert!(difference < 1e-12, "{difference:e}");
    assert!(largest_difference(&input.samples, &free.samples) > 1e-2);
}

#[test]
fn an_unknown_input_is_refused_with_the_runs_inputs() {
    let prepared = pendulum_with("input swing.q = 0; input gain = 2;");
    let mut simulator = Simulator::new(&prepared, &[]).expect("starts");
    assert_eq!(simulator.input_names(), ["swing.q"]);
    simulator
        .set_input("swing.q", 0.5)
        .expect("an effort input");
    simulator.set_input("gain", 3.0).expect("a value input");
    let refused = simulator.set_input("gian", 1.0).expect_err("no such input");
    assert_eq!(
        refused.message,
        "no input `gian`: the run's inputs are swing.q, gain; did you mean `gain`?"
    );
}
