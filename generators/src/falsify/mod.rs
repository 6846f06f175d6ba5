//! Adaptive falsification: searches that steer toward failures by minimising robustness.
//!
//! The cost of a test is the minimum robustness over the scenario's monitors (`<= 0`: the test
//! failed), as in S-TaLiRo and Breach (Fainekos and Pappas 2009). A [`Falsifier`] is a
//! [`Generator`] whose [`Generator::ask`] returns the points its searches want next and whose
//! [`Generator::tell`] hands the measured robustness back to them.
//!
//! - **Searches.** Nelder–Mead ([`Method::NelderMead`]), particle swarm
//!   ([`Method::ParticleSwarm`]) and simulated annealing ([`Method::Annealing`]) are argmin's
//!   solvers; the cross-entropy method ([`Method::CrossEntropy`]) is ours. Each search runs
//!   on its own thread behind a channel (`lane.rs` says why).
//! - **Parallel lanes.** [`Tuning::lanes`] searches run side by side and one batch holds one
//!   request of each (a point for Nelder–Mead and annealing, a whole swarm or population for
//!   the others). The batch does not depend on the number of worker threads, so results do
//!   not either.
//! - **Space-filling starts.** Every search starts from the next unused points of one
//!   scrambled Halton sequence over the continuous parameters (Owen 2017, seeded by the
//!   campaign seed): a point for Nelder–Mead and annealing, the whole initial swarm or first
//!   population for the others. So the first batch is as spread out as `halton-scrambled`'s
//!   first points, and restarts keep filling the space instead of landing where earlier
//!   searches have been (the global phase of Breach's falsification works alike).
//! - **Restarts.** When a search ends (converged, or at its iteration limit) its lane starts
//!   the next one. Each search's own random choices (annealing moves, swarm velocities,
//!   cross-entropy samples) come from ChaCha8 stream `k` of the campaign seed for search `k`.
//! - **Discrete parameters.** Searches run over the continuous coordinates only. The discrete
//!   ones are fixed per search, to the rows of a strength-2 covering array (IPOG) over them,
//!   taken in turn: search `k` uses row `k mod rows`. So every pair of discrete levels gets
//!   searched within the first `rows` searches.
//! - **Bounds.** Points are clamped into `[0, 1)` before they are simulated. Nelder–Mead may
//!   step outside; such a point costs its clamped point's robustness plus
//!   [`OUTSIDE_PENALTY`] per unit of L1 distance outside, so the simplex comes back.
//!
//! The budget is the campaign's: the generator never decides to stop, and the campaign asks
//! exactly as many points as it has simulations.

mod bayes;
mod cross_entropy;
pub mod gp;
mod lane;

use std::collections::VecDeque;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use bayes::{Acquisition, BayesOpt, BoTuning};
pub use cross_entropy::CrossEntropy;

use crate::{Generator, GeneratorError, Halton, ParamSpace, Point};

/// The search method of a [`Falsifier`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Nelder–Mead simplex search (Nelder and Mead 1965) with restarts from space-filling
    /// points: argmin's `NelderMead`.
    NelderMead,
    /// Particle swarm optimisation (Kennedy and Eberhart 1995): argmin's `ParticleSwarm`.
    ParticleSwarm,
    /// Simulated annealing (Kirkpatrick et al. 1983) with re-annealing: argmin's
    /// `SimulatedAnnealing`.
    Annealing,
    /// The cross-entropy method ([`CrossEntropy`]).
    CrossEntropy,
}

