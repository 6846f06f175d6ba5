//! Bayesian-optimisation falsification: a Gaussian process over the robustness, and the next
//! tests where an acquisition function says a failure is most likely to be found.
//!
//! The loop (Jones, Schonlau and Welch, "Efficient global optimization of expensive black-box
//! functions", J. Global Optim. 13, 1998; the baseline of VerifAI's and most falsification
//! papers' comparisons):
//! 1. An initial design: the first [`BoTuning::initial_points`] points of a scrambled Halton
//!    sequence over the continuous parameters (Owen 2017, seeded), the discrete ones taking
//!    the rows of a pairwise covering array (IPOG) in turn, as the other falsifiers do.
//! 2. Then, per batch: the hyper-parameters of a Matérn 5/2 process ([`super::gp`]) by
//!    marginal likelihood (L-BFGS from the previous optimum and the defaults, with random
//!    restarts every few batches); the acquisition maximised by multi-start L-BFGS (argmin)
//!    over the continuous coordinates from the best of [`BoTuning::candidates`] random
//!    candidates and the best points so far, each with its discrete levels fixed; the
//!    batch's further points by the kriging believer (Ginsbourger, Le Riche and Carraro,
//!    "Kriging is well-suited to parallelize optimization", 2010): the process conditioned on
//!    its own mean at the points already chosen.
//!
//! Discrete parameters enter the process one-hot (one input per level, each with its own
//! length scale). Robustness values that are not finite (a test that errored: NaN; +∞) count
//! as the largest finite value seen, −∞ as the smallest, so that one such test does not
//! swamp the standardised targets. The process sees at most [`BoTuning::max_train`] points:
//! past that, the best half and the most recent half (fitting is cubic in the points).
//!
//! Deterministic: every random choice comes from ChaCha8 seeded by the campaign seed, and all
//! arithmetic is sequential, so the points do not depend on the number of threads.

use std::collections::VecDeque;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::gp::{fit_hyper, Gp, Hyper, HyperBounds};
use crate::{Generator, GeneratorError, Halton, ParamSpace, Point};

/// The largest `f64` below 1: points are clamped into `[0, ONE_BELOW]`.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// What the next tests maximise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Acquisition {
    /// Expected improvement below the lowest robustness so far, minus `xi` times the
    /// targets' standard deviation (Jones et al. 1998).
    ExpectedImprovement {
        /// Exploration margin, in standard deviations of the robustness seen. Default 0.01.
        xi: f64,
    },
    /// The lower confidence bound `μ − β σ`, minimised (Srinivas et al., "Gaussian process
    /// optimization in the bandit setting", ICML 2010).
    LowerConfidenceBound {
        /// Weight of the standard deviation. Default 2.
        beta: f64,
    },
}

/// Settings of [`BayesOpt`]. [`BoTuning::default`] is what `falsify-bo` uses.
#[derive(Debug, Clone, PartialEq)]
pub struct BoTuning {
    /// Points of the initial design; `None`: `max(8, 2 (p + 1))` with `p` the process's
    /// inputs (continuous parameters plus discrete levels).
    pub initial_points: Option<usize>,
    /// Points per batch, `>= 1`. Default 4.
    pub batch: usize,
    /// Most points the process is conditioned on. Default 256.
    pub max_train: usize,
    /// Random candidates scored before the acquisition is maximised. Default 512.
    pub candidates: usize,
    /// L-BFGS starts of the acquisition's maximisation. Default 4.
    pub starts: usize,
    /// L-BFGS iterations per acquisition start. Default 40.
    pub acquisition_iters: u64,
    /// L-BFGS iterations per hyper-parameter start. Default 60.
    pub hyper_iters: u64,
    /// Two random hyper-parameter starts every this many batches (1: every batch). Default 5.
    pub hyper_restart_every: u64,
    /// The acquisition function. Default expected improvement with `xi = 0.01`.
    pub acquisition: Acquisition,
}

impl Default for BoTuning {
    fn default() -> Self {
        BoTuning {
            initial_points: None,
            batch: 4,
            max_train: 256,
            candidates: 512,
            starts: 4,
            acquisition_iters: 40,
            hyper_iters: 60,
            hyper_restart_every: 5,
            acquisition: Acquisition::ExpectedImprovement { xi: 0.01 },
        }
    }
}

/// The standard normal density and distribution function at `z`.
fn normal(z: f64) -> (f64, f64) {
    let pdf = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let cdf = 0.5 * libm::erfc(-z / std::f64::consts::SQRT_2);
    (pdf, cdf)
}

