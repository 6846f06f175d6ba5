//! Post-optimisation of a covering array: fewer rows by simulated annealing.
//!
//! The pass removes the row that covers the fewest tuples alone, then repairs the array by
//! simulated annealing until every coverable t-tuple is covered again, and repeats, keeping
//! the last complete array. A move takes an uncovered tuple and writes it into one of a few
//! rows drawn at random, the one whose change uncovers the fewest other tuples, accepted when
//! it does not add uncovered tuples or with probability `exp(-Δ / T)` (Metropolis); the
//! temperature falls geometrically and rises again when the repair stalls. This is the
//! row-removal-and-repair scheme of the annealing constructions of covering arrays (Cohen,
//! Colbourn and Ling, "Constructing strength three covering arrays with augmented annealing",
//! Discrete Mathematics 308, 2008; Torres-Jimenez and Rodriguez-Tello, "New bounds for binary
//! covering arrays using simulated annealing", Information Sciences 185, 2012), with the
//! uncovered-tuple moves of Nurmela's tabu search ("Upper bounds for covering arrays by tabu
//! search", Discrete Applied Mathematics 138, 2004).
//!
//! The work is counted in moves, not seconds, so the same array, budget and seed give the
//! same result on any machine and for any thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::{Constraints, CoveringArray};

/// A count that marks a tuple the constraints forbid: it is never uncovered.
const FORBIDDEN: u32 = 1 << 30;

/// Seconds one move of the annealing takes on one core of the 2-core reference machine, at
/// most: [`MOVE_BASE_S`] plus [`MOVE_UNIT_S`] per tuple index it computes (the slowest moves
/// measured on 5^10 at t = 2, 3 and 4 with `examples/covering_frontier.rs` and
/// `paracosm-cover generate --model`, so that a budget of `s` seconds runs at most about `s`). The budget is counted in moves, from
/// this model of their cost, so that the result does not depend on the machine or its load.
pub const MOVE_BASE_S: f64 = 12.0e-6;

/// See [`MOVE_BASE_S`].
pub const MOVE_UNIT_S: f64 = 2.0e-8;

/// Rows a move weighs for strengths below 4 (3 from strength 4 on).
const SAMPLE: usize = 6;

/// How a covering array is post-optimised ([`optimise`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optimise {
    /// Moves per chain: [`MOVES_PER_SECOND`] per second asked for.
    pub moves: u64,
    /// Independent chains, each with its own seed (run in parallel with rayon); the smallest
    /// array wins, the first chain on a tie.
    pub chains: usize,
    /// The seed of the first chain; chain `i` uses `seed + i`.
    pub seed: u64,
}

impl Optimise {
    /// About `seconds` of work per chain on the reference machine for an array of strength
    /// `t` over `levels`, two chains (its two cores): the moves [`MOVE_BASE_S`]'s cost model
    /// fits in that time.
    pub fn seconds(seconds: f64, levels: &[u32], t: usize, seed: u64) -> Self {
        let k = levels.len();
        // C(k - 1, t - 1): the subsets holding one column.
        let (n, r) = (k.saturating_sub(1) as f64, t.saturating_sub(1));
        let per_column = (0..r).fold(1.0, |a, i| a * (n - i as f64) / (i as f64 + 1.0));
        let sample = if t >= 4 { 3 } else { SAMPLE };
        let per_move = MOVE_BASE_S + MOVE_UNIT_S * (sample * t) as f64 * per_column.max(1.0);
        Optimise {
            moves: (seconds.max(0.0) / per_move) as u64,
            chains: 2,
            seed,
        }
    }
}

