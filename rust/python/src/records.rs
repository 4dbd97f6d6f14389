//! Frozen records that cross the binding: the run requests Python builds with keywords,
//! checked once when made, and the results the runs return, with named attributes
//! instead of positional tuples and dicts.

use crate::arrays::{fixed, from_rows, from_vec, rows, vector};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::ccsp::{CcspConfig, CcspOutput, Coordinates, SlowKappa};
use rhoprop_core::fit::{FitJob, FitOutput, FitSettings};
use rhoprop_core::integrators::FixedMethod;
use rhoprop_core::kappa::KappaProcess;
use rhoprop_core::montecarlo::{covariance_factor, MonteCarloConfig, MonteCarloOutput};
use rhoprop_core::problem::Problem;
use rhoprop_core::propagate::Trajectory;

/// The initial-value problem every run shares: epoch (UT1 s since J2000), state (6,)
/// m and m/s, Cd*A/m (m^2/kg), floor altitude (m), zonal degree and the other forces
/// (field degree, third bodies, Cr*A/m m^2/kg).
#[pyclass(frozen, name = "Problem", module = "rhoprop._core")]
pub struct PyProblem {
    pub inner: Problem,
}

#[pymethods]
impl PyProblem {
    #[new]
    #[pyo3(signature = (*, epoch, state, drag, floor_altitude, zonal_degree = 2,
        forces = (None, None, 0.0)))]
    fn new(
        epoch: f64,
        state: PyReadonlyArray1<'_, f64>,
        drag: f64,
        floor_altitude: f64,
        zonal_degree: u8,
        forces: (Option<u8>, Option<bool>, f64),
    ) -> PyResult<Self> {
        let inner =
            crate::arrays::problem(epoch, &state, drag, floor_altitude, zonal_degree, forces)?;
        inner.validate().map_err(crate::errors::to_py)?;
        Ok(Self { inner })
    }
}

/// What `propagate` returns: times (n,) s, states (n, 6), decayed_at (s or None), the
/// right-hand-side evaluations and the clipped ones.
#[pyclass(frozen, get_all, name = "Propagated", module = "rhoprop._core")]
pub struct Propagated {
    times: Py<PyArray1<f64>>,
    states: Py<PyArray2<f64>>,
    decayed_at: Option<f64>,
    rhs_evaluations: u64,
    clipped: u64,
}

impl Propagated {
    pub fn new(py: Python<'_>, tr: Trajectory) -> Self {
        Self {
            times: from_vec(tr.times).into_pyarray(py).unbind(),
            states: from_rows(&tr.states).into_pyarray(py).unbind(),
            decayed_at: tr.decayed_at,
            rhs_evaluations: tr.evaluations,
            clipped: tr.clipped,
        }
    }
}

/// A Monte Carlo run: its problem, output times (s), kappa process (kind, parameters),
/// perturbation, fixed-step method and its largest step (s), members, seed, optional
/// initial covariance (6, 6), whether densities are recorded, and drag_sigma.
#[pyclass(frozen, name = "MonteCarloRun", module = "rhoprop._core")]
pub struct PyMonteCarloRun {
    pub cfg: MonteCarloConfig,
}

#[pymethods]
impl PyMonteCarloRun {
    #[new]
    #[pyo3(signature = (problem, *, output_times, kappa, perturbation, method, step, members,
        seed, initial_covariance = None, record_density = false, drag_sigma = 0.0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        problem: &PyProblem,
        output_times: PyReadonlyArray1<'_, f64>,
        kappa: (String, Vec<f64>),
        perturbation: &str,
        method: &str,
        step: f64,
        members: usize,
        seed: u64,
        initial_covariance: Option<PyReadonlyArray2<'_, f64>>,
        record_density: bool,
        drag_sigma: f64,
    ) -> PyResult<Self> {
        let initial_factor = match initial_covariance {
            None => None,
            Some(c) => Some(
                covariance_factor(&crate::arrays::matrix6("initial_covariance", &c)?)
                    .map_err(crate::errors::to_py)?,
            ),
        };
        let cfg = MonteCarloConfig {
            problem: problem.inner,
            initial_factor,
            kappa: KappaProcess::from_spec(&kappa.0, &kappa.1).map_err(crate::errors::to_py)?,
            perturbation: crate::arrays::perturbation(perturbation)?,
            method: FixedMethod::from_name(method).map_err(crate::errors::to_py)?,
            max_step: step,
            output_times: vector("output_times", &output_times)?.to_vec(),
            members,
            seed,
            record_density,
            drag_sigma,
        };
        Ok(Self { cfg })
    }
}

/// What `monte_carlo` returns: positions and velocities (n, nt, 3), densities (n, nt) or
/// None, clipped evaluations (n,), decay times (n,) s (inf: none), the step used (s) and
/// the factor on Cd*A/m of each member (n,).
#[pyclass(frozen, get_all, name = "MonteCarloOutput", module = "rhoprop._core")]
pub struct MonteCarloOut {
    positions: Py<PyArray3<f64>>,
    velocities: Py<PyArray3<f64>>,
    densities: Option<Py<PyArray2<f64>>>,
    clipped: Py<PyArray1<u64>>,
    decay_times: Py<PyArray1<f64>>,
    step: f64,
    drag_factors: Py<PyArray1<f64>>,
}

