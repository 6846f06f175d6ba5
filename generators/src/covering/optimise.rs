//! Post-optimisation of a covering array: fewer rows by simulated annealing.
//!
//! The pass removes the row that covers the fewest tuples alone, then repairs the array by
//! simulated annealing until every coverable t-tuple is covered again, and repeats, keeping
//! the last complete array. A move takes an uncovered tuple and writes it into a row: among the
//! rows that already agree with it in all but one column, the one whose change uncovers the
//! fewest other tuples (Nurmela's move, "Upper bounds for covering arrays by tabu search",
//! Discrete Applied Mathematics 138, 2004), or a row drawn at random if it does better; when no
//! row is that close, the best of a few of the closest rows and one drawn at random. A move is accepted when it does not add uncovered
//! tuples, or with probability `exp(-Δ / T)` (Metropolis); the temperature falls geometrically
//! and rises again when the repair stalls. This is the row-removal-and-repair scheme of the
//! annealing constructions of covering arrays (Cohen, Colbourn and Ling, "Constructing strength
//! three covering arrays with augmented annealing", Discrete Mathematics 308, 2008;
//! Torres-Jimenez and Rodriguez-Tello, "New bounds for binary covering arrays using simulated
//! annealing", Information Sciences 185, 2012).
//!
//! The pass starts from the smaller of the array it is given and, for a uniform model without
//! constraints or seed rows, an algebraic construction ([`super::construct`]).
//!
//! The work is counted in units (a tuple index computed, or a few cells of a row compared), not
//! seconds, so the same array, budget and seed give the same result on any machine and for any
//! thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::{Constraints, CoveringArray};

/// A count that marks a tuple the constraints forbid: it is never uncovered.
const FORBIDDEN: u32 = 1 << 30;

/// Seconds one unit of work takes on one core of the 2-core reference machine, at most (the
/// slowest rate measured on the uniform models of `examples/covering_frontier.rs`, t = 2–4,
/// v = 2–6, k ≤ 20), so that a budget of `s` seconds runs at most about `s`. The budget is
/// counted in units from this rate, so that the result does not depend on the machine or its
/// load.
pub const WORK_UNIT_S: f64 = 8.5e-9;

/// Units of work a move costs besides the tuple indices it computes and the cells it compares:
/// drawing the tuple, decoding it and choosing among the rows.
const MOVE_UNITS: u64 = 96;

/// Units of work weighing one row costs besides its tuple indices (the cells it would change).
const ROW_UNITS: u64 = 16;

/// Rows a move weighs when none agrees with the tuple in all but one column: this many of the
/// closest (and, as always, one drawn at random).
const CLOSEST: usize = 2;

/// Rows agreeing with the tuple in all but one column that a move weighs, at most, from
/// strength 3 on (more makes the search greedier and, measured on 3^10 at t = 3, worse).
const NEAR: usize = 12;

/// [`NEAR`] at strength 2 (measured on 3^10, 4^10 and 3^20 at t = 2: 12 left them at IPOG's
/// size or near it).
const NEAR_PAIRS: usize = 4;

/// How a covering array is post-optimised ([`optimise`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optimise {
    /// Units of work per chain: one per [`WORK_UNIT_S`] of the seconds asked for.
    pub work: u64,
    /// Independent chains, each with its own seed (run in parallel with rayon); the smallest
    /// array wins, the first chain on a tie.
    pub chains: usize,
    /// The seed of the first chain; chain `i` uses `seed + i`.
    pub seed: u64,
}

