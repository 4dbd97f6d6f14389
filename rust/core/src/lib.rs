//! rhoprop-core: the numerical core of rhoprop.
//!
//! Pure Rust, no Python. Orbit propagation (two-body + J2 + drag) of batches of members
//! held structure-of-arrays, with the thermospheric density given by an [`density::Atmosphere`]
//! that answers mean and standard deviation. The modules follow the data flow:
//! [`constants`] -> [`time`] -> [`frames`] -> [`density`] -> [`dynamics`] ->
//! [`integrators`] -> [`propagate`].

// Structure-of-arrays lane loops index several arrays in lockstep; iterator rewrites of
// them read worse and vectorise no better.
#![allow(clippy::needless_range_loop)]

pub mod ccsp;
pub mod constants;
pub mod density;
pub mod dynamics;
pub mod ensemble;
pub mod error;
pub mod frames;
pub mod integrators;
pub mod kappa;
pub mod propagate;
pub mod rng;
pub mod time;

pub use error::CoreError;
