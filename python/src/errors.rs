//! The exceptions the package raises, and the library's errors turned into them: errors in a
//! program carry its diagnostics (file, line, column, message), located in its sources.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::diagnostics::Diagnostic;

pyo3::create_exception!(
    lsdc,
    LsdcError,
    PyException,
    "An error of lsdc: a file that cannot be read, settings that cannot be used, a study that cannot be done."
);
pyo3::create_exception!(
    lsdc,
    ProgramError,
    LsdcError,
    "Errors in the program, or a value it needs and nobody gave: `args` is (message, diagnostics), each diagnostic with its file, line, column and message."
);
pyo3::create_exception!(
    lsdc,
    RunError,
    LsdcError,
    "A run that cannot start or that stopped: `args` is (message, time)."
);

/// The library's error as a Python exception; `program` locates the diagnostics of errors in
/// it (without it they have no place).
pub fn to_py(error: lsdc::api::Error, program: Option<&lsdc::api::Program>) -> PyErr {
    use lsdc::api::Error;
    match error {
        Error::Program(diagnostics) => program_error(&diagnostics, program),
        Error::Run(failure) => {
            let message = format!("at t = {}: {}", failure.time, failure.message);
            RunError::new_err((message, failure.time))
        }
        Error::States(states) => PyValueError::new_err(states.to_string()),
        other => LsdcError::new_err(other.to_string()),
    }
}

/// A `ProgramError` with the errors among `diagnostics` as its message and every diagnostic.
pub fn program_error(
    diagnostics: &[lsdc::api::Diagnostic],
    program: Option<&lsdc::api::Program>,
) -> PyErr {
    let located: Vec<Diagnostic> = (diagnostics.iter())
        .map(|d| Diagnostic::of(d, program))
        .collect();
    let errors: Vec<String> = (located.iter())
        .filter(|d| d.severity == "error")
        .map(Diagnostic::line)
        .collect();
    let message = errors.join("\n");
    Python::attach(|py| match PyList::new(py, located) {
        Ok(list) => ProgramError::new_err((message, list.unbind())),
        Err(error) => error,
    })
}
