//! Point evaluation of the analytic density models (JB2008, Jacchia-Roberts 1971) on
//! arrays of points, in parallel with the GIL released. The Python models sample these
//! into density fields; nothing here is called from the propagators.

use crate::arrays::{rows, vector};
use crate::errors::to_py;
use numpy::ndarray::{Array1, ArrayView1, ArrayView2};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use rhoprop_core::density::jacchia_roberts::jacchia_roberts;
use rhoprop_core::density::jb2008::{self, Jb2008Indices, Jb2008Output};
use rhoprop_core::CoreError;

/// Points per parallel task.
const CHUNK: usize = 256;

/// (exospheric temperature K, local temperature K, density kg/m^3) arrays.
/// What the model functions return per point (n,): the exospheric temperature (K), the
/// temperature at the point (K) and the density (kg/m^3).
#[pyclass(frozen, get_all, name = "ModelPoints", module = "rhoprop._core")]
pub struct ModelPoints {
    exospheric_temperature: Py<PyArray1<f64>>,
    temperature: Py<PyArray1<f64>>,
    density: Py<PyArray1<f64>>,
}

fn check_len(name: &str, got: usize, want: usize) -> PyResult<()> {
    if got == want {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name} has {got} rows, expected {want} (one per point)"
        )))
    }
}

/// Evaluates `f(i)` for i in 0..n in parallel; the first error (by index) wins. Called
/// on one of the core's worker threads (a density tile sampled for a propagation in
/// flight, through a streamed field's source), it evaluates on that thread alone: a
/// parallel loop there would let the thread take up other propagation work while it
/// waits, which asks for the tile being made and waits on its own lock for ever.
fn par_eval<F>(py: Python<'_>, n: usize, f: F) -> PyResult<Vec<Jb2008Output>>
where
    F: Fn(usize) -> Result<Jb2008Output, CoreError> + Sync,
{
    if rayon::current_thread_index().is_some() {
        return py
            .detach(|| (0..n).map(&f).collect::<Result<Vec<_>, CoreError>>())
            .map_err(to_py);
    }
    let pool = crate::pool::current()?;
    py.detach(|| {
        pool.install(|| {
            (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(&f)
                .collect::<Result<Vec<_>, CoreError>>()
        })
    })
    .map_err(to_py)
}

fn indices_row(v: &ArrayView2<'_, f64>, i: usize) -> Jb2008Indices {
    Jb2008Indices::from_array(std::array::from_fn(|j| v[[i, j]]))
}

fn triple(py: Python<'_>, out: &[Jb2008Output]) -> ModelPoints {
    let column = |f: fn(&Jb2008Output) -> f64| {
        out.iter()
            .map(f)
            .collect::<Array1<f64>>()
            .into_pyarray(py)
            .unbind()
    };
    ModelPoints {
        exospheric_temperature: column(|o| o.tinf),
        temperature: column(|o| o.temp),
        density: column(|o| o.rho),
    }
}

/// Views of named point arrays (times, latitudes, longitudes, altitudes), all of the first
/// one's length.
fn points<'a, 'py>(
    arrays: [(&str, &'a PyReadonlyArray1<'py, f64>); 4],
) -> PyResult<[ArrayView1<'a, f64>; 4]> {
    let views = [
        vector(arrays[0].0, arrays[0].1)?,
        vector(arrays[1].0, arrays[1].1)?,
        vector(arrays[2].0, arrays[2].1)?,
        vector(arrays[3].0, arrays[3].1)?,
    ];
    for (k, v) in views.iter().enumerate().skip(1) {
        check_len(arrays[k].0, v.len(), views[0].len())?;
    }
    Ok(views)
}

/// The JB2008 routine called as the reference is: modified Julian dates ``amjd`` (n,),
/// ``geometry`` (n, 5) = Sun right ascension, Sun declination, point right ascension,
/// point latitude (rad) and altitude (km), ``indices`` (n, 9) = F10, F10B, S10, S10B, M10,
/// M10B, Y10, Y10B (sfu) and dTc (K). Returns a `ModelPoints`.
#[pyfunction]
pub fn jb2008_core<'py>(
    py: Python<'py>,
    amjd: PyReadonlyArray1<'py, f64>,
    geometry: PyReadonlyArray2<'py, f64>,
    indices: PyReadonlyArray2<'py, f64>,
) -> PyResult<ModelPoints> {
    let t = vector("amjd", &amjd)?;
    let g = rows("geometry", &geometry, 5)?;
    let ix = rows("indices", &indices, 9)?;
    check_len("geometry", g.nrows(), t.len())?;
    check_len("indices", ix.nrows(), t.len())?;
    let out = par_eval(py, t.len(), |i| {
        jb2008::jb2008(
            t[i],
            g[[i, 0]],
            g[[i, 1]],
            g[[i, 2]],
            g[[i, 3]],
            g[[i, 4]],
            &indices_row(&ix, i),
        )
    })?;
    Ok(triple(py, &out))
}

/// JB2008 at modified Julian dates ``amjd`` (n,) UTC, geodetic ``lat``/``lon`` (n,) deg and
/// altitude ``alt`` (n,) m, with ``indices`` (n, 9) as in :func:`jb2008_core` and the
/// reference driver's Sun position and Greenwich angle. Returns a `ModelPoints`.
#[pyfunction]
pub fn jb2008_geodetic<'py>(
    py: Python<'py>,
    amjd: PyReadonlyArray1<'py, f64>,
    lat: PyReadonlyArray1<'py, f64>,
    lon: PyReadonlyArray1<'py, f64>,
    alt: PyReadonlyArray1<'py, f64>,
    indices: PyReadonlyArray2<'py, f64>,
) -> PyResult<ModelPoints> {
    let [t, la, lo, al] = points([("amjd", &amjd), ("lat", &lat), ("lon", &lon), ("alt", &alt)])?;
    let ix = rows("indices", &indices, 9)?;
    check_len("indices", ix.nrows(), t.len())?;
    let out = par_eval(py, t.len(), |i| {
        jb2008::density_geodetic(t[i], la[i], lo[i], al[i], &indices_row(&ix, i))
    })?;
    Ok(triple(py, &out))
}

