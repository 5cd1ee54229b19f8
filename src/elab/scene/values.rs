//! Every scalar a part of the mechanism holds, visited in place: the scene's reduction reads
//! through them what each part depends on (`groups.rs`) and renumbers the joins they name once
//! parts are left out (`renumber.rs`). One traversal per part, so that both see the same values.

use crate::elab::mechanism::{Body, Effort, Link, NamedOutput, OutputValue, Quantity};
use crate::elab::value::{Displacement, Elementary, Frame, Scalar, Vector};

/// What is done to each scalar.
pub(super) type Visit<'a> = &'a mut dyn FnMut(&mut Scalar);

pub(super) fn vector(v: &mut Vector, visit: Visit) {
    for s in v.iter_mut() {
        visit(s);
    }
}

pub(super) fn displacement(d: &mut Displacement, visit: Visit) {
    for step in &mut d.0 {
        match step {
            Elementary::Translation(t) => vector(t, visit),
            Elementary::Rotation { angle, axis } => {
                visit(angle);
                vector(axis, visit);
            }
        }
    }
}

pub(super) fn frame(f: &mut Frame, visit: Visit) {
    displacement(&mut f.displacement, visit);
}

fn quantity<T>(q: &mut Quantity<T>) -> &mut T {
    match q {
        Quantity::Declared(v) | Quantity::Generic(v) => v,
    }
}

fn optional(s: &mut Option<Scalar>, visit: Visit) {
    if let Some(s) = s {
        visit(s);
    }
}

pub(super) fn body(b: &mut Body, visit: Visit) {
    visit(quantity(&mut b.mass));
    displacement(quantity(&mut b.iframe), visit);
    vector(quantity(&mut b.inertia), visit);
}

/// A link's chain, efforts and written extras (the mimic's leader is a join, not a scalar:
/// see `groups.rs` and `renumber.rs`).
pub(super) fn link(l: &mut Link, visit: Visit) {
    l.dofs.iter_mut().for_each(|d| displacement(d, visit));
    for (_, v) in l.forces.iter_mut().chain(&mut l.torques) {
        vector(v, visit);
    }
    optional(&mut l.potential, visit);
    let Some(extras) = l.written_extras_mut() else {
        return;
    };
    if let Some(contact) = &mut extras.contact {
        visit(&mut contact.radius);
        optional(&mut contact.friction, visit);
    }
    let stops = &mut extras.stops;
    for bound in [&mut stops.lower, &mut stops.upper, &mut stops.restitution] {
        optional(bound, visit);
    }
    let rotor = &mut extras.rotor;
    optional(&mut rotor.inertia, visit);
    optional(&mut rotor.ratio, visit);
    if let Some(axis) = &mut rotor.axis {
        vector(axis, visit);
    }
    optional(&mut extras.mimic.multiplier, visit);
    optional(&mut extras.mimic.offset, visit);
    optional(&mut extras.friction.dry, visit);
    optional(&mut extras.friction.viscous, visit);
}

pub(super) fn effort(e: &mut Effort, visit: Visit) {
    vector(quantity(&mut e.value), visit);
    optional(&mut e.potential, visit);
    if let Some(field) = &mut e.field {
        vector(field, visit);
    }
}

pub(super) fn output(o: &mut NamedOutput, visit: Visit) {
    match &mut o.value {
        OutputValue::Scalar(s) => visit(s),
        OutputValue::Vector(v) => vector(v, visit),
        OutputValue::Matrix(m) => m.iter_mut().for_each(|row| vector(row, visit)),
        OutputValue::Frame(f) => frame(f, visit),
    }
}
