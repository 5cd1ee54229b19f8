//! The contacts of a mechanism (`join plane and ball with rolling(r)`, `sliding(r, f)`, and a
//! disc's `rolling_disc(r)`, `sliding_disc(r, f)`), their numbers evaluated, where each touches
//! its plane, and the degrees of freedom they leave a tree: their rows in position and in
//! velocity. The rows for the equations of motion and their solve are in `dynamics::contacts`.
//!
//! A sphere of centre C and radius r touches the plane of normal n at p = C − r n. A thin disc
//! of centre C, axis a and radius r touches it at the lowest point of its rim, p = C − r u,
//! with u = (n − (n·a) a)/s the unit vector of the disc's plane closest to n and
//! s = |n − (n·a) a| = √(1 − (n·a)²) the sine of the disc's tilt from lying flat: its centre
//! is at the height r s (O'Reilly, *Intermediate Dynamics for Engineers*, 2008, §9.5, the
//! rolling disk). At s = 0 the disc lies flat and every point of its rim is lowest: the
//! contact has no point there.

use crate::diag::Diagnostic;
use crate::elab::mechanism::{Mechanism, RoundShape};
use crate::elab::value::BodyRef;
use crate::source::Span;
use nalgebra::{DMatrix, Matrix3, Vector3};
use serde::Serialize;

use super::eval::eval;
use super::forward::Configuration;
use super::mobility::rank;
use super::model::{constant_pose, KinematicModel};
use crate::spatial::{self, Pose};

/// The regularisation velocity ε of Coulomb friction, in m/s: the friction force is
/// f|λₙ| w/√(|w|² + ε²). At a slip speed |w| it is short of f|λₙ| by the fraction
/// 1 − |w|/√(|w|² + ε²) ≈ ε²/(2|w|²) (5e-13 at 1 m/s); while the tangential force needed
/// to stick is a fraction ρ < 1 of f|λₙ|, the body creeps at ε ρ/√(1 − ρ²).
pub const SLIP_REGULARISATION: f64 = 1e-6;

/// A contact of the model, numbers evaluated.
#[derive(Clone, Debug)]
pub struct ContactModel {
    /// `as name`, or `contact1`, … in declaration order.
    pub name: String,
    /// The plane's body and its frame on it: origin on the plane, z along the normal.
    pub plane_body: usize,
    pub plane: Pose,
    /// The round body and its centre frame on it.
    pub round_body: usize,
    pub centre: Pose,
    pub radius: f64,
    /// A sphere, or a disc whose axis is the z axis of `centre`.
    pub shape: RoundShape,
    /// `None` for rolling without slipping; the Coulomb coefficient of a sliding contact.
    pub friction: Option<f64>,
    /// Where its law (`rolling(...)`, …) is written.
    pub span: Span,
}

/// Where a contact's round body touches its plane, in fixed axes.
#[derive(Clone, Copy, Debug)]
pub struct Touch {
    /// The plane's axes: columns x, y (tangential) and its normal n.
    pub axes: Matrix3<f64>,
    pub centre: Vector3<f64>,
    /// The unit vector from the centre towards the contact point: −n for a sphere, −u for a
    /// disc (see the module's documentation).
    pub down: Vector3<f64>,
    /// The contact point, centre + r `down`.
    pub point: Vector3<f64>,
    /// The gap between the body and the plane: (C − O)·n − r for a sphere, (C − O)·n − r s
    /// for a disc; zero when they touch.
    pub gap: f64,
    /// A disc's axis a (the z axis of its centre frame), and s, the sine of its tilt from lying
    /// flat (0 flat, 1 upright); `None` for a sphere.
    pub disc: Option<(Vector3<f64>, f64)>,
}

