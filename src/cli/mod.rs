//! Helpers shared by the command-line tools.

pub mod fuzz;
pub mod process;

use std::process::ExitCode;

use clap::Parser;
use paracosm_engine::sut::{ExternalConfig, SutConfig};
use paracosm_generators::Strategy;

use crate::Error;

/// The value parser of `--strategy`: the names of [`Strategy::LIST`], each with its
/// [`Strategy::help`] in `--help`.
pub fn strategy_parser() -> impl clap::builder::TypedValueParser<Value = Strategy> {
    strategy_parser_of(|_| true)
}

/// The value parser of `paracosm-fuzz dataset --strategy`: the strategies that choose points
/// up front (no falsifier, whose points follow robustness, and no `points`, which dataset
/// has no `--points` for), so that `--help` offers only what it accepts.
pub fn dataset_strategy_parser() -> impl clap::builder::TypedValueParser<Value = Strategy> {
    strategy_parser_of(|s| s != Strategy::Points && !Strategy::FALSIFIERS.contains(&s))
}

fn strategy_parser_of(
    keep: fn(Strategy) -> bool,
) -> impl clap::builder::TypedValueParser<Value = Strategy> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(Strategy::LIST.into_iter().filter(|&s| keep(s)).map(|s| {
        let v = PossibleValue::new(s.name()).help(s.help());
        if s == Strategy::FullFactorial {
            v.alias("variation")
        } else {
            v
        }
    }))
    .map(|name| name.parse::<Strategy>().expect("a name of Strategy::LIST"))
}

/// The strategy named by `--strategy` and `--scramble`.
///
/// # Errors
/// [`Error::BadInput`] when `--scramble` is given with a strategy other than `halton`.
pub fn strategy(chosen: Strategy, scramble: bool) -> Result<Strategy, Error> {
    match (chosen, scramble) {
        (Strategy::Halton | Strategy::ScrambledHalton, true) => Ok(Strategy::ScrambledHalton),
        (s, true) => Err(Error::BadInput(format!(
            "--scramble applies to --strategy halton only, not {s}"
        ))),
        (s, false) => Ok(s),
    }
}

