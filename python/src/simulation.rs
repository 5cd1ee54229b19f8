//! A run stepped from Python (`Prepared.simulation`): the library's `Simulator` owned together
//! with the prepared mechanism it borrows, advanced step by step with the inputs' efforts set
//! between steps (a zero-order hold, as a sampled controller applies its commands).

use std::sync::Arc;

use lsdc::api::{Prepared, Simulator, Start};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::columns::{as_columns, column_names, report_dict, to_dict};
use crate::errors::{to_py, LsdcError};

/// The run, or nothing once finished.
type Running<'p> = Option<Simulator<'p>>;

self_cell::self_cell!(
    /// The prepared mechanism and the run that borrows it, owned together.
    struct OwnedRun {
        owner: Arc<Prepared>,
        #[not_covariant]
        dependent: Running,
    }
);

/// A simulation advanced from Python: `step()` takes one step of the integrator,
/// `advance_to(t)` steps to t and lands on it; between steps `coordinates()` reads the state
/// and `set_input(name, value)` sets an input (an effort along a coordinate, `"swing.q"`, or a
/// value, `"voltage"`), `set_inputs(efforts)` the generalised forces along the effort inputs,
/// held until set again; every input holds its declared start value until set. The samples at the settings' output times that the steps pass are kept until
/// `take_samples()`; `finish()` ends the run.
#[pyclass(module = "lsdc._native", unsendable)]
pub struct Simulation {
    run: OwnedRun,
    names: Vec<String>,
}

/// The error of a finished simulation's use.
fn finished() -> PyErr {
    LsdcError::new_err("the simulation is finished")
}

impl Simulation {
    /// A run of `prepared` from its initial state with efforts along `inputs`.
    pub fn start(
        prepared: Arc<Prepared>,
        inputs: &[String],
    ) -> Result<Simulation, lsdc::api::Error> {
        let names = column_names(&prepared);
        let inputs: Vec<&str> = inputs.iter().map(String::as_str).collect();
        let run = OwnedRun::try_new(prepared, |prepared| {
            Simulator::new(prepared, &inputs).map(Some)
        })?;
        Ok(Simulation { run, names })
    }

    /// `action` on the running simulator; an error once finished.
    fn with<T>(
        &mut self,
        action: impl FnOnce(&mut Simulator<'_>) -> Result<T, lsdc::api::RunFailure>,
    ) -> PyResult<T> {
        self.run.with_dependent_mut(|_, running| match running {
            Some(simulator) => action(simulator).map_err(|f| to_py(f.into(), None)),
            None => Err(finished()),
        })
    }
}

#[pymethods]
impl Simulation {
    /// The time of the current state (s).
    #[getter]
    fn time(&mut self) -> PyResult<f64> {
        self.with(|s| Ok(s.time()))
    }

    /// The names of the effort inputs' velocities, in the order of their efforts: the
    /// program's declared ones (`input swing.q = 0;`), then those named to
    /// `Prepared.simulation(inputs=...)`.
    #[getter]
    fn input_names(&mut self) -> PyResult<Vec<String>> {
        self.with(|s| Ok(s.input_names()))
    }

    /// The names of the program's value inputs (`input voltage = 0;`).
    #[getter]
    fn value_input_names(&mut self) -> PyResult<Vec<String>> {
        self.with(|s| Ok(s.value_input_names()))
    }

    /// Sets the input `name` to `value`, held until set again: an effort input by its
    /// coordinate's name (`"swing.q"`: the torque along it), a value input by its name
    /// (`"voltage"`). Raises `LsdcError` for a name that is not an input of the run, listing
    /// them.
    fn set_input(&mut self, name: &str, value: f64) -> PyResult<()> {
        self.with(|s| s.set_input(name, value))
    }

    /// The declared coordinates and rates at the current state: a tuple (q, v) of arrays, in
    /// the order of `Prepared.coordinate_names`.
    fn coordinates<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let (q, v) = self.with(|s| s.coordinates())?;
        PyTuple::new(py, [PyArray1::from_vec(py, q), PyArray1::from_vec(py, v)])
    }

    /// Sets the generalised forces along the effort inputs (in the order of `input_names`),
    /// held until set again.
    fn set_inputs(&mut self, efforts: Vec<f64>) -> PyResult<()> {
        self.with(|s| s.set_inputs(&efforts))
    }

    /// Takes one step of the integrator towards the end of the settings' duration.
    fn step(&mut self) -> PyResult<()> {
        self.with(|s| s.step())
    }

    /// Steps until time `t` and lands on it exactly.
    fn advance_to(&mut self, t: f64) -> PyResult<()> {
        self.with(|s| s.advance_to(t))
    }

    /// Starts again at time 0 from the prepared initial state, or from the declared
    /// `coordinates` and `rates` given; the inputs' efforts and the samples not taken are kept.
    #[pyo3(signature = (coordinates = None, rates = None))]
    fn reset(&mut self, coordinates: Option<Vec<f64>>, rates: Option<Vec<f64>>) -> PyResult<()> {
        self.run.with_dependent_mut(|prepared, running| {
            let Some(simulator) = running else {
                return Err(finished());
            };
            let start = Start {
                coordinates: coordinates.as_deref().unwrap_or(&prepared.coordinates),
                rates: rates.as_deref().unwrap_or(&prepared.rates),
            };
            simulator.reset(&start).map_err(|f| to_py(f.into(), None))
        })
    }

    /// The samples the steps delivered since last taken: a dict of the columns' names to
    /// arrays, as `Prepared.simulate` gives them.
    fn take_samples<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let samples = self.with(|s| Ok(s.take_samples()))?;
        to_dict(py, &self.names, &samples)
    }

    /// Ends the run: the samples not taken yet (with the output times not reached when the run
    /// went to its end) as `lsdc.Columns`, with the run's `report`.
    fn finish<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // The run ends inside the cell: what it returns borrows nothing.
        let ended =
            (self.run).with_dependent_mut(|_, running| running.take().map(Simulator::finish));
        let Some((samples, report)) = ended else {
            return Err(finished());
        };
        let columns = to_dict(py, &self.names, &samples)?;
        let report = report_dict(py, &report)?;
        as_columns(py, columns, report)
    }

    /// The names of the samples' columns.
    #[getter]
    fn column_names(&self) -> Vec<String> {
        self.names.clone()
    }
}