/// A Gaussian-process Bayesian-optimisation falsifier (see the module docs).
pub struct BayesOpt {
    name: &'static str,
    tuning: BoTuning,
    d: usize,
    levels: Vec<u32>,
    rows: Vec<Vec<u32>>,
    rng: ChaCha8Rng,
    initial: Halton,
    initial_points: usize,
    /// Points told so far with their robustness, in the order told.
    observed: Vec<(Point, f64)>,
    /// Points handed out and not yet told.
    handed: VecDeque<Point>,
    handed_total: usize,
    hyper: Option<Hyper>,
    batches: u64,
}

impl BayesOpt {
    /// A falsifier over `space` seeded with `seed`, maximising expected improvement
    /// ([`BoTuning::default`]).
    ///
    /// # Errors
    /// [`GeneratorError::Covering`] when the space has no continuous parameter or its
    /// discrete array cannot be built.
    pub fn new(space: &ParamSpace, seed: u64) -> Result<Self, GeneratorError> {
        Self::with_tuning(space, seed, BoTuning::default())
    }

    /// As [`BayesOpt::new`], with explicit settings.
    ///
    /// # Errors
    /// As [`BayesOpt::new`].
    pub fn with_tuning(
        space: &ParamSpace,
        seed: u64,
        tuning: BoTuning,
    ) -> Result<Self, GeneratorError> {
        let d = space.continuous_dims();
        if d == 0 {
            return Err(GeneratorError::Covering(
                "Bayesian optimisation searches continuous parameters (VarInterval), and this \
                 space has none: use --strategy ipog"
                    .into(),
            ));
        }
        let levels = space.level_counts();
        let rows = match levels.len() {
            0 => vec![Vec::new()],
            n => {
                let array = crate::covering::ipog(&levels, n.min(2))
                    .map_err(|e| GeneratorError::Covering(e.to_string()))?;
                (0..array.len()).map(|r| array.row(r).to_vec()).collect()
            }
        };
        let p = d + levels.iter().map(|&l| l as usize).sum::<usize>();
        let initial_points = tuning.initial_points.unwrap_or((2 * (p + 1)).max(8)).max(1);
        let name = match tuning.acquisition {
            Acquisition::ExpectedImprovement { .. } => "falsify-bo",
            Acquisition::LowerConfidenceBound { .. } => "falsify-bo-lcb",
        };
        Ok(BayesOpt {
            name,
            tuning: BoTuning {
                batch: tuning.batch.max(1),
                starts: tuning.starts.max(1),
                max_train: tuning.max_train.max(2),
                ..tuning
            },
            d,
            levels,
            rows,
            rng: ChaCha8Rng::seed_from_u64(seed),
            initial: Halton::scrambled(&ParamSpace::unit_cube(d), seed),
            initial_points,
            observed: Vec::new(),
            handed: VecDeque::new(),
            handed_total: 0,
            hyper: None,
            batches: 0,
        })
    }

    /// The inputs of the process: the continuous coordinates, then one-hot levels.
    fn encode(&self, p: &Point, out: &mut Vec<f64>) {
        out.extend_from_slice(&p.continuous);
        for (k, &l) in self.levels.iter().enumerate() {
            for v in 0..l {
                out.push(if p.discrete[k] == v { 1.0 } else { 0.0 });
            }
        }
    }

    /// The training set: inputs (`n × p`) and targets with non-finite values replaced.
    fn training(&self) -> (Vec<f64>, Vec<f64>) {
        let finite: Vec<f64> = self
            .observed
            .iter()
            .map(|(_, r)| *r)
            .filter(|r| r.is_finite())
            .collect();
        let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let (hi, lo) = if finite.is_empty() {
            (1.0, 0.0)
        } else {
            (hi, lo)
        };
        let target = |r: f64| {
            if r.is_finite() {
                r
            } else if r == f64::NEG_INFINITY {
                lo
            } else {
                hi
            }
        };
        let n = self.observed.len();
        let keep: Vec<usize> = if n <= self.tuning.max_train {
            (0..n).collect()
        } else {
            let half = self.tuning.max_train / 2;
            let mut by_cost: Vec<usize> = (0..n).collect();
            by_cost.sort_by(|&a, &b| {
                target(self.observed[a].1)
                    .total_cmp(&target(self.observed[b].1))
                    .then(a.cmp(&b))
            });
            let mut chosen = vec![false; n];
            for &i in by_cost.iter().take(half) {
                chosen[i] = true;
            }
            let mut recent = 0;
            for i in (0..n).rev() {
                if recent >= self.tuning.max_train - half {
                    break;
                }
                if !chosen[i] {
                    chosen[i] = true;
                    recent += 1;
                }
            }
            (0..n).filter(|&i| chosen[i]).collect()
        };
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in keep {
            self.encode(&self.observed[i].0, &mut x);
            y.push(target(self.observed[i].1));
        }
        (x, y)
    }

