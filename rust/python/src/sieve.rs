//! `screen_candidates`, `screen_approaches` and `screen_stretches`: the all-on-all
//! screening sieve, its minima and their stretches within the distance (see
//! `rhoprop_core::sieve`), on one `Tracks` record of sampled tracks, each returning a
//! record.

use crate::long_call::long_call;
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::sieve::{self, SieveSettings, Tracks};

/// A C-contiguous (n, nt, 3) array as rows of 3.
fn triples<'a>(
    name: &str,
    a: &'a PyReadonlyArray3<'_, f64>,
    nt: usize,
) -> PyResult<&'a [[f64; 3]]> {
    let shape = a.shape();
    if shape[1] != nt || shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (objects, {nt}, 3), got {shape:?}"
        )));
    }
    let flat = a
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name} must be C-contiguous")))?;
    Ok(flat.as_chunks::<3>().0)
}

/// Sampled tracks of n objects on a common grid, checked when made: grid times (nt,) s,
/// positions and velocities (n, nt, 3) m and m/s (C-contiguous; held, not copied) and
/// the samples each object has (n,).
#[pyclass(frozen, name = "Tracks", module = "rhoprop._core")]
pub struct PyTracks {
    times: Vec<f64>,
    samples: Vec<usize>,
    positions: Py<PyArray3<f64>>,
    velocities: Py<PyArray3<f64>>,
}

#[pymethods]
impl PyTracks {
    #[new]
    #[pyo3(signature = (*, times, positions, velocities, samples))]
    fn new(
        times: PyReadonlyArray1<'_, f64>,
        positions: Bound<'_, PyArray3<f64>>,
        velocities: Bound<'_, PyArray3<f64>>,
        samples: PyReadonlyArray1<'_, u64>,
    ) -> PyResult<Self> {
        let n = samples.len();
        let nt = times.len();
        for (name, a) in [("positions", &positions), ("velocities", &velocities)] {
            if a.shape()[0] != n {
                return Err(PyValueError::new_err(format!(
                    "{name} must hold the {n} objects of samples, got {}",
                    a.shape()[0]
                )));
            }
            triples(name, &a.readonly(), nt)?;
        }
        Ok(Self {
            times: times.as_array().to_vec(),
            samples: samples.as_array().iter().map(|&s| s as usize).collect(),
            positions: positions.unbind(),
            velocities: velocities.unbind(),
        })
    }
}

impl PyTracks {
    /// Runs `f` on the core's view of these tracks with each object's coefficient
    /// `fourth` (zeros where unused), the arrays borrowed read-only meanwhile.
    fn with<R>(
        &self,
        py: Python<'_>,
        fourth: &[f64],
        f: impl FnOnce(&Tracks<'_>) -> PyResult<R>,
    ) -> PyResult<R> {
        let nt = self.times.len();
        let positions = self.positions.bind(py).readonly();
        let velocities = self.velocities.bind(py).readonly();
        let tracks = Tracks {
            times: &self.times,
            positions: triples("positions", &positions, nt)?,
            velocities: triples("velocities", &velocities, nt)?,
            samples: &self.samples,
            fourth,
        };
        f(&tracks)
    }
}

/// What `screen_candidates` returns: the candidate intervals (i, j, k) sorted and the
/// pair-interval counts of each stage (spatial, coarse, interpolated).
#[pyclass(frozen, get_all, name = "Candidates", module = "rhoprop._core")]
pub struct Candidates {
    i: Py<PyArray1<u32>>,
    j: Py<PyArray1<u32>>,
    k: Py<PyArray1<u32>>,
    spatial: u64,
    coarse: u64,
    interpolated: u64,
}

/// All-on-all sieve of `tracks` with each object's interpolation coefficient `fourth`
/// (n,): the intervals where two objects may come within `distance` m.
#[pyfunction]
#[pyo3(signature = (tracks, fourth, distance, max_acceleration, hermite_samples,
    progress = None))]
pub fn screen_candidates<'py>(
    py: Python<'py>,
    tracks: &Bound<'py, PyTracks>,
    fourth: PyReadonlyArray1<'py, f64>,
    distance: f64,
    max_acceleration: f64,
    hermite_samples: usize,
    progress: Option<Py<PyAny>>,
) -> PyResult<Candidates> {
    let tr = tracks.get();
    if fourth.len() != tr.samples.len() {
        return Err(PyValueError::new_err(format!(
            "fourth must hold the {} objects of the tracks, got {}",
            tr.samples.len(),
            fourth.len()
        )));
    }
    let fourth = fourth.as_array().to_vec();
    let settings = SieveSettings {
        distance,
        max_acceleration,
        hermite_samples,
    };
    let out = tr.with(py, &fourth, |t| {
        long_call(py, progress, |p| sieve::candidates(t, &settings, p))
    })?;
    let c = out.counts;
    Ok(Candidates {
        i: out.i.into_pyarray(py).unbind(),
        j: out.j.into_pyarray(py).unbind(),
        k: out.k.into_pyarray(py).unbind(),
        spatial: c.spatial,
        coarse: c.coarse,
        interpolated: c.interpolated,
    })
}

