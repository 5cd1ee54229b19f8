//! Reading a URDF file as an LSD program.
