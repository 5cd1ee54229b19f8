//! The planar form of a planar mechanism: every joint turning about axes parallel to one
//! normal or sliding across it, every loop closed so, every effort in the plane (`decide`).
//! Its bodies then move in parallel planes, and the recursions need only the three rows of the
//! spatial vectors that such motions and forces use (`algebra`: 3-vectors for motions and
//! forces, 3 × 3 inertias), the loops only their three rows in the plane. The run's
//! right-hand side takes this form when asked (`simulate --planar`; `algorithms`,
//! `loops::planar_rows`); its results are the spatial form's, the default, to round-off, which
//! passages through singular configurations amplify (docs/guarantees.md).

pub mod algebra;
pub mod algorithms;
pub mod decide;
pub mod model;

pub use algorithms::PlanarData;
pub use decide::decide;
pub use model::PlanarModel;
