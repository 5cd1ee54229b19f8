//! The symbolic equations of example programs, and a reproducible sequence of sample values.

use std::path::PathBuf;

use lsdc::diag::Diagnostic;
use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::symbolic::{self, Equations};

/// The equations of the program at `path`, relative to the crate's root.
pub fn equations_of(path: &str) -> Equations {
    generated(path).expect("equations")
}

/// The equations of the program at `path`, or `None` for a mechanism whose equations are
/// refused (contacts E0825, geared rotors E0826, motions imposed in time E0828;
/// `symbolic_equations` checks the refusals).
pub fn written_equations(path: &str) -> Option<Equations> {
    match generated(path) {
        Ok(equations) => Some(equations),
        Err(refused) if ["E0825", "E0826", "E0828"].contains(&refused[0].code) => None,
        Err(errors) => panic!("{path}: {errors:?}"),
    }
}

fn generated(path: &str) -> Result<Equations, Vec<Diagnostic>> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path);
    let compilation = compile_files(&[path], &LoadOptions::default()).expect("readable");
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    symbolic::generate(mechanism, &topology)
}

/// A deterministic pseudo-random sequence in [-1, 1).
pub struct Sequence(pub u64);

impl Sequence {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}
