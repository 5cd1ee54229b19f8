//! The dynamics on NumPy arrays: RNEA, CRBA, ABA and the bodies' Jacobians at N states given
//! as (N, nq) and (N, nv) arrays, evaluated in Rust one state after another (the GIL released,
//! no Python call per state). One state may be given as 1-D arrays, and gives 1-D results.
//! The numbers are those of `lsdc eval` (`lsdc::api::StateBatch`).

use std::borrow::Cow;

use lsdc::api::StateBatch;
use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::prepared::Prepared;

/// An array argument: its numbers row after row, the number of states, and whether it was one
/// state (1-D).
struct States<'a> {
    values: Cow<'a, [f64]>,
    count: usize,
    single: bool,
}

/// Reads `array` (1-D: one state; 2-D: a state per row) of `width` columns.
fn states<'a>(
    name: &str,
    array: &'a PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    width: usize,
) -> PyResult<States<'a>> {
    let shape = array.shape().to_vec();
    let (count, columns, single) = match shape.as_slice() {
        [n] => (1, *n, true),
        [rows, n] => (*rows, *n, false),
        _ => {
            return Err(PyValueError::new_err(format!(
                "`{name}` has {} dimensions: give one state (1-D) or a state per row (2-D)",
                shape.len()
            )))
        }
    };
    if columns != width {
        return Err(PyValueError::new_err(format!(
            "`{name}` has {columns} columns, the mechanism has {width}"
        )));
    }
    let values = match array.as_slice() {
        Ok(slice) => Cow::Borrowed(slice),
        Err(_) => Cow::Owned(array.as_array().iter().copied().collect()),
    };
    Ok(States {
        values,
        count,
        single,
    })
}

/// Zeros for an optional argument of `count` states.
fn zeros_or<'a>(
    name: &str,
    array: &'a Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    width: usize,
    like: &States<'_>,
) -> PyResult<States<'a>> {
    let given = match array {
        Some(array) => states(name, array, width)?,
        None => States {
            values: Cow::Owned(vec![0.0; width * like.count]),
            count: like.count,
            single: like.single,
        },
    };
    if given.count != like.count {
        return Err(PyValueError::new_err(format!(
            "`{name}` has {} states, `q` has {}",
            given.count, like.count
        )));
    }
    Ok(given)
}

/// `values` as an array of shape (count, *shape), or `shape` alone for one state.
fn shaped<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    q: &States<'_>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let mut full = Vec::with_capacity(shape.len() + 1);
    if !q.single {
        full.push(q.count);
    }
    full.extend_from_slice(shape);
    numpy::PyArray1::from_vec(py, values).reshape(full)
}

/// Runs `evaluate` on a fresh batch of `prepared`'s dynamics with the GIL released.
fn batch<T: Send>(
    py: Python<'_>,
    prepared: &Prepared,
    evaluate: impl FnOnce(&mut StateBatch<'_>) -> Result<T, lsdc::api::StatesError> + Send,
) -> PyResult<T> {
    let prepared = &*prepared.inner;
    let result = py.detach(|| evaluate(&mut StateBatch::new(prepared)));
    result.map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Inverse dynamics (RNEA) at the states: see `Prepared.rnea`.
pub fn rnea<'py>(
    py: Python<'py>,
    prepared: &Prepared,
    q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    v: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
    a: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (nq, nv) = StateBatch::new(&prepared.inner).dimensions();
    let q = states("q", &q, nq)?;
    let (v, a) = (zeros_or("v", &v, nv, &q)?, zeros_or("a", &a, nv, &q)?);
    let mut tau = vec![0.0; q.count * nv];
    let inputs = (&*q.values, &*v.values, &*a.values);
    batch(py, prepared, |batch| batch.rnea(q.count, inputs, &mut tau))?;
    shaped(py, tau, &q, &[nv])
}

/// Forward dynamics (ABA) at the states: see `Prepared.aba`.
pub fn aba<'py>(
    py: Python<'py>,
    prepared: &Prepared,
    q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    v: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
    tau: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (nq, nv) = StateBatch::new(&prepared.inner).dimensions();
    let q = states("q", &q, nq)?;
    let (v, tau) = (zeros_or("v", &v, nv, &q)?, zeros_or("tau", &tau, nv, &q)?);
    let mut a = vec![0.0; q.count * nv];
    let inputs = (&*q.values, &*v.values, &*tau.values);
    batch(py, prepared, |batch| batch.aba(q.count, inputs, &mut a))?;
    shaped(py, a, &q, &[nv])
}

/// The mass matrix (CRBA) at the positions: see `Prepared.crba`.
pub fn crba<'py>(
    py: Python<'py>,
    prepared: &Prepared,
    q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (nq, nv) = StateBatch::new(&prepared.inner).dimensions();
    let q = states("q", &q, nq)?;
    let mut mass = vec![0.0; q.count * nv * nv];
    batch(py, prepared, |batch| {
        batch.crba(q.count, &q.values, &mut mass)
    })?;
    shaped(py, mass, &q, &[nv, nv])
}

/// A body's Jacobian at the positions: see `Prepared.jacobian`.
pub fn jacobian<'py>(
    py: Python<'py>,
    prepared: &Prepared,
    q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    body: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let batch_of = StateBatch::new(&prepared.inner);
    let (nq, nv) = batch_of.dimensions();
    let names = batch_of.body_names();
    let Some(index) = names.iter().position(|n| n == body) else {
        return Err(PyValueError::new_err(format!(
            "no body `{body}`: the bodies are {}",
            names.join(", ")
        )));
    };
    let q = states("q", &q, nq)?;
    let mut jacobian = vec![0.0; q.count * 6 * nv];
    batch(py, prepared, |batch| {
        batch.jacobians(q.count, &q.values, index, &mut jacobian)
    })?;
    shaped(py, jacobian, &q, &[6, nv])
}
