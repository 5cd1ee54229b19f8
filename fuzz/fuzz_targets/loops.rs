//! Feeds random closed-loop mechanisms to the back end (tree, assembly, the loops' structure,
//! simulation with every integrator): planar chains of revolutes closed on the ground (four-bars
//! of any proportions, parallelograms started anywhere, flat included, trusses that cannot move)
//! and spatial loops of revolutes about random axes (most of them rigid, some overconstrained).
//! None of it may panic; a run that completes with projection leaves its loops closed.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lsdc::api::{run, Program, SettingsChanges};
use lsdc::prepare::Integrator;

/// Numbers in [lo, hi) read from the bytes, 0 once they run out.
struct Numbers<'a>(&'a [u8]);

impl Numbers<'_> {
    fn next(&mut self, lo: f64, hi: f64) -> f64 {
        let Some((&byte, rest)) = self.0.split_first() else {
            return lo;
        };
        self.0 = rest;
        lo + (hi - lo) * f64::from(byte) / 256.0
    }
}

/// A closed chain of `n` bars from the earth back to it: revolutes about z (planar) or about
/// random axes (spatial), bar lengths and initial angles from the bytes.
fn chain(numbers: &mut Numbers<'_>, n: usize, planar: bool) -> String {
    let mut text = String::from(
        "import joints ;\nimport gravity ;\nlet bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n",
    );
    let mut axis = || {
        if planar {
            "[0, 0, 1]".to_string()
        } else {
            format!(
                "[{:.3}, {:.3}, 1]",
                numbers.next(-1.0, 1.0),
                numbers.next(-1.0, 1.0)
            )
        }
    };
    let axes: Vec<String> = (0..=n).map(|_| axis()).collect();
    let lengths: Vec<f64> = (0..n).map(|_| numbers.next(0.2, 3.0)).collect();
    for (k, length) in lengths.iter().enumerate() {
        text += &format!("let b{k} = bar({length:.3}) ;\n");
        text += &format!("apply weight_in(b{k}, [0, -9.81, 0]) on b{k}.iframe ;\n");
    }
    text += &format!("join earth and b0 with revolute({}) as j0 ;\n", axes[0]);
    for k in 1..n {
        text += &format!(
            "join [{:.3}, 0, 0] ++ 1 @ b{} and b{k} with revolute({}) as j{k} ;\n",
            lengths[k - 1],
            k - 1,
            axes[k]
        );
    }
    let ground = numbers.next(0.0, 3.0);
    text += &format!(
        "join [{:.3}, 0, 0] ++ 1 @ b{} and [{ground:.3}, 0, 0] ++ 1 @ earth with revolute({}) as jn ;\n",
        lengths[n - 1],
        n - 1,
        axes[n]
    );
    let initial: Vec<String> = (0..n)
        .map(|k| format!("j{k}.q = {:.3}", numbers.next(-3.2, 3.2)))
        .collect();
    text += &format!("initial {} ;\n", initial.join(", "));
    text += &format!("initial j0.q' = {:.3} ;\n", numbers.next(-5.0, 5.0));
    text
}

fuzz_target!(|data: &[u8]| {
    let Some((&shape, rest)) = data.split_first() else {
        return;
    };
    let mut numbers = Numbers(rest);
    let n = 2 + usize::from(shape % 5);
    let planar = shape & 0x80 == 0;
    let text = chain(&mut numbers, n, planar);
    let program = Program::from_text("fuzz.lsd", &text, None, &Default::default());
    let integrator = match shape / 5 % 4 {
        0 => Integrator::Rk4,
        1 => Integrator::DormandPrince,
        2 => Integrator::Implicit,
        _ => Integrator::Symplectic,
    };
    let changes = SettingsChanges {
        integrator: Some(integrator),
        duration: Some(0.05),
        step: Some(1e-3),
        tolerance: Some(1e-8),
        ..Default::default()
    };
    let Ok(prepared) = program.prepare(&[], &changes) else {
        return;
    };
    let simulation = run(&prepared, &mut |_| {});
    if simulation.report.failure.is_none() {
        if let Some(c) = &simulation.report.constraints {
            assert!(c.position_residual < 1e-8, "loops open: {}", c.position_residual);
        }
    }
});
