//! URDF, the robot description format most robots come with: reading a URDF file as an LSD
//! program (`import`) and writing a tree mechanism as URDF (`export`).

pub mod export;
pub mod import;
