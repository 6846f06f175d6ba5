use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::{Generator, GeneratorError, ParamSpace, Point};

/// The radical inverse `γ_q(j) = Σ_i b_i q^(-i-1)` of `j = Σ_i b_i q^i` in base `q`
/// (PARACOSM §3.2; Halton 1960). Result in `[0, 1)`.
///
/// Computed as the integer with reversed digits over `q^k`, so the value is exact whenever
/// `q^k < 2^53`, i.e. for every index a campaign can reach.
///
/// # Panics
/// If `q < 2` (no base-`q` representation exists); callers pass primes.
pub fn radical_inverse(mut j: u64, q: u64) -> f64 {
    assert!(q >= 2, "radical inverse needs a base >= 2, got {q}");
    // u128: `q^k` passes 2^64 for the largest indices (it wrapped to 0, a value of inf).
    let mut reversed: u128 = 0;
    let mut denom: u128 = 1;
    while j > 0 {
        reversed = reversed * u128::from(q) + u128::from(j % q);
        denom *= u128::from(q);
        j /= q;
    }
    // Below 1 whatever the rounding: with `q^k` past 2^53 (indices past 2^53 in base 2)
    // numerator and denominator may round to the same float.
    (reversed as f64 / denom as f64).min(1.0 - f64::EPSILON / 2.0)
}

/// The first `d` primes, `2, 3, 5, 7, ...`: the co-prime bases of the Halton sequence.
pub fn first_primes(d: usize) -> Vec<u64> {
    let mut primes = Vec::with_capacity(d);
    let mut candidate = 2u64;
    while primes.len() < d {
        if primes
            .iter()
            .take_while(|&&p| p * p <= candidate)
            .all(|&p| !candidate.is_multiple_of(p))
        {
            primes.push(candidate);
        }
        candidate += 1;
    }
    primes
}

/// The Halton sequence `E_n = {(γ_{q_1}(j), ..., γ_{q_N}(j)) | 0 <= j < n}` in the first `N`
/// primes (PARACOSM §3.2). Dispersion `O(1/n)` (paper Proposition 3.3).
///
/// Indexing starts at `j = 0`, as in the paper, so the first point is the origin
/// `(0, ..., 0)`. Parameter `k` in declaration order uses the `k`-th prime. A discrete parameter
/// with `L` levels takes level `floor(L · γ)`. Deterministic: there is no seed, and point `j`
/// is available alone through [`Halton::point`].
#[derive(Debug, Clone)]
pub struct Halton {
    primes: Vec<u64>,
    /// `None` for a continuous parameter, `Some(L)` for a discrete one with `L` levels.
    levels: Vec<Option<u32>>,
    next: u64,
    /// One digit scramble per dimension, for the randomised sequence.
    scramble: Option<Vec<DigitScramble>>,
}

/// Random digit permutations for one base, evaluated through lookup tables of `k` digits.
///
/// The scrambled radical inverse is `Σ_{i<D} π_i(b_i) q^(-i-1)` over `D = floor(52 / log2 q)`
/// digit positions, with an independent random permutation `π_i` of `0..q` per position (the
/// digits past the index's length are 0, and are permuted too). `D` keeps `q^-D >= 2^-52`,
/// so the largest value `1 - q^-D` stays below 1 in `f64`.
#[derive(Debug, Clone)]
struct DigitScramble {
    /// `q^k`: the number of entries of each table.
    chunk: u64,
    /// `tables[c][v]`: the contribution of digit positions `ck..ck+k` for chunk value `v`.
    tables: Vec<Vec<f64>>,
}

impl DigitScramble {
    fn new(q: u64, rng: &mut ChaCha8Rng) -> Self {
        let digits = (52.0 / (q as f64).log2()).floor() as usize;
        // Chunks of k digits with q^k <= 4096 entries.
        let mut k = 1;
        while q.pow(k as u32 + 1) <= 4096 {
            k += 1;
        }
        let chunk = q.pow(k as u32);
        let perms: Vec<Vec<u64>> = (0..digits)
            .map(|_| {
                let mut p: Vec<u64> = (0..q).collect();
                p.shuffle(rng);
                p
            })
            .collect();
        let scale: Vec<f64> = (0..digits)
            .map(|i| (q as f64).powi(-(i as i32) - 1))
            .collect();
        let mut tables = Vec::new();
        let mut pos = 0;
        while pos < digits {
            let width = k.min(digits - pos);
            // Grow the table one digit position at a time: entries for `w` digits are those
            // for `w - 1` digits plus the new position's permuted digit.
            let mut table = vec![0.0; chunk as usize];
            table[0] = 0.0;
            let mut filled = 1usize;
            for i in 0..width {
                let (perm, s) = (&perms[pos + i], scale[pos + i]);
                for top in (1..q as usize).rev() {
                    for low in 0..filled {
                        table[top * filled + low] = table[low] + perm[top] as f64 * s;
                    }
                }
                for slot in &mut table[..filled] {
                    *slot += perm[0] as f64 * s;
                }
                filled *= q as usize;
            }
            tables.push(table);
            pos += width;
        }
        DigitScramble { chunk, tables }
    }

