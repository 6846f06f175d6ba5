//! `paracosm-cover estimate`: coverage of a test set.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use paracosm_generators::coverage::{
    discrepancy, dispersion, k_epsilon_covering, kwise_coverage, star_discrepancy, CoverageError,
    Discrepancy, Dispersion, DispersionOptions, KEpsilonCovering, KWiseCoverage, StarDiscrepancy,
    StarOptions,
};

use super::TestSet;

/// A continuous coverage metric, by its `--metrics` name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// `dispersion`: largest empty box (exact or bracketed).
    Dispersion,
    /// `cd`, `wd`, `md`, `l2star`: scipy's L2-type discrepancies.
    L2(Discrepancy),
    /// `star`: L∞ star discrepancy (exact or bracketed).
    Star,
}

impl FromStr for Metric {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "dispersion" => Ok(Metric::Dispersion),
            "star" => Ok(Metric::Star),
            other => Discrepancy::ALL
                .into_iter()
                .find(|k| k.name() == other)
                .map(Metric::L2)
                .ok_or_else(|| {
                    format!(
                        "unknown metric `{other}` (known: dispersion, cd, wd, md, l2star, star)"
                    )
                }),
        }
    }
}

/// The coverage of a test set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Number of tests.
    pub tests: usize,
    /// Continuous parameters, in coordinate order.
    pub continuous: Vec<String>,
    /// Discrete parameters, in coordinate order.
    pub discrete: Vec<String>,
    /// k-wise coverage for strengths `1..=strength` (empty without discrete parameters).
    pub kwise: Vec<KWiseCoverage>,
    /// Dispersion of the continuous coordinates (unit cube), if asked for.
    pub dispersion: Option<Dispersion>,
    /// L2-type discrepancies by name (`cd`, `wd`, `md` squared; `l2star` square-rooted).
    pub discrepancy: Vec<(String, f64)>,
    /// L∞ star discrepancy, if asked for.
    pub star: Option<StarDiscrepancy>,
    /// The (k, ε)-covering verdict, when ε was given.
    pub k_epsilon: Option<KEpsilonCovering>,
    /// Metrics asked for but not computed, each with the reason (too costly for this `n` and
    /// `d`, or a value that overflows). Empty when every metric was computed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped: Vec<String>,
}

/// Largest `n² · d` for which the L2 discrepancies (CD, WD, MD, L2-star; `O(n² d)` each) are
/// computed: 10^10, about 10 s each on one core.
pub const MAX_L2_WORK: f64 = 1e10;

/// Computes the requested metrics over the continuous coordinates of `set`, k-wise coverage
/// for strengths `1..=strength` over its discrete ones (listing up to `max_missing` uncovered
/// tuples per strength), and the (k, ε) verdict with `k = strength` when `epsilon` is given.
///
/// # Errors
/// [`CoverageError`] for a strength larger than the number of discrete parameters (or above
/// 6), or an `epsilon` outside `[0, 1]`.
pub fn estimate(
    set: &TestSet,
    metrics: &[Metric],
    strength: Option<usize>,
    epsilon: Option<f64>,
    max_missing: usize,
) -> Result<Estimate, CoverageError> {
    let nd = set.space.level_counts().len();
    let nc = set.space.continuous_dims();
    let strength = match strength {
        Some(t) => {
            if nd == 0 || t == 0 || t > nd.min(6) {
                return Err(CoverageError::Strength {
                    t,
                    max: nd.min(6),
                    discrete: nd,
                });
            }
            t
        }
        None => nd.min(2),
    };
    let kwise = (1..=strength)
        .map(|t| kwise_coverage(&set.space, &set.points, t, max_missing))
        .collect::<Result<Vec<_>, _>>()?;
    let coords: Vec<f64> = set
        .points
        .iter()
        .flat_map(|p| p.continuous.iter().copied())
        .collect();
    let mut out = Estimate {
        tests: set.points.len(),
        continuous: set.space.continuous().map(|p| p.name.clone()).collect(),
        discrete: set.space.discrete().map(|p| p.name.clone()).collect(),
        kwise,
        dispersion: None,
        discrepancy: Vec::new(),
        star: None,
        k_epsilon: None,
        skipped: Vec::new(),
    };
    if nc > 0 {
        for m in metrics {
            match m {
                Metric::Dispersion => {
                    out.dispersion = Some(dispersion(&coords, nc, &DispersionOptions::default())?)
                }
                Metric::L2(k) => {
                    let n = set.points.len() as f64;
                    if n * n * nc as f64 > MAX_L2_WORK {
                        out.skipped.push(format!(
                            "{}: skipped, n² · d = {:.1e} is past the limit of {MAX_L2_WORK:.0e}",
                            k.name(),
                            n * n * nc as f64
                        ));
                        continue;
                    }
                    let v = discrepancy(&coords, nc, *k)?;
                    if v.is_finite() {
                        out.discrepancy.push((k.name().to_owned(), v));
                    } else {
                        out.skipped.push(format!(
                            "{}: not a finite number in d = {nc} (its product over the \
                             dimensions overflows)",
                            k.name()
                        ));
                    }
                }
                Metric::Star => {
                    out.star = Some(star_discrepancy(&coords, nc, &StarOptions::default())?)
                }
            }
        }
    }
    if let Some(eps) = epsilon {
        out.k_epsilon = Some(k_epsilon_covering(
            &set.space,
            &set.points,
            strength.max(1),
            eps,
            &DispersionOptions::default(),
        )?);
    }
    Ok(out)
}

