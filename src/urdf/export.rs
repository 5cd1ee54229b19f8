//! Writing a tree mechanism as URDF.
