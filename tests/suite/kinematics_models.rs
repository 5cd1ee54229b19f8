//! `lsdc kinematics` on the Delta ISIR88 (examples/delta_isir88.lsd, full model with its 6 idle
//! rod spins) against the seed's closed forms (notes on the Delta seed, §3.3 and §4.1; table
//! T8), central differences of the forward geometric model and second differences of the
//! closed-form inverse geometric model.

use lsdc::kinematics::forward::forward;
use lsdc::prepare::Prepared;
use lsdc::studies::configurations::{close_from, Declared, StateRequest};
use lsdc::studies::kinematic_models::{
    actuation, models_at, Actuation, KinematicModels, Output, OutputKind, SINGULAR_TOLERANCE,
};
use nalgebra::{Matrix3, Vector3};

use crate::common::programs::{mechanism, prepared};

const L1: f64 = 0.200;
const L2: f64 = 0.300;
const R: f64 = 0.126;
const PHI: [f64; 3] = [
    0.0,
    2.0 * std::f64::consts::PI / 3.0,
    4.0 * std::f64::consts::PI / 3.0,
];

/// The seed's inverse geometric model (§3.3, with its fixes), branch α = β − δ.
pub fn igm(p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::from_fn(|i, _| igm_branches(p, i)[0])
}

/// Chain i's two arm angles reaching p: β − δ (the seed's branch) and β + δ (III.15).
fn igm_branches(p: &Vector3<f64>, i: usize) -> [f64; 2] {
    let (s, c) = PHI[i].sin_cos();
    let (x, y, z) = (c * p.x + s * p.y, -s * p.x + c * p.y, p.z);
    let e2 = L2 * L2 - y * y;
    let ab = (z * z + (x - R).powi(2)).sqrt();
    let beta = (-z).atan2(x - R);
    let delta = ((L1 * L1 + ab * ab - e2) / (2.0 * L1 * ab)).acos();
    [beta - delta, beta + delta]
}

/// The seed's inverse Jacobian J (α̇ = J·Ṗ), §4.1 with its fixes: row i is G_αi·Rz(φ_i)ᵀ.
fn inverse_jacobian(p: &Vector3<f64>) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for i in 0..3 {
        let (s, c) = PHI[i].sin_cos();
        let (x, y, z) = (c * p.x + s * p.y, -s * p.x + c * p.y, p.z);
        let ab = (z * z + (x - R).powi(2)).sqrt();
        let e2 = L2 * L2 - y * y;
        let delta = ((L1 * L1 + ab * ab - e2) / (2.0 * L1 * ab)).acos();
        let d = L1 * ab * delta.sin();
        let bh = ab - L1 * delta.cos();
        let g = [
            z / (ab * ab) + bh * (x - R) / (d * ab),
            y / d,
            -(x - R) / (ab * ab) + bh * z / (d * ab),
        ];
        // P_i = Rz(φ)ᵀ P: ∂α/∂P = G · Rz(φ)ᵀ.
        j[(i, 0)] = g[0] * c - g[1] * s;
        j[(i, 1)] = g[0] * s + g[1] * c;
        j[(i, 2)] = g[2];
    }
    j
}

/// The Delta example with its arms actuated and the nacelle as output.
pub struct Delta {
    pub prepared: Prepared,
    pub output: Output,
    pub actuation: Actuation,
}

pub fn delta() -> Delta {
    let prepared = prepared("delta_isir88", &[]);
    let frame = lsdc::kinematics::frames::resolve(
        &mechanism("delta_isir88", &[]),
        &prepared.kinematics,
        "nacelle",
    )
    .expect("the nacelle is a body");
    let names = ["A1.q", "A2.q", "A3.q"].map(String::from);
    let actuation = actuation(&prepared, &names).expect("the arms' coordinates");
    let output = Output {
        frame,
        kind: OutputKind::Point,
    };
    Delta {
        prepared,
        output,
        actuation,
    }
}

impl Delta {
    fn close(&self, start: &[f64], request: StateRequest) -> Result<Declared, String> {
        close_from(&self.prepared, start, &request, &self.output.frame)
    }

    fn at_point(&self, start: &[f64], p: [f64; 3]) -> Result<Declared, String> {
        let request = StateRequest {
            point: Some(p),
            ..Default::default()
        };
        self.close(start, request)
    }

    /// The nacelle's position at a configuration.
    fn position(&self, declared: &Declared) -> Vector3<f64> {
        let configuration = forward(&self.prepared.kinematics, &declared.coordinates).expect("");
        (self.output.frame.pose(&configuration)).translation.vector
    }

    fn models(&self, declared: &Declared, rates: &[f64]) -> KinematicModels {
        let model = &self.prepared.model;
        let (q, _) = model
            .state_from_declared(&declared.coordinates, &declared.rates)
            .expect("a state");
        models_at(
            model,
            &self.actuation,
            &self.output,
            &q,
            rates,
            SINGULAR_TOLERANCE,
        )
        .expect("the models")
    }
}

fn matrix(rows: &[Vec<f64>]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| rows[r][c])
}

