//! The "1 thread" runs shared by `benches/core.rs` and `examples/field_ratio.rs`: the
//! 64-member, 1-day Monte Carlo on the paper's orbit and the synthetic field it runs
//! through (included by `#[path]`: a subfolder, so Cargo does not take it for a bench of
//! its own).

use rhoprop_core::density::GriddedField;
use rhoprop_core::dynamics::Perturbation;
use rhoprop_core::integrators::FixedMethod;
use rhoprop_core::kappa::KappaProcess;
use rhoprop_core::montecarlo::MonteCarloConfig;
use rhoprop_core::problem::Problem;

/// The paper's orbit and spacecraft at a 2002 epoch (8.4e7 s after J2000), J2, floor 120 km.
pub fn paper_problem() -> Problem {
    Problem {
        epoch: 8.4e7,
        y0: rhoprop_core::constants::PAPER_STATE,
        drag: 3.0912 * 0.0015,
        floor_altitude: 120e3,
        zonal_degree: 2,
        forces: rhoprop_core::problem::Forces::AUTO,
    }
}

/// 64 members x 1 day of `problem`: GaussMarkov 18 min, RK8 180 s, hourly output.
pub fn one_day_monte_carlo(problem: Problem) -> MonteCarloConfig {
    MonteCarloConfig {
        problem,
        initial_factor: None,
        kappa: KappaProcess::GaussMarkov {
            half_life: 1080.0,
            interval: 180.0,
        },
        perturbation: Perturbation::Additive,
        method: FixedMethod::Rk8,
        max_step: 180.0,
        output_times: (0..=24).map(|i| i as f64 * 3600.0).collect(),
        members: 64,
        seed: 1,
        record_density: false,
        drag_sigma: 0.0,
    }
}

/// A field shaped like a sampled NRLMSIS one over a day (hourly nodes, every third one
/// repeated as a driver step; 25 km x 6 deg x 15 deg): an exponential profile with a
/// diurnal bulge, 20 % sigma.
pub fn synthetic_field(epoch: f64) -> GriddedField {
    let mut time = Vec::new();
    for k in 0..=25 {
        time.push(k as f64 * 3600.0 - 1800.0);
        if k % 3 == 1 && k < 25 {
            time.push(k as f64 * 3600.0 - 1800.0);
        }
    }
    let (na, nl, no) = (9, 31, 24);
    let mut ln_mean = Vec::new();
    for it in 0..time.len() {
        for ia in 0..na {
            for il in 0..nl {
                for io in 0..no {
                    let h = 300e3 + 25e3 * ia as f64;
                    let bulge = 0.3 * (io as f64 * 15f64.to_radians()).cos()
                        + 0.1 * (il as f64 * 6f64.to_radians()).sin()
                        + 1e-6 * it as f64;
                    ln_mean.push((3.725e-12f64).ln() - (h - 400e3) / 58.515e3 + bulge);
                }
            }
        }
    }
    let rel_sigma = vec![0.2; ln_mean.len()];
    GriddedField::new(
        epoch,
        time,
        (300e3, 25e3, na),
        (-90.0, 6.0, nl),
        0.0,
        no,
        ln_mean,
        rel_sigma,
    )
    .unwrap()
}
