//! Dynamics of tree mechanisms: an immutable [`model::Model`] compiled from the mechanism, scratch
//! [`algorithms::Data`], and the recursive algorithms on them: inverse dynamics (RNEA), the mass
//! matrix (CRBA), forward dynamics (ABA), energy and momentum.

pub mod algorithms;
pub mod model;

internal! {
    mod actuators;
    mod angles;
    mod compiled;
    mod contacts;
    mod dense;
    mod derivatives;
    mod driven_points;
    mod driven_subtrees;
    mod drives;
    mod effort_derivatives;
    mod efforts;
    mod elements;
    mod energy;
    mod friction;
    mod joint;
    mod loops;
    mod mimics;
    mod planar;
    mod reduced_model;
    mod response;
    mod rotors;
    mod rows;
    mod sampled;
    mod scalar;
    mod states;
    mod stops;
    mod welds;
}