/// Settings of the searches. [`Tuning::default`] is what the strategies use.
#[derive(Debug, Clone, PartialEq)]
pub struct Tuning {
    /// Searches run side by side, `>= 1`. Default 4.
    pub lanes: usize,
    /// Nelder–Mead: edge of the initial simplex, in unit-cube coordinates. Default 0.15.
    pub simplex_edge: f64,
    /// Nelder–Mead: converged when the costs of the simplex have this standard deviation.
    /// Default 1e-3 (cost units: the monitors', metres for the shipped ones). Larger values
    /// restart searches just as they close in on a small failure region.
    pub nm_sd_tolerance: f64,
    /// Nelder–Mead: iterations before a restart. Default 30.
    pub nm_max_iters: u64,
    /// Particle swarm: particles per swarm. Default 8.
    pub swarm_size: usize,
    /// Particle swarm: iterations before a restart. Default 12.
    pub pso_max_iters: u64,
    /// Annealing: initial temperature, in cost units. Default 1.
    pub initial_temperature: f64,
    /// Annealing: largest step per coordinate at the initial temperature. Default 0.25.
    pub anneal_step: f64,
    /// Annealing: restart after this many iterations without a new best. Default 40.
    pub sa_stall_best: u64,
    /// Annealing: iterations before a restart. Default 150.
    pub sa_max_iters: u64,
    /// Cross-entropy: points per population. Default 12.
    pub ce_population: usize,
    /// Cross-entropy: elite points per population. Default 3.
    pub ce_elite: usize,
    /// Cross-entropy: populations before a restart. Default 12.
    pub ce_max_iters: u64,
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            lanes: 4,
            simplex_edge: 0.15,
            nm_sd_tolerance: 1e-3,
            nm_max_iters: 30,
            swarm_size: 8,
            pso_max_iters: 12,
            initial_temperature: 1.0,
            anneal_step: 0.25,
            sa_stall_best: 40,
            sa_max_iters: 150,
            ce_population: 12,
            ce_elite: 3,
            ce_max_iters: 12,
        }
    }
}

/// Cost given to a search for a point it asked for after the campaign ended.
pub(crate) const ABANDONED_COST: f64 = 1e12;
/// Added to the cost per unit of L1 distance a solver's point lies outside `[0, 1]^d`.
pub const OUTSIDE_PENALTY: f64 = 1e3;
/// Costs are clamped into `±COST_LIMIT`; NaN (a test that errored) becomes `+COST_LIMIT`.
pub const COST_LIMIT: f64 = 1e9;
/// The largest `f64` below 1: points are clamped into `[0, ONE_BELOW]`.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// One running search.
struct Lane {
    requests: Receiver<Vec<Vec<f64>>>,
    answers: Sender<Vec<f64>>,
    thread: Option<JoinHandle<()>>,
    /// The discrete levels of this search's points.
    row: Vec<u32>,
    /// The request being served: its solver points and the costs told so far.
    open: Option<(Vec<Vec<f64>>, Vec<f64>)>,
}

/// A point handed out and not yet told: which lane wants it, and its solver coordinates.
struct Pending {
    lane: usize,
    solver_x: Vec<f64>,
    point: Point,
}

/// An adaptive test generator: [`Tuning::lanes`] searches of one [`Method`] over the
/// continuous parameters, the discrete ones fixed per search by a covering array (see the
/// module docs).
pub struct Falsifier {
    method: Method,
    tuning: Tuning,
    seed: u64,
    d: usize,
    rows: Vec<Vec<u32>>,
    lanes: Vec<Lane>,
    searches_started: u64,
    /// The start points of the searches, consumed in order.
    starts: Halton,
    /// Points requested by the lanes and not yet asked for.
    queue: VecDeque<Pending>,
    /// Points asked for and not yet told, in the order they were handed out.
    handed: VecDeque<Pending>,
}

impl Falsifier {
    /// A falsifier of `method` over `space`, seeded with `seed`, with [`Tuning::default`].
    ///
    /// # Errors
    /// [`GeneratorError::Covering`] when the space has no continuous parameter (there is
    /// nothing to search: use a covering array) or its discrete array cannot be built.
    pub fn new(space: &ParamSpace, method: Method, seed: u64) -> Result<Self, GeneratorError> {
        Self::with_tuning(space, method, seed, Tuning::default())
    }

