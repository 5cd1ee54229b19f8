//! The planar drag with penalty joints: each body of a planar mechanism has three coordinates
//! (X, Y, Θ: its reference point and angle in the fixed plane), each pivot is a stiff spring
//! K_L pulling its two points together, and the dragged point is pulled towards the target by
//! a spring K_M ≪ K_L. By virtual work, the quasi-static configuration makes the springs'
//! energy stationary; with the trigonometric terms linearised about the previous configuration
//! each move is one symmetric linear solve K Δu = f.
//!
//! For a point A of body i with local coordinates (a, b), A = O_i + R(Θ_i)(a, b), and its
//! linearisation about Θ_i^p has the rows
//! `∂A/∂(X_i, Y_i, Θ_i) = [1, 0, −cv_i; 0, 1, −cw_i]`, cv_i = a sin Θ_i^p + b cos Θ_i^p,
//! cw_i = −a cos Θ_i^p + b sin Θ_i^p. A spring k between A on body i and B on body j has the
//! gap g = A − B ≈ g^p + G Δu with G = [∂A/∂u_i, −∂B/∂u_j], and adds k GᵀG to K and −k Gᵀg^p
//! to f: written out on x0 these are the blocks `[−K_L, 0, K_L cv_i, K_L, 0, −K_L cv_j; …]`
//! of the virtual work on body i, with the reaction −F on body j's virtual displacement.
//! Earth's coordinates are fixed (the blocking term), so it has no columns.

use nalgebra::{DMatrix, DVector, Vector2, Vector3};

use super::forward::forward;
use super::frames::FramePoint;
use super::model::{KinematicModel, SingleMotion};
use crate::spatial::Pose;

/// A pivot: the point `first` of body `first_body` is pinned to the point `second` of body
/// `second_body` (0 = earth), both in their body's coordinates.
#[derive(Clone, Debug)]
pub struct Pivot {
    pub first_body: usize,
    pub first: Vector2<f64>,
    pub second_body: usize,
    pub second: Vector2<f64>,
}

/// A planar mechanism of pivots: what the penalty method sees of a kinematic model.
#[derive(Clone, Debug)]
pub struct PlanarModel {
    pub bodies: usize,
    pub pivots: Vec<Pivot>,
    pub body_names: Vec<String>,
}

/// The configuration: (X, Y, Θ) of each body but earth (body j at index j − 1).
pub type PlanarState = Vec<[f64; 3]>;

#[derive(Clone, Copy, Debug)]
pub struct Stiffness {
    /// K_L, of the pivots.
    pub link: f64,
    /// K_M, of the spring to the target.
    pub mouse: f64,
}

/// The point dragged: on body `body`, at `local` in its coordinates.
#[derive(Clone, Copy, Debug)]
pub struct PlanarPoint {
    pub body: usize,
    pub local: Vector2<f64>,
}

/// The pivots of a kinematic model made only of revolutes about z between frames of the plane;
/// otherwise, why the penalty method cannot handle it.
pub fn planar_model(
    model: &KinematicModel,
    body_names: Vec<String>,
) -> Result<PlanarModel, String> {
    let mut pivots = Vec::new();
    for joint in &model.joints {
        let about_z = matches!(joint.single_motion(), Some(SingleMotion::Rotation { axis, .. })
            if axis.x == 0.0 && axis.y == 0.0);
        if !about_z || !in_plane(&joint.first) || !in_plane(&joint.second) {
            return Err(format!(
                "`{}` is not a pivot about z between frames of the plane: the penalty method handles planar mechanisms of pivots (revolutes about z)",
                joint.name
            ));
        }
        pivots.push(Pivot {
            first_body: joint.first_body,
            first: joint.first.translation.vector.xy(),
            second_body: joint.second_body,
            second: joint.second.translation.vector.xy(),
        });
    }
    Ok(PlanarModel {
        bodies: model.topology.body_count(),
        pivots,
        body_names,
    })
}

/// A frame on a body turned only about z: planar.
fn in_plane(pose: &Pose) -> bool {
    let axis = pose.rotation.scaled_axis();
    axis.x.abs() < 1e-12 && axis.y.abs() < 1e-12
}

/// The planar state of the configuration `q` of the kinematic model.
pub fn planar_state(
    model: &KinematicModel,
    q: &[f64],
) -> Result<PlanarState, super::eval::EvalError> {
    let configuration = forward(model, q)?;
    Ok(configuration.poses[1..]
        .iter()
        .map(|pose| {
            let r = pose.rotation.to_rotation_matrix();
            let t = pose.translation.vector;
            [t.x, t.y, r[(1, 0)].atan2(r[(0, 0)])]
        })
        .collect())
}

/// The dragged frame as a planar point.
pub fn planar_point(frame: &FramePoint) -> PlanarPoint {
    PlanarPoint {
        body: frame.body,
        local: frame.offset.translation.vector.xy(),
    }
}

impl PlanarModel {
    /// Position of a body's point in the fixed plane.
    pub fn position(&self, state: &PlanarState, body: usize, local: &Vector2<f64>) -> Vector2<f64> {
        if body == 0 {
            return *local;
        }
        let [x, y, angle] = state[body - 1];
        let (sin, cos) = angle.sin_cos();
        Vector2::new(
            x + cos * local.x - sin * local.y,
            y + sin * local.x + cos * local.y,
        )
    }

