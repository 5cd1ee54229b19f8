//! The modes of a linearisation: the eigenvalues λ of A (a real Schur decomposition, nalgebra's
//! Francis QR iteration), each with its natural frequency ωₙ = |λ| and damping ratio
//! ζ = −Re λ / |λ| (a pair λ = −ζωₙ ± iωₙ√(1 − ζ²) of a mass-spring-damper; a real λ has ζ = ±1,
//! and λ = 0 none).

use nalgebra::DMatrix;
use serde::Serialize;

/// Iterations of the QR algorithm per row of A before it gives up: far more than it needs.
const ITERATIONS_PER_ROW: usize = 1000;

#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Eigenvalue {
    pub re: f64,
    pub im: f64,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct Mode {
    pub eigenvalue: Eigenvalue,
    /// |λ|, rad/s.
    pub natural_frequency: f64,
    /// −Re λ / |λ|; `None` for λ = 0.
    pub damping_ratio: Option<f64>,
}

/// The eigenvalues of `a`, ordered by natural frequency then imaginary part; `None` when an
/// entry is not finite or the iteration does not converge.
pub fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<Eigenvalue>> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    if a.nrows() == 0 {
        return Some(Vec::new());
    }
    let schur = a
        .clone()
        .try_schur(f64::EPSILON, ITERATIONS_PER_ROW * a.nrows())?;
    let mut found: Vec<Eigenvalue> = schur
        .complex_eigenvalues()
        .iter()
        .map(|l| Eigenvalue { re: l.re, im: l.im })
        .collect();
    found.sort_by(|a, b| {
        let size = |l: &Eigenvalue| l.re.hypot(l.im);
        size(a).total_cmp(&size(b)).then(a.im.total_cmp(&b.im))
    });
    Some(found)
}

/// The mode of each eigenvalue.
pub fn modes(eigenvalues: &[Eigenvalue]) -> Vec<Mode> {
    eigenvalues
        .iter()
        .map(|&eigenvalue| {
            let natural_frequency = eigenvalue.re.hypot(eigenvalue.im);
            let damping_ratio =
                (natural_frequency > 0.0).then(|| -eigenvalue.re / natural_frequency);
            Mode {
                eigenvalue,
                natural_frequency,
                damping_ratio,
            }
        })
        .collect()
}