/// What `screen_approaches` returns: per minimum the objects (i, j), its time t (s),
/// both states there (m, 6) and where it lies (edge: 0 inside, 1 at the window's start,
/// 2 at its end).
#[pyclass(frozen, get_all, name = "Approaches", module = "rhoprop._core")]
pub struct Approaches {
    i: Py<PyArray1<u32>>,
    j: Py<PyArray1<u32>>,
    t: Py<PyArray1<f64>>,
    states1: Py<PyArray2<f64>>,
    states2: Py<PyArray2<f64>>,
    edge: Py<PyArray1<u8>>,
}

/// Minima of the distance within `distance` m in the candidate intervals (i, j, k) of
/// `tracks`, on the quintic Hermite interpolant with the gravity acceleration of
/// `zonal_degree`; the grid's ends are the window's own where `window_start` /
/// `window_end` say so.
#[pyfunction]
#[pyo3(signature = (tracks, i, j, k, zonal_degree, distance, progress = None,
    window_start = false, window_end = false))]
#[allow(clippy::too_many_arguments)]
pub fn screen_approaches<'py>(
    py: Python<'py>,
    tracks: &Bound<'py, PyTracks>,
    i: PyReadonlyArray1<'py, u32>,
    j: PyReadonlyArray1<'py, u32>,
    k: PyReadonlyArray1<'py, u32>,
    zonal_degree: u8,
    distance: f64,
    progress: Option<Py<PyAny>>,
    window_start: bool,
    window_end: bool,
) -> PyResult<Approaches> {
    let tr = tracks.get();
    let zeros = vec![0.0; tr.samples.len()];
    let (ci, cj, ck) = (
        i.as_array().to_vec(),
        j.as_array().to_vec(),
        k.as_array().to_vec(),
    );
    let ends = sieve::WindowEnds {
        start: window_start,
        end: window_end,
    };
    let found = tr.with(py, &zeros, |t| {
        long_call(py, progress, |p| {
            sieve::approaches(t, (&ci, &cj, &ck), zonal_degree, distance, ends, p)
        })
    })?;
    let states = |f: &dyn Fn(&sieve::Approach) -> [f64; 6]| {
        Array2::from_shape_fn((found.len(), 6), |(m, q)| f(&found[m])[q])
            .into_pyarray(py)
            .unbind()
    };
    let column = |f: &dyn Fn(&sieve::Approach) -> u32| {
        found
            .iter()
            .map(f)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .unbind()
    };
    Ok(Approaches {
        i: column(&|a| a.i),
        j: column(&|a| a.j),
        t: found
            .iter()
            .map(|a| a.t)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .unbind(),
        states1: states(&|a| a.state_i),
        states2: states(&|a| a.state_j),
        edge: found
            .iter()
            .map(|a| a.edge as u8)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .unbind(),
    })
}

/// What `screen_stretches` returns: per minimum the first and last times (s) between
/// which the objects stay within the distance around it.
#[pyclass(frozen, get_all, name = "Stretches", module = "rhoprop._core")]
pub struct Stretches {
    first: Py<PyArray1<f64>>,
    last: Py<PyArray1<f64>>,
}

/// Per minimum (i, j, t s) of `tracks`, the stretch within `distance` m around it (cubic
/// Hermite relative motion, crossings by bisection).
#[pyfunction]
#[pyo3(signature = (tracks, i, j, t, distance, progress = None))]
pub fn screen_stretches<'py>(
    py: Python<'py>,
    tracks: &Bound<'py, PyTracks>,
    i: PyReadonlyArray1<'py, u32>,
    j: PyReadonlyArray1<'py, u32>,
    t: PyReadonlyArray1<'py, f64>,
    distance: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Stretches> {
    let tr = tracks.get();
    let zeros = vec![0.0; tr.samples.len()];
    let (ci, cj, ct) = (
        i.as_array().to_vec(),
        j.as_array().to_vec(),
        t.as_array().to_vec(),
    );
    let out = tr.with(py, &zeros, |tracks| {
        long_call(py, progress, |p| {
            sieve::stretches(tracks, &ci, &cj, &ct, distance, p)
        })
    })?;
    Ok(Stretches {
        first: out
            .iter()
            .map(|s| s.0)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .unbind(),
        last: out
            .iter()
            .map(|s| s.1)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .unbind(),
    })
}

/// Adds the tracks and the sieve's records to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTracks>()?;
    m.add_class::<Candidates>()?;
    m.add_class::<Approaches>()?;
    m.add_class::<Stretches>()?;
    Ok(())
}
