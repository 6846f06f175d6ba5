//! `paracosm-cover estimate`: coverage of a test set.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use paracosm_generators::coverage::{
    discrepancy, dispersion_with_progress, k_epsilon_covering, kwise_coverage,
    star_discrepancy_with_progress, CoverageError, Discrepancy, Dispersion, DispersionOptions,
    KEpsilonCovering, KWiseCoverage, StarDiscrepancy, StarOptions,
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
    /// Over a constrained space: the share of it the constraints leave valid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub valid: Option<paracosm_generators::ValidFraction>,
    /// Over a constrained space with continuous parameters: the largest empty cube centred
    /// in the valid region ([`paracosm_generators::coverage::valid_gap`]), the dispersion
    /// of the valid region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub valid_gap: Option<paracosm_generators::coverage::ValidGap>,
    /// Metrics asked for but not computed, each with the reason (too costly for this `n` and
    /// `d`, or a value that overflows). Empty when every metric was computed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped: Vec<String>,
}

/// Largest `n² · d` for which the L2 discrepancies (CD, WD, MD, L2-star; `O(n² d)` each) are
/// computed: 10^10, about 10 s each on one core.
pub const MAX_L2_WORK: f64 = 1e10;

/// Largest dimension in which paracosm computes the star discrepancy exactly (its sweeps are
/// for d = 1 to 4; past it, a bracket).
pub const STAR_EXACT_MAX_DIMS: usize = 4;

/// How an exact computation's progress is told: the metric's name, then `(done, total)`
/// units of its work ([`paracosm_generators::coverage::Progress`]).
pub type ExactProgress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// The limits `paracosm-cover estimate` computes within: the defaults, or, with `--exact`,
/// none, so that the dispersion (every `d`) and the star discrepancy (`d <= 4`) are exact
/// whatever the time and memory.
fn limits(exact: bool, d: usize) -> (DispersionOptions, StarOptions) {
    if exact {
        (
            DispersionOptions {
                exact_max_points: vec![usize::MAX; d.max(3) - 2],
                ..DispersionOptions::default()
            },
            StarOptions {
                exact_max_points: [usize::MAX; 4],
                ..StarOptions::default()
            },
        )
    } else {
        (DispersionOptions::default(), StarOptions::default())
    }
}

/// Computes the requested metrics over the continuous coordinates of `set`, k-wise coverage
/// for strengths `1..=strength` over its discrete ones (listing up to `max_missing` uncovered
/// tuples per strength), and the (k, ε) verdict with `k = strength` when `epsilon` is given.
/// With `exact` (`--exact`) the dispersion and the star discrepancy are computed exactly
/// wherever paracosm has an exact algorithm, past the default limits
/// ([`DispersionOptions::exact_max_points`], [`StarOptions::exact_max_points`]), telling the
/// hook how far each has come.
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
    exact: Option<ExactProgress<'_>>,
) -> Result<Estimate, CoverageError> {
    let nd = set.space.level_counts().len();
    let nc = set.space.continuous_dims();
    let (dispersion_limits, star_limits) = limits(exact.is_some(), nc);
    let hook = |name: &'static str| {
        move |done: u64, total: u64| {
            if let Some(tell) = exact {
                tell(name, done, total);
            }
        }
    };
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
        valid: None,
        valid_gap: None,
        skipped: Vec::new(),
    };
    if set.space.is_constrained() {
        out.valid = Some(
            set.space
                .valid_fraction()
                .map_err(|e| CoverageError::Constraints(e.to_string()))?,
        );
        out.valid_gap = paracosm_generators::coverage::valid_gap(&set.space, &set.points)?;
    }
    if nc > 0 {
        for m in metrics {
            match m {
                Metric::Dispersion => {
                    out.dispersion = Some(dispersion_with_progress(
                        &coords,
                        nc,
                        &dispersion_limits,
                        &hook("dispersion"),
                    )?)
                }
                Metric::L2(k) => add_l2(&mut out, &coords, nc, *k)?,
                Metric::Star => {
                    out.star = Some(star_discrepancy_with_progress(
                        &coords,
                        nc,
                        &star_limits,
                        &hook("star discrepancy"),
                    )?)
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
            &dispersion_limits,
        )?);
    }
    Ok(out)
}

/// Adds the L2-type discrepancy `k` of `coords` (`n × nc`, row-major, in the unit cube) to
/// `out`, or the reason it is skipped (past [`MAX_L2_WORK`], or not a finite number).
///
/// # Errors
/// What [`discrepancy`] returns.
fn add_l2(
    out: &mut Estimate,
    coords: &[f64],
    nc: usize,
    k: Discrepancy,
) -> Result<(), CoverageError> {
    let n = (coords.len() / nc) as f64;
    if n * n * nc as f64 > MAX_L2_WORK {
        out.skipped.push(format!(
            "{}: skipped, n² · d = {:.1e} is past the limit of {MAX_L2_WORK:.0e}",
            k.name(),
            n * n * nc as f64
        ));
        return Ok(());
    }
    let v = discrepancy(coords, nc, k)?;
    if v.is_finite() {
        out.discrepancy.push((k.name().to_owned(), v));
    } else {
        out.skipped.push(format!(
            "{}: not a finite number in d = {nc} (its product over the dimensions overflows)",
            k.name()
        ));
    }
    Ok(())
}

impl Estimate {
    /// The valid fraction and the k-wise lines of [`Estimate`]'s table.
    fn fmt_kwise(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(v) = &self.valid {
            writeln!(f, "valid space       {v}")?;
        }
        for k in &self.kwise {
            let forbidden = if k.forbidden > 0 {
                format!(" valid tuples; {} forbidden", k.forbidden)
            } else {
                " tuples".to_owned()
            };
            writeln!(
                f,
                "{}-wise coverage   {:>8.4}  ({} of {}{forbidden})",
                k.strength, k.fraction, k.covered, k.total
            )?;
            for m in &k.missing {
                let t: Vec<String> = m.values.iter().map(|(n, v)| format!("{n}={v}")).collect();
                writeln!(f, "    missing: {}", t.join(", "))?;
            }
        }
        Ok(())
    }
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
        self.fmt_kwise(f)?;
        if let Some(d) = &self.dispersion {
            if d.exact {
                writeln!(f, "dispersion        {:.6e}  exact", d.lower)?;
            } else {
                writeln!(
                    f,
                    "dispersion        [{:.6e}, {:.6e}]  bracket (--exact computes it)",
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
        if let Some(g) = &self.valid_gap {
            writeln!(
                f,
                "valid-region gap  {:.6e}  lower bound (the largest empty cube centred in the \
                 valid region, half side; {} valid probes)",
                g.radius, g.probes
            )?;
            writeln!(f, "    centre (unit cube): {:?}", g.centre)?;
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
                let how = if self.continuous.len() <= STAR_EXACT_MAX_DIMS {
                    "--exact computes it".to_owned()
                } else {
                    format!(
                        "no exact algorithm past d = {STAR_EXACT_MAX_DIMS}: this is d = {}",
                        self.continuous.len()
                    )
                };
                writeln!(
                    f,
                    "star discrepancy  [{:.6e}, {:.6e}]  bracket ({how})",
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
