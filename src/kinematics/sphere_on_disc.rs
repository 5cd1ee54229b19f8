//! W0820: a sphere's contact (`rolling(r)`, `sliding(r, f)`) on a body whose inertia is a thin
//! disc's, at a configuration where the disc is tilted or its joints let it tilt. A sphere's
//! contact keeps the centre at the height r whatever the body's tilt, where a disc's centre is
//! at r sin θ (θ its tilt from lying flat): a coin written with `rolling(r)` rolls on as a ball
//! would. A disc whose axis stays parallel to the plane (a wheel or a cylinder in a plane
//! motion, `examples/rolling_cylinder.lsd`) touches where a sphere would, and is not reported.

use nalgebra::Vector3;

use super::contacts::{contact_models, ContactModel};
use super::forward::{forward, Configuration};
use super::model::{constant_pose, constant_vector, KinematicModel};
use crate::diag::number::shortest;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Mechanism, RoundShape};
use crate::elab::value::BodyRef;

/// How far from a thin disc's principal moments a body's may be, as a fraction of its largest:
/// the two others equal (a body of revolution) and their sum the largest (the perpendicular
/// axis theorem of a plane lamina). A uniform disc of thickness h and radius r is off the
/// lamina by h²/(3r²): 5 % admits a coin up to 0.39 r thick (a 2 mm euro coin of radius 12 mm:
/// 0.9 %); a sphere (equal moments) is off by 100 %, a cylinder as long as its diameter by
/// 71 %.
const THIN_DISC: f64 = 0.05;

/// Below this, the disc's axis is taken as parallel to the plane (a cosine), and a joint's
/// motion as turning it nothing out of the plane (a rate per unit of the joint's rate).
const PARALLEL: f64 = 1e-9;

/// W0820 for each sphere's contact whose round body has a thin disc's inertia, tilted or free
/// to tilt at the coordinates `q` (none where the geometry has no value there: that is
/// reported otherwise).
pub fn sphere_contacts_on_discs(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    q: &[f64],
) -> Vec<Diagnostic> {
    let contacts = contact_models(mechanism, kinematics, &mut Vec::new());
    if contacts.is_empty() {
        return Vec::new();
    }
    let Ok(configuration) = forward(kinematics, q) else {
        return Vec::new();
    };
    let configuration = &configuration;
    let spheres = contacts.iter().filter(|c| c.shape == RoundShape::Sphere);
    spheres
        .filter(|contact| {
            disc_axis(mechanism, kinematics, contact.round_body).is_some_and(|axis| {
                let poses = &configuration.poses;
                let axis = poses[contact.round_body].rotation * axis;
                can_tilt(contact, configuration, &axis)
            })
        })
        .map(|contact| warning(mechanism, kinematics, contact))
        .collect()
}

/// The symmetry axis of body `number` in its frame, when its inertia is a thin disc's.
fn disc_axis(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    number: usize,
) -> Option<Vector3<f64>> {
    let id = *kinematics.topology.bodies.get(number.checked_sub(1)?)?;
    let body = mechanism.body(id);
    let unknowns = &kinematics.unknowns;
    let moments = constant_vector(body.inertia.value(), unknowns).ok()?;
    let iframe = constant_pose(body.iframe.value(), unknowns).ok()?;
    let largest = moments.imax();
    let (first, second) = (moments[(largest + 1) % 3], moments[(largest + 2) % 3]);
    let scale = moments[largest];
    let thin = (first - second).abs() <= THIN_DISC * scale
        && (first + second - scale).abs() <= THIN_DISC * scale;
    (scale > 0.0 && thin).then(|| iframe.rotation * Vector3::ith(largest, 1.0))
}

/// Whether the disc of axis `axis` (fixed axes) is tilted on the contact's plane, or a motion
/// of the joints turns its axis out of parallel with the plane: the rate of n·a is
/// (ω_disc − ω_plane)·(a × n).
fn can_tilt(contact: &ContactModel, configuration: &Configuration, axis: &Vector3<f64>) -> bool {
    let plane = configuration.poses[contact.plane_body] * contact.plane;
    let normal = plane.rotation * Vector3::z();
    if normal.dot(axis).abs() > PARALLEL {
        return true;
    }
    let tilting = axis.cross(&normal);
    let (disc, plane) = (
        &configuration.jacobian(contact.round_body),
        &configuration.jacobian(contact.plane_body),
    );
    (0..disc.ncols()).any(|column| {
        let spin = (disc.column(column) - plane.column(column))
            .fixed_rows::<3>(0)
            .into_owned();
        spin.dot(&tilting).abs() > PARALLEL * spin.norm().max(1.0)
    })
}

fn warning(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    contact: &ContactModel,
) -> Diagnostic {
    let id = kinematics.topology.bodies[contact.round_body - 1];
    let body = mechanism.body_name(BodyRef::Body(id));
    let radius = shortest(contact.radius);
    let (law, disc_law) = match contact.friction {
        None => (
            format!("rolling({radius})"),
            format!("rolling_disc({radius})"),
        ),
        Some(f) => {
            let f = shortest(f);
            (
                format!("sliding({radius}, {f})"),
                format!("sliding_disc({radius}, {f})"),
            )
        }
    };
    Diagnostic::warning(
        "W0820",
        format!("`{law}` is a sphere's contact, and `{body}` has a thin disc's inertia"),
    )
    .primary(
        contact.span,
        format!("keeps the centre of `{body}` at the height {radius} whatever its tilt"),
    )
    .help(format!(
        "for a coin or a wheel, write `{disc_law}`: it touches at the lowest point of the rim of a disc whose axis is the z axis of the join's second frame; `{law}` fits a disc only while its axis stays parallel to the plane"
    ))
}
