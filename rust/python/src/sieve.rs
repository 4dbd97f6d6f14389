//! `screen_candidates`, `screen_approaches` and `screen_stretches`: the all-on-all
//! screening sieve, its minima and their stretches within the distance (see
//! `rhoprop_core::sieve`).

use crate::long_call::long_call;
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::sieve::{self, SieveSettings, Tracks};

/// (i, j, k) of the candidate intervals and the counts (spatial, coarse, interpolated).
type CandidatesOut<'py> = (
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    (u64, u64, u64),
);

/// (i, j, t, states of i (m, 6), states of j (m, 6)) of the approaches.
type ApproachesOut<'py> = (
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u8>>,
);

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

/// What both calls take besides the sample arrays, checked and owned: grid times (s),
/// samples per object and the interpolation coefficient per object (zeros where unused).
struct Grid {
    times: Vec<f64>,
    samples: Vec<usize>,
    fourth: Vec<f64>,
}

impl Grid {
    fn new(
        times: &PyReadonlyArray1<'_, f64>,
        samples: &PyReadonlyArray1<'_, u64>,
        positions: &PyReadonlyArray3<'_, f64>,
        velocities: &PyReadonlyArray3<'_, f64>,
        fourth: Option<&PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Self> {
        let n = samples.len();
        if positions.shape()[0] != n
            || velocities.shape()[0] != n
            || fourth.is_some_and(|f| f.len() != n)
        {
            return Err(PyValueError::new_err(format!(
                "positions, velocities (and fourth) must hold the {n} objects of samples"
            )));
        }
        Ok(Grid {
            times: times.as_array().to_vec(),
            samples: samples.as_array().iter().map(|&s| s as usize).collect(),
            fourth: fourth.map_or_else(|| vec![0.0; n], |f| f.as_array().to_vec()),
        })
    }

    /// The core's view of the tracks (the sample arrays read in place).
    fn tracks<'a>(
        &'a self,
        positions: &'a PyReadonlyArray3<'_, f64>,
        velocities: &'a PyReadonlyArray3<'_, f64>,
    ) -> PyResult<Tracks<'a>> {
        Ok(Tracks {
            times: &self.times,
            positions: triples("positions", positions, self.times.len())?,
            velocities: triples("velocities", velocities, self.times.len())?,
            samples: &self.samples,
            fourth: &self.fourth,
        })
    }
}

/// Candidate intervals of every object pair on a common grid; see
/// `rhoprop.conjunction.screen_all`. times (nt,) s, positions and velocities
/// (n, nt, 3) m and m/s, samples (n,) valid samples per object, fourth (n,). Runs with
/// the GIL released; progress counts grid intervals; Ctrl-C cancels it.
#[pyfunction]
#[pyo3(signature = (times, positions, velocities, samples, fourth, distance, max_acceleration,
    hermite_samples, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn screen_candidates<'py>(
    py: Python<'py>,
    times: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray3<'py, f64>,
    velocities: PyReadonlyArray3<'py, f64>,
    samples: PyReadonlyArray1<'py, u64>,
    fourth: PyReadonlyArray1<'py, f64>,
    distance: f64,
    max_acceleration: f64,
    hermite_samples: usize,
    progress: Option<Py<PyAny>>,
) -> PyResult<CandidatesOut<'py>> {
    let g = Grid::new(&times, &samples, &positions, &velocities, Some(&fourth))?;
    let tracks = g.tracks(&positions, &velocities)?;
    let settings = SieveSettings {
        distance,
        max_acceleration,
        hermite_samples,
    };
    let out = long_call(py, progress, |p| sieve::candidates(&tracks, &settings, p))?;
    let c = out.counts;
    Ok((
        out.i.into_pyarray(py),
        out.j.into_pyarray(py),
        out.k.into_pyarray(py),
        (c.spatial, c.coarse, c.interpolated),
    ))
}

