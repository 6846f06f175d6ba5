//! Sampling densities of parameters: where a parameter's values are likely, for random
//! sampling. Coverage generators (Halton, Sobol, IPOG, ...) ignore them and cover the
//! parameter's whole domain; [`crate::UniformRandom`] draws through them.
//!
//! A density maps one uniform draw `u ∈ [0, 1)` to a value by the inverse of its cumulative
//! distribution truncated to the parameter's domain (inverse transform sampling; Devroye,
//! *Non-Uniform Random Variate Generation*, 1986, §II.2), so a parameter still takes exactly
//! one draw of the stream.

use serde::{Deserialize, Serialize};

/// How a parameter's values are distributed for random sampling (OpenSCENARIO 1.3's
/// stochastic distributions).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Density {
    /// Normal with mean `mean` and standard deviation `sd` (> 0), truncated to the
    /// parameter's interval.
    Normal {
        /// Mean, in the parameter's unit.
        mean: f64,
        /// Standard deviation, in the parameter's unit, > 0.
        sd: f64,
    },
    /// Log-normal: `ln X` is normal with mean `mu` and standard deviation `sigma` (> 0),
    /// truncated to the parameter's interval (which must lie in `(0, ∞)` to hold mass).
    LogNormal {
        /// Mean of `ln X`.
        mu: f64,
        /// Standard deviation of `ln X`, > 0.
        sigma: f64,
    },
    /// Piecewise uniform: bins `(lo, hi, weight)`, ordered, not overlapping, `lo < hi`,
    /// weights ≥ 0 and not all 0; the parameter's interval spans them.
    Histogram(Vec<(f64, f64, f64)>),
    /// Weights of a discrete parameter's levels, in level order, ≥ 0 and not all 0.
    Weights(Vec<f64>),
}

/// The standard normal cumulative distribution function, `Φ(z) = (1 + erf(z/√2)) / 2`.
fn std_normal_cdf(z: f64) -> f64 {
    0.5 * (1.0 + libm::erf(z / std::f64::consts::SQRT_2))
}

