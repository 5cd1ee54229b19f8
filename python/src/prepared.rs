//! A prepared mechanism (`Program.prepare`): its whole runs (`simulate`), runs stepped from
//! Python (`simulation`), and its dynamics at states given as NumPy arrays (`arrays.rs`).

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use lsdc::api::StateBatch;
use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn};

use crate::arrays;
use crate::columns::{as_columns, column_names, report_dict, to_dict};
use crate::errors::to_py;
use crate::simulation::Simulation;

/// A mechanism made ready to run: values of the unknowns, the dynamic model, the initial state
/// (closed on the loops) and the settings.
#[pyclass(module = "lsdc._native", frozen)]
pub struct Prepared {
    pub program: Arc<lsdc::api::Program>,
    pub inner: Arc<lsdc::api::Prepared>,
}

impl Prepared {
    pub fn new(program: Arc<lsdc::api::Program>, prepared: lsdc::api::Prepared) -> Prepared {
        Prepared {
            program,
            inner: Arc::new(prepared),
        }
    }
}

#[pymethods]
impl Prepared {
    /// The names of the declared coordinates (`swing.q`), the columns of the samples.
    #[getter]
    fn coordinate_names(&self) -> Vec<String> {
        self.inner.coordinate_names.clone()
    }

    /// The names of the samples' columns, in the order of `lsdc simulate`'s CSV header.
    #[getter]
    fn column_names(&self) -> Vec<String> {
        column_names(&self.inner)
    }

    /// The settings' duration (s) and time between outputs (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.settings.duration
    }

    /// The warnings of the preparation.
    #[getter]
    fn warnings(&self) -> Vec<crate::diagnostics::Diagnostic> {
        (self.inner.warnings.iter())
            .map(|d| crate::diagnostics::Diagnostic::of(d, Some(&self.program)))
            .collect()
    }

    /// Runs the simulation to the end of its duration (the GIL released meanwhile): its
    /// samples as `lsdc.Columns`, a dict of the CSV header's names to NumPy arrays equal to
    /// `lsdc simulate`'s CSV bit for bit, with the run's `report` (its `failure` `None` or
    /// (time, message), the rows before it kept; a failed run also warns).
    pub fn simulate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let prepared = self.inner.clone();
        let simulation = py.detach(move || lsdc::api::run(&prepared, &mut |_| {}));
        let names = column_names(&self.inner);
        let columns: Bound<'py, PyDict> = to_dict(py, &names, &simulation.samples)?;
        let report = report_dict(py, &simulation.report)?;
        as_columns(py, columns, report)
    }

    /// The number of positions (q's entries).
    #[getter]
    fn nq(&self) -> usize {
        StateBatch::new(&self.inner).dimensions().0
    }

    /// The number of velocities (v's entries).
    #[getter]
    fn nv(&self) -> usize {
        StateBatch::new(&self.inner).dimensions().1
    }

    /// The names of q's entries, as `lsdc eval` gives them.
    #[getter]
    fn position_names(&self) -> Vec<String> {
        StateBatch::new(&self.inner).position_names()
    }

    /// The names of v's entries (and of a's, τ's, the mass matrix's rows and columns).
    #[getter]
    fn velocity_names(&self) -> Vec<String> {
        StateBatch::new(&self.inner).velocity_names()
    }

    /// The bodies' names, as `jacobian` takes them.
    #[getter]
    fn body_names(&self) -> Vec<String> {
        StateBatch::new(&self.inner).body_names().to_vec()
    }

    /// Inverse dynamics (RNEA): the generalised forces τ = M(q) a + c(q, v) − f(q, v) that
    /// give the accelerations `a` at (q, v) with the program's efforts f, as `lsdc eval`'s
    /// `rnea`. `q` (N, nq), `v` and `a` (N, nv), zeros when absent; one state as 1-D arrays.
    #[pyo3(signature = (q, v = None, a = None))]
    fn rnea<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        v: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
        a: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        arrays::rnea(py, self, q, v, a)
    }

    /// Forward dynamics (ABA): the accelerations a = M(q)⁻¹ (τ + f(q, v) − c(q, v)) under the
    /// generalised forces `tau` and the program's efforts f, as `lsdc eval`'s `aba`. `q` (N,
    /// nq), `v` and `tau` (N, nv), zeros when absent. Raises `ValueError` naming the state
    /// where the mass matrix is singular.
    #[pyo3(signature = (q, v = None, tau = None))]
    fn aba<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        v: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
        tau: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        arrays::aba(py, self, q, v, tau)
    }

    /// The mass matrix (CRBA) at positions `q` (N, nq): an (N, nv, nv) array, as `lsdc
    /// eval`'s `crba`.
    fn crba<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        arrays::crba(py, self, q)
    }

    /// The Jacobian of body `body` (its name) at positions `q` (N, nq): an (N, 6, nv) array
    /// whose column j is the body's spatial velocity for a unit velocity j, in the body's own
    /// frame, angular velocity first, then the velocity of its origin (Pinocchio's `LOCAL`).
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        body: &str,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        arrays::jacobian(py, self, q, body)
    }

    /// A run stepped from Python, with generalised forces along the velocities named in
    /// `inputs` (`"swing.q"`), held at zero until set (`Simulation.set_inputs`).
    #[pyo3(signature = (inputs = Vec::new()))]
    fn simulation(&self, inputs: Vec<String>) -> PyResult<Simulation> {
        Simulation::start(self.inner.clone(), &inputs).map_err(|e| to_py(e, Some(&self.program)))
    }
}
