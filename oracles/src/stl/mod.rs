//! Signal temporal logic (STL) with quantitative robustness (space robustness of Fainekos &
//! Pappas 2009; Donzé & Maler 2010), in discrete time over uniformly sampled traces.
//!
//! Syntax ([`parse`], a `pest` grammar): predicates `signal < c`, `<=`, `>`, `>=`, and
//! comparisons of linear combinations of signals (`a - b > 8`, `x < y + 1`, `2 * x <= y`);
//! `true`, `false`; `!φ` (or `not`), `φ & ψ` (`and`), `φ | ψ` (`or`), `φ -> ψ`; `G[a,b] φ`,
//! `F[a,b] φ` and `φ U[a,b] ψ` with bounds in seconds. Example:
//! `G[0,10](a > 0 -> F[0,2](b < 1))`.
//!
//! Robustness ρ at sample `i` (positive: satisfied with that margin):
//! - `x > c`, `x >= c`: `x(i) - c`; `x < c`, `x <= c`: `c - x(i)`; for linear combinations
//!   `L > R`: `L(i) - R(i)`, and `L < R`: `R(i) - L(i)` (as RTAMT and Breach do);
//! - `!φ`: `-ρφ`; `φ & ψ`: `min`; `φ | ψ`: `max`; `φ -> ψ`: `max(-ρφ, ρψ)`;
//! - `G[a,b] φ`: `min` of `ρφ(j)` over `j ∈ [i + a/dt, i + b/dt]` within the trace (`+inf`
//!   when the window is past the end); `F[a,b] φ`: `max` (`-inf` when empty);
//! - `φ U[a,b] ψ`: `max` over `j ∈ [i + a/dt, i + b/dt]` of `min(ρψ(j), min_{k ∈ [i, j)} ρφ(k))`.
//!
//! Window minima and maxima use Lemire's streaming algorithm (a monotone deque, "Streaming
//! maximum-minimum filter using no more than three comparisons per element", 2006): O(n) per
//! operator, whatever the window.

mod eval;
mod online;
mod parse;
mod window;

pub use eval::{eval_bounds, robustness, Trace};
pub use online::StlMonitor;
pub use parse::parse;
pub use window::{sliding_max, sliding_min};

use thiserror::Error;

/// A comparison in a predicate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cmp {
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
}

/// An STL formula. Time bounds are in seconds, `0 <= lo <= hi`.
#[derive(Debug, Clone, PartialEq)]
pub enum Formula {
    /// `true`: robustness `+inf`.
    True,
    /// `false`: robustness `-inf`.
    False,
    /// `Σ coefficient × signal  op  value`: a comparison of two linear combinations of
    /// signals, with every signal moved to the left and every constant to the right
    /// (`a - b > 8`, `speed < lead.speed + 1`: terms `[(1, speed), (-1, lead.speed)]`, value 1).
    Pred {
        /// `(coefficient, signal name)`, each signal once; empty for a comparison of constants.
        terms: Vec<(f64, String)>,
        /// The comparison.
        op: Cmp,
        /// The threshold, in the signals' unit.
        value: f64,
    },
    /// `!φ`.
    Not(Box<Formula>),
    /// `φ & ψ`.
    And(Box<Formula>, Box<Formula>),
    /// `φ | ψ`.
    Or(Box<Formula>, Box<Formula>),
    /// `φ -> ψ`.
    Implies(Box<Formula>, Box<Formula>),
    /// `G[lo,hi] φ`.
    Globally(f64, f64, Box<Formula>),
    /// `F[lo,hi] φ`.
    Eventually(f64, f64, Box<Formula>),
    /// `φ U[lo,hi] ψ`.
    Until(f64, f64, Box<Formula>, Box<Formula>),
}

/// Most operators (`!`, `&`, `|`, `->`, `G`, `F`, `U`) plus bracket nesting a formula may have:
/// parsing, evaluating and dropping a formula recurse once per level, and a chain of 10,000
/// `G[0,1]` would overflow the stack (an abort, not an error).
pub const MAX_OPERATORS: usize = 256;

impl Formula {
    /// The formula with every time bound above `horizon_s + 1` (seconds) lowered to it, and
    /// whether any was. Over a trace of at most `horizon_s` seconds the robustness is
    /// unchanged (a window is cut at the trace's end either way, and one that starts past it
    /// stays past it), while online evaluation, which pads unknown samples up to the largest
    /// bound, needs memory O(horizon samples) instead of O(bound).
    pub fn clamped(&self, horizon_s: f64) -> (Formula, bool) {
        let cap = horizon_s + 1.0;
        let mut changed = false;
        let mut c = |x: f64| {
            if x > cap {
                changed = true;
                cap
            } else {
                x
            }
        };
        let f = self.map_bounds(&mut c);
        (f, changed)
    }

