//! The commands that look at a mechanism's motion: `lsdc drag` and `lsdc view`.

pub mod drag;
pub mod view;
