//! The axes of the failure plots. A continuous parameter spans its interval; a discrete one
//! has a column per level, in declaration order, with points jittered within it, up to
//! [`MAX_CATEGORIES`] levels (past that a plot would draw a label and a heat-map cell per
//! level: two parameters of 10^6 levels asked for 10^12 cells); a parameter of more levels
//! is drawn as numbers, its values when they are all numbers, else its level indices, binned
//! like an interval; a strip plot's other axis is the outcome (pass, fail, error).

use paracosm_generators::{Domain, ParamSpace, Value};

use super::PlotError;
use crate::record::{RunRecord, Status};

/// Most levels a discrete parameter's axis draws one band each for (see the module's
/// documentation).
pub(crate) const MAX_CATEGORIES: usize = 60;

/// Half the width of the band a category's points are jittered over (a category spans 1).
const JITTER: f64 = 0.35;

/// One axis of a failure plot.
#[derive(Debug, Clone)]
pub(crate) enum Axis {
    /// A continuous parameter: coordinates are its values in `[lo, hi]`.
    Interval {
        name: String,
        lo: f64,
        hi: f64,
        label: String,
    },
    /// A discrete parameter: level `i` is the band `[i - 0.5, i + 0.5)`.
    Levels {
        name: String,
        levels: Vec<Value>,
        label: String,
    },
    /// A discrete parameter of more than [`MAX_CATEGORIES`] levels, not all numbers: a
    /// test's coordinate is its level's index (found by the level's text), in
    /// `[0, levels − 1]`, binned like an interval.
    Index {
        name: String,
        index: std::collections::HashMap<String, usize>,
        levels: usize,
        label: String,
    },
    /// The test's outcome: pass, fail, error as bands 0, 1, 2.
    Outcome,
    /// One band holding every test (the second axis of a one-parameter heat map).
    All,
}

const OUTCOMES: [&str; 3] = ["pass", "fail", "error"];

