//! Dynamics of tree mechanisms: an immutable [`model::Model`] compiled from the mechanism, scratch
//! [`algorithms::Data`], and the recursive algorithms on them: inverse dynamics (RNEA), the mass
//! matrix (CRBA), forward dynamics (ABA), energy and momentum.

pub mod algorithms;
pub mod model;

// Modules `pub` only with the cfg `lsdc_internals` (see the crate root's "The library's
// boundary"), written out so that rustfmt formats their files.
#[cfg(lsdc_internals)]
pub mod actuators;
#[cfg(not(lsdc_internals))]
pub(crate) mod actuators;
#[cfg(lsdc_internals)]
pub mod angles;
#[cfg(not(lsdc_internals))]
pub(crate) mod angles;
#[cfg(lsdc_internals)]
pub mod compiled;
#[cfg(not(lsdc_internals))]
pub(crate) mod compiled;
#[cfg(lsdc_internals)]
pub mod contacts;
#[cfg(not(lsdc_internals))]
pub(crate) mod contacts;
#[cfg(lsdc_internals)]
pub mod coupled_aba;
#[cfg(not(lsdc_internals))]
pub(crate) mod coupled_aba;
#[cfg(lsdc_internals)]
pub mod dense;
#[cfg(not(lsdc_internals))]
pub(crate) mod dense;
#[cfg(lsdc_internals)]
pub mod derivatives;
#[cfg(not(lsdc_internals))]
pub(crate) mod derivatives;
#[cfg(lsdc_internals)]
pub mod driven_points;
#[cfg(not(lsdc_internals))]
pub(crate) mod driven_points;
#[cfg(lsdc_internals)]
pub mod driven_subtrees;
#[cfg(not(lsdc_internals))]
pub(crate) mod driven_subtrees;
#[cfg(lsdc_internals)]
pub mod drives;
#[cfg(not(lsdc_internals))]
pub(crate) mod drives;
#[cfg(lsdc_internals)]
pub mod effort_derivatives;
#[cfg(not(lsdc_internals))]
pub(crate) mod effort_derivatives;
#[cfg(lsdc_internals)]
pub mod efforts;
#[cfg(not(lsdc_internals))]
pub(crate) mod efforts;
#[cfg(lsdc_internals)]
pub mod elements;
#[cfg(not(lsdc_internals))]
pub(crate) mod elements;
#[cfg(lsdc_internals)]
pub mod energy;
#[cfg(not(lsdc_internals))]
pub(crate) mod energy;
#[cfg(lsdc_internals)]
pub mod friction;
#[cfg(not(lsdc_internals))]
pub(crate) mod friction;
#[cfg(lsdc_internals)]
pub mod joint;
#[cfg(not(lsdc_internals))]
pub(crate) mod joint;
#[cfg(lsdc_internals)]
pub mod loops;
#[cfg(not(lsdc_internals))]
pub(crate) mod loops;
#[cfg(lsdc_internals)]
pub mod mimics;
#[cfg(not(lsdc_internals))]
pub(crate) mod mimics;
#[cfg(lsdc_internals)]
pub mod planar;
#[cfg(not(lsdc_internals))]
pub(crate) mod planar;
#[cfg(lsdc_internals)]
pub mod reduced_model;
#[cfg(not(lsdc_internals))]
pub(crate) mod reduced_model;
#[cfg(lsdc_internals)]
pub mod response;
#[cfg(not(lsdc_internals))]
pub(crate) mod response;
#[cfg(lsdc_internals)]
pub mod rotors;
#[cfg(not(lsdc_internals))]
pub(crate) mod rotors;
#[cfg(lsdc_internals)]
pub mod rows;
#[cfg(not(lsdc_internals))]
pub(crate) mod rows;
#[cfg(lsdc_internals)]
pub mod sampled;
#[cfg(not(lsdc_internals))]
pub(crate) mod sampled;
#[cfg(lsdc_internals)]
pub mod scalar;
#[cfg(not(lsdc_internals))]
pub(crate) mod scalar;
#[cfg(lsdc_internals)]
pub mod states;
#[cfg(not(lsdc_internals))]
pub(crate) mod states;
#[cfg(lsdc_internals)]
pub mod stops;
#[cfg(not(lsdc_internals))]
pub(crate) mod stops;
#[cfg(lsdc_internals)]
pub mod welds;
#[cfg(not(lsdc_internals))]
pub(crate) mod welds;
