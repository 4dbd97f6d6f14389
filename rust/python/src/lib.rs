//! rhoprop._core: the thin pyo3 binding of rhoprop-core. It converts arrays and errors,
//! releases the GIL around core calls and does nothing else; the documented Python API
//! lives in the `rhoprop` package.

mod arrays;
mod ccsp;
mod conjunction;
mod constants;
mod density;
mod errors;
mod fit;
mod frames;
mod long_call;
mod memory;
mod models;
mod montecarlo;
mod pool;
mod propagation;
mod records;
mod sieve;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    memory::return_large_blocks();
    m.add_class::<density::PyExponential>()?;
    m.add_class::<density::PyGridded>()?;
    m.add_class::<density::PyStreamed>()?;
    m.add_class::<density::PyFieldTile>()?;
    m.add_function(wrap_pyfunction!(propagation::propagate, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo::monte_carlo, m)?)?;
    m.add_function(wrap_pyfunction!(ccsp::ccsp, m)?)?;
    m.add_function(wrap_pyfunction!(ccsp::ccsp_many, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit_orbits, m)?)?;
    m.add_function(wrap_pyfunction!(frames::gmst, m)?)?;
    m.add_function(wrap_pyfunction!(frames::inertial_to_fixed, m)?)?;
    m.add_function(wrap_pyfunction!(frames::geodetic, m)?)?;
    m.add_function(wrap_pyfunction!(frames::geodetic_to_fixed, m)?)?;
    m.add_function(wrap_pyfunction!(frames::rtn_basis, m)?)?;
    m.add_function(wrap_pyfunction!(frames::equinoctial_elements, m)?)?;
    m.add_function(wrap_pyfunction!(frames::equinoctial_to_cartesian, m)?)?;
    m.add_function(wrap_pyfunction!(sieve::screen_candidates, m)?)?;
    m.add_function(wrap_pyfunction!(sieve::screen_approaches, m)?)?;
    m.add_function(wrap_pyfunction!(sieve::screen_stretches, m)?)?;
    sieve::register(m)?;
    records::register(m)?;
    models::register(m)?;
    conjunction::register(m)?;
    constants::register(m)?;
    Ok(())
}
