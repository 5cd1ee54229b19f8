//! Closure of the complementary links: for a join `A on a`, `B on b` with chain D(q), the loop is
//! closed when pose(a)·A·D(q) = pose(b)·B. The residual has 6 rows per loop: the rotation error
//! of the relative rotation (its skew part, zero when the frames agree, see `RotationError`)
//! and the position difference, both in the world frame; its Jacobian is exact (not a finite
//! difference) over the coordinates of the loop's cycle, stored by loop (`ClosureJacobian`). The
//! coordinates above a loop's last common ancestor are left out of its rows: they move the whole
//! loop rigidly, so that their exact entries are zero in the rotation rows and ω × r in the
//! position rows, which vanish with the residual r (see `closure`).

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, UnitQuaternion, Vector3};

use super::eval::EvalError;
use super::forward::{forward, Configuration};
use super::model::KinematicModel;
use crate::elimination::Sparse;
use crate::spatial::{self, Twist};

pub struct Closure {
    /// 6 rows per complementary link, in link order.
    pub residual: DVector<f64>,
    /// ∂residual/∂q, 6 rows per complementary link.
    pub jacobian: ClosureJacobian,
    pub configuration: Configuration,
}

impl Closure {
    /// Largest position error and largest rotation error (skew part, ≈ angle) of loop k.
    pub fn loop_errors(&self, k: usize) -> (f64, f64) {
        let rows = self.residual.rows(6 * k, 6);
        let rotation = rows.rows(0, 3).amax();
        let position = rows.rows(3, 3).amax();
        (position, rotation)
    }
}

/// The error of a relative rotation R by angle θ about a unit axis, from its skew part
/// s = sin θ · axis: s itself within a quarter turn (θ ≤ 90°). Beyond, s shrinks back to zero
/// at a half turn, which would make a loop closed in position but turned by 180° look closed (a
/// cut revolute assembled at q + π): there the error grows on, (2 − |s|) · s / |s|, continuous
/// at 90° and 2 at a half turn.
struct RotationError {
    skew: Vector3<f64>,
    /// Beyond a quarter turn, |s| (0 at a half turn exactly).
    beyond: Option<f64>,
}

impl RotationError {
    fn of(relative: &Matrix3<f64>) -> RotationError {
        let skew = spatial::skew_vector(relative);
        let beyond = (relative.trace() < 1.0).then(|| skew.norm());
        RotationError { skew, beyond }
    }

    fn value(&self, relative: &Matrix3<f64>) -> Vector3<f64> {
        match self.beyond {
            None => self.skew,
            Some(norm) if norm > 0.0 => self.skew * (2.0 / norm - 1.0),
            // At a half turn exactly, the axis from the rotation's quaternion.
            Some(_) => {
                let rotation = Rotation3::from_matrix_unchecked(*relative);
                UnitQuaternion::from_rotation_matrix(&rotation)
                    .axis()
                    .map_or(self.skew, |axis| axis.into_inner() * 2.0)
            }
        }
    }

    /// The error's derivative, from the skew part's `d_skew`: exact but at a half turn exactly.
    fn derivative(&self, d_skew: Vector3<f64>) -> Vector3<f64> {
        match self.beyond {
            Some(norm) if norm > 0.0 => {
                let s = &self.skew;
                d_skew * (2.0 / norm - 1.0) - s * (2.0 * s.dot(&d_skew) / norm.powi(3))
            }
            _ => d_skew,
        }
    }
}

