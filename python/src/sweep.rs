//! Sweeps from Python: the design from keyword arguments as `lsdc sweep`'s options make it
//! (`--grid`, `--values`, `--vary` with `--sample`, `--design`, `--seed`), the shard, and the
//! table of runs (`SweepTable`): its CSV text, identical to the file `lsdc sweep -o runs.csv`
//! writes, its columns as NumPy arrays, and `gather`, the shards' tables merged.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use lsdc::api::{Cells, Distribution, GridAxis, Sampling, Shard, SweepDesign, SweepTable as Table};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::{to_py, LsdcError};

/// The arguments that make a sweep's design.
pub struct DesignArgs {
    pub grid: Vec<String>,
    pub values_file: Option<PathBuf>,
    pub vary: BTreeMap<String, String>,
    pub sample: Option<usize>,
    pub design: String,
    pub seed: u64,
}

fn invalid(why: String) -> PyErr {
    PyValueError::new_err(why)
}

/// The axes of `grid`: strings `"NAME=FROM:TO:COUNT"` as `--grid` takes them, or a mapping of
/// names to (from, to, count), written with Python's `repr` of each number (which reads back
/// to the same float).
pub fn grid_axes(grid: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(grid) = grid else {
        return Ok(Vec::new());
    };
    if let Ok(mapping) = grid.cast::<PyDict>() {
        let mut axes = Vec::new();
        for (name, axis) in mapping.iter() {
            let (from, to, count): (f64, f64, usize) = axis
                .extract()
                .map_err(|_| invalid(format!("grid axis `{name}`: give (from, to, count)")))?;
            let repr = |x: f64| -> PyResult<String> {
                Ok(x.into_pyobject(grid.py())?.repr()?.to_string())
            };
            axes.push(format!("{name}={}:{}:{count}", repr(from)?, repr(to)?));
        }
        return Ok(axes);
    }
    grid.extract::<Vec<String>>().map_err(|_| {
        invalid("`grid`: give axes \"NAME=FROM:TO:COUNT\" or {name: (from, to, count)}".into())
    })
}

impl DesignArgs {
    /// The design, as `lsdc sweep`'s `read_design` makes it from the same options.
    pub fn design(&self) -> PyResult<SweepDesign> {
        let given = [
            !self.grid.is_empty(),
            self.values_file.is_some(),
            !self.vary.is_empty(),
        ];
        if given.iter().filter(|g| **g).count() > 1 {
            return Err(invalid(
                "give one design: `grid`, `values_file` or `vary` with `sample`".into(),
            ));
        }
        if !self.grid.is_empty() {
            let axes = (self.grid.iter())
                .map(|a| GridAxis::parse(a))
                .collect::<Result<Vec<_>, _>>()
                .map_err(invalid)?;
            return Ok(lsdc::api::sweep_grid(&axes));
        }
        if let Some(path) = &self.values_file {
            return list(path);
        }
        match (self.vary.is_empty(), self.sample) {
            (false, Some(count)) => {
                let variables = (self.vary.iter())
                    .map(|(name, text)| {
                        let distribution = Distribution::parse(text)
                            .map_err(|why| invalid(format!("`vary` of `{name}`: {why}")))?;
                        Ok((name.trim().to_string(), distribution))
                    })
                    .collect::<PyResult<Vec<_>>>()?;
                let sampling = match self.design.as_str() {
                    "random" => Sampling::MonteCarlo,
                    "latin" => Sampling::LatinHypercube,
                    "sobol" => Sampling::Sobol,
                    other => {
                        return Err(invalid(format!(
                            "design `{other}`: choose \"random\", \"latin\" or \"sobol\""
                        )))
                    }
                };
                lsdc::api::sweep_sample(&variables, count, sampling, self.seed).map_err(invalid)
            }
            (false, None) => Err(invalid("`vary` needs `sample`, the number of runs".into())),
            (true, Some(_)) => Err(invalid("`sample` needs `vary`, the distributions".into())),
            (true, None) => Err(invalid("no runs: give a grid (`grid`), a list (`values_file`) or a sample (`vary` with `sample`)".into())),
        }
    }
}

