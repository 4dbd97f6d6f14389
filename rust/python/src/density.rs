//! Density sources as frozen Python classes wrapping the core types.

use crate::arrays::{row3, rows, vector};
use crate::errors::to_py;
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray4};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use rhoprop_core::density::{
    Atmosphere, Exponential, FieldTile, GriddedField, StreamedField, TileSource,
};
use rhoprop_core::frames::EarthRotation;
use rhoprop_core::time::gmst;
use rhoprop_core::CoreError;
use std::borrow::Cow;
use std::sync::Arc;

/// (mean, sigma) arrays, kg/m^3.
type MeanSigma<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// Exponential atmosphere rho0 * exp(-(h - h0)/H), h = |r| - Re (spherical altitude).
#[pyclass(frozen, name = "ExponentialAtmosphere", module = "rhoprop._core")]
pub struct PyExponential(pub Exponential);

#[pymethods]
impl PyExponential {
    #[new]
    #[pyo3(signature = (rho0, h0, scale_height, rel_sigma = 0.0))]
    fn new(rho0: f64, h0: f64, scale_height: f64, rel_sigma: f64) -> PyResult<Self> {
        Exponential::new(rho0, h0, scale_height, rel_sigma)
            .map(Self)
            .map_err(to_py)
    }

    /// This atmosphere with its sigma times `factor` (finite, >= 0).
    fn with_sigma_scale(&self, factor: f64) -> PyResult<Self> {
        self.0.with_sigma_scale(factor).map(Self).map_err(to_py)
    }

    /// Mean and sigma (kg/m^3) at inertial positions (n, 3) m and times ut1 (n,) s
    /// since J2000.
    fn mean_sigma<'py>(
        &self,
        py: Python<'py>,
        ut1: PyReadonlyArray1<'py, f64>,
        positions: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<MeanSigma<'py>> {
        mean_sigma_at(py, &self.0, ut1, positions)
    }
}

/// Density sampled on a (time, altitude, latitude, longitude) grid of ln(mean) and
/// sigma/mean, interpolated multilinearly; periodic in longitude; an error outside.
#[pyclass(frozen, weakref, name = "GriddedAtmosphere", module = "rhoprop._core")]
pub struct PyGridded(pub Arc<GriddedField>);

#[pymethods]
impl PyGridded {
    #[new]
    #[pyo3(signature = (epoch, time, altitude, latitude, lon0, ln_mean, rel_sigma))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        epoch: f64,
        time: PyReadonlyArray1<'_, f64>,
        altitude: (f64, f64, usize),
        latitude: (f64, f64, usize),
        lon0: f64,
        ln_mean: PyReadonlyArray4<'_, f64>,
        rel_sigma: PyReadonlyArray4<'_, f64>,
    ) -> PyResult<Self> {
        let (time, nlon, ln_mean, rel_sigma) =
            tile_arrays(time, altitude, latitude, &ln_mean, &rel_sigma)?;
        GriddedField::new(
            epoch, time, altitude, latitude, lon0, nlon, ln_mean, rel_sigma,
        )
        .map(|f| Self(Arc::new(f)))
        .map_err(to_py)
    }

    /// A field of `tiles` (each starting where the one before ends, one spatial grid;
    /// times in s from `epoch`). `open_altitude`: above the top altitude node ln(mean)
    /// continues along the top cell's slope and sigma/mean is held, below the bottom node
    /// the bottom level is held, instead of an error.
    #[staticmethod]
    #[pyo3(signature = (epoch, tiles, open_altitude))]
    fn from_tiles(
        epoch: f64,
        tiles: Vec<PyRef<'_, PyFieldTile>>,
        open_altitude: bool,
    ) -> PyResult<Self> {
        let tiles = tiles.iter().map(|t| t.0.clone()).collect();
        GriddedField::from_tiles(epoch, tiles, open_altitude)
            .map(|f| Self(Arc::new(f)))
            .map_err(to_py)
    }

    /// Bytes of the values of the field's tiles.
    #[getter]
    fn nbytes(&self) -> usize {
        self.0.tiles().iter().map(|t| t.bytes()).sum()
    }

    /// This field with every sigma times `factor` (finite, >= 0); the tiles are shared.
    fn with_sigma_scale(&self, factor: f64) -> PyResult<Self> {
        self.0
            .with_sigma_scale(factor)
            .map(|f| Self(Arc::new(f)))
            .map_err(to_py)
    }

    /// Mean and sigma (kg/m^3) at inertial positions (n, 3) m and times ut1 (n,) s
    /// since J2000.
    fn mean_sigma<'py>(
        &self,
        py: Python<'py>,
        ut1: PyReadonlyArray1<'py, f64>,
        positions: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<MeanSigma<'py>> {
        mean_sigma_at(py, self.0.as_ref(), ut1, positions)
    }
}

