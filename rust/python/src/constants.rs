//! Core constants and facts exported to Python, so the Python package never retypes them.

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rhoprop_core::constants;
use rhoprop_core::kappa::KappaProcess;
use rhoprop_core::problem::{DEFAULT_FLOOR_ALTITUDE, MAX_DRAG_SIGMA};
use rhoprop_core::simd::SimdPath;

/// The instruction set the batch kernels run with on this CPU: "avx2+fma" or "portable".
#[pyfunction]
fn simd_path() -> &'static str {
    SimdPath::detect().name()
}

/// Adds the constants, the kappa kind names and `simd_path` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MU", constants::MU)?;
    m.add("R_EARTH", constants::R_EARTH)?;
    m.add("R_POLE", constants::R_POLE)?;
    m.add("J2", constants::J2)?;
    m.add("WGS84_F", constants::WGS84_F)?;
    m.add("OMEGA_EARTH", constants::OMEGA_EARTH)?;
    m.add("SECONDS_PER_DAY", constants::SECONDS_PER_DAY)?;
    m.add("DEFAULT_FLOOR_ALTITUDE", DEFAULT_FLOOR_ALTITUDE)?;
    m.add("MAX_STEPS", rhoprop_core::integrators::MAX_STEPS)?;
    m.add("MAX_DRAG_SIGMA", MAX_DRAG_SIGMA)?;
    m.add("KAPPA_KINDS", PyTuple::new(m.py(), KappaProcess::KINDS)?)?;
    m.add_function(wrap_pyfunction!(simd_path, m)?)?;
    Ok(())
}
