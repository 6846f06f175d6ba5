//! One search of a [`super::Falsifier`], run on its own thread behind a pair of channels.
//!
//! argmin's solvers are pull-style: inside `Solver::next_iter` they call the cost function and
//! expect its value back at once. A campaign is push-style: it simulates a whole batch in
//! parallel, then reports. Driving `next_iter` ourselves would not help, since the cost is still
//! asked for from inside it, so each search runs argmin's `Executor` on a thread of its own
//! whose cost function sends the points it wants to the generator and blocks until the
//! campaign has simulated them ([`Bridge`]). The thread does no numerical work worth a core:
//! it waits.

use std::cell::RefCell;
use std::sync::mpsc::{Receiver, Sender};

use argmin::core::{CostFunction, Error, Executor};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::{Particle, ParticleSwarm};
use argmin::solver::simulatedannealing::{Anneal, SimulatedAnnealing};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::cross_entropy::CrossEntropy;
use super::{reflect, Method, Tuning, ABANDONED_COST};

/// The cost function a search thread sees: every evaluation is a round trip to the generator.
pub(super) struct Bridge {
    /// Points the search wants evaluated (solver coordinates, possibly outside `[0, 1)`).
    pub(super) requests: Sender<Vec<Vec<f64>>>,
    /// Their costs, in the same order.
    pub(super) answers: Receiver<Vec<f64>>,
    /// Proposals of simulated annealing.
    pub(super) rng: RefCell<ChaCha8Rng>,
    /// Largest step of an annealing move, per coordinate, at the initial temperature.
    pub(super) anneal_step: f64,
    /// The initial temperature, to scale the annealing steps.
    pub(super) initial_temperature: f64,
}

impl Bridge {
    /// Costs of `points`, asked of the generator. When the generator is gone (the campaign
    /// ended), every point costs [`ABANDONED_COST`], which makes every solver stall and stop
    /// quickly instead of failing: argmin's Nelder–Mead unwraps its first costs.
    fn evaluate(&self, points: Vec<Vec<f64>>) -> Vec<f64> {
        let n = points.len();
        if self.requests.send(points).is_err() {
            return vec![ABANDONED_COST; n];
        }
        match self.answers.recv() {
            Ok(costs) if costs.len() == n => costs,
            _ => vec![ABANDONED_COST; n],
        }
    }
}

impl CostFunction for Bridge {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, param: &Vec<f64>) -> Result<f64, Error> {
        Ok(self.evaluate(vec![param.clone()])[0])
    }

    /// One request for the whole swarm, so that its particles run in parallel.
    fn bulk_cost<P>(&self, params: &[P]) -> Result<Vec<f64>, Error>
    where
        P: std::borrow::Borrow<Vec<f64>>,
    {
        Ok(self.evaluate(params.iter().map(|p| p.borrow().clone()).collect()))
    }
}

impl Anneal for Bridge {
    type Param = Vec<f64>;
    type Output = Vec<f64>;
    type Float = f64;

    /// Moves every coordinate by a uniform step in `±anneal_step · sqrt(T / T0)` (at least 2 %
    /// of the range), reflected into `[0, 1]`: the neighbourhood shrinks as the search cools.
    fn anneal(&self, param: &Vec<f64>, temperature: f64) -> Result<Vec<f64>, Error> {
        let scale = (self.anneal_step * (temperature / self.initial_temperature).sqrt()).max(0.02);
        let mut rng = self.rng.borrow_mut();
        Ok(param
            .iter()
            .map(|&x| reflect(x + rng.random_range(-scale..=scale)))
            .collect())
    }
}

/// Runs one search of `method` in `d` dimensions to its end (convergence, its iteration
/// limit, or the generator going away). `starts` holds its start point (Nelder–Mead,
/// annealing) or its initial swarm or population (at least one point). Errors of argmin end
/// the search early; the generator then starts the next one, so they are not reported.
pub(super) fn search(
    method: Method,
    tuning: &Tuning,
    d: usize,
    mut starts: Vec<Vec<f64>>,
    bridge: Bridge,
) {
    if starts.is_empty() {
        starts.push(vec![0.5; d]);
    }
    let start = starts[0].clone();
    match method {
        Method::NelderMead => {
            // A right-angled initial simplex of edge `simplex_edge`, pointing into the cube.
            let mut simplex = vec![start.clone()];
            for i in 0..d {
                let mut v = start.clone();
                v[i] += if start[i] < 0.5 {
                    tuning.simplex_edge
                } else {
                    -tuning.simplex_edge
                };
                simplex.push(v);
            }
            let solver = NelderMead::new(simplex).with_sd_tolerance(tuning.nm_sd_tolerance);
            if let Ok(solver) = solver {
                let _ = Executor::new(bridge, solver)
                    .configure(|s| s.max_iters(tuning.nm_max_iters))
                    .timer(false)
                    .run();
            }
        }
        Method::ParticleSwarm => {
            // The initial swarm at the given points, with random velocities in ±range as
            // argmin would draw them.
            let costs = bridge.evaluate(starts.clone());
            let particles: Vec<Particle<Vec<f64>, f64>> = {
                let mut rng = bridge.rng.borrow_mut();
                starts
                    .iter()
                    .zip(costs)
                    .map(|(p, c)| {
                        let v = (0..d).map(|_| rng.random_range(-1.0..1.0)).collect();
                        Particle::new(p.clone(), c, v)
                    })
                    .collect()
            };
            let seed = bridge.rng.borrow_mut().random::<u64>();
            let solver = ParticleSwarm::new((vec![0.0; d], vec![1.0; d]), particles.len())
                .with_rng_generator(ChaCha8Rng::seed_from_u64(seed));
            let _ = Executor::new(bridge, solver)
                .configure(|s| s.population(particles).max_iters(tuning.pso_max_iters))
                .timer(false)
                .run();
        }
        Method::Annealing => {
            let seed = bridge.rng.borrow_mut().random::<u64>();
            let solver = SimulatedAnnealing::new_with_rng(
                tuning.initial_temperature,
                ChaCha8Rng::seed_from_u64(seed),
            );
            if let Ok(solver) = solver {
                let solver = solver
                    .with_stall_best(tuning.sa_stall_best)
                    .with_reannealing_best(tuning.sa_stall_best / 2);
                let _ = Executor::new(bridge, solver)
                    .configure(|s| s.param(start).max_iters(tuning.sa_max_iters))
                    .timer(false)
                    .run();
            }
        }
        Method::CrossEntropy => {
            let seed = bridge.rng.borrow_mut().random::<u64>();
            let mut ce = CrossEntropy::new(
                d,
                tuning.ce_population,
                tuning.ce_elite,
                ChaCha8Rng::seed_from_u64(seed),
            )
            .with_first_population(starts);
            for _ in 0..tuning.ce_max_iters {
                let population = ce.ask();
                let costs = bridge.evaluate(population);
                if costs.iter().all(|&c| c == ABANDONED_COST) || ce.tell(&costs) {
                    break;
                }
            }
        }
    }
}