    fn inputs(&self) -> usize {
        self.d + self.levels.iter().map(|&l| l as usize).sum::<usize>()
    }

    /// The hyper-parameters for this batch.
    fn hyper_for(&mut self, x: &[f64], y: &[f64]) -> Hyper {
        let p = self.inputs();
        let default = Hyper {
            log_length: vec![0.3f64.ln(); p],
            log_signal: 0.0,
            log_noise: 1e-4f64.ln(),
        };
        let mut starts = vec![default.clone()];
        if let Some(h) = &self.hyper {
            starts.insert(0, h.clone());
        }
        let bounds = HyperBounds::default();
        if self
            .batches
            .is_multiple_of(self.tuning.hyper_restart_every.max(1))
        {
            for _ in 0..2 {
                let draw = |rng: &mut ChaCha8Rng, (lo, hi): (f64, f64)| {
                    lo + (hi - lo) * rng.random::<f64>()
                };
                starts.push(Hyper {
                    log_length: (0..p)
                        .map(|_| draw(&mut self.rng, (0.05f64.ln(), 2f64.ln())))
                        .collect(),
                    log_signal: draw(&mut self.rng, (0.1f64.ln(), 10f64.ln())),
                    log_noise: draw(&mut self.rng, (1e-6f64.ln(), 1e-2f64.ln())),
                });
            }
        }
        let h = fit_hyper(x, p, y, &starts, &bounds, self.tuning.hyper_iters).unwrap_or(default);
        self.hyper = Some(h.clone());
        h
    }

    /// The next `q` points by the acquisition and the kriging believer.
    fn propose(&mut self, q: usize) -> Vec<Point> {
        let (mut x, mut y) = self.training();
        let p = self.inputs();
        let hyper = self.hyper_for(&x, &y);
        let best = y.iter().copied().fold(f64::INFINITY, f64::min);
        let mut out = Vec::with_capacity(q);
        for _ in 0..q {
            let Ok(gp) = Gp::fit(&x, p, &y, &hyper) else {
                break;
            };
            let (_, y_sd) = {
                let n = y.len() as f64;
                let m = y.iter().sum::<f64>() / n;
                (
                    m,
                    (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt(),
                )
            };
            let point = self.maximise(&gp, best, y_sd.max(1e-12));
            self.encode(&point, &mut x);
            // The kriging believer: the process's own mean stands in for the result.
            let mut enc = Vec::new();
            self.encode(&point, &mut enc);
            y.push(gp.predict(&enc).0);
            out.push(point);
        }
        out
    }

    /// The point that maximises the acquisition: random candidates and the best points
    /// scored, the best few refined by L-BFGS over the continuous coordinates.
    fn maximise(&mut self, gp: &Gp, best: f64, y_sd: f64) -> Point {
        let acquisition = self.tuning.acquisition;
        let score = |enc: &[f64]| -> f64 { cost_of(gp, enc, acquisition, best, y_sd).0 };
        let mut candidates: Vec<Point> = Vec::with_capacity(self.tuning.candidates + 4);
        for _ in 0..self.tuning.candidates {
            let continuous = (0..self.d).map(|_| self.rng.random::<f64>()).collect();
            let discrete = self
                .levels
                .iter()
                .map(|&l| self.rng.random_range(0..l))
                .collect();
            candidates.push(Point {
                discrete,
                continuous,
            });
        }
        let mut by_robustness: Vec<&(Point, f64)> = self.observed.iter().collect();
        by_robustness.sort_by(|a, b| a.1.total_cmp(&b.1));
        candidates.extend(by_robustness.iter().take(4).map(|(p, _)| p.clone()));
        let mut scored: Vec<(f64, usize)> = candidates
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut enc = Vec::new();
                self.encode(c, &mut enc);
                (score(&enc), i)
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut winner = (scored[0].0, candidates[scored[0].1].clone());
        for &(_, i) in scored.iter().take(self.tuning.starts) {
            let start = &candidates[i];
            let mut suffix = Vec::new();
            self.encode(
                &Point {
                    discrete: start.discrete.clone(),
                    continuous: Vec::new(),
                },
                &mut suffix,
            );
            let problem = AcquisitionProblem {
                gp,
                suffix: &suffix,
                acquisition,
                best,
                y_sd,
            };
            let u0: Vec<f64> = start
                .continuous
                .iter()
                .map(|&v| (2.0 * v - 1.0).clamp(-1.0, 1.0).asin())
                .collect();
            let run = Executor::new(problem, LBFGS::new(MoreThuenteLineSearch::new(), 7))
                .configure(|s| s.param(u0).max_iters(self.tuning.acquisition_iters))
                .run();
            if let Ok(r) = run {
                let state = r.state();
                if let Some(u) = &state.best_param {
                    if state.best_cost < winner.0 {
                        winner = (
                            state.best_cost,
                            Point {
                                discrete: start.discrete.clone(),
                                continuous: u.iter().map(|&v| to_unit(v)).collect(),
                            },
                        );
                    }
                }
            }
        }
        let mut point = winner.1;
        for v in &mut point.continuous {
            *v = v.clamp(0.0, ONE_BELOW);
        }
        point
    }
}

/// `[0, 1]` from an unconstrained coordinate: `(1 + sin u) / 2`.
fn to_unit(u: f64) -> f64 {
    (1.0 + u.sin()) / 2.0
}

/// The acquisition to minimise at `enc` and its gradient in the encoded coordinates: `−EI`
/// or `μ − β σ`.
fn cost_of(
    gp: &Gp,
    enc: &[f64],
    acquisition: Acquisition,
    best: f64,
    y_sd: f64,
) -> (f64, Vec<f64>) {
    let (mu, sd, dmu, dsd) = gp.predict_with_gradient(enc);
    match acquisition {
        Acquisition::ExpectedImprovement { xi } => {
            let imp = best - mu - xi * y_sd;
            if sd < 1e-12 {
                return (-imp.max(0.0), vec![0.0; enc.len()]);
            }
            let z = imp / sd;
            let (pdf, cdf) = normal(z);
            let ei = imp * cdf + sd * pdf;
            let grad = dmu
                .iter()
                .zip(&dsd)
                .map(|(m, s)| cdf * m - pdf * s)
                .collect();
            (-ei, grad)
        }
        Acquisition::LowerConfidenceBound { beta } => (
            mu - beta * sd,
            dmu.iter().zip(&dsd).map(|(m, s)| m - beta * s).collect(),
        ),
    }
}

/// The acquisition over unconstrained continuous coordinates `u` (`x = (1 + sin u) / 2`),
/// the one-hot levels fixed.
struct AcquisitionProblem<'a> {
    gp: &'a Gp,
    suffix: &'a [f64],
    acquisition: Acquisition,
    best: f64,
    y_sd: f64,
}

