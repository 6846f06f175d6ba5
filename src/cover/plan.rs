//! `paracosm-cover plan`: how many tests a (k, ε)-covering set needs.

use std::fmt;

use serde::Serialize;

use paracosm_generators::coverage::{dispersion, subset_products, DispersionOptions};
use paracosm_generators::{Halton, ParamSpace};

/// A test budget plan for a space.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// Strength `k`.
    pub strength: usize,
    /// Target dispersion `ε` of each discrete group's continuous part.
    pub epsilon: f64,
    /// Failure probability `δ` of the random k-wise family.
    pub delta: f64,
    /// Rows of a random k-wise family by Proposition 3.2, `2^k (k ln N − ln δ)`: valid for
    /// binary parameters; `None` unless every discrete parameter has 2 levels.
    pub random_kwise_prop32: Option<u64>,
    /// Rows of a random k-wise family by the union bound for mixed levels,
    /// `m = ceil(ln(T / δ) / −ln(1 − 1 / V))` with `T` the number of k-tuples and `V` the
    /// largest product of `k` level counts.
    pub random_kwise_union: Option<u64>,
    /// The smallest `m` with `Σ_tuples (1 − 1/Π_S v)^m <= δ` (the exact union bound).
    pub random_kwise_exact_union: Option<u64>,
    /// `n · dispersion` of the Halton sequence in the continuous dimension, measured at
    /// `n = 64, 256, 1024` (largest value; upper bounds where dispersion is bracketed).
    pub halton_constant: Option<f64>,
    /// Halton points per discrete group: `ceil(C / ε)`.
    pub halton_per_group: Option<u64>,
    /// Total tests: rows × points per group (each factor 1 when absent).
    pub total: u64,
}

/// Plans a (k, ε)-covering test set for `space` (PARACOSM §3.2): a random k-wise family for
/// the discrete part (Proposition 3.2 and its union-bound form for mixed levels), and for each
/// of its rows a Halton set whose dispersion is at most `ε`, sized from the measured constant
/// `C = max_n n · dispersion(E_n)` (Proposition 3.3: dispersion is `O(1/n)`).
pub fn plan(space: &ParamSpace, strength: usize, epsilon: f64, delta: f64) -> Plan {
    let levels = space.level_counts();
    let nd = levels.len();
    let k = strength.min(nd);
    let (mut prop32, mut union, mut exact) = (None, None, None);
    if nd > 0 && k > 0 {
        if levels.iter().all(|&v| v == 2) {
            let m = 2f64.powi(k as i32) * (k as f64 * (nd as f64).ln() - delta.ln());
            prop32 = Some(m.ceil().max(1.0) as u64);
        }
        let products = subset_products(&levels, k);
        let tuples: f64 = products.iter().sum();
        let vmax = products.iter().copied().fold(1.0, f64::max);
        union = Some(if vmax <= 1.0 {
            1
        } else {
            ((tuples / delta).ln() / -(1.0 - 1.0 / vmax).ln())
                .ceil()
                .max(1.0) as u64
        });
        let bound = |m: f64| -> f64 { products.iter().map(|&p| p * (1.0 - 1.0 / p).powf(m)).sum() };
        let (mut lo, mut hi) = (0u64, union.unwrap_or(1).max(1));
        while lo < hi {
            let mid = (lo + hi) / 2;
            if bound(mid as f64) <= delta {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        exact = Some(lo.max(1));
    }
    let nc = space.continuous_dims();
    let (mut constant, mut per_group) = (None, None);
    if nc > 0 {
        let h = Halton::new(space);
        let c = [64usize, 256, 1024]
            .iter()
            .map(|&n| {
                let pts = h.unit_points(0, n);
                let d =
                    dispersion(&pts, nc, &DispersionOptions::default()).map_or(1.0, |d| d.upper);
                n as f64 * d
            })
            .fold(0.0, f64::max);
        constant = Some(c);
        per_group = Some((c / epsilon).ceil().max(1.0) as u64);
    }
    let rows = exact.unwrap_or(1);
    Plan {
        strength: k,
        epsilon,
        delta,
        random_kwise_prop32: prop32,
        random_kwise_union: union,
        random_kwise_exact_union: exact,
        halton_constant: constant,
        halton_per_group: per_group,
        total: rows * per_group.unwrap_or(1),
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let k = if self.random_kwise_exact_union.is_some() {
            self.strength.to_string()
        } else {
            "k".to_owned()
        };
        writeln!(
            f,
            "plan for a ({k}, {})-covering set with failure probability δ = {}",
            self.epsilon, self.delta
        )?;
        match self.random_kwise_exact_union {
            None => writeln!(f, "discrete part: none")?,
            Some(exact) => {
                if let Some(m) = self.random_kwise_prop32 {
                    writeln!(
                        f,
                        "random k-wise, Prop. 3.2  2^k (k ln N - ln δ)               = {m} rows"
                    )?;
                }
                if let Some(m) = self.random_kwise_union {
                    writeln!(
                        f,
                        "random k-wise, union bound ln(T/δ) / -ln(1 - 1/V)         = {m} rows"
                    )?;
                }
                writeln!(
                    f,
                    "random k-wise, exact union bound Σ (1 - 1/Π v)^m <= δ    = {exact} rows"
                )?;
            }
        }
        match (self.halton_constant, self.halton_per_group) {
            (Some(c), Some(n)) => writeln!(
                f,
                "continuous part: Halton, n = ceil(C / ε) with C = max n·dispersion = {c:.3} (n = 64, 256, 1024) => {n} points per row"
            )?,
            _ => writeln!(f, "continuous part: none")?,
        }
        writeln!(f, "total: {} tests", self.total)
    }
}