/// Values read from a tile's arrays: time nodes, longitude count, ln_mean and rel_sigma
/// as row-major slices (borrowed when C-contiguous).
type TileArrays<'a> = (Vec<f64>, usize, Cow<'a, [f64]>, Cow<'a, [f64]>);

/// The arrays of a field or tile checked against its axes.
fn tile_arrays<'a>(
    time: PyReadonlyArray1<'_, f64>,
    altitude: (f64, f64, usize),
    latitude: (f64, f64, usize),
    ln_mean: &'a PyReadonlyArray4<'_, f64>,
    rel_sigma: &'a PyReadonlyArray4<'_, f64>,
) -> PyResult<TileArrays<'a>> {
    let a = ln_mean.as_array();
    let b = rel_sigma.as_array();
    if a.shape() != b.shape() {
        return Err(PyValueError::new_err(format!(
            "ln_mean {:?} and rel_sigma {:?} must have the same shape",
            a.shape(),
            b.shape()
        )));
    }
    let time: Vec<f64> = time.as_array().to_vec();
    let expect = [time.len(), altitude.2, latitude.2];
    if a.shape()[..3] != expect {
        return Err(PyValueError::new_err(format!(
            "ln_mean has shape {:?}, expected ({}, {}, {}, nlon) from the axes",
            a.shape(),
            expect[0],
            expect[1],
            expect[2]
        )));
    }
    let nlon = a.shape()[3];
    // A C-contiguous array is read in place (the tile copies it once, interleaved);
    // otherwise iterating the view yields the logical row-major order whatever the
    // strides.
    let ln_mean: Cow<'a, [f64]> = a
        .to_slice()
        .map_or_else(|| Cow::Owned(a.iter().copied().collect()), Cow::Borrowed);
    let rel_sigma: Cow<'a, [f64]> = b
        .to_slice()
        .map_or_else(|| Cow::Owned(b.iter().copied().collect()), Cow::Borrowed);
    Ok((time, nlon, ln_mean, rel_sigma))
}

/// One time window of a sampled field (an atlas tile), shared by the fields composed
/// from it without a copy.
#[pyclass(frozen, weakref, name = "FieldTile", module = "rhoprop._core")]
pub struct PyFieldTile(pub Arc<FieldTile>);

#[pymethods]
impl PyFieldTile {
    /// `time` nodes in s on the composed field's time axis, `altitude` (start m, step m,
    /// count), `latitude` (start deg, step deg, count), `lon0` deg, values
    /// (nt, nalt, nlat, nlon).
    #[new]
    #[pyo3(signature = (time, altitude, latitude, lon0, ln_mean, rel_sigma))]
    fn new(
        time: PyReadonlyArray1<'_, f64>,
        altitude: (f64, f64, usize),
        latitude: (f64, f64, usize),
        lon0: f64,
        ln_mean: PyReadonlyArray4<'_, f64>,
        rel_sigma: PyReadonlyArray4<'_, f64>,
    ) -> PyResult<Self> {
        let (time, nlon, ln_mean, rel_sigma) =
            tile_arrays(time, altitude, latitude, &ln_mean, &rel_sigma)?;
        FieldTile::new(time, altitude, latitude, lon0, nlon, ln_mean, rel_sigma)
            .map(|t| Self(Arc::new(t)))
            .map_err(to_py)
    }

    /// Bytes of the values held.
    #[getter]
    fn nbytes(&self) -> usize {
        self.0.bytes()
    }

    /// First and last time node, s.
    #[getter]
    fn span(&self) -> (f64, f64) {
        self.0.span()
    }
}

/// A field whose tiles a Python callable gives when the run reaches them (`source(k)` ->
/// `FieldTile`, k = 0 .. len - 1), at most `keep` held between lookups: a months-long run
/// holds a few tiles, not all. Lookups give the bits of the field of all the tiles.
#[pyclass(frozen, weakref, name = "StreamedAtmosphere", module = "rhoprop._core")]
pub struct PyStreamed(pub Arc<StreamedField>);

#[pymethods]
impl PyStreamed {
    /// Tile k spans `bounds[k]` to `bounds[k + 1]` s from `epoch` (s since J2000, UT1);
    /// `open_altitude` as `GriddedAtmosphere.from_tiles`.
    #[new]
    #[pyo3(signature = (epoch, bounds, source, open_altitude, keep))]
    fn new(
        epoch: f64,
        bounds: Vec<f64>,
        source: Py<PyAny>,
        open_altitude: bool,
        keep: usize,
    ) -> PyResult<Self> {
        let source = Box::new(PySource(source));
        StreamedField::new(epoch, bounds, source, open_altitude, keep)
            .map(|f| Self(Arc::new(f)))
            .map_err(to_py)
    }

