//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod programs;
pub mod symbolic;
pub mod trees;
