//! Parameter spaces and test generators for scenario-based testing (PARACOSM paper, §3).
//!
//! A scenario leaves some of its input streams open, constrained by `VarInterval` (a real
//! interval) or `VarEnum` (a finite set of levels). Those open streams form a [`ParamSpace`].
//! A [`Generator`] proposes [`Point`]s of that space: continuous coordinates in `[0, 1)` and level
//! indices for the discrete parameters. [`ParamSpace::decode`] maps a point back to named values
//! in the parameters' units.
//!
//! Generators here: uniform random ([`UniformRandom`], ChaCha8), Halton ([`Halton`], the paper's
//! radical-inverse construction, §3.2), Owen-scrambled Sobol ([`Sobol`], via `sobol_burley`),
//! covering suites ([`covering`]) and adaptive falsifiers that minimise robustness
//! ([`falsify::Falsifier`], on argmin).
//!
//! This crate depends on nothing else of the workspace, so researchers can use it alone.
#![warn(missing_docs)]

mod constraint;
pub mod coverage;
pub mod covering;
mod density;
mod error;
mod factorial;
pub mod falsify;
mod generator;
mod given;
mod halton;
mod point;
mod random;
mod sobol;
mod space;
mod strategy;
mod valid;

pub use constraint::{
    wilson, Constraint, ConstraintError, FnConstraint, ValidFraction, Violation,
    MAX_ENUMERATED_COMBINATIONS, MAX_PROBES_PER_COMBINATION, VALID_FRACTION_SAMPLES,
};
pub use density::Density;
pub use error::GeneratorError;
pub use factorial::FullFactorial;
pub use generator::Generator;
pub use given::GivenPoints;
pub use halton::{first_primes, radical_inverse, Halton};
pub use point::Point;
pub use random::UniformRandom;
pub use sobol::{Sobol, SOBOL_MAX_DIMENSIONS, SOBOL_MAX_POINTS};
pub use space::{Assignment, Domain, Param, ParamSpace, Value};
pub use strategy::Strategy;
pub use valid::ValidOnly;
