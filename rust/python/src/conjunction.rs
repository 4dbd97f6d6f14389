//! Probability of collision: the 2-D Gaussian Pc and the Monte Carlo pair count.

use crate::arrays::{fixed, rows};
use crate::errors::to_py;
use crate::long_call::long_call;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rhoprop_core::conjunction::{self, HardBodyShape, NpdPolicy};
use rhoprop_core::encounter;

/// A (3, 3) matrix, row-major.
fn matrix3(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<[[f64; 3]; 3]> {
    let v = a.as_array();
    if v.shape() != [3, 3] {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (3, 3), got {:?}",
            v.shape()
        )));
    }
    Ok(std::array::from_fn(|i| std::array::from_fn(|j| v[[i, j]])))
}

fn array2<const R: usize, const C: usize>(m: &[[f64; C]; R]) -> Array2<f64> {
    Array2::from_shape_fn((R, C), |(i, j)| m[i][j])
}

/// What `pc_2d` returns: pc, miss distance (m), relative speed (m/s), the encounter-plane
/// covariance integrated (2, 2) m^2, whether it was repaired, the projected covariance
/// before repair (2, 2) m^2 and the encounter axes (3, 3), rows x, y, z.
#[pyclass(frozen, get_all, name = "Pc2d", module = "rhoprop._core")]
pub struct Pc2d {
    pc: f64,
    miss_distance: f64,
    relative_speed: f64,
    covariance: Py<PyArray2<f64>>,
    repaired: bool,
    projected_covariance: Py<PyArray2<f64>>,
    axes: Py<PyArray2<f64>>,
}

/// Short-encounter 2-D Pc of two objects at TCA; see `rhoprop.conjunction.pc_2d` for the
/// documented API. Inertial r (3,) m, v (3,) m/s, position covariances (3, 3) m^2.
/// Returns a `Pc2d` record.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn pc_2d<'py>(
    py: Python<'py>,
    r1: PyReadonlyArray1<'py, f64>,
    v1: PyReadonlyArray1<'py, f64>,
    cov1: PyReadonlyArray2<'py, f64>,
    r2: PyReadonlyArray1<'py, f64>,
    v2: PyReadonlyArray1<'py, f64>,
    cov2: PyReadonlyArray2<'py, f64>,
    hard_body_radius: f64,
    shape: &str,
    npd: &str,
) -> PyResult<Pc2d> {
    let shape = HardBodyShape::from_name(shape).map_err(to_py)?;
    let npd = NpdPolicy::from_name(npd).map_err(to_py)?;
    let out = conjunction::pc_2d(
        fixed::<3>("r1", &r1)?,
        fixed::<3>("v1", &v1)?,
        &matrix3("cov1", &cov1)?,
        fixed::<3>("r2", &r2)?,
        fixed::<3>("v2", &v2)?,
        &matrix3("cov2", &cov2)?,
        hard_body_radius,
        shape,
        npd,
    )
    .map_err(to_py)?;
    Ok(Pc2d {
        pc: out.pc,
        miss_distance: out.encounter.miss_distance,
        relative_speed: out.encounter.relative_speed,
        covariance: array2(&out.covariance).into_pyarray(py).unbind(),
        repaired: out.repaired,
        projected_covariance: array2(&out.encounter.covariance).into_pyarray(py).unbind(),
        axes: array2(&out.encounter.axes).into_pyarray(py).unbind(),
    })
}

/// Monte Carlo Pc over all pairs of member states (n1, 6) and (n2, 6) (m, m/s): the
/// fraction of pairs whose straight-line relative motion passes within the hard-body
/// radius. Returns (hits, pairs, pc, variance). Runs with the GIL released; Ctrl-C
/// cancels it.
#[pyfunction]
pub fn pc_pairs(
    py: Python<'_>,
    members1: PyReadonlyArray2<'_, f64>,
    members2: PyReadonlyArray2<'_, f64>,
    hard_body_radius: f64,
) -> PyResult<PairsPc> {
    let to_rows = |name: &str, a: &PyReadonlyArray2<'_, f64>| -> PyResult<Vec<[f64; 6]>> {
        let v = rows(name, a, 6)?;
        Ok((0..v.nrows())
            .map(|i| std::array::from_fn(|k| v[[i, k]]))
            .collect())
    };
    let m1 = to_rows("members1", &members1)?;
    let m2 = to_rows("members2", &members2)?;
    let out = long_call(py, None, |p| {
        conjunction::pc_pairs(&m1, &m2, hard_body_radius, p)
    })?;
    Ok(PairsPc {
        hits: out.hits,
        pairs: out.pairs,
        pc: out.pc,
        variance: out.variance,
    })
}

/// What `pc_pairs` returns: the pairs that hit, all pairs, their fraction (the Pc) and
/// its variance.
#[pyclass(frozen, get_all, name = "PairsPc", module = "rhoprop._core")]
pub struct PairsPc {
    hits: u64,
    pairs: u64,
    pc: f64,
    variance: f64,
}

/// How many relative states (n, 6) (LVLH x y z m, u v w m/s at TCA) come within
/// `hard_body_radius` m over [-span/2, span/2] s of Clohessy-Wiltshire motion of mean
/// motion `mean_motion` rad/s, on `coarse_points` and `grid_points` even times; see
/// `rhoprop.conjunction.encounter.pc_interval`. GIL released; Ctrl-C cancels it.
#[pyfunction]
pub fn interval_hits(
    py: Python<'_>,
    states: PyReadonlyArray2<'_, f64>,
    mean_motion: f64,
    span: f64,
    hard_body_radius: f64,
    coarse_points: usize,
    grid_points: usize,
) -> PyResult<u64> {
    let v = rows("states", &states, 6)?;
    let q: Vec<[f64; 6]> = (0..v.nrows())
        .map(|i| std::array::from_fn(|k| v[[i, k]]))
        .collect();
    long_call(py, None, |p| {
        encounter::interval_hits(
            &q,
            mean_motion,
            span,
            hard_body_radius,
            coarse_points,
            grid_points,
            p,
        )
    })
}

/// Registers the conjunction functions (one line in `lib.rs`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Pc2d>()?;
    m.add_class::<PairsPc>()?;
    m.add_function(wrap_pyfunction!(pc_2d, m)?)?;
    m.add_function(wrap_pyfunction!(interval_hits, m)?)?;
    m.add_function(wrap_pyfunction!(pc_pairs, m)?)?;
    m.add(
        "HARD_BODY_SHAPES",
        PyTuple::new(m.py(), HardBodyShape::NAMES)?,
    )?;
    Ok(())
}
