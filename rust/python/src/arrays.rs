//! Array conversion and shape checks. numpy arrays arrive as row-major views (read
//! through `as_array()`, never copied into nested Vecs); results leave as owned
//! ndarrays handed to numpy without a copy.

use numpy::ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::PyResult;
use rhoprop_core::dynamics::Perturbation;
use rhoprop_core::problem::Problem;

/// A (n,) float64 array as a view.
pub fn vector<'a>(name: &str, a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<ArrayView1<'a, f64>> {
    let v = a.as_array();
    if v.is_empty() {
        return Err(PyValueError::new_err(format!("{name} must not be empty")));
    }
    Ok(v)
}

/// A (n, k) float64 array as a view, checking k.
pub fn rows<'a>(
    name: &str,
    a: &'a PyReadonlyArray2<'_, f64>,
    k: usize,
) -> PyResult<ArrayView2<'a, f64>> {
    let v = a.as_array();
    if v.ncols() != k {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (n, {k}), got {:?}",
            v.shape()
        )));
    }
    Ok(v)
}

/// A fixed-length vector from a (k,) array.
pub fn fixed<const K: usize>(name: &str, a: &PyReadonlyArray1<'_, f64>) -> PyResult<[f64; K]> {
    let v = a.as_array();
    if v.len() != K {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape ({K},), got {:?}",
            v.shape()
        )));
    }
    Ok(std::array::from_fn(|i| v[i]))
}

/// Row `i` of a (n, 3) view.
pub fn row3(v: &ArrayView2<'_, f64>, i: usize) -> [f64; 3] {
    [v[[i, 0]], v[[i, 1]], v[[i, 2]]]
}

/// A Vec of fixed-size rows as an (n, K) array.
pub fn from_rows<const K: usize>(rows: &[[f64; K]]) -> Array2<f64> {
    Array2::from_shape_fn((rows.len(), K), |(i, j)| rows[i][j])
}

/// A Vec as a (n,) array.
pub fn from_vec(v: Vec<f64>) -> Array1<f64> {
    Array1::from_vec(v)
}

/// A (6, 6) matrix, row-major.
pub fn matrix6(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<[[f64; 6]; 6]> {
    let v = a.as_array();
    if v.shape() != [6, 6] {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (6, 6), got {:?}",
            v.shape()
        )));
    }
    Ok(std::array::from_fn(|i| std::array::from_fn(|j| v[[i, j]])))
}

/// The perturbation form from its Python name (parsed by the core).
pub fn perturbation(name: &str) -> PyResult<Perturbation> {
    Perturbation::from_name(name).map_err(crate::errors::to_py)
}

/// The initial-value problem of a run, the one place the binding builds it.
pub fn problem(
    epoch: f64,
    state: &PyReadonlyArray1<'_, f64>,
    drag: f64,
    floor_altitude: f64,
    zonal_degree: u8,
    forces: (Option<u8>, Option<bool>, f64),
) -> PyResult<Problem> {
    Ok(Problem {
        epoch,
        y0: fixed::<6>("state", state)?,
        drag,
        floor_altitude,
        zonal_degree,
        forces: rhoprop_core::problem::Forces {
            field_degree: forces.0,
            third_bodies: forces.1,
            radiation: forces.2,
        },
    })
}