impl MonteCarloOut {
    pub fn new(py: Python<'_>, out: MonteCarloOutput, n: usize, nt: usize) -> Self {
        let shape3 = |v: Vec<f64>| {
            Array3::from_shape_vec((n, nt, 3), v).expect("core returns members x times x 3")
        };
        Self {
            positions: shape3(out.positions).into_pyarray(py).unbind(),
            velocities: shape3(out.velocities).into_pyarray(py).unbind(),
            densities: out.densities.map(|d| {
                Array2::from_shape_vec((n, nt), d)
                    .expect("core returns members x times")
                    .into_pyarray(py)
                    .unbind()
            }),
            clipped: Array1::from_vec(out.clipped).into_pyarray(py).unbind(),
            decay_times: Array1::from_vec(out.decay_times).into_pyarray(py).unbind(),
            step: out.step,
            drag_factors: Array1::from_vec(out.drag_factors).into_pyarray(py).unbind(),
        }
    }
}

/// A CCSP run: its problem, initial covariance (6, 6), update times (s), scaling
/// (lambda1 + n, lambda2 + p), perturbation, largest RK8 step (s), drag_sigma, further
/// output times (s), coordinates, the weight of the per-update kappa and the slow
/// density term (scale, half-life s; inf: constant) or None.
#[pyclass(frozen, name = "CcspRun", module = "rhoprop._core")]
pub struct PyCcspRun {
    pub cfg: CcspConfig,
}

#[pymethods]
impl PyCcspRun {
    #[new]
    #[pyo3(signature = (problem, *, initial_covariance, update_times, scaling, perturbation,
        step, drag_sigma = 0.0, output_times = None, coordinates = "equinoctial",
        kappa_scale = 1.0, slow = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        problem: &PyProblem,
        initial_covariance: PyReadonlyArray2<'_, f64>,
        update_times: PyReadonlyArray1<'_, f64>,
        scaling: (f64, f64),
        perturbation: &str,
        step: f64,
        drag_sigma: f64,
        output_times: Option<PyReadonlyArray1<'_, f64>>,
        coordinates: &str,
        kappa_scale: f64,
        slow: Option<(f64, f64)>,
    ) -> PyResult<Self> {
        let cfg = CcspConfig {
            problem: problem.inner,
            p0: crate::arrays::matrix6("initial_covariance", &initial_covariance)?,
            update_times: vector("update_times", &update_times)?.to_vec(),
            output_times: match &output_times {
                Some(times) if !times.as_array().is_empty() => {
                    vector("output_times", times)?.to_vec()
                }
                _ => Vec::new(),
            },
            scaling,
            kappa_scale,
            perturbation: crate::arrays::perturbation(perturbation)?,
            method: FixedMethod::Rk8,
            max_step: step,
            drag_sigma,
            coordinates: coordinates_arg(coordinates)?,
            slow: slow.map(|(scale, half_life)| SlowKappa { scale, half_life }),
        };
        Ok(Self { cfg })
    }
}

fn coordinates_arg(name: &str) -> PyResult<Coordinates> {
    match name {
        "equinoctial" => Ok(Coordinates::Equinoctial),
        "cartesian" => Ok(Coordinates::Cartesian),
        _ => Err(PyValueError::new_err(format!(
            "coordinates must be 'equinoctial' or 'cartesian', got {name:?}"
        ))),
    }
}

/// What `ccsp` returns (and `ccsp_many` per object): decayed_at (s, or None: when a
/// sigma point crossed the floor; the outputs end before it), times (nt,), means (nt, 6),
/// covariances (nt, 6, 6), cross (nt, 6) and drag_cross (nt, 6) covariances with the
/// consider parameters; in equinoctial coordinates also element_means (nt, 6) and
/// element_covariances (nt, 6, 6), else None.
#[pyclass(frozen, get_all, name = "CcspOutput", module = "rhoprop._core")]
pub struct CcspOut {
    decayed_at: Option<f64>,
    times: Py<PyArray1<f64>>,
    means: Py<PyArray2<f64>>,
    covariances: Py<PyArray3<f64>>,
    cross: Py<PyArray2<f64>>,
    drag_cross: Py<PyArray2<f64>>,
    element_means: Option<Py<PyArray2<f64>>>,
    element_covariances: Option<Py<PyArray3<f64>>>,
}

