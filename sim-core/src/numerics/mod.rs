//! Numerical building blocks of the solvers, each tested on its own:
//!
//! - `gbs`: one Gragg-Bulirsch-Stoer extrapolation step (the elastica's integrator);
//! - `elliptic`: Carlson's symmetric elliptic integrals and Legendre's forms from them (the
//!   elastica's closed form).
//!
//! Crate-private: they serve [`crate::statics::elastica`] and are not part of the API.

pub(crate) mod elliptic;
pub(crate) mod gbs;