/// Writes `line` and a newline to stderr. A stderr that cannot be written (a pipe whose
/// reader has gone, as in `2>&1 | head -1`) is not an error: the line is dropped and the
/// campaign goes on, writes its files and exits with its own code (`eprintln!` panicked
/// there, exit 101, before the first test ran).
pub fn to_stderr(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// Parses the command line of `tool`. On `--help`/`--version` prints and returns
/// `Err(ExitCode::SUCCESS)`; on bad usage prints `tool: error: <one-line reason> (see --help)` to
/// stderr and returns `Err(2)`.
pub fn parse_args<T: Parser>(tool: &str) -> Result<T, ExitCode> {
    T::try_parse().map_err(|e| {
        if e.use_stderr() {
            to_stderr(&format!("{tool}: error: {} (see --help)", one_line(&e)));
            ExitCode::from(2)
        } else {
            let _ = e.print();
            ExitCode::SUCCESS
        }
    })
}

/// The options that choose a system under test (`paracosm-fuzz` and its `replay`).
#[derive(Debug, Clone, clap::Args)]
pub struct SutArgs {
    /// Built-in system under test, instead of the scenario's default: aeb (lidar), vision
    /// (camera) or pilotnet (the shipped ONNX network, camera).
    #[arg(long, value_name = "NAME", conflicts_with_all = ["sut_cmd", "sut_onnx"])]
    pub sut: Option<String>,
    /// Run an ONNX model as the system under test, in process (tract), with the TOML
    /// manifest beside it (same stem, `.toml`) that declares its camera, input and outputs.
    #[arg(long, value_name = "MODEL.onnx", conflicts_with = "sut_cmd")]
    pub sut_onnx: Option<std::path::PathBuf>,
    /// Run the system under test as a program speaking SUT_PROTOCOL.md over stdin/stdout,
    /// e.g. "python3 my_controller.py" (split like a shell would, without expansion).
    #[arg(long, value_name = "COMMAND")]
    pub sut_cmd: Option<String>,
    /// With --sut-cmd: longest wait for any answer of the program, in seconds (default 10, at
    /// most 3600).
    #[arg(long, value_name = "SECONDS", requires = "sut_cmd")]
    pub sut_timeout: Option<f64>,
    /// With --sut-cmd: start a fresh process for every test, instead of keeping one alive
    /// per worker and sending it a reset message.
    #[arg(long, requires = "sut_cmd")]
    pub sut_fresh: bool,
}

/// `--sut-timeout` when it is not given, s.
pub const DEFAULT_SUT_TIMEOUT_S: f64 = 10.0;

/// The longest `--sut-timeout`, s: an hour. Longer waits are no use to a test and overflow
/// the clock's arithmetic.
pub const MAX_SUT_TIMEOUT_S: f64 = 3600.0;

impl SutArgs {
    /// The system under test chosen (`--sut NAME` or `--sut-cmd COMMAND`), or `None` to keep
    /// the scenario's.
    ///
    /// # Errors
    /// [`Error::BadInput`] for an unknown name, a command that does not split (an unclosed
    /// quote) or is empty, or a timeout that is not a positive number of seconds up to
    /// [`MAX_SUT_TIMEOUT_S`].
    pub fn config(&self) -> Result<Option<SutConfig>, Error> {
        let timeout_s = self.sut_timeout.unwrap_or(DEFAULT_SUT_TIMEOUT_S);
        if !(timeout_s.is_finite() && timeout_s > 0.0 && timeout_s <= MAX_SUT_TIMEOUT_S) {
            return Err(Error::BadInput(format!(
                "--sut-timeout {timeout_s} must be a positive number of seconds, at most \
                 {MAX_SUT_TIMEOUT_S} (an hour)"
            )));
        }
        if let Some(model) = &self.sut_onnx {
            return SutConfig::onnx(model)
                .map(Some)
                .map_err(|e| Error::BadInput(format!("--sut-onnx: {e}")));
        }
        match (&self.sut, &self.sut_cmd) {
            (Some(n), _) => SutConfig::builtin(n)
                .map(Some)
                .map_err(|e| Error::BadInput(format!("--sut: {e}"))),
            (None, Some(c)) => {
                let words = shlex::split(c).filter(|w| !w.is_empty()).ok_or_else(|| {
                    Error::BadInput(format!("--sut-cmd {c:?} is empty or has an unclosed quote"))
                })?;
                paracosm_engine::sut::check_command(&words)
                    .map_err(|e| Error::BadInput(format!("--sut-cmd: {e}")))?;
                Ok(Some(SutConfig::External(ExternalConfig::new(
                    words,
                    timeout_s,
                    !self.sut_fresh,
                ))))
            }
            (None, None) => Ok(None),
        }
    }
}

/// `paracosm-fuzz report`'s options that redraw plots from the records.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct Redraw {
    /// Redraw the failure map and the failure-rate plot over these one or two parameters
    /// (`--map walking_speed,trigger_distance`), into `failure_map-A-B.{png,svg}` and
    /// `failure_rate-A-B.{png,svg}` beside the records.
    #[arg(long, value_delimiter = ',', value_name = "A,B")]
    pub map: Option<Vec<String>>,
    /// What the failure map's points are coloured by: `outcome` (red failed, blue passed) or
    /// `robustness` (a diverging scale centred at 0, so near misses show; the file name ends
    /// in `-robustness`). Given alone, redraws the map over the scenario's map axes.
    #[arg(long, value_name = "outcome|robustness")]
    pub color: Option<crate::report::plot::Coloring>,
    /// Redraw the scatterplot matrix of the parameters (`pairs.{png,svg}`).
    #[arg(long)]
    pub pairs: bool,
    /// Write the campaign's web page again (`report.html`).
    #[arg(long)]
    pub html: bool,
    /// Draw the tests over the road map (`failure_map-road.{png,svg}`): each test where the
    /// actor its parameters place (the one whose start moves most between tests, e.g. with an
    /// `onLane(s=...)` parameter) started, red for a failure, blue for a pass. Refused when no
    /// parameter places an actor or a parameter shapes the roads.
    #[arg(long)]
    pub on_map: bool,
}

/// The text a tool prints on stderr for an error whose message is `message`: the first line
/// is always `TOOL: error: REASON`, then the location and the caret where there is one, then
/// (for an error raised inside a function of the program) the Starlark call stack, after the
/// reason rather than before it.
pub fn error_text(tool: &str, message: &str) -> String {
    const TRACEBACK: &str = "Traceback (most recent call last):";
    let (stack, rest) = match message.strip_prefix(TRACEBACK) {
        Some(after) => match after.find("\nerror: ") {
            Some(k) => (Some(after[..k].trim_matches('\n')), &after[k + 1..]),
            None => (None, message),
        },
        None => (None, message),
    };
    let rest = rest.strip_prefix("error: ").unwrap_or(rest);
    let mut out = format!("{tool}: error: {}", rest.trim_end());
    if let Some(stack) = stack {
        out.push_str(&format!("\n{TRACEBACK}\n{stack}"));
    }
    out
}