/// A number in `[-0.5, 0.5)` from a test id and an axis salt: the same test always lands at
/// the same place (splitmix64's finaliser).
fn unit_hash(id: u64, salt: u64) -> f64 {
    let mut z = id.wrapping_add(salt.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

impl Axis {
    /// The axis of parameter `name` of `space`.
    ///
    /// # Errors
    /// [`PlotError::NotAnAxis`] when `space` has no such parameter; [`PlotError::Span`] when
    /// its interval is wider than a 64-bit float can measure.
    pub(crate) fn of(space: &ParamSpace, name: &str) -> Result<Axis, PlotError> {
        let p = space
            .param(name)
            .ok_or_else(|| PlotError::NotAnAxis(name.to_owned()))?;
        Ok(match &p.domain {
            Domain::Interval { lo, hi } if !(hi - lo).is_finite() => {
                return Err(PlotError::Span {
                    name: name.to_owned(),
                    lo: *lo,
                    hi: *hi,
                })
            }
            Domain::Interval { lo, hi } => Axis::Interval {
                name: name.to_owned(),
                lo: *lo,
                hi: *hi,
                label: p.label(),
            },
            Domain::Levels(levels) if levels.len() <= MAX_CATEGORIES => Axis::Levels {
                name: name.to_owned(),
                levels: levels.clone(),
                label: p.label(),
            },
            Domain::Levels(levels) => many_levels(name, levels, p.label()),
        })
    }

    /// The coordinate range `(min, max)`.
    pub(crate) fn range(&self) -> (f64, f64) {
        match self {
            Axis::Interval { lo, hi, .. } => (*lo, *hi),
            Axis::Levels { levels, .. } => (-0.5, levels.len() as f64 - 0.5),
            Axis::Index { levels, .. } => (0.0, levels.saturating_sub(1).max(1) as f64),
            Axis::Outcome => (-0.5, OUTCOMES.len() as f64 - 0.5),
            Axis::All => (-0.5, 0.5),
        }
    }

    /// The axis title.
    pub(crate) fn label(&self) -> String {
        match self {
            Axis::Interval { label, .. } | Axis::Levels { label, .. } => label.clone(),
            Axis::Index { label, .. } => format!("{label} (level index)"),
            Axis::Outcome => "outcome".into(),
            Axis::All => String::new(),
        }
    }

    /// The names of its bands, when it is categorical.
    pub(crate) fn categories(&self) -> Option<Vec<String>> {
        match self {
            Axis::Interval { .. } | Axis::Index { .. } => None,
            Axis::Levels { levels, .. } => Some(levels.iter().map(|l| l.to_string()).collect()),
            Axis::Outcome => Some(OUTCOMES.map(str::to_owned).to_vec()),
            Axis::All => Some(vec!["all tests".into()]),
        }
    }

    /// The band index of `r` on a categorical axis.
    fn category(&self, r: &RunRecord) -> Option<usize> {
        match self {
            Axis::Interval { .. } | Axis::Index { .. } => None,
            Axis::Levels { name, levels, .. } => {
                let v = r.params.as_ref()?.get(name)?;
                levels.iter().position(|l| l == v)
            }
            Axis::Outcome => Some(match r.status {
                Status::Pass => 0,
                Status::Fail => 1,
                Status::Error => 2,
            }),
            Axis::All => Some(0),
        }
    }

    /// Where `r` is drawn; categories are jittered by the test id (`salt` tells the two axes
    /// apart). `None` when the record lacks the value.
    pub(crate) fn coord(&self, r: &RunRecord, salt: u64) -> Option<f64> {
        match self {
            Axis::Interval { name, .. } => r.params.as_ref()?.real(name),
            Axis::Index { .. } => self.index_of(r),
            _ => self
                .category(r)
                .map(|i| i as f64 + 2.0 * JITTER * unit_hash(r.id, salt)),
        }
    }

    /// Number of heat-map cells along the axis: `bins` for an interval, one per category.
    pub(crate) fn bins(&self, bins: usize) -> usize {
        match self.categories() {
            Some(c) => c.len(),
            None => bins.max(1),
        }
    }

    /// The level index of `r` on an [`Axis::Index`], as a coordinate.
    fn index_of(&self, r: &RunRecord) -> Option<f64> {
        match self {
            Axis::Index { name, index, .. } => {
                let v = r.params.as_ref()?.get(name)?;
                index.get(&v.to_string()).map(|&i| i as f64)
            }
            _ => None,
        }
    }

    /// The heat-map cell of `r` along the axis (of [`Axis::bins`]`(bins)`).
    pub(crate) fn bin(&self, r: &RunRecord, bins: usize) -> Option<usize> {
        match self {
            Axis::Interval { lo, hi, name, .. } => {
                let v = r.params.as_ref()?.real(name)?;
                let n = bins.max(1);
                Some((((v - lo) / (hi - lo) * n as f64).floor().max(0.0) as usize).min(n - 1))
            }
            Axis::Index { .. } => {
                let (lo, hi) = self.range();
                let v = self.index_of(r)?;
                let n = bins.max(1);
                Some((((v - lo) / (hi - lo) * n as f64).floor().max(0.0) as usize).min(n - 1))
            }
            _ => self.category(r),
        }
    }

    /// The coordinates `(from, to)` of cell `k` of `n` along the axis.
    pub(crate) fn bin_span(&self, k: usize, n: usize) -> (f64, f64) {
        match self {
            Axis::Interval { .. } | Axis::Index { .. } => {
                let (lo, hi) = self.range();
                let d = (hi - lo) / n as f64;
                (lo + k as f64 * d, lo + (k + 1) as f64 * d)
            }
            _ => (k as f64 - 0.5, k as f64 + 0.5),
        }
    }
}

/// The axis of a discrete parameter `name` of more than [`MAX_CATEGORIES`] `levels`: an
/// interval over its values when they are all finite numbers spanning more than one value,
/// else its level indices.
fn many_levels(name: &str, levels: &[Value], label: String) -> Axis {
    let numbers: Option<Vec<f64>> = levels
        .iter()
        .map(|l| l.as_f64().filter(|x| x.is_finite()))
        .collect();
    if let Some(xs) = numbers {
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if hi > lo && (hi - lo).is_finite() {
            return Axis::Interval {
                name: name.to_owned(),
                lo,
                hi,
                label,
            };
        }
    }
    let mut index = std::collections::HashMap::with_capacity(levels.len());
    for (i, l) in levels.iter().enumerate() {
        index.entry(l.to_string()).or_insert(i);
    }
    Axis::Index {
        name: name.to_owned(),
        index,
        levels: levels.len(),
        label,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_is_reproducible_and_stays_in_its_band() {
        for id in 0..1000 {
            let u = unit_hash(id, 1);
            assert!((-0.5..0.5).contains(&u));
            assert_eq!(u, unit_hash(id, 1));
        }
        assert_ne!(unit_hash(3, 1), unit_hash(3, 2));
    }
}