    /// As [`Falsifier::new`], with explicit settings.
    ///
    /// # Errors
    /// As [`Falsifier::new`].
    pub fn with_tuning(
        space: &ParamSpace,
        method: Method,
        seed: u64,
        tuning: Tuning,
    ) -> Result<Self, GeneratorError> {
        let d = space.continuous_dims();
        if d == 0 {
            return Err(GeneratorError::Covering(
                "adaptive falsification searches continuous parameters (VarInterval), and this \
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
        let mut f = Falsifier {
            method,
            tuning: Tuning {
                lanes: tuning.lanes.max(1),
                ..tuning
            },
            seed,
            d,
            rows,
            lanes: Vec::new(),
            searches_started: 0,
            starts: Halton::scrambled(&ParamSpace::unit_cube(d), seed),
            queue: VecDeque::new(),
            handed: VecDeque::new(),
        };
        f.lanes = (0..f.tuning.lanes).map(|_| f.start_search()).collect();
        Ok(f)
    }

    /// The discrete rows the searches take in turn (level indices, one row per search).
    pub fn discrete_rows(&self) -> &[Vec<u32>] {
        &self.rows
    }

    /// Searches started so far, restarts included.
    pub fn searches_started(&self) -> u64 {
        self.searches_started
    }

    fn start_search(&mut self) -> Lane {
        let k = self.searches_started;
        self.searches_started += 1;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(k);
        let starts_needed = match self.method {
            Method::NelderMead | Method::Annealing => 1,
            Method::ParticleSwarm => self.tuning.swarm_size,
            Method::CrossEntropy => self.tuning.ce_population,
        };
        let starts: Vec<Vec<f64>> = self
            .starts
            .ask(starts_needed)
            .unwrap_or_default()
            .into_iter()
            .map(|p| p.continuous)
            .collect();
        let (req_tx, req_rx) = channel();
        let (ans_tx, ans_rx) = channel();
        let bridge = lane::Bridge {
            requests: req_tx,
            answers: ans_rx,
            rng: std::cell::RefCell::new(rng),
            anneal_step: self.tuning.anneal_step,
            initial_temperature: self.tuning.initial_temperature,
        };
        let (method, tuning, d) = (self.method, self.tuning.clone(), self.d);
        let thread = std::thread::Builder::new()
            .name(format!("paracosm-search-{k}"))
            .spawn(move || lane::search(method, &tuning, d, starts, bridge))
            .ok();
        Lane {
            requests: req_rx,
            answers: ans_tx,
            thread,
            row: self.rows[(k % self.rows.len() as u64) as usize].clone(),
            open: None,
        }
    }

    /// Takes the next request of every lane that has none open, restarting ended searches.
    fn collect_requests(&mut self) {
        for i in 0..self.lanes.len() {
            if self.lanes[i].open.is_some() {
                continue;
            }
            // A search that ends before asking anything is replaced; give up on the lane
            // after a few in a row rather than spin.
            for _ in 0..4 {
                match self.lanes[i].requests.recv() {
                    Ok(xs) if !xs.is_empty() => {
                        let row = self.lanes[i].row.clone();
                        for x in &xs {
                            self.queue.push_back(Pending {
                                lane: i,
                                solver_x: x.clone(),
                                point: Point {
                                    discrete: row.clone(),
                                    continuous: x.iter().map(|v| v.clamp(0.0, ONE_BELOW)).collect(),
                                },
                            });
                        }
                        self.lanes[i].open = Some((xs, Vec::new()));
                        break;
                    }
                    _ => {
                        let fresh = self.start_search();
                        let old = std::mem::replace(&mut self.lanes[i], fresh);
                        old.finish();
                    }
                }
            }
        }
    }
}

impl Lane {
    fn finish(mut self) {
        drop(self.answers);
        drop(self.requests);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Falsifier {
    fn drop(&mut self) {
        for lane in self.lanes.drain(..) {
            lane.finish();
        }
    }
}

/// The cost a search sees for a point at solver coordinates `x` whose clamped point had
/// robustness `robustness`.
fn cost(robustness: f64, x: &[f64]) -> f64 {
    let r = if robustness.is_nan() {
        COST_LIMIT
    } else {
        robustness.clamp(-COST_LIMIT, COST_LIMIT)
    };
    let outside: f64 = x.iter().map(|&v| (-v).max(0.0) + (v - 1.0).max(0.0)).sum();
    r + OUTSIDE_PENALTY * outside
}

impl Generator for Falsifier {
    fn name(&self) -> &'static str {
        match self.method {
            Method::NelderMead => "falsify-nm",
            Method::ParticleSwarm => "falsify-pso",
            Method::Annealing => "falsify-sa",
            Method::CrossEntropy => "falsify-ce",
        }
    }

    /// Up to `n` points the searches want evaluated. Fewer (possibly none) when every search
    /// waits for the robustness of points already handed out: tell those first.
    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        if self.queue.is_empty() {
            self.collect_requests();
        }
        let take = n.min(self.queue.len());
        let batch: Vec<Pending> = self.queue.drain(..take).collect();
        let points = batch.iter().map(|p| p.point.clone()).collect();
        self.handed.extend(batch);
        Ok(points)
    }

    /// Robustness of points handed out by [`Generator::ask`], in the order they were handed
    /// out (a prefix of them is fine). Points that do not match are ignored.
    fn tell(&mut self, evaluated: &[(Point, f64)]) {
        for (point, robustness) in evaluated {
            let Some(front) = self.handed.front() else {
                return;
            };
            if &front.point != point {
                continue;
            }
            let p = self.handed.pop_front().expect("front exists");
            let lane = &mut self.lanes[p.lane];
            let Some((xs, costs)) = lane.open.as_mut() else {
                continue;
            };
            costs.push(cost(*robustness, &p.solver_x));
            if costs.len() == xs.len() {
                let (_, costs) = lane.open.take().expect("open request");
                // A search that has ended no longer listens; its lane restarts on next ask.
                let _ = lane.answers.send(costs);
            }
        }
    }

    /// One request per lane: [`Tuning::lanes`] points for Nelder–Mead and annealing, times
    /// the swarm or population size for the others.
    fn batch(&self) -> Option<usize> {
        let per_lane = match self.method {
            Method::NelderMead | Method::Annealing => 1,
            Method::ParticleSwarm => self.tuning.swarm_size,
            Method::CrossEntropy => self.tuning.ce_population,
        };
        Some(self.tuning.lanes * per_lane)
    }
}

/// `x` reflected at the faces of `[0, 1]` (a move past a face comes back by its excess).
pub(super) fn reflect(x: f64) -> f64 {
    let m = x.rem_euclid(2.0);
    if m > 1.0 {
        2.0 - m
    } else {
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_keeps_points_in_the_cube() {
        assert_eq!(reflect(0.25), 0.25);
        assert!((reflect(1.25) - 0.75).abs() < 1e-12);
        assert!((reflect(-0.25) - 0.25).abs() < 1e-12);
        assert!((reflect(2.5) - 0.5).abs() < 1e-12);
    }
    use crate::{Param, Value};

    const ALL: [Method; 4] = [
        Method::NelderMead,
        Method::ParticleSwarm,
        Method::Annealing,
        Method::CrossEntropy,
    ];

    /// Runs `budget` evaluations of `f` (robustness) the way a campaign does: batches of
    /// `batch()`, told in order. Returns every point.
    fn drive(g: &mut Falsifier, budget: usize, f: impl Fn(&Point) -> f64) -> Vec<Point> {
        let mut all = Vec::new();
        while all.len() < budget {
            let n = g.batch().unwrap().min(budget - all.len());
            let pts = g.ask(n).unwrap();
            assert!(
                !pts.is_empty(),
                "a falsifier always has points after a tell"
            );
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

    /// Robustness: distance to a small failure disc around (0.83, 0.21), only for level 2.
    fn robustness(p: &Point) -> f64 {
        let d = ((p.continuous[0] - 0.83).powi(2) + (p.continuous[1] - 0.21).powi(2)).sqrt();
        d - 0.03 + if p.discrete[0] == 2 { 0.0 } else { 0.5 }
    }

    #[test]
    fn every_method_stays_in_bounds_is_deterministic_and_finds_a_small_failure_region() {
        for m in ALL {
            let run = || {
                let mut g = Falsifier::new(&space(), m, 11).unwrap();
                drive(&mut g, 600, robustness)
            };
            let a = run();
            assert_eq!(a.len(), 600);
            assert_eq!(a, run(), "{m:?} is not deterministic");
            assert!(a
                .iter()
                .flat_map(|p| &p.continuous)
                .all(|x| (0.0..1.0).contains(x)));
            let first = a.iter().position(|p| robustness(p) <= 0.0);
            eprintln!("{m:?}: first failure at {first:?}");
            // The disc covers 0.09 % of the square times a third of the levels: uniform
            // sampling needs about 3,400 points on average.
            assert!(first.is_some(), "{m:?} found no failure in 600");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        #[test]
        fn any_tuning_spends_the_budget_exactly_inside_the_bounds(
            seed in 0u64..1000,
            budget in 1usize..150,
            method in 0usize..4,
            lanes in 1usize..6,
            w in proptest::collection::vec(-3.0f64..3.0, 2),
            errors in proptest::bool::ANY,
        ) {
            let tuning = Tuning { lanes, ..Tuning::default() };
            let mut g = Falsifier::with_tuning(&space(), ALL[method], seed, tuning).unwrap();
            // A slope the searches chase out of the cube, and tests that error (NaN).
            let pts = drive(&mut g, budget, |p| {
                let r = w[0] * p.continuous[0] + w[1] * p.continuous[1];
                if errors && p.continuous[0] > 0.7 { f64::NAN } else { r }
            });
            proptest::prop_assert_eq!(pts.len(), budget);
            for p in &pts {
                proptest::prop_assert!(p.continuous.iter().all(|x| (0.0..1.0).contains(x)));
                proptest::prop_assert!(p.discrete[0] < 3);
            }
        }
    }

    #[test]
    fn searches_take_the_covering_rows_in_turn() {
        let mut g = Falsifier::new(&space(), Method::NelderMead, 1).unwrap();
        assert_eq!(g.discrete_rows().len(), 3);
        let pts = g.ask(4).unwrap();
        let levels: Vec<u32> = pts.iter().map(|p| p.discrete[0]).collect();
        assert_eq!(levels, vec![0, 1, 2, 0]);
    }

    #[test]
    fn ask_without_tell_runs_dry_and_a_space_without_intervals_is_refused() {
        let mut g = Falsifier::new(&space(), Method::Annealing, 1).unwrap();
        assert_eq!(g.ask(10).unwrap().len(), 4);
        assert!(g.ask(10).unwrap().is_empty());
        let discrete = ParamSpace::new(vec![Param::levels("c", vec![Value::Int(0)])]).unwrap();
        assert!(Falsifier::new(&discrete, Method::CrossEntropy, 0).is_err());
    }

    #[test]
    fn costs_are_penalised_outside_and_errors_are_worst() {
        assert_eq!(cost(1.5, &[0.5, 0.5]), 1.5);
        assert!((cost(1.0, &[-0.1, 1.2]) - (1.0 + OUTSIDE_PENALTY * 0.3)).abs() < 1e-9);
        assert_eq!(cost(f64::NAN, &[0.5]), COST_LIMIT);
        assert_eq!(cost(f64::NEG_INFINITY, &[0.5]), -COST_LIMIT);
    }
}