impl fmt::Display for Estimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} tests; continuous: {}; discrete: {}",
            self.tests,
            list(&self.continuous),
            list(&self.discrete)
        )?;
        for k in &self.kwise {
            writeln!(
                f,
                "{}-wise coverage   {:>8.4}  ({} of {} tuples)",
                k.strength, k.fraction, k.covered, k.total
            )?;
            for m in &k.missing {
                let t: Vec<String> = m.values.iter().map(|(n, v)| format!("{n}={v}")).collect();
                writeln!(f, "    missing: {}", t.join(", "))?;
            }
        }
        if let Some(d) = &self.dispersion {
            if d.exact {
                writeln!(f, "dispersion        {:.6e}  exact", d.lower)?;
            } else {
                writeln!(
                    f,
                    "dispersion        [{:.6e}, {:.6e}]  bracket",
                    d.lower, d.upper
                )?;
            }
            writeln!(
                f,
                "    witness box (unit cube): lo {:?}, hi {:?}",
                d.witness.lo, d.witness.hi
            )?;
            writeln!(f, "    method: {}", d.method)?;
        }
        for (name, v) in &self.discrepancy {
            let note = if name == "l2star" {
                ""
            } else {
                " (squared, as scipy)"
            };
            writeln!(f, "{name:<17} {v:.6e}{note}")?;
        }
        for note in &self.skipped {
            writeln!(f, "{note}")?;
        }
        if let Some(s) = &self.star {
            if s.exact {
                writeln!(f, "star discrepancy  {:.6e}  exact", s.lower)?;
            } else {
                writeln!(
                    f,
                    "star discrepancy  [{:.6e}, {:.6e}]  bracket",
                    s.lower, s.upper
                )?;
            }
        }
        if let Some(k) = &self.k_epsilon {
            let verdict = match k.covering {
                Some(true) => "yes",
                Some(false) => "no",
                None => "undecided (the dispersion bracket straddles ε)",
            };
            if k.kwise.is_some() {
                writeln!(f, "({}, {})-covering: {verdict}", k.k, k.epsilon)?;
            } else {
                writeln!(
                    f,
                    "(k, {})-covering: {verdict} (no discrete parameters: only the dispersion condition applies)",
                    k.epsilon
                )?;
            }
            if let Some((group, d)) = &k.worst_group {
                writeln!(
                    f,
                    "    largest dispersion in one discrete group (level indices {group:?}): [{:.6e}, {:.6e}] over {} groups",
                    d.lower, d.upper, k.groups
                )?;
            }
        }
        Ok(())
    }
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "none".to_owned()
    } else {
        names.join(", ")
    }
}
