//! A program loaded, checked and elaborated (`lsdc.load`): its diagnostics, and what is made
//! of it: a prepared mechanism (`prepare`), a linear model (`linearize`), a sweep (`sweep`).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use lsdc::api::{LinearizeRequest, LoadOptions, OperatingPoint};
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::diagnostics::Diagnostic;
use crate::errors::{program_error, to_py, LsdcError};
use crate::prepared::Prepared;
use crate::settings::{overrides, RunSettings};
use crate::sweep::{self, DesignArgs, SweepTable};

/// A program (an `.lsd` file and its imports, or a URDF file read as one), checked and
/// elaborated. Errors in it do not raise here: they are in `diagnostics`, and preparing it
/// raises `ProgramError` with them.
#[pyclass(module = "lsdc._native", frozen)]
pub struct Program {
    pub inner: Arc<lsdc::api::Program>,
}

/// The load options of `-L DIR` and `--scene NAME`.
fn options(library_path: Vec<PathBuf>, scene: Option<String>) -> LoadOptions {
    LoadOptions {
        library_dirs: library_path,
        scene,
        ..Default::default()
    }
}

/// Loads a program or a URDF file with what it imports, then checks and elaborates it.
/// `library_path`: directories searched for imports (as `-L`); `scene`: the scene to study
/// (as `--scene`). Raises `LsdcError` only when the file cannot be read; errors in the
/// program are in the result's `diagnostics`.
#[pyfunction]
#[pyo3(signature = (path, *, library_path = Vec::new(), scene = None))]
pub fn load(path: PathBuf, library_path: Vec<PathBuf>, scene: Option<String>) -> PyResult<Program> {
    let program = lsdc::api::Program::from_file(&path, &options(library_path, scene))
        .map_err(|e| to_py(e, None))?;
    Ok(Program {
        inner: Arc::new(program),
    })
}

/// Checks and elaborates a program given as text; `name` is how its diagnostics name it, and
/// its relative imports are looked up in `directory`.
#[pyfunction]
#[pyo3(signature = (text, *, name = "<text>".to_string(), directory = None, library_path = Vec::new(), scene = None))]
pub fn load_text(
    text: &str,
    name: String,
    directory: Option<PathBuf>,
    library_path: Vec<PathBuf>,
    scene: Option<String>,
) -> Program {
    let options = options(library_path, scene);
    let program = lsdc::api::Program::from_text(&name, text, directory.as_deref(), &options);
    Program {
        inner: Arc::new(program),
    }
}

impl Program {
    /// Raises `ProgramError` with the diagnostics when the program has errors.
    fn usable(&self) -> PyResult<()> {
        match self.inner.has_errors() {
            true => Err(program_error(self.inner.diagnostics(), Some(&self.inner))),
            false => Ok(()),
        }
    }
}

#[pymethods]
impl Program {
    /// Errors and warnings of every phase, in the order found.
    #[getter]
    fn diagnostics(&self) -> Vec<Diagnostic> {
        let program = &self.inner;
        (program.diagnostics().iter())
            .map(|d| Diagnostic::of(d, Some(program)))
            .collect()
    }

    /// Whether a phase reported an error.
    #[getter]
    fn has_errors(&self) -> bool {
        self.inner.has_errors()
    }

    /// The diagnostics as `lsdc check` prints them: file, line, column, source lines, help.
    fn render(&self) -> String {
        self.inner.render()
    }

    /// Raises `ProgramError` when the program has errors; its warnings otherwise.
    fn check(&self) -> PyResult<Vec<Diagnostic>> {
        self.usable()?;
        Ok(self.diagnostics())
    }

    /// The scenes the program declares, in order.
    #[getter]
    fn scene_names(&self) -> Vec<String> {
        self.inner.scene_names().to_vec()
    }

