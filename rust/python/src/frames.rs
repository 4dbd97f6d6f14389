//! Vectorised frame and time functions over numpy arrays.

use crate::arrays::{row3, rows, vector};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::frames::{self, EarthRotation, Geodetic};
use rhoprop_core::time;

fn same_len(a: usize, b: usize, what: &str) -> PyResult<()> {
    if a == b {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{what}: lengths differ ({a} vs {b})"
        )))
    }
}

/// GMST (IAU-82) in radians for UT1 seconds since J2000 (n,).
#[pyfunction]
pub fn gmst<'py>(
    py: Python<'py>,
    ut1: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let t = vector("ut1", &ut1)?;
    Ok(t.mapv(time::gmst).into_pyarray(py))
}

/// Inertial (n, 3) -> Earth-fixed (n, 3) positions at UT1 seconds since J2000 (n,).
#[pyfunction]
pub fn inertial_to_fixed<'py>(
    py: Python<'py>,
    ut1: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let t = vector("ut1", &ut1)?;
    let p = rows("positions", &positions, 3)?;
    same_len(t.len(), p.nrows(), "ut1 and positions")?;
    let mut out = Array2::zeros((t.len(), 3));
    for i in 0..t.len() {
        let f = EarthRotation::new(time::gmst(t[i])).to_fixed(row3(&p, i));
        for c in 0..3 {
            out[[i, c]] = f[c];
        }
    }
    Ok(out.into_pyarray(py))
}

/// Earth-fixed positions (n, 3) m -> geodetic WGS-84 (n, 3): lat deg, lon deg, alt m.
#[pyfunction]
pub fn geodetic<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let p = rows("positions", &positions, 3)?;
    let mut out = Array2::zeros((p.nrows(), 3));
    for i in 0..p.nrows() {
        let g = frames::geodetic(row3(&p, i));
        out[[i, 0]] = g.lat.to_degrees();
        out[[i, 1]] = g.lon.to_degrees();
        out[[i, 2]] = g.alt;
    }
    Ok(out.into_pyarray(py))
}

/// Geodetic WGS-84 (n, 3) lat deg, lon deg, alt m -> Earth-fixed positions (n, 3) m.
#[pyfunction]
pub fn geodetic_to_fixed<'py>(
    py: Python<'py>,
    lla: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let g = rows("lla", &lla, 3)?;
    let mut out = Array2::zeros((g.nrows(), 3));
    for i in 0..g.nrows() {
        let r = frames::geodetic_to_fixed(Geodetic {
            lat: g[[i, 0]].to_radians(),
            lon: g[[i, 1]].to_radians(),
            alt: g[[i, 2]],
        });
        for c in 0..3 {
            out[[i, c]] = r[c];
        }
    }
    Ok(out.into_pyarray(py))
}

/// RTN bases (n, 3, 3) of positions and velocities (n, 3); rows are R, T, N.
#[pyfunction]
pub fn rtn_basis<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f64>,
    velocities: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let p = rows("positions", &positions, 3)?;
    let v = rows("velocities", &velocities, 3)?;
    same_len(p.nrows(), v.nrows(), "positions and velocities")?;
    let mut out = Array3::zeros((p.nrows(), 3, 3));
    for i in 0..p.nrows() {
        let (r, w) = (row3(&p, i), row3(&v, i));
        if frames::norm(frames::cross(r, w)) == 0.0 {
            return Err(PyValueError::new_err(format!(
                "row {i}: position and velocity are parallel (or zero); RTN is undefined"
            )));
        }
        let b = frames::rtn_basis(r, w);
        for a in 0..3 {
            for c in 0..3 {
                out[[i, a, c]] = b[a][c];
            }
        }
    }
    Ok(out.into_pyarray(py))
}
