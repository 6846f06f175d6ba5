use std::ops::ControlFlow;

use serde::Serialize;

use crate::Frame;

/// The outcome of a monitor over a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// Whether the property held over the whole run.
    pub passed: bool,
    /// Quantitative robustness in the monitor's unit (metres for the shipped monitors):
    /// `> 0` satisfied with that margin, `<= 0` violated. `passed == (robustness > 0)` for
    /// every shipped monitor.
    pub robustness: f64,
    /// Time of the first violation in seconds since the start, `None` if none.
    pub first_violation_s: Option<f64>,
    /// Extra measurements, e.g. `("min_distance_m", 0.4)`.
    #[serde(skip)]
    pub metrics: Vec<(&'static str, f64)>,
}

/// A test oracle fed one frame at a time.
///
/// `observe` returns `ControlFlow::Break(())` once the verdict is settled: no later frame can
/// change it, whether it passed or failed. A runner then stops feeding that monitor (its
/// verdict stays as it was when it settled) and may stop the run early: a run with several
/// monitors stops when every monitor has settled, or when one has settled as failed
/// (`verdict().passed` false); until then the others keep observing, so one monitor's early
/// verdict never cuts another's observation short while the run could still pass. `verdict`
/// may be called at any time and reflects the frames seen so far.
pub trait Monitor: Send {
    /// A short name used as the key in results files, e.g. `collision`.
    fn name(&self) -> &str;

    /// Consumes one frame.
    ///
    /// Frames come in increasing time order. A frame lacking a signal the monitor needs is a
    /// violation of the monitor's contract with the simulator; the shipped monitors treat it as
    /// a failed verdict (robustness `-inf`) rather than panicking.
    fn observe(&mut self, frame: &Frame<'_>) -> ControlFlow<()>;

    /// The verdict over the frames seen so far.
    fn verdict(&self) -> Verdict;

    /// Called when the run stops early (another monitor settled as failed) while this one has
    /// not settled: settles it if the frames already seen decide its verdict, and says whether
    /// they do. A monitor that checks its verdict only every few frames (an `Stl` formula,
    /// every 0.25 s) may have been decided by a frame since its last check; such a monitor
    /// failed and was not cut short. The default, for monitors that settle on the frame that
    /// decides them: `false`.
    fn settle_now(&mut self) -> bool {
        false
    }
}