/// Jacchia-Roberts 1971 at modified Julian dates ``mjd`` (n,) UTC, geodetic ``lat``/``lon``
/// (n,) deg, altitude ``alt`` (n,) m (>= 90 km) and ``drivers`` (n, 3) = F10.7, its 81-day
/// centred mean (sfu) and Kp. Returns a `ModelPoints`.
#[pyfunction]
pub fn jacchia_roberts_geodetic<'py>(
    py: Python<'py>,
    mjd: PyReadonlyArray1<'py, f64>,
    lat: PyReadonlyArray1<'py, f64>,
    lon: PyReadonlyArray1<'py, f64>,
    alt: PyReadonlyArray1<'py, f64>,
    drivers: PyReadonlyArray2<'py, f64>,
) -> PyResult<ModelPoints> {
    let [t, la, lo, al] = points([("mjd", &mjd), ("lat", &lat), ("lon", &lon), ("alt", &alt)])?;
    let d = rows("drivers", &drivers, 3)?;
    check_len("drivers", d.nrows(), t.len())?;
    let out = par_eval(py, t.len(), |i| {
        jacchia_roberts(t[i], la[i], lo[i], al[i], d[[i, 0]], d[[i, 1]], d[[i, 2]]).map(|o| {
            Jb2008Output {
                tinf: o.tinf,
                temp: o.temp,
                rho: o.rho,
            }
        })
    })?;
    Ok(triple(py, &out))
}

/// Registers the model functions (one line in `lib.rs`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ModelPoints>()?;
    m.add_function(wrap_pyfunction!(jb2008_core, m)?)?;
    m.add_function(wrap_pyfunction!(jb2008_geodetic, m)?)?;
    m.add_function(wrap_pyfunction!(jacchia_roberts_geodetic, m)?)?;
    Ok(())
}