impl CcspOut {
    pub fn new(py: Python<'_>, out: CcspOutput) -> Self {
        let nt = out.times.len();
        let six = |v: &[[f64; 6]]| {
            Array2::from_shape_fn((nt, 6), |(i, j)| v[i][j])
                .into_pyarray(py)
                .unbind()
        };
        let six_by_six = |v: &[[[f64; 6]; 6]]| {
            Array3::from_shape_fn((nt, 6, 6), |(i, j, k)| v[i][j][k])
                .into_pyarray(py)
                .unbind()
        };
        let elements = !out.element_means.is_empty();
        Self {
            decayed_at: out.decayed_at,
            times: Array1::from_vec(out.times.clone())
                .into_pyarray(py)
                .unbind(),
            means: six(&out.means),
            covariances: six_by_six(&out.covariances),
            cross: six(&out.cross),
            drag_cross: six(&out.drag_cross),
            element_means: elements.then(|| six(&out.element_means)),
            element_covariances: elements.then(|| six_by_six(&out.element_covariances)),
        }
    }
}

/// One object of `fit_orbits`: epoch (UT1 s), p0 (7,) = [r, v, Cd*A/m], the Cd*A/m
/// prior and its sigma (m^2/kg), grid spacing (s), grid steps back and forward, the
/// observations' grid rows (k,), observed positions (k, 3) m and weights (k, 9) 1/m
/// (row-major 3x3).
#[pyclass(frozen, name = "FitJob", module = "rhoprop._core")]
pub struct PyFitJob {
    pub job: FitJob,
}

#[pymethods]
impl PyFitJob {
    #[new]
    #[pyo3(signature = (*, epoch, p0, prior, prior_sigma, spacing, back, forward, rows,
        observed, weights))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        epoch: f64,
        p0: PyReadonlyArray1<'_, f64>,
        prior: f64,
        prior_sigma: f64,
        spacing: f64,
        back: usize,
        forward: usize,
        rows: PyReadonlyArray1<'_, i64>,
        observed: PyReadonlyArray2<'_, f64>,
        weights: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Self> {
        let observed = crate::records::rows_of("observed", &observed, 3)?;
        let weights = crate::records::rows_of("weights", &weights, 9)?;
        let grid_rows = rows
            .as_array()
            .iter()
            .map(|&r| {
                usize::try_from(r)
                    .map_err(|_| PyValueError::new_err(format!("observation row {r} is negative")))
            })
            .collect::<PyResult<Vec<usize>>>()?;
        Ok(Self {
            job: FitJob {
                epoch,
                p0: fixed::<7>("p0", &p0)?,
                prior,
                prior_sigma,
                spacing,
                back,
                forward,
                rows: grid_rows,
                observed: observed.iter().map(|r| [r[0], r[1], r[2]]).collect(),
                weights: weights
                    .iter()
                    .map(|r| std::array::from_fn(|i| std::array::from_fn(|j| r[3 * i + j])))
                    .collect(),
            },
        })
    }
}

/// The rows of a (k, width) array, checked, as vectors.
fn rows_of(name: &str, array: &PyReadonlyArray2<'_, f64>, width: usize) -> PyResult<Vec<Vec<f64>>> {
    Ok(rows(name, array, width)?
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect())
}

/// Settings every job of a `fit_orbits` call shares: grid step (s), zonal degree, floor
/// altitude (m), most iterations and the smallest Cd*A/m (m^2/kg).
#[pyclass(frozen, name = "FitConfig", module = "rhoprop._core")]
pub struct PyFitConfig {
    pub settings: FitSettings,
}

#[pymethods]
impl PyFitConfig {
    #[new]
    #[pyo3(signature = (*, step, zonal_degree, floor_altitude, max_iterations, min_drag))]
    fn new(
        step: f64,
        zonal_degree: u8,
        floor_altitude: f64,
        max_iterations: usize,
        min_drag: f64,
    ) -> Self {
        Self {
            settings: FitSettings {
                step,
                zonal_degree,
                floor_altitude,
                max_iterations,
                min_drag,
            },
        }
    }
}

/// What `fit_orbits` returns per job: p (7,) = [r, v, Cd*A/m] at the epoch, the grid
/// states (n, 6), J^T J (7, 7), the iterations and whether it converged.
#[pyclass(frozen, get_all, name = "FitOutput", module = "rhoprop._core")]
pub struct FitOut {
    p: Py<PyArray1<f64>>,
    states: Py<PyArray2<f64>>,
    normal: Py<PyArray2<f64>>,
    iterations: usize,
    converged: bool,
}

impl FitOut {
    pub fn new(py: Python<'_>, o: FitOutput) -> Self {
        Self {
            p: o.p.to_vec().into_pyarray(py).unbind(),
            states: from_rows(&o.states).into_pyarray(py).unbind(),
            normal: Array2::from_shape_fn((7, 7), |(i, j)| o.normal[i][j])
                .into_pyarray(py)
                .unbind(),
            iterations: o.iterations,
            converged: o.converged,
        }
    }
}

/// Adds the records to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyProblem>()?;
    m.add_class::<Propagated>()?;
    m.add_class::<PyMonteCarloRun>()?;
    m.add_class::<MonteCarloOut>()?;
    m.add_class::<PyCcspRun>()?;
    m.add_class::<CcspOut>()?;
    m.add_class::<PyFitJob>()?;
    m.add_class::<PyFitConfig>()?;
    m.add_class::<FitOut>()?;
    Ok(())
}
