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