    /// The scrambled radical inverse of `j`, in `[0, 1)`: `t_0 + (t_1 + (t_2 + ...))` with
    /// `t_c` the table entry of chunk `c`, added from the highest chunk down.
    fn value(&self, j: u64) -> f64 {
        Self::clamp(self.tables[0][(j % self.chunk) as usize] + self.high(j / self.chunk))
    }

    /// `t_1 + (t_2 + ...)` for the chunks above the first, given `j / chunk`.
    fn high(&self, mut rest: u64) -> f64 {
        let mut digits = [0usize; 64];
        for slot in digits.iter_mut().take(self.tables.len()).skip(1) {
            *slot = (rest % self.chunk) as usize;
            rest /= self.chunk;
        }
        let mut sum = 0.0;
        for c in (1..self.tables.len()).rev() {
            sum += self.tables[c][digits[c]];
        }
        sum
    }

    /// Writes the values of `start..start + out.len() / stride` into `out[i * stride]`,
    /// equal to [`DigitScramble::value`] but with one table look-up per index: the higher
    /// chunks change once every `q^k` indices.
    fn fill(&self, start: u64, out: &mut [f64], stride: usize) {
        let mut low = (start % self.chunk) as usize;
        let mut rest = start / self.chunk;
        let mut high = self.high(rest);
        let first = &self.tables[0];
        for slot in out.iter_mut().step_by(stride) {
            *slot = Self::clamp(first[low] + high);
            low += 1;
            if low == first.len() {
                low = 0;
                rest += 1;
                high = self.high(rest);
            }
        }
    }

    /// Rounding may carry `1 - q^-D` up to 1; keep values in `[0, 1)`.
    fn clamp(u: f64) -> f64 {
        u.min(1.0 - f64::EPSILON / 2.0)
    }
}

impl Halton {
    /// A Halton generator over `space`, starting at index 0.
    pub fn new(space: &ParamSpace) -> Self {
        let levels = space.layout();
        Halton {
            primes: first_primes(levels.len()),
            levels,
            next: 0,
            scramble: None,
        }
    }

    /// The randomised Halton sequence (Owen, "A randomized Halton algorithm in R", 2017): every
    /// base digit of every coordinate goes through a random permutation of `0..q`, one
    /// permutation per base and digit position, drawn from `ChaCha8Rng::seed_from_u64(seed)`.
    /// Each coordinate stays uniform on `[0, 1)` and the sequence keeps its stratification.
    /// Point `j` is still available alone ([`Halton::point`]); tables of 4,096 entries per
    /// chunk of digits make it a few lookups per coordinate.
    pub fn scrambled(space: &ParamSpace, seed: u64) -> Self {
        let mut h = Halton::new(space);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        h.scramble = Some(
            h.primes
                .iter()
                .map(|&q| DigitScramble::new(q, &mut rng))
                .collect(),
        );
        h
    }

    /// The continuous coordinates of points `start..start + n` as an `n × N_C` row-major
    /// matrix in `[0, 1)` (level indices are left out): the layout of
    /// `scipy.stats.qmc.Halton.random`. Computed in parallel.
    pub fn unit_points(&self, start: u64, n: usize) -> Vec<f64> {
        let dims: Vec<usize> = (0..self.levels.len())
            .filter(|&k| self.levels[k].is_none())
            .collect();
        let d = dims.len();
        let mut out = vec![0.0; n * d];
        if d == 0 {
            return out;
        }
        out.par_chunks_mut(d * 256)
            .enumerate()
            .for_each(|(block, rows)| {
                let first = start + (block * 256) as u64;
                for (col, &k) in dims.iter().enumerate() {
                    match &self.scramble {
                        Some(s) => s[k].fill(first, &mut rows[col..], d),
                        None => {
                            for (r, slot) in rows[col..].iter_mut().step_by(d).enumerate() {
                                *slot = radical_inverse(first + r as u64, self.primes[k]);
                            }
                        }
                    }
                }
            });
        out
    }

    /// Point `j` of the sequence.
    pub fn point(&self, j: u64) -> Point {
        let mut p = Point::default();
        for (k, (q, levels)) in self.primes.iter().zip(&self.levels).enumerate() {
            let u = match &self.scramble {
                Some(s) => s[k].value(j),
                None => radical_inverse(j, *q),
            };
            match levels {
                None => p.continuous.push(u),
                Some(l) => p.discrete.push(((u * *l as f64) as u32).min(l - 1)),
            }
        }
        p
    }
}

impl Generator for Halton {
    fn name(&self) -> &'static str {
        if self.scramble.is_some() {
            "halton-scrambled"
        } else {
            "halton"
        }
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let start = self.next;
        self.next += n as u64;
        Ok((0..n)
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| self.point(start + i as u64))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Param;