    /// Prepares the mechanism for simulation and evaluation, as `lsdc simulate` does:
    /// `values` give unknowns and `given` values by name (`--set NAME=VALUE`), `initial` the
    /// initial values of declared coordinates (`"swing.q"`) and rates (`"swing.q'"`) as if the
    /// program's `initial` said them; the keyword arguments change its `simulate` declaration
    /// (`every` is `--every`, the time between outputs). Raises `ProgramError` with the
    /// diagnostics when a value is missing or a loop cannot be assembled.
    #[pyo3(signature = (values = None, *, initial = None, integrator = None, duration = None, every = None, tolerance = None, step = None, max_steps = None, stabilisation = "projection", baumgarte_rate = 10.0, reactions = false))]
    #[allow(clippy::too_many_arguments)]
    fn prepare(
        &self,
        values: Option<BTreeMap<String, f64>>,
        initial: Option<BTreeMap<String, f64>>,
        integrator: Option<String>,
        duration: Option<f64>,
        every: Option<f64>,
        tolerance: Option<f64>,
        step: Option<f64>,
        max_steps: Option<usize>,
        stabilisation: &str,
        baumgarte_rate: f64,
        reactions: bool,
    ) -> PyResult<Prepared> {
        self.usable()?;
        let settings = RunSettings {
            integrator,
            duration,
            every,
            tolerance,
            step,
            max_steps,
        };
        let changes = settings.simulate_changes(stabilisation, baumgarte_rate, reactions)?;
        let (values, initial) = (overrides(values), overrides(initial));
        let program = &self.inner;
        let prepared = match initial.is_empty() {
            true => program.prepare(&values, &changes),
            false => program.prepare_with_initial(&values, &initial, &changes),
        };
        let prepared = prepared.map_err(|e| to_py(e, Some(program)))?;
        Ok(Prepared::new(self.inner.clone(), prepared))
    }