/// `array` with fewer rows where the annealing finds them, every t-tuple `cons` allows still
/// covered and no row breaking `cons`; its first `frozen` rows (seed rows) are kept as they
/// are. Returns `array` itself when no smaller array is found within the budget.
pub fn optimise(
    array: &CoveringArray,
    cons: &Constraints,
    frozen: usize,
    how: Optimise,
) -> CoveringArray {
    let k = array.levels.len();
    if k == 0 || array.len() <= frozen + 1 || how.moves == 0 {
        return array.clone();
    }
    let rows: Vec<Vec<u32>> = (0..array.len()).map(|r| array.row(r).to_vec()).collect();
    let best = (0..how.chains.max(1))
        .into_par_iter()
        .map(|i| {
            let mut chain = Chain::new(&array.levels, array.strength, cons, rows.clone());
            chain.run(frozen, how.moves, how.seed.wrapping_add(i as u64))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .reduce(|a, b| if b.len() < a.len() { b } else { a })
        .unwrap_or(rows);
    CoveringArray {
        levels: array.levels.clone(),
        strength: array.strength,
        rows: best.concat(),
    }
}

/// One annealing chain: the array, the count of rows covering each t-tuple, and the list of
/// uncovered tuples.
struct Chain<'a> {
    cons: &'a Constraints,
    rows: Vec<Vec<u32>>,
    /// Columns of each t-subset, flat (`t` per subset).
    cols: Vec<usize>,
    /// Radix weight of each column of each subset, flat: a tuple's index in its subset.
    weights: Vec<usize>,
    /// Start of each subset's tuples in `counts`.
    base: Vec<usize>,
    /// The subsets holding each column.
    by_column: Vec<Vec<u32>>,
    counts: Vec<u32>,
    uncovered: Vec<u32>,
    /// Place of each tuple in `uncovered`, `u32::MAX` when covered.
    pos: Vec<u32>,
    t: usize,
    /// Subsets touched by the move being weighed (stamps, to visit each once).
    stamp: Vec<u32>,
    now: u32,
}

impl<'a> Chain<'a> {
    fn new(levels: &'a [u32], t: usize, cons: &'a Constraints, rows: Vec<Vec<u32>>) -> Self {
        let k = levels.len();
        let subsets = crate::coverage::subsets(k, t);
        let mut cols = Vec::with_capacity(subsets.len() * t);
        let mut weights = Vec::with_capacity(subsets.len() * t);
        let mut base = Vec::with_capacity(subsets.len() + 1);
        let mut by_column = vec![Vec::new(); k];
        let mut total = 0usize;
        for (s, sub) in subsets.iter().enumerate() {
            base.push(total);
            let mut w = 1usize;
            let mut ws = vec![0; t];
            for (j, &c) in sub.iter().enumerate().rev() {
                ws[j] = w;
                w *= levels[c] as usize;
            }
            cols.extend_from_slice(sub);
            weights.extend(ws);
            for &c in sub {
                by_column[c].push(s as u32);
            }
            total += w;
        }
        base.push(total);
        let mut chain = Chain {
            cons,
            rows,
            cols,
            weights,
            base,
            by_column,
            counts: vec![0; total],
            uncovered: Vec::new(),
            pos: vec![u32::MAX; total],
            t,
            stamp: vec![0; subsets.len()],
            now: 0,
        };
        if !cons.is_empty() {
            for id in 0..total {
                if !cons.completable(levels, &chain.cells(id)) {
                    chain.counts[id] = FORBIDDEN;
                }
            }
        }
        for r in 0..chain.rows.len() {
            for s in 0..chain.stamp.len() {
                let id = chain.id(s, &chain.rows[r]);
                chain.counts[id] += 1;
            }
        }
        chain
    }

    /// The index of row `row`'s tuple in subset `s`.
    fn id(&self, s: usize, row: &[u32]) -> usize {
        let at = s * self.t;
        let mut i = self.base[s];
        for j in at..at + self.t {
            i += self.weights[j] * row[self.cols[j]] as usize;
        }
        i
    }

    /// The `(column, level)` cells of tuple `id`.
    fn cells(&self, id: usize) -> Vec<(usize, u32)> {
        let s = self.base.partition_point(|&b| b <= id) - 1;
        let mut rest = id - self.base[s];
        let at = s * self.t;
        (at..at + self.t)
            .map(|j| {
                let w = self.weights[j];
                let level = rest / w;
                rest %= w;
                (self.cols[j], level as u32)
            })
            .collect()
    }

    fn uncover(&mut self, id: usize) {
        self.pos[id] = self.uncovered.len() as u32;
        self.uncovered.push(id as u32);
    }

    fn cover(&mut self, id: usize) {
        let p = self.pos[id] as usize;
        let last = *self.uncovered.last().expect("an uncovered tuple");
        self.uncovered[p] = last;
        self.pos[last as usize] = p as u32;
        self.uncovered.pop();
        self.pos[id] = u32::MAX;
    }

    /// Removes row `r` from the counts and the array.
    fn remove(&mut self, r: usize) {
        let row = self.rows.swap_remove(r);
        for s in 0..self.stamp.len() {
            let id = self.id(s, &row);
            self.counts[id] -= 1;
            if self.counts[id] == 0 {
                self.uncover(id);
            }
        }
    }

    /// The subsets holding any of `changed`, each once.
    fn touched(&mut self, changed: &[usize]) -> Vec<u32> {
        self.now = self.now.wrapping_add(1);
        if self.now == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.now = 1;
        }
        let mut out = Vec::new();
        for &c in changed {
            for &s in &self.by_column[c] {
                if self.stamp[s as usize] != self.now {
                    self.stamp[s as usize] = self.now;
                    out.push(s);
                }
            }
        }
        out
    }

    /// The change in uncovered tuples if row `r` became `new` (differing in `changed`).
    fn delta(&mut self, r: usize, new: &[u32], changed: &[usize]) -> i64 {
        let touched = self.touched(changed);
        let mut d = 0i64;
        for s in touched {
            let (old_id, new_id) = (self.id(s as usize, &self.rows[r]), self.id(s as usize, new));
            if old_id != new_id {
                d += i64::from(self.counts[old_id] == 1) - i64::from(self.counts[new_id] == 0);
            }
        }
        d
    }

    /// Makes row `r` the row `new` (differing in `changed`).
    fn apply(&mut self, r: usize, new: Vec<u32>, changed: &[usize]) {
        for s in self.touched(changed) {
            let old_id = self.id(s as usize, &self.rows[r]);
            let new_id = self.id(s as usize, &new);
            if old_id == new_id {
                continue;
            }
            self.counts[old_id] -= 1;
            if self.counts[old_id] == 0 {
                self.uncover(old_id);
            }
            if self.counts[new_id] == 0 {
                self.cover(new_id);
            }
            self.counts[new_id] += 1;
        }
        self.rows[r] = new;
    }

    /// The row, not frozen, whose tuples the fewest other rows also cover.
    fn least_needed(&self, frozen: usize) -> usize {
        (frozen..self.rows.len())
            .map(|r| {
                let alone = (0..self.stamp.len())
                    .filter(|&s| self.counts[self.id(s, &self.rows[r])] == 1)
                    .count();
                (alone, r)
            })
            .min()
            .map_or(frozen, |(_, r)| r)
    }

    /// Shrinks the array within `moves`; returns the smallest complete array found.
    fn run(&mut self, frozen: usize, moves: u64, seed: u64) -> Vec<Vec<u32>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut best = self.rows.clone();
        let mut left = moves;
        let sample = if self.t >= 4 { 3 } else { SAMPLE };
        while left > 0 && self.rows.len() > frozen + 1 {
            let r = self.least_needed(frozen);
            self.remove(r);
            let mut temperature = 0.5f64;
            let mut stalled = 0u64;
            let mut fewest = self.uncovered.len();
            while !self.uncovered.is_empty() && left > 0 {
                left -= 1;
                let id = self.uncovered[rng.random_range(0..self.uncovered.len())] as usize;
                let cells = self.cells(id);
                let free = self.rows.len() - frozen;
                // The rows closest to the tuple (fewest cells to change), a few drawn among
                // them, and one row at random.
                let mismatch = |row: &[u32]| cells.iter().filter(|&&(c, l)| row[c] != l).count();
                let nearest = (frozen..self.rows.len())
                    .map(|r| mismatch(&self.rows[r]))
                    .min()
                    .unwrap_or(0);
                let near: Vec<usize> = (frozen..self.rows.len())
                    .filter(|&r| mismatch(&self.rows[r]) == nearest)
                    .collect();
                let mut candidates: Vec<usize> = (0..sample.min(near.len()))
                    .map(|_| near[rng.random_range(0..near.len())])
                    .collect();
                candidates.push(frozen + rng.random_range(0..free));
                let mut chosen: Option<(i64, usize, Vec<u32>, Vec<usize>)> = None;
                for r in candidates {
                    let mut new = self.rows[r].clone();
                    let mut changed = Vec::with_capacity(self.t);
                    for &(c, l) in &cells {
                        if new[c] != l {
                            new[c] = l;
                            changed.push(c);
                        }
                    }
                    if !self.cons.is_empty() && self.cons.violated_by(&new) {
                        continue;
                    }
                    let d = self.delta(r, &new, &changed);
                    if chosen.as_ref().is_none_or(|c| d < c.0) {
                        chosen = Some((d, r, new, changed));
                    }
                }
                let Some((d, r, new, changed)) = chosen else {
                    continue;
                };
                if d <= 0 || rng.random::<f64>() < (-(d as f64) / temperature).exp() {
                    self.apply(r, new, &changed);
                }
                if self.uncovered.len() < fewest {
                    fewest = self.uncovered.len();
                    stalled = 0;
                } else {
                    stalled += 1;
                }
                if left.is_multiple_of(1024) {
                    temperature = (temperature * 0.97).max(0.05);
                }
                if stalled > 20_000 {
                    // Stalled: warm up again.
                    temperature = 0.5;
                    stalled = 0;
                    fewest = self.uncovered.len();
                }
            }
            if self.uncovered.is_empty() {
                best = self.rows.clone();
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::covering::{ipog, ipog_with};

    #[test]
    fn the_pass_shrinks_an_ipog_array_and_keeps_it_covering() {
        let levels = vec![3; 8];
        let a = ipog(&levels, 2).unwrap();
        let b = optimise(
            &a,
            &Constraints::default(),
            0,
            Optimise::seconds(0.5, &levels, 2, 1),
        );
        assert!(b.len() < a.len(), "{} -> {}", a.len(), b.len());
        let raw = crate::coverage::kwise_coverage_rows(&levels, &b.rows, 2, 0).unwrap();
        assert_eq!(raw.covered, raw.total);
        // The same budget and seed give the same array.
        let again = optimise(
            &a,
            &Constraints::default(),
            0,
            Optimise::seconds(0.5, &levels, 2, 1),
        );
        assert_eq!(again, b);
    }

    #[test]
    fn constraints_and_seed_rows_are_kept() {
        let levels = vec![3; 6];
        let cons = crate::covering::forbidden_pairs(&levels, &[(0, 0, 1, 1), (2, 2, 3, 0)]);
        let seed = vec![vec![Some(2), Some(2), Some(2), Some(2), Some(2), Some(2)]];
        let a = ipog_with(&levels, 2, &cons, &seed).unwrap();
        let b = optimise(&a, &cons, 1, Optimise::seconds(0.3, &levels, 2, 2));
        assert_eq!(b.row(0), a.row(0));
        for r in 0..b.len() {
            assert!(!cons.violated_by(b.row(r)), "row {r}: {:?}", b.row(r));
        }
        let (covered, coverable) =
            crate::covering::coverage_with_constraints(&levels, &b.rows, 2, &cons);
        assert_eq!(covered, coverable);
        assert!(b.len() <= a.len());
    }
}