    /// The 2 × 3 rows of ∂A/∂(X, Y, Θ) of a body's point, linearised at `state`.
    fn point_rows(state: &PlanarState, body: usize, local: &Vector2<f64>) -> [[f64; 3]; 2] {
        let (sin, cos) = state[body - 1][2].sin_cos();
        let cv = local.x * sin + local.y * cos;
        let cw = -local.x * cos + local.y * sin;
        [[1.0, 0.0, -cv], [0.0, 1.0, -cw]]
    }

    /// Adds a spring `k` between two points (a point of earth, body 0, is fixed) to K and f.
    fn add_spring(
        &self,
        state: &PlanarState,
        k: f64,
        ends: [(usize, Vector2<f64>); 2],
        matrix: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) {
        let [(body_a, a), (body_b, b)] = ends;
        let gap = self.position(state, body_a, &a) - self.position(state, body_b, &b);
        // The gap's rows: +∂A/∂u_a, −∂B/∂u_b, by column index.
        let mut rows: Vec<(usize, [f64; 2])> = Vec::new();
        for (body, local, sign) in [(body_a, a, 1.0), (body_b, b, -1.0)] {
            if body == 0 {
                continue;
            }
            let [x_row, y_row] = Self::point_rows(state, body, &local);
            let columns = x_row.iter().zip(&y_row).enumerate();
            rows.extend(columns.map(|(c, (x, y))| (3 * (body - 1) + c, [sign * x, sign * y])));
        }
        for &(i, gi) in &rows {
            force[i] -= k * (gi[0] * gap.x + gi[1] * gap.y);
            for &(j, gj) in &rows {
                matrix[(i, j)] += k * (gi[0] * gj[0] + gi[1] * gj[1]);
            }
        }
    }

    /// The linear system K Δu = f of one move: pivots of stiffness K_L, the point pulled
    /// towards `target` by K_M, linearised at `state`.
    pub fn system(
        &self,
        state: &PlanarState,
        point: &PlanarPoint,
        target: &Vector2<f64>,
        stiffness: Stiffness,
    ) -> (DMatrix<f64>, DVector<f64>) {
        let n = 3 * self.bodies;
        let mut matrix = DMatrix::zeros(n, n);
        let mut force = DVector::zeros(n);
        for pivot in &self.pivots {
            let ends = [
                (pivot.first_body, pivot.first),
                (pivot.second_body, pivot.second),
            ];
            self.add_spring(state, stiffness.link, ends, &mut matrix, &mut force);
        }
        // The target is a fixed point: a point of earth.
        let ends = [(point.body, point.local), (0, *target)];
        self.add_spring(state, stiffness.mouse, ends, &mut matrix, &mut force);
        (matrix, force)
    }

    /// One move: the linearised system solved once. A mechanism whose free motions the target
    /// does not hold (mobility above 2) leaves K singular; a damping of 1e-10 K_M on every
    /// coordinate then picks the smallest motion.
    pub fn step(
        &self,
        state: &PlanarState,
        point: &PlanarPoint,
        target: &Vector2<f64>,
        stiffness: Stiffness,
    ) -> PlanarState {
        let (mut matrix, force) = self.system(state, point, target, stiffness);
        for i in 0..matrix.nrows() {
            matrix[(i, i)] += 1e-10 * stiffness.mouse;
        }
        let Some(step) = matrix.cholesky().map(|c| c.solve(&force)) else {
            return state.clone();
        };
        state
            .iter()
            .enumerate()
            .map(|(j, u)| {
                [
                    u[0] + step[3 * j],
                    u[1] + step[3 * j + 1],
                    u[2] + step[3 * j + 2],
                ]
            })
            .collect()
    }

    /// The largest distance between the two points of a pivot.
    pub fn largest_gap(&self, state: &PlanarState) -> f64 {
        self.pivots
            .iter()
            .map(|p| self.gap(state, p).norm())
            .fold(0.0, f64::max)
    }

    fn gap(&self, state: &PlanarState, pivot: &Pivot) -> Vector2<f64> {
        self.position(state, pivot.first_body, &pivot.first)
            - self.position(state, pivot.second_body, &pivot.second)
    }

    /// The springs' energy: ½ K_L Σ gap² + ½ K_M |A − M|².
    pub fn energy(
        &self,
        state: &PlanarState,
        point: &PlanarPoint,
        target: &Vector2<f64>,
        stiffness: Stiffness,
    ) -> f64 {
        let links: f64 = self
            .pivots
            .iter()
            .map(|p| self.gap(state, p).norm_squared())
            .sum();
        let mouse = (self.position(state, point.body, &point.local) - target).norm_squared();
        0.5 * stiffness.link * links + 0.5 * stiffness.mouse * mouse
    }
}

/// The dragged point's position in the fixed frame, as a 3-vector (z = 0).
pub fn point_position(
    model: &PlanarModel,
    state: &PlanarState,
    point: &PlanarPoint,
) -> Vector3<f64> {
    let p = model.position(state, point.body, &point.local);
    Vector3::new(p.x, p.y, 0.0)
}