impl ContactModel {
    /// The candidate rows of this contact among its three (x, y tangential, z normal).
    pub fn rows(&self) -> &'static [usize] {
        match self.friction {
            None => &[0, 1, 2],
            Some(_) => &[2],
        }
    }

    /// Where the round body touches the plane, with `plane_body` and `round_body` the fixed-axes
    /// poses of the contact's two bodies. A disc lying flat (s = 0) gives a NaN point.
    pub fn touch(&self, plane_body: &Pose, round_body: &Pose) -> Touch {
        let plane = plane_body * self.plane;
        let centre_frame = round_body * self.centre;
        let centre = centre_frame.translation.vector;
        let axes = plane.rotation.to_rotation_matrix().into_inner();
        let normal = axes.column(2).into_owned();
        let height = (centre - plane.translation.vector).dot(&normal);
        let (down, gap, disc) = match self.shape {
            RoundShape::Sphere => (-normal, height - self.radius, None),
            RoundShape::Disc => {
                let axis = centre_frame.rotation * Vector3::z();
                let in_plane = normal - normal.dot(&axis) * axis;
                let sine = in_plane.norm();
                let down = -in_plane / sine;
                (down, height - self.radius * sine, Some((axis, sine)))
            }
        };
        Touch {
            axes,
            centre,
            down,
            point: centre + self.radius * down,
            gap,
            disc,
        }
    }

    /// The rate of `touch.down` (the contact point's rate is the centre's velocity plus r times
    /// it), with `round_spin` and `plane_spin` the two bodies' angular velocities in fixed axes.
    /// A sphere's turns with the plane; a disc's, u̇ = (ẇ − u (u·ẇ))/s for w = n − (n·a) a, with
    /// ṅ = ω_plane × n and ȧ = ω_disc × a.
    pub fn down_rate(
        &self,
        touch: &Touch,
        round_spin: &Vector3<f64>,
        plane_spin: &Vector3<f64>,
    ) -> Vector3<f64> {
        let normal = touch.axes.column(2).into_owned();
        let normal_rate = plane_spin.cross(&normal);
        let Some((axis, sine)) = touch.disc else {
            return -normal_rate;
        };
        let axis_rate = round_spin.cross(&axis);
        let cosine = normal.dot(&axis);
        let cosine_rate = normal_rate.dot(&axis) + normal.dot(&axis_rate);
        let in_plane_rate = normal_rate - cosine_rate * axis - cosine * axis_rate;
        let up = -touch.down;
        -(in_plane_rate - up * up.dot(&in_plane_rate)) / sine
    }
}

/// The contacts of `mechanism`, evaluated; errors for a radius that is not positive (E0820), a
/// friction coefficient that is negative (E0821), a body that no joint places (E0822) and a
/// contact of a body with itself (E0823).
pub fn contact_models(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    errors: &mut Vec<Diagnostic>,
) -> Vec<ContactModel> {
    let mut contacts = Vec::new();
    for (index, contact) in mechanism.contacts.iter().enumerate() {
        let name = mechanism.contact_name(index);
        let Some(law) = mechanism.link(contact.link).contact() else {
            continue;
        };
        let number = |body: BodyRef| match body {
            BodyRef::Earth => Some(0),
            BodyRef::Body(id) => kinematics.topology.number_of.get(&id).copied(),
        };
        let (Some(plane_body), Some(round_body)) =
            (number(contact.first.body), number(contact.second.body))
        else {
            errors.push(
                Diagnostic::error(
                    "E0822",
                    format!("a body of the contact `{name}` is not part of the mechanism"),
                )
                .primary(contact.span, "this contact")
                .help("join both bodies to the mechanism with joints (a `free` or `planar` joint for the rolling body): a contact constrains their motion but does not place them"),
            );
            continue;
        };
        if plane_body == round_body {
            errors.push(
                Diagnostic::error(
                    "E0823",
                    format!("the contact `{name}` joins a body with itself"),
                )
                .primary(contact.span, "both frames are on the same body"),
            );
            continue;
        }
        let unknowns = &kinematics.unknowns;
        let radius = eval(&law.radius, unknowns).ok();
        let friction = law.friction.as_ref().map(|f| eval(f, unknowns).ok());
        let (Some(radius), Ok(plane), Ok(centre)) = (
            radius,
            constant_pose(&contact.first.displacement, unknowns),
            constant_pose(&contact.second.displacement, unknowns),
        ) else {
            errors.push(
                Diagnostic::error("E0820", format!("the contact `{name}` needs numbers"))
                    .primary(law.span, "its radius, or a frame it joins, has no value")
                    .help("give the radius a number (`rolling(0.1)`), or its unknowns values with `given`"),
            );
            continue;
        };
        if !(radius > 0.0 && radius.is_finite()) {
            errors.push(
                Diagnostic::error(
                    "E0820",
                    format!("the radius of the contact `{name}` is {radius}"),
                )
                .primary(law.span, "the radius must be a positive number"),
            );
            continue;
        }
        let friction = match friction {
            Some(Some(f)) if f >= 0.0 && f.is_finite() => Some(f),
            None => None,
            Some(value) => {
                let shown = value.map_or("unknown".to_string(), |f| f.to_string());
                errors.push(
                    Diagnostic::error(
                        "E0821",
                        format!("the friction coefficient of the contact `{name}` is {shown}"),
                    )
                    .primary(
                        law.span,
                        "Coulomb's coefficient must be a number, zero or positive",
                    ),
                );
                continue;
            }
        };
        contacts.push(ContactModel {
            name,
            plane_body,
            plane,
            round_body,
            centre,
            radius,
            shape: law.shape,
            friction,
            span: law.span,
        });
    }
    contacts
}