pub fn closure(model: &KinematicModel, q: &[f64]) -> Result<Closure, EvalError> {
    let configuration = forward(model, q)?;
    let loops = model.complementary();
    let nq = model.coordinate_count;
    let mut residual = DVector::zeros(6 * loops.len());
    let mut blocks = Vec::with_capacity(loops.len());
    for (k, joint) in loops.iter().enumerate() {
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (chain, subspace) = joint.chain(coordinates)?;
        let base = configuration.poses[joint.first_body] * joint.first;
        let end = base * chain;
        let target = configuration.poses[joint.second_body] * joint.second;
        let (r_end, r_target) = (
            end.rotation.to_rotation_matrix(),
            target.rotation.to_rotation_matrix(),
        );
        let (p_end, p_target) = (end.translation.vector, target.translation.vector);
        let relative = r_end.matrix().transpose() * r_target.matrix();
        let error = RotationError::of(&relative);
        let rotation_error = error.value(&relative);
        let position_error = p_target - p_end;
        for r in 0..3 {
            residual[6 * k + r] = rotation_error[r];
            residual[6 * k + 3 + r] = position_error[r];
        }
        // The loop's columns: its cycle, the coordinates moving the chain's end (the first
        // body's path to earth up to the last common ancestor, and the join's own) or the
        // target (the second body's path, as far). A coordinate above the common ancestor
        // moves both frames alike: it leaves the rotation rows at zero exactly and turns the
        // position error r, ω × r, without changing its size (so nothing assembly minimises);
        // it is left out, as the dynamics' rows leave it out (`dynamics::loops::rows`), so
        // that a loop's rows cost its cycle however deep in the tree it closes.
        let end_path = configuration.path_columns(joint.first_body);
        let target_path = configuration.path_columns(joint.second_body);
        let own = joint.offset..joint.offset + joint.coordinate_count();
        let mut columns: Vec<usize> = (end_path.iter())
            .filter(|c| target_path.binary_search(c).is_err())
            .chain(
                target_path
                    .iter()
                    .filter(|c| end_path.binary_search(c).is_err()),
            )
            .copied()
            .chain(own.clone())
            .collect();
        columns.sort_unstable();
        let mut values = DMatrix::zeros(6, columns.len());
        for (local, &c) in columns.iter().enumerate() {
            // Twists of the chain's end and of the target frame for coordinate c.
            let v_end = if own.contains(&c) {
                let column = Twist::from_column_slice(subspace.column(c - joint.offset).as_slice());
                spatial::motion_to_parent(&base, &column)
            } else if end_path.binary_search(&c).is_ok() {
                configuration.column(c)
            } else {
                Twist::zeros()
            };
            let v_target = if target_path.binary_search(&c).is_ok() {
                configuration.column(c)
            } else {
                Twist::zeros()
            };
            let dw: Vector3<f64> = spatial::angular(&v_target) - spatial::angular(&v_end);
            let d_relative = r_end.matrix().transpose() * spatial::skew(&dw) * r_target.matrix();
            let d_rotation = error.derivative(spatial::skew_vector(&d_relative));
            let d_position = spatial::point_velocity(&v_target, &p_target)
                - spatial::point_velocity(&v_end, &p_end);
            for r in 0..3 {
                values[(r, local)] = d_rotation[r];
                values[(3 + r, local)] = d_position[r];
            }
        }
        blocks.push(ClosureBlock { columns, values });
    }
    let jacobian = ClosureJacobian {
        columns: nq,
        blocks,
    };
    // An overflowing configuration has no closure error worth solving for (and no SVD).
    if !residual
        .iter()
        .chain(jacobian.blocks.iter().flat_map(|b| b.values.iter()))
        .all(|x| x.is_finite())
    {
        return Err(EvalError::NotFinite);
    }
    Ok(Closure {
        residual,
        jacobian,
        configuration,
    })
}

/// The rows of one loop over the coordinates they depend on.
#[derive(Clone, Debug)]
pub struct ClosureBlock {
    /// The coordinates, in increasing order.
    pub columns: Vec<usize>,
    /// 6 × `columns.len()`.
    pub values: DMatrix<f64>,
}

/// The closure Jacobian Φ′(q), 6 rows per loop, stored by loop over the loop's cycle: a chain of
/// m loops meeting a few coordinates each costs what its length costs, where the dense 6m × n matrix costs m n (a
/// ladder of 1,000 loops: 6,000 × 3,002 entries, nearly all zero, at every evaluation).
#[derive(Clone, Debug)]
pub struct ClosureJacobian {
    /// The coordinate count n.
    pub columns: usize,
    pub blocks: Vec<ClosureBlock>,
}

impl ClosureJacobian {
    pub fn nrows(&self) -> usize {
        6 * self.blocks.len()
    }

