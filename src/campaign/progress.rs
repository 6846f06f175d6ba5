//! A progress bar on stderr (indicatif) as a campaign [`Observer`], with each test's log
//! (`--verbose`).

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::record::{RunRecord, Status};
use crate::{Error, Observer};

/// Counts tests and failures on a bar drawn on stderr when it is a terminal (hidden
/// otherwise); with `verbose`, prints each test's log lines as `test ID: LINE` as it ends.
/// Clones share the bar.
#[derive(Clone)]
pub struct Progress {
    bar: ProgressBar,
    failures: u64,
    verbose: bool,
    /// Lines held until the first test starts ([`Progress::hold`]), shared by the clones.
    held: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Progress {
    /// A hidden bar until [`Progress::start`].
    pub fn new(verbose: bool) -> Self {
        Progress {
            bar: ProgressBar::hidden(),
            failures: 0,
            verbose,
            held: std::sync::Arc::default(),
        }
    }

    /// Holds `lines` (the load's warnings) until the campaign starts its tests, when
    /// [`Observer::started`] prints them: a refusal found after the load but before any test
    /// (a covering array too large to build) is then the first line on stderr, and the
    /// caller prints the held lines after it ([`Progress::release`]).
    pub fn hold(&self, lines: Vec<String>) {
        self.held
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .extend(lines);
    }

    /// Prints the lines still held ([`Progress::hold`]) on stderr.
    pub fn release(&self) {
        let lines = std::mem::take(
            &mut *self
                .held
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
        );
        for line in lines {
            self.note(&line);
        }
    }

    /// Shows the bar for `tests` tests (on a terminal only).
    pub fn start(&self, tests: u64) {
        if std::io::stderr().is_terminal() {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        self.bar.set_length(tests);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} tests, {msg} ({per_sec}, eta {eta})",
        ) {
            self.bar.set_style(style);
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    /// Prints `line` on stderr without tearing the bar.
    pub fn note(&self, line: &str) {
        self.bar.suspend(|| crate::cli::to_stderr(line));
    }
}

impl Observer for Progress {
    fn started(&mut self, _prior: &[RunRecord]) -> Result<(), Error> {
        self.release();
        Ok(())
    }

    fn record(&mut self, r: &RunRecord) -> Result<(), Error> {
        self.failures += u64::from(r.status == Status::Fail);
        if self.verbose {
            self.bar.suspend(|| {
                r.log
                    .iter()
                    .for_each(|line| crate::cli::to_stderr(&format!("test {}: {line}", r.id)))
            });
        }
        self.bar.set_message(format!("{} failed", self.failures));
        self.bar.inc(1);
        Ok(())
    }
}
