//! Joint analysis: what a link's dof chain is (revolute, prismatic, …, or general), its degrees
//! of freedom (the rank of its motion subspace at a generic configuration) and its degree of
//! constraint (6 − DOF).

use nalgebra::{DMatrix, Matrix3, Vector3};
use serde::Serialize;

use super::eval::EvalError;
use super::mobility::rank;
use super::model::JointModel;
use crate::spatial::{angular, linear, Twist};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    Weld,
    Revolute,
    Prismatic,
    Helical,
    Cylindrical,
    Universal,
    Spherical,
    Planar,
    /// Translations only (two or three directions).
    Translational,
    Free,
    General,
}

#[derive(Clone, Debug, Serialize)]
pub struct JointAnalysis {
    pub kind: JointKind,
    pub coordinates: usize,
    pub dof: usize,
    pub constraint: usize,
}

/// A generic configuration: coordinates no rational design would pick.
pub(crate) fn generic_coordinates(n: usize) -> Vec<f64> {
    (0..n).map(|i| 0.3719 + 0.2113 * i as f64).collect()
}

pub fn analyse(joint: &JointModel) -> Result<JointAnalysis, EvalError> {
    let n = joint.coordinate_count();
    let (_, subspace) = joint.chain(&generic_coordinates(n))?;
    // A rheonomic chain's hidden coordinates are imposed, not freedoms: its declared ones at
    // a generic instant.
    let subspace = subspace.columns(0, joint.declared_count()).into_owned();
    let dof = rank(&subspace);
    let kind = classify(&subspace, dof);
    Ok(JointAnalysis {
        kind,
        coordinates: joint.declared_count(),
        dof,
        constraint: 6 - dof,
    })
}

fn columns(subspace: &DMatrix<f64>) -> Vec<Twist> {
    (0..subspace.ncols())
        .map(|k| Twist::from_column_slice(subspace.column(k).as_slice()))
        .collect()
}

fn angular_rank(twists: &[Twist]) -> usize {
    let m = DMatrix::from_fn(3, twists.len(), |r, c| angular(&twists[c])[r]);
    rank(&m)
}

/// Whether some point stays still under every twist (rotations about axes through one point).
fn common_fixed_point(twists: &[Twist]) -> bool {
    // Point c with v_k + ω_k × c = 0, i.e. [ω_k]× c = v_k, in the least-squares sense.
    let mut a = DMatrix::zeros(3 * twists.len(), 3);
    let mut b = nalgebra::DVector::zeros(3 * twists.len());
    for (k, t) in twists.iter().enumerate() {
        let w = angular(t);
        let hat = Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0);
        a.view_mut((3 * k, 0), (3, 3)).copy_from(&hat);
        b.rows_mut(3 * k, 3).copy_from(&linear(t));
    }
    let Some(c) =
        crate::linalg::svd(a.clone(), true, true).and_then(|svd| svd.solve(&b, 1e-12).ok())
    else {
        return false;
    };
    (a * c - b).amax() < 1e-9
}

fn classify(subspace: &DMatrix<f64>, dof: usize) -> JointKind {
    let twists = columns(subspace);
    let rotations = angular_rank(&twists);
    let tolerance = 1e-9;
    match (dof, rotations) {
        (0, _) => JointKind::Weld,
        (6, _) => JointKind::Free,
        (1, 0) => JointKind::Prismatic,
        (1, _) => {
            let t = twists
                .iter()
                .find(|t| angular(t).norm() > tolerance)
                .copied()
                .unwrap_or_else(Twist::zeros);
            let w = angular(&t);
            let pitch = w.dot(&linear(&t)) / w.norm_squared();
            if pitch.abs() < tolerance {
                JointKind::Revolute
            } else {
                JointKind::Helical
            }
        }
        (2 | 3, 0) => JointKind::Translational,
        (2, 1) => {
            // Rotation about an axis plus translation along the same axis.
            let axis = twists
                .iter()
                .map(angular)
                .find(|w| w.norm() > tolerance)
                .map(|w| w.normalize());
            let along = axis.map(|a| spans(subspace, &Twist::new(0.0, 0.0, 0.0, a.x, a.y, a.z)));
            if along == Some(true) {
                JointKind::Cylindrical
            } else {
                JointKind::General
            }
        }
        (2, 2) if common_fixed_point(&twists) => JointKind::Universal,
        (3, 3) if common_fixed_point(&twists) => JointKind::Spherical,
        (3, 1) => {
            let normal = twists
                .iter()
                .map(angular)
                .find(|w| w.norm() > tolerance)
                .map(|w| w.normalize());
            let in_plane = |v: Vector3<f64>| normal.is_some_and(|n| n.dot(&v).abs() < tolerance);
            if twists.iter().all(|t| in_plane(linear(t))) {
                JointKind::Planar
            } else {
                JointKind::General
            }
        }
        _ => JointKind::General,
    }
}

/// Whether twist `t` lies in the column span of `subspace`.
fn spans(subspace: &DMatrix<f64>, t: &Twist) -> bool {
    let mut extended = DMatrix::zeros(6, subspace.ncols() + 1);
    extended
        .columns_mut(0, subspace.ncols())
        .copy_from(subspace);
    extended.column_mut(subspace.ncols()).copy_from(t);
    rank(&extended) == rank(subspace)
}