#[cfg(test)]
mod error_text_tests {
    use super::error_text;

    #[test]
    fn the_reason_comes_first_and_the_call_stack_after_it() {
        let m = "Traceback (most recent call last):\n  * a.star:3, in <module>\n      x = f(5.0)\n\
                 error: VarInterval(5, 1) is empty\n --> a.star:2:12\n  |\n";
        let t = error_text("paracosm-fuzz", m);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[0], "paracosm-fuzz: error: VarInterval(5, 1) is empty");
        assert_eq!(lines[1], " --> a.star:2:12");
        assert!(t.contains("Traceback (most recent call last):\n  * a.star:3, in <module>"));
        assert!(t.find("Traceback").unwrap() > t.find("-->").unwrap());
        // A message that already says `error:` is not doubled; any other gets it.
        assert_eq!(error_text("t", "error: x"), "t: error: x");
        assert_eq!(
            error_text("t", "`d` is not a folder"),
            "t: error: `d` is not a folder"
        );
    }
}

/// Parses a count that must be at least 1 (`--budget`, `-n`). A clap value parser: its
/// message becomes clap's usage error (exit code 2).
///
/// # Errors
/// [`NotPositive`] naming the rule, for clap to report.
pub fn positive(s: &str) -> Result<u64, NotPositive> {
    match s.parse::<u64>() {
        Ok(0) => Err(NotPositive::Zero),
        Ok(n) => Ok(n),
        Err(e) => Err(NotPositive::NotANumber(e)),
    }
}

/// Why a count is refused by [`positive`]; clap prints the message after the value.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NotPositive {
    /// The count is 0.
    #[error("must be at least 1")]
    Zero,
    /// Not a whole number (the parser's reason). Not a `#[source]`: the message already says
    /// it, and a report that follows sources would say it twice.
    #[error("not a whole number ({0})")]
    NotANumber(std::num::ParseIntError),
}

/// A clap error as one line: its first paragraph with the lines joined and the `error: `
/// prefix dropped, e.g. `the following required arguments were not provided: <SCENARIO>`.
pub fn one_line(e: &clap::Error) -> String {
    let rendered = e.to_string();
    let paragraph: Vec<&str> = rendered
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let line = paragraph.join(" ");
    let line = line.trim_start_matches("error: ");
    if line.is_empty() {
        "invalid arguments".to_owned()
    } else {
        line.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scramble_only_goes_with_halton() {
        assert_eq!(
            strategy(Strategy::Halton, true).unwrap(),
            Strategy::ScrambledHalton
        );
        assert_eq!(strategy(Strategy::Sobol, false).unwrap(), Strategy::Sobol);
        assert!(strategy(Strategy::Random, true).is_err());
    }

    #[test]
    fn sut_options_choose_a_builtin_or_a_command_or_nothing() {
        let args = |sut: Option<&str>, cmd: Option<&str>, timeout: f64| SutArgs {
            sut: sut.map(str::to_owned),
            sut_cmd: cmd.map(str::to_owned),
            sut_onnx: None,
            sut_timeout: Some(timeout),
            sut_fresh: false,
        };
        assert_eq!(args(None, None, 10.0).config().unwrap(), None);
        assert_eq!(
            args(Some("vision"), None, 10.0)
                .config()
                .unwrap()
                .unwrap()
                .name(),
            "vision"
        );
        let cmd = args(None, Some("python3 'my ctl.py' --fast"), 2.0)
            .config()
            .unwrap()
            .unwrap();
        assert_eq!(cmd.name(), "python3 my ctl.py --fast");
        assert!(args(Some("lidar"), None, 10.0)
            .config()
            .unwrap_err()
            .to_string()
            .contains("aeb, vision"));
        assert!(args(None, Some("python3 'oops"), 10.0).config().is_err());
        assert!(args(None, Some("   "), 10.0).config().is_err());
        assert!(args(None, Some("x"), 0.0).config().is_err());
    }

    #[test]
    fn positive_rejects_zero_and_garbage() {
        assert_eq!(positive("3"), Ok(3));
        assert_eq!(positive("0"), Err(NotPositive::Zero));
        assert_eq!(positive("0").unwrap_err().to_string(), "must be at least 1");
        assert_eq!(
            positive("ten").unwrap_err().to_string(),
            "not a whole number (invalid digit found in string)"
        );
        assert!(positive("-1").is_err());
        assert!(positive("ten").is_err());
    }
}
