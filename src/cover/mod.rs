//! The library side of `paracosm-cover`: parameter-space specs, reading test sets from CSV or
//! `results.jsonl`, coverage reports and budget plans.

pub mod commands;
mod input;
mod pict;
mod plan;
mod report;
mod spec;

pub use input::{parse_tests, read_tests, InputError, TestSet};
pub use pict::{parse_pict, read_seeds, PictError, PictModel};
pub use plan::{
    halton_points_for, plan, plan_suites, suite_per_row, HaltonSize, Plan, PlanError, SuitePlan,
    MAX_MEASURED, MAX_PLANNED,
};
pub use report::{estimate, Estimate, ExactProgress, Metric, STAR_EXACT_MAX_DIMS};
pub use spec::{load_space, parse_space, SpecError};