    /// Prepares the program with `values` and the settings given (as `prepare`), then runs it
    /// to the end of its duration: `lsdc.load(path).simulate(duration=2.0, every=0.5)` gives
    /// the columns of `lsdc simulate path --duration 2 --every 0.5`, bit for bit.
    #[pyo3(signature = (values = None, *, initial = None, integrator = None, duration = None, every = None, tolerance = None, step = None, max_steps = None, stabilisation = "projection", baumgarte_rate = 10.0, reactions = false))]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        values: Option<BTreeMap<String, f64>>,
        initial: Option<BTreeMap<String, f64>>,
        integrator: Option<String>,
        duration: Option<f64>,
        every: Option<f64>,
        tolerance: Option<f64>,
        step: Option<f64>,
        max_steps: Option<usize>,
        stabilisation: &str,
        baumgarte_rate: f64,
        reactions: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let prepared = self.prepare(
            values,
            initial,
            integrator,
            duration,
            every,
            tolerance,
            step,
            max_steps,
            stabilisation,
            baumgarte_rate,
            reactions,
        )?;
        prepared.simulate(py)
    }

    /// The linear model ẋ = A x + B u, y = C x + D u about an operating point, as `lsdc
    /// linearize` computes it: the initial state (default), the state a run reaches at
    /// `at_time`, or the equilibrium the `inputs` hold (`equilibrium=True`). `inputs`:
    /// coordinates along which a generalised force is an input, or constant states held as
    /// inputs; `coordinates`: the independent coordinates of a mechanism with loops. A dict:
    /// `A`, `B`, `C`, `D` (NumPy), `states`, `inputs`, `outputs`, the operating `state` and
    /// `input`, `eigenvalues` (complex) and the entries' estimated errors `A_error`, ….
    #[pyo3(signature = (values = None, *, inputs = Vec::new(), coordinates = Vec::new(), at_time = None, equilibrium = false))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        values: Option<BTreeMap<String, f64>>,
        inputs: Vec<String>,
        coordinates: Vec<String>,
        at_time: Option<f64>,
        equilibrium: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.usable()?;
        if at_time.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
            return Err(PyValueError::new_err(
                "`at_time` must be a positive number of seconds",
            ));
        }
        let point = match (at_time, equilibrium) {
            (Some(_), true) => {
                return Err(PyValueError::new_err(
                    "`at_time` and `equilibrium` are two operating points: give one",
                ))
            }
            (Some(_), false) => OperatingPoint::EndOfRun,
            (None, true) => OperatingPoint::Equilibrium,
            (None, false) => OperatingPoint::Initial,
        };
        let changes = lsdc::api::SettingsChanges {
            duration: at_time,
            ..Default::default()
        };
        let program = &self.inner;
        let prepared =
            (program.prepare(&overrides(values), &changes)).map_err(|e| to_py(e, Some(program)))?;
        let request = LinearizeRequest {
            point,
            inputs,
            coordinates,
        };
        let model =
            (program.linearize(&prepared, &request)).map_err(|e| to_py(e, Some(program)))?;
        let dict = PyDict::new(py);
        for (key, matrix) in [
            ("A", &model.a),
            ("B", &model.b),
            ("C", &model.c),
            ("D", &model.d),
            ("A_error", &model.a_error),
            ("B_error", &model.b_error),
            ("C_error", &model.c_error),
        ] {
            let rows: Vec<Vec<f64>> = (matrix.row_iter())
                .map(|row| row.iter().copied().collect())
                .collect();
            let array = match rows.is_empty() {
                true => PyArray2::zeros(py, [0, matrix.ncols()], false),
                false => {
                    PyArray2::from_vec2(py, &rows).map_err(|e| LsdcError::new_err(e.to_string()))?
                }
            };
            dict.set_item(key, array)?;
        }
        dict.set_item("point", model.point)?;
        dict.set_item("time", model.time)?;
        dict.set_item("states", &model.states)?;
        dict.set_item("inputs", &model.inputs)?;
        dict.set_item("outputs", &model.outputs)?;
        dict.set_item("coordinates", &model.coordinates)?;
        dict.set_item("dependent", &model.dependent)?;
        dict.set_item("state", PyArray1::from_slice(py, &model.state))?;
        dict.set_item("input", PyArray1::from_slice(py, &model.input))?;
        dict.set_item(
            "accelerations",
            PyArray1::from_slice(py, &model.accelerations),
        )?;
        let eigenvalues: Vec<numpy::Complex64> = (model.eigenvalues.iter())
            .map(|e| numpy::Complex64::new(e.re, e.im))
            .collect();
        dict.set_item("eigenvalues", PyArray1::from_vec(py, eigenvalues))?;
        Ok(dict)
    }

    /// Runs the program over a design of values, as `lsdc sweep` does, and returns its table
    /// of runs (a row per run: `run`, the varied names, `status`, …, `end(Q)`, `min(Q)`,
    /// `max(Q)`). The design: `grid` (axes `"NAME=FROM:TO:COUNT"`, or `{name: (from, to,
    /// count)}`), `values_file` (a CSV file of runs) or `vary` (`{name: "uniform(0, 1)"}`)
    /// with `sample` (N runs; `design` `"random"`, `"latin"` or `"sobol"`, `seed`). `values`
    /// are the values every run takes (`--set`); `shard=(k, n)` runs the k-th of n parts (k
    /// from 1), `threads` the threads (every core by default).
    #[pyo3(signature = (*, grid = None, values_file = None, vary = None, sample = None, design = "random", seed = 0, values = None, integrator = None, duration = None, every = None, tolerance = None, step = None, max_steps = None, shard = None, threads = None))]
    #[allow(clippy::too_many_arguments)]
    fn sweep(
        &self,
        py: Python<'_>,
        grid: Option<&Bound<'_, PyAny>>,
        values_file: Option<PathBuf>,
        vary: Option<BTreeMap<String, String>>,
        sample: Option<usize>,
        design: &str,
        seed: u64,
        values: Option<BTreeMap<String, f64>>,
        integrator: Option<String>,
        duration: Option<f64>,
        every: Option<f64>,
        tolerance: Option<f64>,
        step: Option<f64>,
        max_steps: Option<usize>,
        shard: Option<(usize, usize)>,
        threads: Option<usize>,
    ) -> PyResult<SweepTable> {
        self.usable()?;
        let args = DesignArgs {
            grid: sweep::grid_axes(grid)?,
            values_file,
            vary: vary.unwrap_or_default(),
            sample,
            design: design.to_string(),
            seed,
        };
        let design = args.design()?;
        let shard = sweep::shard(shard)?;
        if threads == Some(0) {
            return Err(PyValueError::new_err(
                "`threads=0`: give at least one thread",
            ));
        }
        let settings = RunSettings {
            integrator,
            duration,
            every,
            tolerance,
            step,
            max_steps,
        };
        let changes = settings.changes()?;
        let values = overrides(values);
        let program = self.inner.clone();
        let table = py.detach(move || program.sweep(&values, &changes, design, shard, threads));
        let table = table.map_err(|e| to_py(e, Some(&self.inner)))?;
        Ok(SweepTable { table })
    }
}