    pub fn ncols(&self) -> usize {
        self.columns
    }

    /// Φ′ as a dense matrix, for the small mechanisms and the decisions that need it whole.
    pub fn dense(&self) -> DMatrix<f64> {
        self.select_columns(&(0..self.columns).collect::<Vec<_>>())
    }

    /// The columns `selected` of Φ′, dense (6m × `selected.len()`).
    pub fn select_columns(&self, selected: &[usize]) -> DMatrix<f64> {
        let mut position = vec![usize::MAX; self.columns];
        for (k, &c) in selected.iter().enumerate() {
            position[c] = k;
        }
        let mut dense = DMatrix::zeros(self.nrows(), selected.len());
        for (k, block) in self.blocks.iter().enumerate() {
            for (local, &c) in block.columns.iter().enumerate() {
                if position[c] != usize::MAX {
                    dense
                        .view_mut((6 * k, position[c]), (6, 1))
                        .copy_from(&block.values.column(local));
                }
            }
        }
        dense
    }

    /// The rows as sparse vectors over the coordinates, their zero entries left out.
    pub fn sparse_rows(&self) -> Vec<Sparse> {
        let mut rows = Vec::with_capacity(self.nrows());
        for block in &self.blocks {
            for r in 0..6 {
                rows.push(
                    (block.columns.iter().enumerate())
                        .map(|(local, &c)| (c, block.values[(r, local)]))
                        .filter(|&(_, value)| value != 0.0)
                        .collect(),
                );
            }
        }
        rows
    }

    /// The columns as sparse vectors over the rows, their zero entries left out.
    pub fn sparse_columns(&self) -> Vec<Sparse> {
        let mut columns = vec![Vec::new(); self.columns];
        for (k, block) in self.blocks.iter().enumerate() {
            for (local, &c) in block.columns.iter().enumerate() {
                for r in 0..6 {
                    let value = block.values[(r, local)];
                    if value != 0.0 {
                        columns[c].push((6 * k + r, value));
                    }
                }
            }
        }
        columns
    }

    /// The largest entry in absolute value.
    pub fn amax(&self) -> f64 {
        (self.blocks.iter()).fold(0.0, |m, b| m.max(b.values.amax()))
    }

    /// Each entry (row r, column c) times `rows[r] · columns[c]`.
    pub fn scaled(&self, rows: &[f64], columns: &[f64]) -> ClosureJacobian {
        let blocks = (self.blocks.iter().enumerate())
            .map(|(k, block)| {
                let values = DMatrix::from_fn(6, block.columns.len(), |r, local| {
                    block.values[(r, local)] * rows[6 * k + r] * columns[block.columns[local]]
                });
                ClosureBlock {
                    columns: block.columns.clone(),
                    values,
                }
            })
            .collect();
        ClosureJacobian {
            columns: self.columns,
            blocks,
        }
    }

    /// (self − other) / divisor, for two Jacobians over the same loops and columns (the
    /// closure at two configurations of one mechanism).
    pub fn difference(&self, other: &ClosureJacobian, divisor: f64) -> ClosureJacobian {
        let blocks = (self.blocks.iter().zip(&other.blocks))
            .map(|(a, b)| ClosureBlock {
                columns: a.columns.clone(),
                values: (&a.values - &b.values) / divisor,
            })
            .collect();
        ClosureJacobian {
            columns: self.columns,
            blocks,
        }
    }

    /// Φ′ m for a dense m (n × k): 6m × k.
    pub fn mul_dense(&self, m: &DMatrix<f64>) -> DMatrix<f64> {
        let mut product = DMatrix::zeros(self.nrows(), m.ncols());
        for (k, block) in self.blocks.iter().enumerate() {
            // A loop over every coordinate (one loop through the whole mechanism, the
            // necklace) reads m as it is, without a copy of its rows.
            let rows = if block.columns.len() == m.nrows() {
                &block.values * m
            } else {
                &block.values * m.select_rows(&block.columns)
            };
            product.rows_mut(6 * k, 6).copy_from(&rows);
        }
        product
    }
}
