//! Vectorised frame and time functions over numpy arrays.

use crate::arrays::{fixed, row3, rows, vector};
use nalgebra::Vector6;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::equinoctial;
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

/// The kind of semi-major axis from its name.
fn semi_major_arg(name: &str) -> PyResult<equinoctial::SemiMajor> {
    match name {
        "osculating" => Ok(equinoctial::SemiMajor::Osculating),
        "energy" => Ok(equinoctial::SemiMajor::Energy),
        _ => Err(PyValueError::new_err(format!(
            "semi_major must be 'osculating' or 'energy', got {name:?}"
        ))),
    }
}

/// The axes of `reference` (a Cartesian state) for equinoctial elements.
fn element_axes(reference: &PyReadonlyArray1<'_, f64>) -> PyResult<equinoctial::Axes> {
    let r = fixed::<6>("reference", reference)?;
    Ok(equinoctial::Axes::for_state(&Vector6::from(r)))
}

/// Cartesian states (n, 6) m, m/s -> equinoctial elements (n, 6) (a m, h, k, p, q,
/// lambda rad), in the axes of `reference` and with lambda within pi of its lambda; a
/// of kind `semi_major` ("osculating" or "energy").
#[pyfunction]
#[pyo3(signature = (states, reference, semi_major = "osculating"))]
pub fn equinoctial_elements<'py>(
    py: Python<'py>,
    states: PyReadonlyArray2<'py, f64>,
    reference: PyReadonlyArray1<'py, f64>,
    semi_major: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let semi = semi_major_arg(semi_major)?;
    let s = rows("states", &states, 6)?;
    let axes = element_axes(&reference)?;
    let r = fixed::<6>("reference", &reference)?;
    let centre = equinoctial::from_cartesian(&Vector6::from(r), axes, "reference")
        .map_err(crate::errors::to_py)?;
    let mut out = Array2::zeros((s.nrows(), 6));
    for i in 0..s.nrows() {
        let x = Vector6::from_iterator(s.row(i).iter().copied());
        let el = equinoctial::from_cartesian_with(&x, axes, semi, &format!("states[{i}]"))
            .map_err(crate::errors::to_py)?;
        let el = equinoctial::unwrap_near(&el, centre[5]);
        for c in 0..6 {
            out[[i, c]] = el[c];
        }
    }
    Ok(out.into_pyarray(py))
}

/// Equinoctial elements (n, 6) -> Cartesian states (n, 6), in the axes of `reference`.
#[pyfunction]
#[pyo3(signature = (elements, reference, semi_major = "osculating"))]
pub fn equinoctial_to_cartesian<'py>(
    py: Python<'py>,
    elements: PyReadonlyArray2<'py, f64>,
    reference: PyReadonlyArray1<'py, f64>,
    semi_major: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let semi = semi_major_arg(semi_major)?;
    let e = rows("elements", &elements, 6)?;
    let axes = element_axes(&reference)?;
    let mut out = Array2::zeros((e.nrows(), 6));
    for i in 0..e.nrows() {
        let el = Vector6::from_iterator(e.row(i).iter().copied());
        if el[0].is_nan() || el[0] <= 0.0 || el[1] * el[1] + el[2] * el[2] >= 1.0 {
            return Err(PyValueError::new_err(format!(
                "elements[{i}] is not an elliptic orbit (a = {} m, h^2 + k^2 = {})",
                el[0],
                el[1] * el[1] + el[2] * el[2]
            )));
        }
        let x = equinoctial::to_cartesian_with(&el, axes, semi);
        for c in 0..6 {
            out[[i, c]] = x[c];
        }
    }
    Ok(out.into_pyarray(py))
}