    fn map_bounds(&self, c: &mut dyn FnMut(f64) -> f64) -> Formula {
        let b = |f: &Formula, c: &mut dyn FnMut(f64) -> f64| Box::new(f.map_bounds(c));
        match self {
            Formula::True | Formula::False | Formula::Pred { .. } => self.clone(),
            Formula::Not(f) => Formula::Not(b(f, c)),
            Formula::And(x, y) => Formula::And(b(x, c), b(y, c)),
            Formula::Or(x, y) => Formula::Or(b(x, c), b(y, c)),
            Formula::Implies(x, y) => Formula::Implies(b(x, c), b(y, c)),
            Formula::Globally(lo, hi, f) => Formula::Globally(c(*lo), c(*hi), b(f, c)),
            Formula::Eventually(lo, hi, f) => Formula::Eventually(c(*lo), c(*hi), b(f, c)),
            Formula::Until(lo, hi, x, y) => Formula::Until(c(*lo), c(*hi), b(x, c), b(y, c)),
        }
    }

    /// The temporal operators whose window lies entirely after `horizon_s` seconds, each as
    /// `(operator, lo, hi, start)`: the operator's letter (`'G'`, `'F'`, `'U'`), its bounds,
    /// and the earliest time it reads, s (its `lo` plus the earliest time its enclosing
    /// operators evaluate it at; the formula itself is judged at `t = 0`). Over a test of
    /// `horizon_s` seconds no sample lies in such a window: an `F` or `U` there can never be
    /// satisfied and a `G` never violated, whatever the test does.
    pub fn windows_after(&self, horizon_s: f64) -> Vec<(char, f64, f64, f64)> {
        let mut out = Vec::new();
        self.windows_from(0.0, horizon_s, &mut out);
        out
    }

    fn windows_from(&self, at: f64, horizon_s: f64, out: &mut Vec<(char, f64, f64, f64)>) {
        let mut check = |op: char, lo: f64, hi: f64| {
            if at + lo > horizon_s {
                out.push((op, lo, hi, at + lo));
                true
            } else {
                false
            }
        };
        match self {
            Formula::True | Formula::False | Formula::Pred { .. } => {}
            Formula::Not(f) => f.windows_from(at, horizon_s, out),
            Formula::And(a, b) | Formula::Or(a, b) | Formula::Implies(a, b) => {
                a.windows_from(at, horizon_s, out);
                b.windows_from(at, horizon_s, out);
            }
            Formula::Globally(lo, hi, f) => {
                if !check('G', *lo, *hi) {
                    f.windows_from(at + lo, horizon_s, out);
                }
            }
            Formula::Eventually(lo, hi, f) => {
                if !check('F', *lo, *hi) {
                    f.windows_from(at + lo, horizon_s, out);
                }
            }
            Formula::Until(lo, hi, a, b) => {
                if !check('U', *lo, *hi) {
                    a.windows_from(at, horizon_s, out);
                    b.windows_from(at + lo, horizon_s, out);
                }
            }
        }
    }

    /// The names of the signals it reads, sorted, without repeats.
    pub fn signals(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.collect(&mut out);
        out.sort();
        out.dedup();
        out
    }

    fn collect(&self, out: &mut Vec<String>) {
        match self {
            Formula::True | Formula::False => {}
            Formula::Pred { terms, .. } => out.extend(terms.iter().map(|(_, s)| s.clone())),
            Formula::Not(f) | Formula::Globally(_, _, f) | Formula::Eventually(_, _, f) => {
                f.collect(out)
            }
            Formula::And(a, b)
            | Formula::Or(a, b)
            | Formula::Implies(a, b)
            | Formula::Until(_, _, a, b) => {
                a.collect(out);
                b.collect(out);
            }
        }
    }
}

/// Errors of the STL front end and evaluator.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StlError {
    /// The text does not parse; the message shows the line with a caret at the column.
    #[error("STL syntax error:\n{0}")]
    Parse(String),
    /// A time interval is empty, negative or not finite.
    #[error("STL interval [{0}, {1}] must satisfy 0 <= a <= b and be finite")]
    Interval(f64, f64),
    /// The trace lacks a signal the formula reads.
    #[error("the trace has no signal `{0}`")]
    MissingSignal(String),
    /// The trace is malformed (signals of different lengths, a non-positive step).
    #[error("invalid trace: {0}")]
    Trace(String),
    /// More operators and bracket nesting than [`MAX_OPERATORS`].
    #[error(
        "the STL formula has {0} operators and nested brackets, more than the limit of {limit}; \
         split it into several Stl monitors",
        limit = MAX_OPERATORS
    )]
    TooComplex(usize),
}
