//! `lsdc._native`: the Python extension module of the `lsdc` package, built on the library's
//! boundary (`lsdc::api`, `lsdc::dynamics`) alone. One file per concept: the errors raised
//! (`errors.rs`), diagnostics (`diagnostics.rs`), a loaded program (`program.rs`), a prepared
//! mechanism and its runs (`prepared.rs`), samples as NumPy columns (`columns.rs`), a run
//! stepped from Python (`simulation.rs`), the dynamics on arrays of states (`arrays.rs`),
//! sweeps and their tables (`sweep.rs`), the settings' keyword arguments (`settings.rs`).

mod arrays;
mod columns;
mod diagnostics;
mod errors;
mod prepared;
mod program;
mod settings;
mod simulation;
mod sweep;

use pyo3::prelude::*;

/// The extension module; `lsdc/__init__.py` re-exports it with the pure Python parts.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LsdcError", py.get_type::<errors::LsdcError>())?;
    m.add("ProgramError", py.get_type::<errors::ProgramError>())?;
    m.add("RunError", py.get_type::<errors::RunError>())?;
    m.add_class::<diagnostics::Diagnostic>()?;
    m.add_class::<program::Program>()?;
    m.add_class::<prepared::Prepared>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<sweep::SweepTable>()?;
    m.add_function(wrap_pyfunction!(program::load, m)?)?;
    m.add_function(wrap_pyfunction!(program::load_text, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::gather, m)?)?;
    Ok(())
}
