//! Test oracles over sampled signal traces: monitors that turn a run into a verdict with a
//! quantitative robustness (`> 0` satisfied, `<= 0` violated).
//!
//! Monitors see only named signals ([`Signals`]) at sample times ([`Frame`]); they know nothing
//! of the simulator, so they work as well on a trace exported from another tool.
//!
//! - [`CollisionMonitor`]: no contact between the ego vehicle and another body (paper §2,
//!   "Invariants and Monitors").
//! - [`DistanceMonitor`]: the ego vehicle travelled at least `min_distance_m`, so it did not pass
//!   by standing still (paper §2).
//! - [`OffRoadMonitor`]: the ego vehicle stays on the drivable surface.
//! - [`TimeToFailureMonitor`]: a wrapped monitor first fails no earlier than a given time.
//! - [`StreamMonitor`]: a user-written monitor, one signal's value taken over the test
//!   (always, at the end, eventually), or a Boolean assertion.
//! - [`stl`]: signal temporal logic formulas and their quantitative robustness.
#![warn(missing_docs)]

mod collision;
mod distance;
mod flag;
mod monitor;
mod off_road;
mod signals;
pub mod stl;
mod stream;
mod time_to_failure;

pub use collision::CollisionMonitor;
pub use distance::DistanceMonitor;
pub use monitor::{Monitor, Verdict};
pub use off_road::OffRoadMonitor;
pub use signals::{Frame, SignalError, Signals};
pub use stream::{Over, StreamMonitor};
pub use time_to_failure::TimeToFailureMonitor;
