//! The symbolic equations of motion against closed forms (notes §9.8) and against the numeric
//! back end.

use std::collections::HashMap;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::symbolic::{self, Equations};

fn equations(path: &str) -> Equations {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path);
    let compilation = compile_files(&[path], &LoadOptions::default()).expect("readable");
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    symbolic::generate(mechanism, &topology).expect("equations")
}

/// A deterministic pseudo-random sequence in [-1, 1).
struct Sequence(u64);

impl Sequence {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[test]
fn fixed_satellite_equals_the_closed_forms_of_section_9_8() {
    let eq = equations("examples/satellite_fixed.lsd");
    let tape = eq.tape();
    let mut random = Sequence(7);
    let (mu4, z34) = (40.0, 0.5);
    for _ in 0..20 {
        let values: HashMap<String, f64> =
            ["hinge.x", "slide.x", "tilt.x", "hinge.x'", "slide.x'", "tilt.x'", "t"].iter().map(|n| (n.to_string(), 2.0 * random.next())).collect();
        let symbols = eq.symbol_values(|n| values.get(n).copied()).expect("every symbol has a value");
        let at = eq.evaluate(&tape, &symbols);
        let (q7, q8, q9) = (values["hinge.x"], values["slide.x"], values["tilt.x"]);
        let (d7, d8, d9) = (values["hinge.x'"], values["slide.x'"], values["tilt.x'"]);
        let expected = [
            [q8 * q8 + z34 * z34 * q9.cos().powi(2), -z34 * q9.cos(), -z34 * q8 * q9.sin()],
            [-z34 * q9.cos(), 1.0, 0.0],
            [-z34 * q8 * q9.sin(), 0.0, z34 * z34],
        ];
        for i in 0..3 {
            for j in 0..3 {
                assert!((at.mass[(i, j)] - mu4 * expected[i][j]).abs() < 1e-12 * mu4, "M[{i}][{j}] = {} ≠ {}", at.mass[(i, j)], mu4 * expected[i][j]);
            }
        }
        // Lagrange's equations with q̈ = 0 give −S.
        let velocity_terms = [
            2.0 * q8 * d7 * d8 - 2.0 * z34 * z34 * q9.sin() * q9.cos() * d7 * d9 - z34 * q8 * q9.cos() * d9 * d9,
            -q8 * d7 * d7 + 2.0 * z34 * q9.sin() * d7 * d9,
            z34 * z34 * q9.sin() * q9.cos() * d7 * d7 - 2.0 * z34 * q9.sin() * d7 * d8,
        ];
        for i in 0..3 {
            assert!((at.second_member[i] + mu4 * velocity_terms[i]).abs() < 1e-12 * mu4, "S[{i}]");
        }
        let det = at.mass.determinant();
        let closed = mu4.powi(3) * q8 * q8 * z34 * z34 * q9.cos().powi(2);
        assert!((det - closed).abs() < 1e-12 * mu4.powi(3), "det M = {det} ≠ {closed}");
    }
}
