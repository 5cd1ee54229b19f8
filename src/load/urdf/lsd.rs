//! Writing LSD text: numbers, vectors, rotations, frames and comments.

use nalgebra::Vector3;
use urdf_rs::Pose;

use crate::diag::number::shortest as number;

pub(super) fn count(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// A program comment around `text`, in which `(*` or `*)` would open or close a comment.
pub(super) fn comment(text: &str) -> String {
    format!("(* {} *)", text.replace("(*", "( *").replace("*)", "* )"))
}

pub(super) fn vector(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", number(v[0]), number(v[1]), number(v[2]))
}

/// `(angle || axis)`, in parentheses as `||` binds more loosely than `++`, `@` and `*`.
pub(super) fn factor(angle: f64, axis: Vector3<f64>) -> String {
    format!("({} || {})", number(angle), vector(axis.into()))
}

/// URDF's roll, pitch, yaw, fixed axes x, y, z: the rotation Rz(yaw) · Ry(pitch) · Rx(roll), as
/// LSD factors, leaving out zero angles.
pub(super) fn rpy_factors(rpy: &[f64; 3]) -> Vec<String> {
    [
        (rpy[2], Vector3::z()),
        (rpy[1], Vector3::y()),
        (rpy[0], Vector3::x()),
    ]
    .into_iter()
    .filter(|(angle, _)| *angle != 0.0)
    .map(|(angle, axis)| factor(angle, axis))
    .collect()
}

/// `[x, y, z] ++ R`, with `R` the product of the factors (`1` for none).
pub(super) fn displacement(xyz: [f64; 3], rotation: &[String]) -> String {
    let rotation = if rotation.is_empty() {
        "1".to_string()
    } else {
        rotation.join(" * ")
    };
    format!("{} ++ {rotation}", vector(xyz))
}

/// A frame at `origin` on `body`: the body itself when the origin is the identity.
pub(super) fn frame(origin: &Pose, body: &str) -> String {
    let rotation = rpy_factors(&origin.rpy);
    if origin.xyz.0 == [0.0; 3] && rotation.is_empty() {
        body.to_string()
    } else {
        format!("{} @ {body}", displacement(origin.xyz.0, &rotation))
    }
}

/// URDF's planar joint moves in the plane normal to its axis. The standard `planar` is normal to
/// z; for another normal the same motion is written as an inline link: translations x and y along
/// two unit vectors u and w of the plane (u × w = normal), then the rotation q about the normal.
pub fn planar(normal: &Vector3<f64>) -> String {
    if *normal == Vector3::z() {
        return "planar".to_string();
    }
    // u: the coordinate axis after the normal's largest component, projected onto the plane, so
    // a normal along x, y or z gets the next two coordinate axes in cyclic order.
    let next = Vector3::ith((normal.iamax() + 1) % 3, 1.0);
    let u = (next - normal * normal.dot(&next)).normalize();
    let w = normal.cross(&u);
    format!(
        "link(x, y, q) dof1 = x * {} + y * {}, dof2 = q || {} end",
        vector(u.into()),
        vector(w.into()),
        vector((*normal).into())
    )
}
