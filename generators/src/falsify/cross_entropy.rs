//! The cross-entropy method for minimisation (Rubinstein 1999; de Boer, Kroese, Mannor and
//! Rubinstein 2005, "A Tutorial on the Cross-Entropy Method", Algorithm 2.1 with smoothing),
//! in ask/tell form. argmin has no cross-entropy solver.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::reflect;

/// Cross-entropy search over `[0, 1]^d` with an axis-aligned Gaussian sampling density.
///
/// The first population is uniform over the cube (or given). After each, the `elite` lowest-cost points
/// give the new mean and standard deviation per coordinate, smoothed as
/// `θ ← α θ_elite + (1 − α) θ` with `α = 0.7` (de Boer et al. 2005, §3.1). Samples are
/// reflected into the cube.
pub struct CrossEntropy {
    d: usize,
    population: usize,
    elite: usize,
    /// Mean per coordinate, `None` before the first population has been told.
    mean: Option<Vec<f64>>,
    sigma: Vec<f64>,
    asked: Vec<Vec<f64>>,
    /// Points of the first population, when given ([`CrossEntropy::with_first_population`]).
    first: Option<Vec<Vec<f64>>>,
    rng: ChaCha8Rng,
}

/// Smoothing weight of the new elite statistics.
const ALPHA: f64 = 0.7;
/// The search has converged when every standard deviation is below this (1 % of the range).
const CONVERGED_SIGMA: f64 = 0.01;

impl CrossEntropy {
    /// A search in `d` dimensions drawing `population` points per iteration and refitting to
    /// the best `elite` of them (`1 <= elite <= population`; clamped into that range).
    pub fn new(d: usize, population: usize, elite: usize, rng: ChaCha8Rng) -> Self {
        let population = population.max(1);
        CrossEntropy {
            d,
            population,
            elite: elite.clamp(1, population),
            mean: None,
            sigma: vec![0.5; d],
            asked: Vec::new(),
            first: None,
            rng,
        }
    }

    /// Uses `points` (each of length `d`, in `[0, 1]`) as the first population instead of
    /// uniform random points, e.g. a space-filling design. Ignored when empty.
    pub fn with_first_population(mut self, points: Vec<Vec<f64>>) -> Self {
        if !points.is_empty() {
            self.population = points.len();
            self.elite = self.elite.min(self.population);
            self.first = Some(points);
        }
        self
    }

    /// The next population: `population` points of `[0, 1]^d`.
    pub fn ask(&mut self) -> Vec<Vec<f64>> {
        let pts: Vec<Vec<f64>> = match &self.mean {
            None if self.first.is_some() => self.first.take().expect("checked"),
            None => (0..self.population)
                .map(|_| (0..self.d).map(|_| self.rng.random::<f64>()).collect())
                .collect(),
            Some(mean) => (0..self.population)
                .map(|_| {
                    mean.iter()
                        .zip(&self.sigma)
                        .map(|(&m, &s)| {
                            let n = Normal::new(m, s.max(1e-12)).expect("finite mean and sd");
                            reflect(n.sample(&mut self.rng))
                        })
                        .collect()
                })
                .collect(),
        };
        self.asked = pts.clone();
        pts
    }

    /// Reports the costs of the last population, in its order. Returns whether the search
    /// has converged (every standard deviation below 0.01).
    pub fn tell(&mut self, costs: &[f64]) -> bool {
        let mut order: Vec<usize> = (0..self.asked.len().min(costs.len())).collect();
        order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
        let elite: Vec<&Vec<f64>> = order
            .iter()
            .take(self.elite)
            .map(|&i| &self.asked[i])
            .collect();
        if elite.is_empty() {
            return true;
        }
        let k = elite.len() as f64;
        let old_mean = self.mean.clone().unwrap_or_else(|| vec![0.5; self.d]);
        let mut mean = vec![0.0; self.d];
        for j in 0..self.d {
            let m = elite.iter().map(|p| p[j]).sum::<f64>() / k;
            let var = elite.iter().map(|p| (p[j] - m).powi(2)).sum::<f64>() / k;
            mean[j] = ALPHA * m + (1.0 - ALPHA) * old_mean[j];
            self.sigma[j] = ALPHA * var.sqrt() + (1.0 - ALPHA) * self.sigma[j];
        }
        self.mean = Some(mean);
        self.sigma.iter().all(|&s| s < CONVERGED_SIGMA)
    }

    /// The current mean of the sampling density, `None` before the first [`CrossEntropy::tell`].
    pub fn mean(&self) -> Option<&[f64]> {
        self.mean.as_deref()
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn finds_the_minimum_of_a_shifted_quadratic() {
        let mut ce = CrossEntropy::new(2, 40, 8, ChaCha8Rng::seed_from_u64(3));
        let f = |p: &[f64]| (p[0] - 0.8).powi(2) + (p[1] - 0.3).powi(2);
        let mut converged = false;
        for _ in 0..60 {
            let pop = ce.ask();
            assert!(pop.iter().flatten().all(|x| (0.0..=1.0).contains(x)));
            let costs: Vec<f64> = pop.iter().map(|p| f(p)).collect();
            if ce.tell(&costs) {
                converged = true;
                break;
            }
        }
        assert!(converged);
        let m = ce.mean().unwrap();
        assert!(
            (m[0] - 0.8).abs() < 0.02 && (m[1] - 0.3).abs() < 0.02,
            "{m:?}"
        );
    }
}