impl AcquisitionProblem<'_> {
    fn eval(&self, u: &[f64]) -> (f64, Vec<f64>) {
        let mut enc: Vec<f64> = u.iter().map(|&v| to_unit(v)).collect();
        enc.extend_from_slice(self.suffix);
        let (c, g) = cost_of(self.gp, &enc, self.acquisition, self.best, self.y_sd);
        let gu = u.iter().zip(&g).map(|(v, gi)| gi * v.cos() / 2.0).collect();
        (c, gu)
    }
}

impl CostFunction for AcquisitionProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, argmin::core::Error> {
        Ok(self.eval(u).0)
    }
}

impl Gradient for AcquisitionProblem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Self::Param) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.eval(u).1)
    }
}

impl Generator for BayesOpt {
    fn name(&self) -> &'static str {
        self.name
    }

    /// Up to `n` points: the initial design first, then a batch from the process once every
    /// point handed out has been told (none while some are pending).
    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let mut out = Vec::new();
        while out.len() < n && self.handed_total < self.initial_points {
            let k = self.handed_total;
            let continuous = self
                .initial
                .ask(1)?
                .pop()
                .map(|p| p.continuous)
                .unwrap_or_default();
            out.push(Point {
                discrete: self.rows[k % self.rows.len()].clone(),
                continuous,
            });
            self.handed_total += 1;
        }
        if out.is_empty() && self.handed.is_empty() && n > 0 {
            out = self.propose(n.min(self.tuning.batch));
            self.batches += 1;
            self.handed_total += out.len();
        }
        self.handed.extend(out.iter().cloned());
        Ok(out)
    }

    /// Robustness of points handed out, in the order handed out (a prefix is fine); points
    /// that do not match are ignored.
    fn tell(&mut self, evaluated: &[(Point, f64)]) {
        for (point, robustness) in evaluated {
            if self.handed.front() != Some(point) {
                continue;
            }
            self.handed.pop_front();
            self.observed.push((point.clone(), *robustness));
        }
    }

    /// [`BoTuning::batch`] points.
    fn batch(&self) -> Option<usize> {
        Some(self.tuning.batch)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Param, Value};

    fn drive(g: &mut BayesOpt, budget: usize, f: impl Fn(&Point) -> f64) -> Vec<Point> {
        let mut all = Vec::new();
        while all.len() < budget {
            let n = g.batch().unwrap().min(budget - all.len());
            let pts = g.ask(n).unwrap();
            assert!(!pts.is_empty(), "points after every tell");
            let told: Vec<(Point, f64)> = pts.iter().map(|p| (p.clone(), f(p))).collect();
            g.tell(&told);
            all.extend(pts);
        }
        all
    }

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::interval("a", 0.0, 1.0, "m"),
            Param::levels("c", vec![Value::Int(0), Value::Int(1), Value::Int(2)]),
            Param::interval("b", 0.0, 1.0, "m"),
        ])
        .unwrap()
    }

    /// The falsifiers' test function: a small failure disc around (0.83, 0.21) for level 2.
    fn robustness(p: &Point) -> f64 {
        let d = ((p.continuous[0] - 0.83).powi(2) + (p.continuous[1] - 0.21).powi(2)).sqrt();
        d - 0.03 + if p.discrete[0] == 2 { 0.0 } else { 0.5 }
    }

    #[test]
    fn finds_a_small_failure_region_deterministically_inside_the_bounds() {
        for acquisition in [
            Acquisition::ExpectedImprovement { xi: 0.01 },
            Acquisition::LowerConfidenceBound { beta: 2.0 },
        ] {
            let tuning = BoTuning {
                acquisition,
                ..BoTuning::default()
            };
            let run = || {
                let mut g = BayesOpt::with_tuning(&space(), 3, tuning.clone()).unwrap();
                drive(&mut g, 120, robustness)
            };
            let a = run();
            assert_eq!(a, run(), "{acquisition:?} is not deterministic");
            assert!(a
                .iter()
                .flat_map(|p| &p.continuous)
                .all(|x| (0.0..1.0).contains(x)));
            let first = a.iter().position(|p| robustness(p) <= 0.0);
            eprintln!("{acquisition:?}: first failure at {first:?}");
            // Uniform sampling needs about 3,400 points on average (0.09 % of the square,
            // a third of the levels).
            assert!(first.is_some(), "{acquisition:?} found no failure in 120");
        }
    }

    #[test]
    fn errors_and_infinities_do_not_break_the_process() {
        let mut g = BayesOpt::new(&space(), 1).unwrap();
        let pts = drive(&mut g, 40, |p| {
            if p.continuous[0] > 0.8 {
                f64::NAN
            } else if p.continuous[1] > 0.9 {
                f64::INFINITY
            } else {
                robustness(p)
            }
        });
        assert_eq!(pts.len(), 40);
        let discrete = ParamSpace::new(vec![Param::levels("c", vec![Value::Int(0)])]).unwrap();
        assert!(BayesOpt::new(&discrete, 0).is_err());
    }

    #[test]
    fn ask_without_tell_runs_dry_after_the_initial_design() {
        let mut g = BayesOpt::new(&space(), 1).unwrap();
        let n0 = g.initial_points;
        assert_eq!(g.ask(1000).unwrap().len(), n0);
        assert!(g.ask(4).unwrap().is_empty());
    }

    /// Expected improvement's gradient against finite differences.
    #[test]
    fn the_acquisition_gradient_is_right() {
        let x = [0.1, 0.2, 0.5, 0.9, 0.7, 0.3, 0.4, 0.6];
        let y = [1.0, 0.3, -0.2, 0.8];
        let h = Hyper {
            log_length: vec![-1.0, -0.5],
            log_signal: 0.0,
            log_noise: -8.0,
        };
        let gp = Gp::fit(&x, 2, &y, &h).unwrap();
        for acquisition in [
            Acquisition::ExpectedImprovement { xi: 0.01 },
            Acquisition::LowerConfidenceBound { beta: 2.0 },
        ] {
            let at = [0.35, 0.55];
            let (_, g) = cost_of(&gp, &at, acquisition, -0.2, 0.4);
            for j in 0..2 {
                let mut a = at;
                let mut b = at;
                a[j] += 1e-6;
                b[j] -= 1e-6;
                let fd = (cost_of(&gp, &a, acquisition, -0.2, 0.4).0
                    - cost_of(&gp, &b, acquisition, -0.2, 0.4).0)
                    / 2e-6;
                assert!(
                    (g[j] - fd).abs() < 1e-5,
                    "{acquisition:?} {j}: {} vs {fd}",
                    g[j]
                );
            }
        }
    }
}