fn relative(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

#[test]
fn kinematics_delta_inverse_jacobian_is_the_seeds_t8() {
    let delta = delta();
    let start = delta.prepared.coordinates.clone();
    // T8's three positions, its printed rows (5 decimals) and determinants.
    let printed = [
        (
            [0.0, 0.0, -0.300],
            [
                [-4.41158, 0.0, -2.56726],
                [2.20579, -3.82054, -2.56726],
                [2.20579, 3.82054, -2.56726],
            ],
            -129.811,
        ),
        (
            [0.05, 0.05, -0.300],
            [
                [-4.12970, 0.87727, -3.14355],
                [3.19106, -3.13918, -2.73207],
                [2.56539, 3.83212, -1.95790],
            ],
            -133.043,
        ),
        (
            [0.0, 0.0, -0.250],
            [
                [-5.09491, 0.0, -2.17244],
                [2.54745, -4.41232, -2.17244],
                [2.54745, 4.41232, -2.17244],
            ],
            -146.511,
        ),
    ];
    for (p, rows, determinant) in printed {
        let declared = delta.at_point(&start, p).expect("reachable");
        let reached = delta.position(&declared);
        assert!(
            (reached - Vector3::from(p)).norm() < 1e-9,
            "{reached} for {p:?}"
        );
        let models = delta.models(&declared, &[0.0; 3]);
        let inverse = matrix(&models.inverse);
        // The closed form at the configuration reached: 1e-9 relative.
        let closed = inverse_jacobian(&reached);
        let error = relative(&inverse, &closed);
        assert!(
            error < 1e-9,
            "J at {p:?}: {error:e} from the closed form\n{inverse}{closed}"
        );
        // The seed's printed digits.
        let table = Matrix3::from_fn(|r, c| rows[r][c]);
        assert!(
            (inverse - table).amax() < 6e-6,
            "{inverse} against T8 {table}"
        );
        assert!((inverse.determinant() - determinant).abs() < 1e-3);
        // The arms' angles are the seed's inverse geometric model (branch β − δ).
        let arms: Vec<f64> = ["A1.q", "A2.q", "A3.q"]
            .iter()
            .map(|n| {
                declared.coordinates[delta
                    .prepared
                    .coordinate_names
                    .iter()
                    .position(|c| c == n)
                    .expect("")]
            })
            .collect();
        let expected = igm(&reached);
        assert!((Vector3::from_vec(arms) - expected).amax() < 1e-9);
        // The direct model is its inverse; the conditioning is that of the inverse.
        let direct = matrix(&models.direct);
        assert!((direct * inverse - Matrix3::identity()).amax() < 1e-12);
        assert!(models.singularity.kind.is_none());
        assert_eq!(
            (models.motions, models.idle_motions),
            (9, 6),
            "3 motions and 6 rod spins"
        );
    }
}

#[test]
fn kinematics_delta_direct_jacobian_matches_central_differences_of_the_forward_model() {
    let delta = delta();
    let start = delta.prepared.coordinates.clone();
    let names = ["A1.q", "A2.q", "A3.q"];
    let held = |alpha: [f64; 3]| {
        let request = StateRequest {
            coordinates: names.iter().map(|n| n.to_string()).zip(alpha).collect(),
            ..Default::default()
        };
        delta.close(&start, request).expect("assembles")
    };
    let alpha = [40f64.to_radians(); 3];
    let declared = held(alpha);
    let direct = matrix(&delta.models(&declared, &[0.0; 3]).direct);
    // T8's forward Jacobian at α = 40° × 3 (printed to 6 decimals).
    let t8 = Matrix3::new(
        -0.125849, 0.062924, 0.062924, 0.0, -0.108988, 0.108988, -0.160100, -0.160100, -0.160100,
    );
    assert!((direct - t8).amax() < 1e-6, "{direct}");
    // The inverse of the closed form at the position reached.
    let closed = inverse_jacobian(&delta.position(&declared))
        .try_inverse()
        .expect("regular");
    assert!(relative(&direct, &closed) < 1e-9, "{direct}{closed}");
    // Central differences of the forward geometric model (assembly with the arms held).
    let h = 1e-5;
    let differences = Matrix3::from_fn(|r, c| {
        let moved = |sign: f64| {
            let mut a = alpha;
            a[c] += sign * h;
            delta.position(&held(a))[r]
        };
        (moved(1.0) - moved(-1.0)) / (2.0 * h)
    });
    assert!(
        relative(&direct, &differences) < 1e-8,
        "{direct}{differences}"
    );
}

#[test]
fn kinematics_delta_acceleration_terms_match_second_differences_of_the_inverse_model() {
    let delta = delta();
    let start = delta.prepared.coordinates.clone();
    let declared = delta
        .at_point(&start, [0.05, 0.05, -0.3])
        .expect("reachable");
    let p = delta.position(&declared);
    let velocity = Vector3::new(0.1, -0.2, 0.3);
    let at_rest = delta.models(&declared, &[0.0; 3]);
    let rates = matrix(&at_rest.inverse) * velocity;
    let models = delta.models(&declared, rates.as_slice());
    // The nacelle moves at the velocity asked for.
    let moving = Vector3::from_vec(models.output_rates.clone());
    assert!((moving - velocity).amax() < 1e-12, "{moving}");
    // Along P(t) = P + t Ṗ (no acceleration), α̈ is the inverse model's term H·α̇.
    let h = 1e-4;
    let second = (igm(&(p + h * velocity)) - 2.0 * igm(&p) + igm(&(p - h * velocity))) / (h * h);
    let term = Vector3::from_vec(models.inverse_acceleration_term.clone());
    assert!(
        (term - second).amax() < 1e-6 * second.amax(),
        "{term} against {second}"
    );
    // The direct model's term is the nacelle's acceleration when the arms do not accelerate.
    let direct_term = Vector3::from_vec(models.direct_acceleration_term.clone());
    let expected = -matrix(&models.direct) * term;
    assert!((direct_term - expected).amax() < 1e-9 * expected.amax());
}