/// The runs of a CSV file of values, its errors located in it.
fn list(path: &Path) -> PyResult<SweepDesign> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| LsdcError::new_err(format!("cannot read `{}`: {e}", path.display())))?;
    lsdc::api::sweep_list(&text).map_err(|e| {
        invalid(format!(
            "{}:{}:{}: {}",
            path.display(),
            e.line,
            e.column,
            e.message
        ))
    })
}

/// The shard `(k, n)`, k from 1; the whole sweep without one.
pub fn shard(shard: Option<(usize, usize)>) -> PyResult<Shard> {
    match shard {
        None => Ok(Shard::WHOLE),
        Some((index, count)) if (1..=count).contains(&index) => Ok(Shard { index, count }),
        Some((index, count)) => Err(invalid(format!(
            "shard ({index}, {count}): give (k, n), the k-th of n parts, 1 ≤ k ≤ n"
        ))),
    }
}

/// A sweep's table of runs (or of one shard's runs).
#[pyclass(module = "lsdc._native", frozen)]
pub struct SweepTable {
    pub table: Table,
}

#[pymethods]
impl SweepTable {
    /// Reads a table from the CSV text of `lsdc sweep -o runs.csv` (or of `SweepTable.csv`).
    #[staticmethod]
    fn from_csv(text: &str) -> PyResult<SweepTable> {
        let table = lsdc::api::sweep_table_from_csv(text).map_err(invalid)?;
        Ok(SweepTable { table })
    }

    /// The table as the CSV text `lsdc sweep -o runs.csv` writes: numbers in Rust's shortest
    /// exponent form, which reads back to the same bits.
    #[getter]
    fn csv(&self) -> String {
        self.table.to_csv()
    }

    /// The columns' names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.table.names().into_iter().map(String::from).collect()
    }

    fn __len__(&self) -> usize {
        self.table.row_count()
    }

    /// The columns as a dict of names to NumPy arrays: numbers as float64 (NaN where empty),
    /// integers as int64 (float64 with NaN where one is missing), texts as lists of str or
    /// None.
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for column in &self.table.columns {
            match &column.cells {
                Cells::Numbers(cells) => {
                    let values: Vec<f64> = cells.iter().map(|x| x.unwrap_or(f64::NAN)).collect();
                    dict.set_item(&column.name, PyArray1::from_vec(py, values))?;
                }
                Cells::Integers(cells) if cells.iter().all(Option::is_some) => {
                    let values: Vec<i64> = cells.iter().flatten().copied().collect();
                    dict.set_item(&column.name, PyArray1::from_vec(py, values))?;
                }
                Cells::Integers(cells) => {
                    let values: Vec<f64> = cells
                        .iter()
                        .map(|x| x.map_or(f64::NAN, |x| x as f64))
                        .collect();
                    dict.set_item(&column.name, PyArray1::from_vec(py, values))?;
                }
                Cells::Texts(cells) => {
                    dict.set_item(&column.name, PyList::new(py, cells)?)?;
                }
            }
        }
        Ok(dict)
    }

    /// The table as a pandas DataFrame (pandas must be installed).
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pandas = py.import("pandas")?;
        pandas.getattr("DataFrame")?.call1((self.columns(py)?,))
    }

    /// Writes the table as `lsdc sweep -o` does: Apache Parquet when the name ends in
    /// `.parquet`, else CSV.
    fn write(&self, path: PathBuf) -> PyResult<()> {
        let format = lsdc::api::TableFormat::of(&path);
        (self.table.write(&path, format))
            .map_err(|why| LsdcError::new_err(format!("cannot write `{}`: {why}", path.display())))
    }
}

/// Merges the tables of a sweep's shards (in any order) into the whole sweep's, as `lsdc
/// sweep gather` merges their files: identical to the table of the sweep run whole.
#[pyfunction]
pub fn gather(parts: Vec<PyRef<'_, SweepTable>>) -> PyResult<SweepTable> {
    let tables = parts.iter().map(|part| part.table.clone()).collect();
    let table = lsdc::api::gather(tables).map_err(|e| to_py(e, None))?;
    Ok(SweepTable { table })
}