    #[test]
    fn first_primes_are_primes() {
        assert_eq!(first_primes(8), [2, 3, 5, 7, 11, 13, 17, 19]);
        assert!(first_primes(0).is_empty());
    }

    /// Value stability: the first 8 points of Halton(2, 3) from index 0, as exact fractions.
    #[test]
    fn halton_2_3_first_eight_points_are_exact() {
        let space = ParamSpace::new(vec![
            Param::interval("x", 0.0, 1.0, "1"),
            Param::interval("y", 0.0, 1.0, "1"),
        ])
        .unwrap();
        let pts = Halton::new(&space).ask(8).unwrap();
        let expected = [
            (0.0, 0.0),
            (1.0 / 2.0, 1.0 / 3.0),
            (1.0 / 4.0, 2.0 / 3.0),
            (3.0 / 4.0, 1.0 / 9.0),
            (1.0 / 8.0, 4.0 / 9.0),
            (5.0 / 8.0, 7.0 / 9.0),
            (3.0 / 8.0, 2.0 / 9.0),
            (7.0 / 8.0, 5.0 / 9.0),
        ];
        for (p, (x, y)) in pts.iter().zip(expected) {
            assert_eq!(p.continuous, [x, y]);
        }
    }

    #[test]
    fn ask_continues_where_it_stopped_and_matches_point() {
        let space = ParamSpace::new(vec![
            Param::interval("x", 0.0, 1.0, "1"),
            Param::levels("c", vec![crate::Value::Int(1), crate::Value::Int(2)]),
        ])
        .unwrap();
        let mut h = Halton::new(&space);
        let a = h.ask(5).unwrap();
        let b = h.ask(5).unwrap();
        assert_eq!(b[0], h.point(5));
        assert_eq!(a[3], h.point(3));
        // base 3 for the discrete parameter: γ_3(1) = 1/3 -> level 0, γ_3(2) = 2/3 -> level 1
        assert_eq!(a[1].discrete, [0]);
        assert_eq!(a[2].discrete, [1]);
    }

    fn unit_space(d: usize) -> ParamSpace {
        ParamSpace::unit_cube(d)
    }

    /// Value stability of the scrambled sequence: seed 7, first three points in 2 dimensions.
    #[test]
    fn scrambled_first_rows_are_pinned() {
        let pts = Halton::scrambled(&unit_space(2), 7).ask(3).unwrap();
        let got: Vec<Vec<f64>> = pts.into_iter().map(|p| p.continuous).collect();
        assert_eq!(got, PINNED_SCRAMBLED.map(|r| r.to_vec()).to_vec());
    }

    const PINNED_SCRAMBLED: [[f64; 2]; 3] = [
        [0.29390818510512995, 0.08245055861031031],
        [0.79390818510513, 0.7491172252769769],
        [0.04390818510512995, 0.4157838919436436],
    ];

    #[test]
    fn scrambling_keeps_the_stratification_of_each_coordinate() {
        // The first q^m points of the base-q coordinate hit each of the q^m strata once.
        let pts = Halton::scrambled(&unit_space(2), 3).ask(243).unwrap();
        let mut seen2 = [0u32; 128];
        let mut seen3 = [0u32; 243];
        for p in &pts[..128] {
            seen2[(p.continuous[0] * 128.0) as usize] += 1;
        }
        for p in &pts {
            seen3[(p.continuous[1] * 243.0) as usize] += 1;
        }
        assert!(seen2.iter().all(|&c| c == 1));
        assert!(seen3.iter().all(|&c| c == 1));
        let other = Halton::scrambled(&unit_space(2), 4).ask(243).unwrap();
        assert_ne!(pts, other);
        assert_ne!(pts, Halton::new(&unit_space(2)).ask(243).unwrap());
    }

    #[test]
    fn unit_points_equal_the_points_continuous_coordinates() {
        let h = Halton::scrambled(&unit_space(3), 5);
        let m = h.unit_points(10, 600);
        for (r, row) in m.chunks_exact(3).enumerate() {
            assert_eq!(row, h.point(10 + r as u64).continuous.as_slice());
        }
    }

    #[test]
    fn scrambled_values_stay_below_one_for_large_indices() {
        let h = Halton::scrambled(&unit_space(8), 1);
        for j in [0u64, 1, 1 << 20, (1 << 40) + 12345, u64::MAX / 3] {
            let p = h.point(j);
            assert!(p.continuous.iter().all(|u| (0.0..1.0).contains(u)), "{p:?}");
        }
    }

    #[test]
    fn radical_inverse_of_large_indices_stays_in_unit_interval() {
        for q in [2, 3, 5, 251] {
            for j in [1u64 << 40, u32::MAX as u64, 123_456_789] {
                let u = radical_inverse(j, q);
                assert!((0.0..1.0).contains(&u), "γ_{q}({j}) = {u}");
            }
        }
    }
}
