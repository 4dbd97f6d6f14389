//! rhoprop-core: the numerical core of rhoprop.
//!
//! Pure Rust, no Python. Orbit propagation (two-body + J2 + drag) of batches of members
//! held structure-of-arrays, with the thermospheric density given by an
//! [`density::Atmosphere`] that answers mean and standard deviation. The modules follow
//! the data flow:
//!
//! - [`constants`], [`time`], [`frames`]: the physical and geometric base;
//! - [`density`]: where the density comes from (analytic or a sampled field);
//! - [`problem`]: the initial-value problem every run starts from, validated once;
//! - [`decay`]: where an orbit crosses the decay floor within a step;
//! - [`kappa`], [`rng`]: the stochastic density offset and its per-member streams;
//! - [`dynamics`]: the one right-hand side every integrator, member and sigma point uses;
//! - [`ephemeris`]: low-precision Sun and Moon, their pull on deep-space orbits;
//! - [`geopotential`]: the tesseral field to degree 8 that deep-space orbits feel;
//! - [`integrators`]: fixed-step RK4/RK8 through one step loop, adaptive DOP853;
//! - [`simd`]: the batch lane width and the runtime instruction-set dispatch;
//! - [`progress`]: progress and cancellation of long calls;
//! - [`propagate`], [`montecarlo`], [`ccsp`]: the three runs the binding exposes;
//! - [`fit`]: least-squares fits of state and Cd*A/m to pseudo-observations, 8 lanes a trial;
//! - [`conjunction`]: probability of collision (2-D Gaussian Pc, Monte Carlo pair count);
//! - [`encounter`]: the hits of the Pc over an encounter interval (CW relative motion);
//! - [`sieve`]: all-on-all screening's candidate intervals (spatial grid, distance bounds);
//! - [`error`]: what can go wrong, with messages fit for the user.

// Structure-of-arrays lane loops index several arrays in lockstep; iterator rewrites of
// them read worse and vectorise no better.
#![allow(clippy::needless_range_loop)]

pub mod ccsp;
pub mod conjunction;
pub mod constants;
pub mod decay;
pub mod density;
pub mod dynamics;
pub mod egm2008;
pub mod encounter;
pub mod ephemeris;
pub mod equinoctial;
pub mod error;
pub mod fit;
pub mod frames;
pub mod geopotential;
pub mod integrators;
pub mod kappa;
pub mod montecarlo;
pub mod problem;
pub mod progress;
pub mod propagate;
pub mod radiation;
pub mod rng;
pub mod sieve;
pub mod simd;
pub mod time;

pub use error::CoreError;