/// The degrees of freedom a tree keeps under its contacts: the normal rows constrain positions
/// (holonomic), the rolling rows velocities only (non-holonomic).
#[derive(Clone, Debug, Serialize)]
pub struct ContactMobility {
    pub contacts: usize,
    /// Independent normal rows: the holonomic constraints.
    pub holonomic_rank: usize,
    /// Independent rows of every kind (normal and rolling).
    pub velocity_rank: usize,
    /// tree dof − holonomic rank: the dimension of the configurations the contacts allow.
    pub position_dof: usize,
    /// tree dof − velocity rank: the independent velocities at a configuration.
    pub velocity_dof: usize,
    /// Mimic couplings, counted off both (`with_couplings`).
    pub couplings: usize,
}

impl ContactMobility {
    /// The degrees of freedom with `couplings` mimic joints more: each holds one coordinate of
    /// the tree to another, one holonomic row more, independent of the contacts' rows at a
    /// generic configuration (as `Mobility::with_couplings` counts them).
    pub fn with_couplings(mut self, couplings: usize) -> ContactMobility {
        self.couplings += couplings;
        self.position_dof = self.position_dof.saturating_sub(couplings);
        self.velocity_dof = self.velocity_dof.saturating_sub(couplings);
        self
    }
}

/// The contacts' rows over the coordinates' rates at `configuration`: the holonomic (normal)
/// rows, then all the candidate rows (`ContactModel::rows`).
fn contact_jacobians(
    contacts: &[ContactModel],
    configuration: &Configuration,
    columns: usize,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut normal = Vec::new();
    let mut all = Vec::new();
    for contact in contacts {
        let poses = &configuration.poses;
        let touch = contact.touch(&poses[contact.plane_body], &poses[contact.round_body]);
        let (axes, point) = (touch.axes, touch.point);
        let (round, plane) = (
            configuration.jacobian(contact.round_body),
            configuration.jacobian(contact.plane_body),
        );
        let velocity_at = |jacobian: &DMatrix<f64>, column: usize| {
            let twist = spatial::Motion::from_iterator(jacobian.column(column).iter().copied());
            spatial::linear(&spatial::shifted(&point, &twist))
        };
        for &row in contact.rows() {
            let axis = axes.column(row).into_owned();
            let entries: Vec<f64> = (0..columns)
                .map(|c| axis.dot(&(velocity_at(&round, c) - velocity_at(&plane, c))))
                .collect();
            if row == 2 {
                normal.push(entries.clone());
            }
            all.push(entries);
        }
    }
    let matrix = |rows: &[Vec<f64>]| DMatrix::from_fn(rows.len(), columns, |r, c| rows[r][c]);
    (matrix(&normal), matrix(&all))
}

/// The degrees of freedom of a tree of `tree_dof` under `contacts`, at `configuration`.
pub fn contact_mobility(
    contacts: &[ContactModel],
    configuration: &Configuration,
    tree_dof: usize,
) -> ContactMobility {
    let (normal, all) = contact_jacobians(contacts, configuration, tree_dof);
    let (holonomic_rank, velocity_rank) = (rank(&normal), rank(&all));
    ContactMobility {
        contacts: contacts.len(),
        holonomic_rank,
        velocity_rank,
        position_dof: tree_dof.saturating_sub(holonomic_rank),
        velocity_dof: tree_dof.saturating_sub(velocity_rank),
        couplings: 0,
    }
}