/// The minima of the distance within `distance` in candidate intervals (i, j, k) of
/// tracks as for `screen_candidates`, on the quintic Hermite interpolant with the gravity
/// acceleration of zonal degree `zonal_degree`. `window_start` / `window_end`: the grid's
/// first / last time is the screening window's own, where a minimum at the end counts.
/// Returns (i, j, t s, states of i (m, 6), states of j (m, 6), edge: 0 inside the window,
/// 1 at its start, 2 at its end) in the candidates' order. GIL released; Ctrl-C cancels it.
#[pyfunction]
#[pyo3(signature = (times, positions, velocities, samples, i, j, k, zonal_degree, distance,
    progress=None, window_start=false, window_end=false))]
#[allow(clippy::too_many_arguments)]
pub fn screen_approaches<'py>(
    py: Python<'py>,
    times: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray3<'py, f64>,
    velocities: PyReadonlyArray3<'py, f64>,
    samples: PyReadonlyArray1<'py, u64>,
    i: PyReadonlyArray1<'py, u32>,
    j: PyReadonlyArray1<'py, u32>,
    k: PyReadonlyArray1<'py, u32>,
    zonal_degree: u8,
    distance: f64,
    progress: Option<Py<PyAny>>,
    window_start: bool,
    window_end: bool,
) -> PyResult<ApproachesOut<'py>> {
    let g = Grid::new(&times, &samples, &positions, &velocities, None)?;
    let tracks = g.tracks(&positions, &velocities)?;
    let (ci, cj, ck) = (
        i.as_array().to_vec(),
        j.as_array().to_vec(),
        k.as_array().to_vec(),
    );
    let found = long_call(py, progress, |p| {
        let ends = sieve::WindowEnds {
            start: window_start,
            end: window_end,
        };
        sieve::approaches(&tracks, (&ci, &cj, &ck), zonal_degree, distance, ends, p)
    })?;
    let states = |f: &dyn Fn(&sieve::Approach) -> [f64; 6]| {
        Array2::from_shape_fn((found.len(), 6), |(m, q)| f(&found[m])[q])
    };
    let (si, sj) = (states(&|a| a.state_i), states(&|a| a.state_j));
    Ok((
        found
            .iter()
            .map(|a| a.i)
            .collect::<Vec<_>>()
            .into_pyarray(py),
        found
            .iter()
            .map(|a| a.j)
            .collect::<Vec<_>>()
            .into_pyarray(py),
        found
            .iter()
            .map(|a| a.t)
            .collect::<Vec<_>>()
            .into_pyarray(py),
        si.into_pyarray(py),
        sj.into_pyarray(py),
        found
            .iter()
            .map(|a| a.edge as u8)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    ))
}

/// (first, last) s of each minimum's stretch within the distance.
type StretchesOut<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// For each minimum (i, j, t s) of tracks as for `screen_approaches`, the (first, last)
/// times s between which the objects stay within `distance` m around it (cubic Hermite
/// relative motion, crossings by bisection). Returns (first (m,), last (m,)). GIL
/// released; progress counts minima; Ctrl-C cancels it.
#[pyfunction]
#[pyo3(signature = (times, positions, velocities, samples, i, j, t, distance, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn screen_stretches<'py>(
    py: Python<'py>,
    times: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray3<'py, f64>,
    velocities: PyReadonlyArray3<'py, f64>,
    samples: PyReadonlyArray1<'py, u64>,
    i: PyReadonlyArray1<'py, u32>,
    j: PyReadonlyArray1<'py, u32>,
    t: PyReadonlyArray1<'py, f64>,
    distance: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<StretchesOut<'py>> {
    let g = Grid::new(&times, &samples, &positions, &velocities, None)?;
    let tracks = g.tracks(&positions, &velocities)?;
    let (ci, cj, ct) = (
        i.as_array().to_vec(),
        j.as_array().to_vec(),
        t.as_array().to_vec(),
    );
    let out = long_call(py, progress, |p| {
        sieve::stretches(&tracks, &ci, &cj, &ct, distance, p)
    })?;
    Ok((
        out.iter().map(|s| s.0).collect::<Vec<_>>().into_pyarray(py),
        out.iter().map(|s| s.1).collect::<Vec<_>>().into_pyarray(py),
    ))
}
