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
    let mut reversed: u64 = 0;
    let mut denom: u64 = 1;
    while j > 0 {
        reversed = reversed * q + j % q;
        denom *= q;
        j /= q;
    }
    reversed as f64 / denom as f64
}

/// The first `d` primes, `2, 3, 5, 7, ...`: the co-prime bases of the Halton sequence.
pub fn first_primes(d: usize) -> Vec<u64> {
    let mut primes = Vec::with_capacity(d);
    let mut candidate = 2u64;
    while primes.len() < d {
        if primes
            .iter()
            .take_while(|&&p| p * p <= candidate)
            .all(|&p| candidate % p != 0)
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
}

impl Halton {
    /// A Halton generator over `space`, starting at index 0.
    pub fn new(space: &ParamSpace) -> Self {
        let levels = space.layout();
        Halton {
            primes: first_primes(levels.len()),
            levels,
            next: 0,
        }
    }

    /// Point `j` of the sequence.
    pub fn point(&self, j: u64) -> Point {
        let mut p = Point::default();
        for (q, levels) in self.primes.iter().zip(&self.levels) {
            let u = radical_inverse(j, *q);
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
        "halton"
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let start = self.next;
        self.next += n as u64;
        Ok((start..self.next).map(|j| self.point(j)).collect())
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
