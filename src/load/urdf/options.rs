//! How a URDF robot is imported (shared by the importer and the program it writes).

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImportOptions {
    /// Join the root link to earth by `free` instead of welding it.
    pub floating_base: bool,
    /// Apply the standard library's `weight` (g along -z) to every link with mass.
    pub gravity: bool,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            floating_base: false,
            gravity: true,
        }
    }
}
