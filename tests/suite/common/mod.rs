//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod programs;
pub mod symbolic;
pub mod trees;

/// The largest |a_i − b_i| over two vectors of the same length.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The first C compiler found: `CC`, `cc`, `gcc`, `clang`.
pub fn c_compiler() -> Option<String> {
    let candidates = std::env::var("CC")
        .into_iter()
        .chain(["cc", "gcc", "clang"].map(String::from));
    candidates.into_iter().find(|c| {
        std::process::Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}
