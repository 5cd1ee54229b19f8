//! Simulations against analytic solutions and conservation laws.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::simulate::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::{run, Simulation};

fn simulate(text: &str, settings: Settings) -> Simulation {
    let options = LoadOptions { library_dirs: Vec::new(), use_environment: false };
    let compilation = compile_text("test.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &settings).unwrap_or_else(|d| panic!("{d:?}"));
    let simulation = run(&prepared, &mut |_| {});
    assert!(simulation.report.failure.is_none(), "{:?}", simulation.report.failure);
    simulation
}

/// Complete elliptic integral of the first kind, K(k), by the arithmetic-geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // The mean converges quadratically; 40 rounds is far more than double precision needs, and
    // a fixed count avoids waiting for a and b to agree to the last bit.
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

#[test]
fn pendulum_period_matches_the_elliptic_integral() {
    let (g, length) = (9.81f64, 0.7f64);
    for amplitude in [0.1, 0.5, 1.0, 2.0, 3.0] {
        let period = 4.0 * (length / g).sqrt() * elliptic_k((amplitude / 2.0f64).sin());
        let text = format!(
            "import joints;\nlet bob = body mass = 1.3, iframe = [0, 0, -{length}] ++ 1, inertia = 0 end;\n\
             join earth and bob with revolute([1, 0, 0]) as swing;\n\
             apply force value = [0, 0, -{g} * bob.mass], body = earth end on bob.iframe;\n\
             initial swing.q = {amplitude};\n"
        );
        let settings = Settings { integrator: Integrator::DormandPrince, duration: 2.0 * period + period / 4.0, output: period / 4.0, rtol: 1e-14, atol: 1e-14, ..Settings::default() };
        let simulation = simulate(&text, settings);
        // At t = T/4 + k T/2 the pendulum passes the vertical: θ = 0 and the timing error is θ/θ̇.
        for sample in simulation.samples.iter().skip(1).step_by(2) {
            let timing_error = sample.coordinates[0] / sample.rates[0];
            assert!(timing_error.abs() < 1e-9 * period, "amplitude {amplitude}: t = {}, θ/θ̇ = {timing_error:e}", sample.time);
        }
    }
}
