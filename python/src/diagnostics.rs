//! A diagnostic as a Python object: its code, severity, message, place and help, as
//! `lsdc check` reports it.

use pyo3::prelude::*;

/// An error or warning about a program: where it points (`file`, `line` and `column` from 1,
/// `None` for a diagnostic about no place), its stable code (docs/diagnostics.md), its message,
/// help and notes.
#[pyclass(module = "lsdc._native", frozen, get_all)]
#[derive(Clone)]
pub struct Diagnostic {
    pub code: String,
    /// `"error"` or `"warning"`.
    pub severity: String,
    pub message: String,
    pub file: Option<String>,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub help: Option<String>,
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// The library's diagnostic, located in `program`'s sources when given.
    pub fn of(diagnostic: &lsdc::api::Diagnostic, program: Option<&lsdc::api::Program>) -> Self {
        let location = program.and_then(|p| p.location(diagnostic));
        Diagnostic {
            code: diagnostic.code.to_string(),
            severity: match diagnostic.is_error() {
                true => "error".to_string(),
                false => "warning".to_string(),
            },
            message: diagnostic.message.clone(),
            file: location.as_ref().map(|l| l.file.clone()),
            line: location.as_ref().map(|l| l.line),
            column: location.as_ref().map(|l| l.column),
            help: diagnostic.help.clone(),
            notes: diagnostic.notes.clone(),
        }
    }

    /// `file:line:column: severity[code]: message`, as a compiler's one-line form.
    pub fn line(&self) -> String {
        let place = match (&self.file, self.line, self.column) {
            (Some(file), Some(line), Some(column)) => format!("{file}:{line}:{column}: "),
            _ => String::new(),
        };
        format!("{place}{}[{}]: {}", self.severity, self.code, self.message)
    }
}

#[pymethods]
impl Diagnostic {
    fn __str__(&self) -> String {
        match &self.help {
            Some(help) => format!("{}\nhelp: {help}", self.line()),
            None => self.line(),
        }
    }

    fn __repr__(&self) -> String {
        format!("<Diagnostic {}>", self.line())
    }

    /// Whether it is an error (a warning leaves the program usable).
    #[getter]
    fn is_error(&self) -> bool {
        self.severity == "error"
    }
}