impl Optimise {
    /// About `seconds` of work per chain on the reference machine, two chains (its two cores).
    pub fn seconds(seconds: f64, seed: u64) -> Self {
        Optimise {
            work: (seconds.max(0.0) / WORK_UNIT_S) as u64,
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
    if k == 0 || array.len() <= frozen + 1 || how.work == 0 {
        return array.clone();
    }
    let (start, used) = algebraic_start(array, cons, frozen, how);
    let array = start.as_ref().unwrap_or(array);
    let how = Optimise {
        work: how.work - used,
        ..how
    };
    let best = (0..how.chains.max(1))
        .into_par_iter()
        .map(|i| {
            let mut chain = Chain::new(&array.levels, array.strength, cons, array.rows.clone());
            chain.run(frozen, how.work, how.seed.wrapping_add(i as u64))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .reduce(|a, b| if b.len() < a.len() { b } else { a })
        .unwrap_or_else(|| array.rows.clone());
    CoveringArray {
        levels: array.levels.clone(),
        strength: array.strength,
        rows: best,
    }
}

/// A starting array with fewer rows than `array`, for a uniform model without constraints or
/// seed rows: an algebraic construction ([`super::construct`]) or, at strength 3 from 8
/// columns on, Chateauneuf and Kreher's doubling ([`super::doubling`]) of two arrays over half
/// the columns, each the smaller of its construction and its IPOG array annealed with a tenth
/// of `how`'s work (a twentieth for the strength-2 half). Returns the array and the work the
/// halves took.
fn algebraic_start(
    array: &CoveringArray,
    cons: &Constraints,
    frozen: usize,
    how: Optimise,
) -> (Option<CoveringArray>, u64) {
    let Some(&v) = array.levels.first() else {
        return (None, 0);
    };
    let (k, t) = (array.levels.len(), array.strength);
    if !cons.is_empty() || frozen > 0 || array.levels.iter().any(|&l| l != v) {
        return (None, 0);
    }
    let mut used = 0;
    let mut best = super::construct(v, k, t);
    if t == 3 && k >= 8 {
        used = how.work / 10 + how.work / 20;
        let half = k.div_ceil(2);
        let part = |t: usize, share: u64| -> Option<CoveringArray> {
            let plain = super::ipog(&vec![v; half], t).ok()?;
            let part = Optimise {
                work: how.work / share,
                ..how
            };
            Some(optimise(&plain, cons, 0, part))
        };
        if let (Some(a), Some(b)) = (part(3, 10), part(2, 20)) {
            let rows: Vec<u32> = super::doubling(&a.rows, &b.rows, half, v)
                .chunks(2 * half)
                .flat_map(|r| r[..k].to_vec())
                .collect();
            let doubled = CoveringArray {
                levels: array.levels.clone(),
                strength: t,
                rows,
            };
            let covers = crate::coverage::kwise_coverage_rows(&doubled.levels, &doubled.rows, t, 0)
                .is_ok_and(|c| c.covered == c.total);
            if covers && best.as_ref().is_none_or(|b| doubled.len() < b.len()) {
                best = Some(doubled);
            }
        }
    }
    (best.filter(|c| c.len() < array.len()), used)
}

/// One annealing chain: the array (`n × k`, row-major), the count of rows covering each
/// t-tuple, and the list of uncovered tuples.
struct Chain<'a> {
    cons: &'a Constraints,
    k: usize,
    t: usize,
    rows: Vec<u32>,
    /// Columns of each t-subset, flat (`t` per subset).
    cols: Vec<usize>,
    /// Radix weight of each column of each subset, flat: a tuple's index in its subset.
    weights: Vec<usize>,
    /// Start of each subset's tuples in `counts`.
    base: Vec<usize>,
    /// The subsets holding each column, each with the column's place in it.
    by_column: Vec<Vec<(u32, u32)>>,
    counts: Vec<u32>,
    uncovered: Vec<u32>,
    /// Place of each tuple in `uncovered`, `u32::MAX` when covered.
    pos: Vec<u32>,
    /// Units of work done.
    work: u64,
    /// A row being weighed against the constraints.
    scratch: Vec<u32>,
}

/// A move: row, then the `(column, level)` cells it writes.
type Move = (usize, Vec<(usize, u32)>);

impl<'a> Chain<'a> {
    fn new(levels: &[u32], t: usize, cons: &'a Constraints, rows: Vec<u32>) -> Self {
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
            for (j, &c) in sub.iter().enumerate() {
                by_column[c].push((s as u32, j as u32));
            }
            total += w;
        }
        base.push(total);
        let mut chain = Chain {
            cons,
            k,
            t,
            rows,
            cols,
            weights,
            base,
            by_column,
            counts: vec![0; total],
            uncovered: Vec::new(),
            pos: vec![u32::MAX; total],
            work: 0,
            scratch: vec![0; k],
        };
        if !cons.is_empty() {
            for id in 0..total {
                if !cons.completable(levels, &chain.cells(id)) {
                    chain.counts[id] = FORBIDDEN;
                }
            }
        }
        for r in 0..chain.len() {
            for s in 0..subsets.len() {
                let id = chain.id(s, r);
                chain.counts[id] += 1;
            }
        }
        for id in 0..total {
            if chain.counts[id] == 0 {
                chain.uncover(id);
            }
        }
        chain
    }

    fn len(&self) -> usize {
        self.rows.len() / self.k
    }

    fn subsets(&self) -> usize {
        self.base.len() - 1
    }

    /// The index of row `r`'s tuple in subset `s`.
    fn id(&self, s: usize, r: usize) -> usize {
        let row = &self.rows[r * self.k..(r + 1) * self.k];
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

    /// Removes row `r` from the counts and the array (the last row takes its place).
    fn remove(&mut self, r: usize) {
        for s in 0..self.subsets() {
            let id = self.id(s, r);
            self.counts[id] -= 1;
            if self.counts[id] == 0 {
                self.uncover(id);
            }
        }
        let last = self.len() - 1;
        self.rows
            .copy_within(last * self.k..(last + 1) * self.k, r * self.k);
        self.rows.truncate(last * self.k);
    }

    /// The change in uncovered tuples if cell `(r, c)` became `level`, without making it.
    fn delta_one(&mut self, r: usize, c: usize, level: u32) -> i64 {
        let old = self.rows[r * self.k + c];
        let mut d = 0i64;
        for &(s, j) in &self.by_column[c] {
            let w = self.weights[s as usize * self.t + j as usize];
            let from = self.id(s as usize, r);
            let to = from + w * level as usize - w * old as usize;
            d += i64::from(self.counts[from] == 1) - i64::from(self.counts[to] == 0);
        }
        self.work += self.by_column[c].len() as u64;
        d
    }

    /// Makes cell `(r, c)` the level `level`; returns the change in uncovered tuples.
    fn set(&mut self, r: usize, c: usize, level: u32) -> i64 {
        let old = self.rows[r * self.k + c];
        if old == level {
            return 0;
        }
        let mut d = 0i64;
        for e in 0..self.by_column[c].len() {
            let (s, j) = self.by_column[c][e];
            let w = self.weights[s as usize * self.t + j as usize];
            let from = self.id(s as usize, r);
            let to = from + w * level as usize - w * old as usize;
            self.counts[from] -= 1;
            if self.counts[from] == 0 {
                self.uncover(from);
                d += 1;
            }
            if self.counts[to] == 0 {
                self.cover(to);
                d -= 1;
            }
            self.counts[to] += 1;
        }
        self.rows[r * self.k + c] = level;
        self.work += 2 * self.by_column[c].len() as u64;
        d
    }

    /// Whether row `r` with `cells` written into it breaks the constraints.
    fn forbidden(&mut self, r: usize, cells: &[(usize, u32)]) -> bool {
        if self.cons.is_empty() {
            return false;
        }
        self.scratch
            .copy_from_slice(&self.rows[r * self.k..(r + 1) * self.k]);
        for &(c, l) in cells {
            self.scratch[c] = l;
        }
        self.cons.violated_by(&self.scratch)
    }

    /// The change in uncovered tuples if `cells` were written into row `r` (made and undone).
    fn delta(&mut self, r: usize, cells: &[(usize, u32)]) -> i64 {
        let old: Vec<u32> = cells
            .iter()
            .map(|&(c, _)| self.rows[r * self.k + c])
            .collect();
        let d: i64 = cells.iter().map(|&(c, l)| self.set(r, c, l)).sum();
        for (&(c, _), &l) in cells.iter().zip(&old).rev() {
            self.set(r, c, l);
        }
        d
    }

    /// The row, not frozen, whose tuples the fewest other rows also cover.
    fn least_needed(&mut self, frozen: usize) -> usize {
        self.work += ((self.len() - frozen) * self.subsets()) as u64;
        (frozen..self.len())
            .map(|r| {
                let alone = (0..self.subsets())
                    .filter(|&s| self.counts[self.id(s, r)] == 1)
                    .count();
                (alone, r)
            })
            .min()
            .map_or(frozen, |(_, r)| r)
    }

    /// The best move that covers the uncovered tuple `cells`, with its change in uncovered
    /// tuples; `None` when every row weighed would break the constraints.
    fn best_move(
        &mut self,
        frozen: usize,
        cells: &[(usize, u32)],
        rng: &mut ChaCha8Rng,
    ) -> Option<(i64, Move)> {
        // The rows closest to the tuple (fewest cells to change), a sample of them kept by
        // reservoir sampling.
        let (n, k) = (self.len(), self.k);
        let mut closest = self.t + 1;
        let near_cap = if self.t <= 2 { NEAR_PAIRS } else { NEAR };
        let mut near: Vec<usize> = Vec::with_capacity(near_cap);
        let mut seen = 0usize;
        for r in frozen..n {
            let row = &self.rows[r * k..(r + 1) * k];
            let m = cells.iter().filter(|&&(c, l)| row[c] != l).count();
            if m < closest {
                closest = m;
                near.clear();
                seen = 0;
            }
            if m == closest {
                seen += 1;
                if near.len() < near_cap {
                    near.push(r);
                } else {
                    let i = rng.random_range(0..seen);
                    if i < near_cap {
                        near[i] = r;
                    }
                }
            }
        }
        self.work += ((n - frozen) * self.t / 2) as u64;
        if closest > 1 {
            near.truncate(CLOSEST);
        }
        near.push(frozen + rng.random_range(0..n - frozen));
        let mut chosen: Option<(i64, Move)> = None;
        for r in near {
            let change: Vec<(usize, u32)> = {
                let row = &self.rows[r * k..(r + 1) * k];
                cells
                    .iter()
                    .copied()
                    .filter(|&(c, l)| row[c] != l)
                    .collect()
            };
            self.work += ROW_UNITS;
            if self.forbidden(r, &change) {
                continue;
            }
            let d = match change[..] {
                [(c, l)] => self.delta_one(r, c, l),
                _ => self.delta(r, &change),
            };
            if chosen.as_ref().is_none_or(|(best, _)| d < *best) {
                chosen = Some((d, (r, change)));
            }
        }
        chosen
    }

    /// Shrinks the array within `budget` units of work; returns the smallest complete array
    /// found (`n × k`, row-major).
    fn run(&mut self, frozen: usize, budget: u64, seed: u64) -> Vec<u32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut best = self.rows.clone();
        let mut moves = 0u64;
        while self.work < budget && self.len() > frozen + 1 {
            let r = self.least_needed(frozen);
            self.remove(r);
            let mut temperature = HOT;
            let mut stalled = 0u64;
            let mut fewest = self.uncovered.len();
            while !self.uncovered.is_empty() && self.work < budget {
                moves += 1;
                self.work += MOVE_UNITS;
                let id = self.uncovered[rng.random_range(0..self.uncovered.len())] as usize;
                let cells = self.cells(id);
                let Some((d, (r, change))) = self.best_move(frozen, &cells, &mut rng) else {
                    continue;
                };
                if d <= 0 || rng.random::<f64>() < (-(d as f64) / temperature).exp() {
                    for (c, l) in change {
                        self.set(r, c, l);
                    }
                }
                if self.uncovered.len() < fewest {
                    fewest = self.uncovered.len();
                    stalled = 0;
                } else {
                    stalled += 1;
                }
                if moves.is_multiple_of(COOL_EVERY) {
                    temperature = (temperature * COOLING).max(COLD);
                }
                if stalled > STALL && temperature <= COLD {
                    // Stalled at the coldest: warm up again.
                    temperature = HOT;
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

/// The temperature a repair starts at, and returns to when it stalls.
const HOT: f64 = 1.5;
/// The coldest temperature.
const COLD: f64 = 0.1;
/// The cooling factor, applied every [`COOL_EVERY`] moves.
const COOLING: f64 = 0.995;
/// See [`COOLING`].
const COOL_EVERY: u64 = 1024;
/// Moves at the coldest temperature without a new fewest count of uncovered tuples before the
/// repair warms up again.
const STALL: u64 = 20_000;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::covering::{ipog, ipog_with};

    #[test]
    fn the_pass_shrinks_an_ipog_array_and_keeps_it_covering() {
        let levels = vec![3; 8];
        let a = ipog(&levels, 2).unwrap();
        let b = optimise(&a, &Constraints::default(), 0, Optimise::seconds(0.5, 1));
        assert!(b.len() < a.len(), "{} -> {}", a.len(), b.len());
        let raw = crate::coverage::kwise_coverage_rows(&levels, &b.rows, 2, 0).unwrap();
        assert_eq!(raw.covered, raw.total);
        // The same budget and seed give the same array.
        let again = optimise(&a, &Constraints::default(), 0, Optimise::seconds(0.5, 1));
        assert_eq!(again, b);
    }

    #[test]
    fn a_uniform_model_starts_from_its_smallest_construction() {
        // 2^20 at t = 3: the doubling of two annealed 10-column halves (12 + 6 rows) is the
        // best known, 18, where IPOG gives 24.
        let levels = vec![2; 20];
        let a = ipog(&levels, 3).unwrap();
        let (start, _) = algebraic_start(&a, &Constraints::default(), 0, Optimise::seconds(0.5, 1));
        let start = start.expect("a start smaller than IPOG's");
        assert_eq!((a.len(), start.len()), (24, 18));
        let raw = crate::coverage::kwise_coverage_rows(&levels, &start.rows, 3, 0).unwrap();
        assert_eq!(raw.covered, raw.total);
        // Constraints or seed rows: no algebraic start.
        let cons = crate::covering::forbidden_pairs(&levels, &[(0, 0, 1, 1)]);
        assert!(algebraic_start(&a, &cons, 0, Optimise::seconds(0.5, 1))
            .0
            .is_none());
        assert!(
            algebraic_start(&a, &Constraints::default(), 1, Optimise::seconds(0.5, 1))
                .0
                .is_none()
        );
    }

    #[test]
    fn constraints_and_seed_rows_are_kept() {
        let levels = vec![3; 6];
        let cons = crate::covering::forbidden_pairs(&levels, &[(0, 0, 1, 1), (2, 2, 3, 0)]);
        let seed = vec![vec![Some(2), Some(2), Some(2), Some(2), Some(2), Some(2)]];
        let a = ipog_with(&levels, 2, &cons, &seed).unwrap();
        let b = optimise(&a, &cons, 1, Optimise::seconds(0.3, 2));
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