impl Density {
    /// The value of draw `u` (`[0, 1)`) on the interval `[lo, hi)`: the `q`-quantile of the
    /// density truncated to the interval, with `q = u`. Outside what the density covers (an
    /// interval where it has no mass), the draw falls uniformly on the interval.
    pub fn quantile(&self, u: f64, lo: f64, hi: f64) -> f64 {
        let uniform = lo + u * (hi - lo);
        let cdf = |x: f64| -> f64 {
            match self {
                Density::Normal { mean, sd } => std_normal_cdf((x - mean) / sd),
                Density::LogNormal { mu, sigma } if x > 0.0 => {
                    std_normal_cdf((x.ln() - mu) / sigma)
                }
                Density::LogNormal { .. } => 0.0,
                Density::Histogram(bins) => {
                    let total: f64 = bins.iter().map(|b| b.2).sum();
                    bins.iter()
                        .map(|&(a, b, w)| w * ((x.min(b) - a) / (b - a)).clamp(0.0, 1.0))
                        .sum::<f64>()
                        / total
                }
                Density::Weights(_) => 0.0,
            }
        };
        if matches!(self, Density::Weights(_)) {
            return uniform;
        }
        let (c0, c1) = (cdf(lo), cdf(hi));
        // No mass on the interval (or a NaN from a bad density): uniform.
        if (c1 - c0).partial_cmp(&1e-300) != Some(std::cmp::Ordering::Greater) {
            return uniform;
        }
        let target = c0 + u * (c1 - c0);
        // Bisection on the monotone CDF: 100 halvings reach the resolution of f64 on any
        // finite interval.
        let (mut a, mut b) = (lo, hi);
        for _ in 0..100 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if cdf(m) < target {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    }

    /// The level of draw `u` (`[0, 1)`) among `n` levels: by the weights, or uniformly when
    /// the density has none for `n` levels.
    pub fn level(&self, u: f64, n: u32) -> u32 {
        match self {
            Density::Weights(w) if w.len() == n as usize && w.iter().sum::<f64>() > 0.0 => {
                let total: f64 = w.iter().sum();
                let mut acc = 0.0;
                for (k, wk) in w.iter().enumerate() {
                    acc += wk / total;
                    if u < acc {
                        return k as u32;
                    }
                }
                // Rounding left `u` past the last sum: the last level with weight.
                w.iter().rposition(|&x| x > 0.0).unwrap_or(0) as u32
            }
            _ => ((u * n as f64) as u32).min(n.saturating_sub(1)),
        }
    }

    /// Why this density cannot serve a parameter on `[lo, hi)` (or with `levels` levels), or
    /// `None` when it can.
    pub fn check(&self, interval: Option<(f64, f64)>, levels: Option<usize>) -> Option<String> {
        let finite = |x: f64| x.is_finite();
        match (self, interval, levels) {
            (Density::Normal { mean, sd }, Some(_), None) => {
                (!(finite(*mean) && finite(*sd) && *sd > 0.0)).then(|| {
                    format!(
                        "a normal density needs a finite mean and sd > 0 (mean {mean}, sd {sd})"
                    )
                })
            }
            (Density::LogNormal { mu, sigma }, Some((_, hi)), None) => {
                if !(finite(*mu) && finite(*sigma) && *sigma > 0.0) {
                    Some(format!("a log-normal density needs a finite mu and sigma > 0 (mu {mu}, sigma {sigma})"))
                } else if hi <= 0.0 {
                    Some(format!("a log-normal density has no mass on an interval below 0 (upper bound {hi})"))
                } else {
                    None
                }
            }
            (Density::Histogram(bins), Some(_), None) => {
                let ok = !bins.is_empty()
                    && bins
                        .iter()
                        .all(|&(a, b, w)| finite(a) && finite(b) && a < b && w >= 0.0)
                    && bins.windows(2).all(|p| p[0].1 <= p[1].0)
                    && bins.iter().map(|b| b.2).sum::<f64>() > 0.0;
                (!ok).then(|| "a histogram needs ordered, non-overlapping bins lo < hi with weights ≥ 0, not all 0".to_owned())
            }
            (Density::Weights(w), None, Some(n)) => {
                if w.len() != n {
                    Some(format!("{} weights for {n} levels", w.len()))
                } else if !w.iter().all(|&x| finite(x) && x >= 0.0) || w.iter().sum::<f64>() <= 0.0
                {
                    Some("weights must be ≥ 0 and not all 0".to_owned())
                } else {
                    None
                }
            }
            (Density::Weights(_), Some(_), _) => {
                Some("weights are for a parameter with levels".to_owned())
            }
            (_, None, _) => Some("a continuous density is for an interval parameter".to_owned()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quantiles of a normal truncated to ±1 sd: the median is the mean, and Φ at the
    /// 84.13 % point of the untruncated normal (mean + sd) maps back to the top end.
    #[test]
    fn a_truncated_normal_maps_draws_by_its_quantiles() {
        let d = Density::Normal {
            mean: 10.0,
            sd: 2.0,
        };
        assert!((d.quantile(0.5, 8.0, 12.0) - 10.0).abs() < 1e-9);
        assert!((d.quantile(0.0, 8.0, 12.0) - 8.0).abs() < 1e-9);
        // Untruncated (a wide interval): the 97.5 % quantile is mean + 1.959964 sd.
        let q = d.quantile(0.975, -1e3, 1e3);
        assert!((q - (10.0 + 1.959_963_985 * 2.0)).abs() < 1e-6, "{q}");
    }

    #[test]
    fn a_log_normal_median_is_exp_mu() {
        let d = Density::LogNormal {
            mu: 1.0,
            sigma: 0.5,
        };
        let q = d.quantile(0.5, 1e-9, 1e6);
        assert!((q - 1f64.exp()).abs() < 1e-6, "{q}");
    }

    #[test]
    fn a_histogram_puts_its_weight_in_its_bins() {
        let d = Density::Histogram(vec![(0.0, 1.0, 1.0), (1.0, 3.0, 3.0)]);
        // A quarter of the mass in [0, 1), the rest spread over [1, 3).
        assert!((d.quantile(0.25, 0.0, 3.0) - 1.0).abs() < 1e-9);
        assert!((d.quantile(0.625, 0.0, 3.0) - 2.0).abs() < 1e-9);
    }

    #[test]
    fn weights_pick_levels_in_proportion() {
        let d = Density::Weights(vec![1.0, 0.0, 3.0]);
        assert_eq!(d.level(0.1, 3), 0);
        assert_eq!(d.level(0.25, 3), 2);
        assert_eq!(d.level(0.99, 3), 2);
        assert_eq!(
            d.check(None, Some(2)),
            Some("3 weights for 2 levels".into())
        );
    }
}