    /// Tiles asked of the source so far.
    #[getter]
    fn loads(&self) -> usize {
        self.0.loads()
    }

    /// Bytes of the tiles the field holds now.
    #[getter]
    fn nbytes(&self) -> usize {
        self.0.held_bytes()
    }

    /// Number of tiles.
    fn __len__(&self) -> usize {
        self.0.len()
    }

    /// This field with every sigma times `factor` (finite, >= 0): the same source, its
    /// own held tiles.
    fn with_sigma_scale(&self, factor: f64) -> PyResult<Self> {
        self.0
            .with_sigma_scale(factor)
            .map(|f| Self(Arc::new(f)))
            .map_err(to_py)
    }

    /// Mean and sigma (kg/m^3) at inertial positions (n, 3) m and times ut1 (n,) s
    /// since J2000.
    fn mean_sigma<'py>(
        &self,
        py: Python<'py>,
        ut1: PyReadonlyArray1<'py, f64>,
        positions: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<MeanSigma<'py>> {
        mean_sigma_at(py, self.0.as_ref(), ut1, positions)
    }
}

/// A Python callable as a tile source. Its exception is kept (`errors::keep_source_error`)
/// and raised as itself when the run's error reaches Python.
struct PySource(Py<PyAny>);

impl TileSource for PySource {
    fn tile(&self, k: usize) -> Result<Arc<FieldTile>, CoreError> {
        Python::attach(|py| {
            let name = format!("density tile {k}");
            match self.0.bind(py).call1((k,)) {
                Ok(out) => match out.cast::<PyFieldTile>() {
                    Ok(tile) => Ok(tile.get().0.clone()),
                    Err(_) => Err(CoreError::rejected(
                        name,
                        "the source must return a rhoprop._core.FieldTile",
                    )),
                },
                Err(e) => {
                    let reason = e.to_string();
                    crate::errors::keep_source_error(e);
                    Err(CoreError::rejected(name, reason))
                }
            }
        })
    }
}

fn mean_sigma_at<'py, A: Atmosphere + ?Sized>(
    py: Python<'py>,
    atmosphere: &A,
    ut1: PyReadonlyArray1<'py, f64>,
    positions: PyReadonlyArray2<'py, f64>,
) -> PyResult<MeanSigma<'py>> {
    let t = vector("ut1", &ut1)?;
    let p = rows("positions", &positions, 3)?;
    if t.len() != p.nrows() {
        return Err(PyValueError::new_err(format!(
            "ut1 has {} times but positions has {} rows",
            t.len(),
            p.nrows()
        )));
    }
    let mut mean = Array1::zeros(t.len());
    let mut sigma = Array1::zeros(t.len());
    for i in 0..t.len() {
        let rot = EarthRotation::new(gmst(t[i]));
        let (m, s) = atmosphere
            .mean_sigma(t[i], row3(&p, i), &rot)
            .map_err(to_py)?;
        mean[i] = m;
        sigma[i] = s;
    }
    Ok((mean.into_pyarray(py), sigma.into_pyarray(py)))
}

/// Runs `$body` with `$a` bound to the core atmosphere behind an `&AtmosphereRef`, the
/// body compiled once per atmosphere type so that the density call inlines into the RHS.
macro_rules! with_atmosphere {
    ($atm:expr, |$a:ident| $body:expr) => {
        match $atm {
            $crate::density::AtmosphereRef::Exponential(e) => {
                let $a: &::rhoprop_core::density::Exponential = e;
                $body
            }
            $crate::density::AtmosphereRef::Gridded(g) => {
                let $a: &::rhoprop_core::density::GriddedField = g;
                $body
            }
            $crate::density::AtmosphereRef::Streamed(g) => {
                let $a: &::rhoprop_core::density::StreamedField = g;
                $body
            }
        }
    };
}
pub(crate) use with_atmosphere;

/// A density source extracted from any of the Python atmosphere classes.
pub enum AtmosphereRef {
    Exponential(Exponential),
    Gridded(Arc<GriddedField>),
    Streamed(Arc<StreamedField>),
}

impl AtmosphereRef {
    /// Extracts the core atmosphere from a Python object.
    pub fn extract(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(e) = obj.cast::<PyExponential>() {
            return Ok(Self::Exponential(e.get().0));
        }
        if let Ok(g) = obj.cast::<PyGridded>() {
            return Ok(Self::Gridded(g.get().0.clone()));
        }
        if let Ok(g) = obj.cast::<PyStreamed>() {
            return Ok(Self::Streamed(g.get().0.clone()));
        }
        Err(PyTypeError::new_err(format!(
            "atmosphere must be an ExponentialAtmosphere, GriddedAtmosphere or StreamedAtmosphere, got {}",
            obj.get_type().name()?
        )))
    }
}
