//! Dynamics of tree mechanisms: an immutable [`model::Model`] compiled from the mechanism, scratch
//! [`algorithms::Data`], and the recursive algorithms on them: inverse dynamics (RNEA), the mass
//! matrix (CRBA), forward dynamics (ABA), energy and momentum.

pub mod actuators;
pub mod algorithms;
pub mod angles;
pub mod compiled;
pub mod contacts;
pub mod dense;
pub mod derivatives;
pub mod driven_points;
pub mod drives;
pub mod efforts;
pub mod elements;
pub mod energy;
pub mod friction;
pub mod joint;
pub mod loops;
pub mod mimics;
pub mod model;
pub mod reduced_model;
pub mod response;
pub mod rotors;
pub mod rows;
pub mod sampled;
pub mod states;
pub mod stops;
pub mod welds;
