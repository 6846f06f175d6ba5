//! Algebraic constructions of covering arrays for uniform models (every column with `v`
//! levels), used as the post-optimisation's starting point where they are smaller than IPOG's
//! array.
//!
//! - [`orthogonal_array`]: Bush's orthogonal arrays OA(q^t; t, q + 1, q) for a prime power `q`
//!   and `t ≤ q` (K. A. Bush, "Orthogonal arrays of index unity", Annals of Mathematical
//!   Statistics 23, 1952): the rows are the polynomials of degree below `t` over GF(q), the
//!   columns their values at the `q` points and their leading coefficient.
//! - [`binary_pairs`]: the binary strength-2 arrays of the fewest rows (Kleitman–Spencer,
//!   Katona).
//! - [`product`]: the product of two strength-2 arrays, `N + M` rows for `k·l` columns, less
//!   the rows both parts share (C. J. Colbourn, "Combinatorial aspects of covering arrays",
//!   Le Matematiche 59, 2004, §3).
//! - [`doubling`]: Chateauneuf and Kreher's doubling for strength 3, CA(N + (v − 1)·M; 3, 2k,
//!   v) from a CA(N; 3, k, v) and a CA(M; 2, k, v) ("On the state of strength-three covering
//!   arrays", Journal of Combinatorial Designs 10, 2002, Theorem 2.1 in the form of
//!   Colbourn's survey above).
//!
//! - Bush's array over the first `q + 1` columns as the seed rows of IPOG ([`super::ipog_with`]),
//!   which grows the other columns and the rows they need.
//!
//! Every array is checked for full coverage before it is returned (`construct`), so a wrong
//! construction could only cost rows, never a tuple.

use std::collections::HashSet;

use super::CoveringArray;

/// Most levels a finite field is built for here: a prime power up to 64.
const MAX_FIELD: usize = 64;

/// The finite field GF(q): its addition and multiplication tables, `q × q`, row-major.
struct Field {
    q: usize,
    add: Vec<u32>,
    mul: Vec<u32>,
}

impl Field {
    /// GF(q) for a prime power `q ≤ 64`; `None` for any other `q`. Elements are the
    /// polynomials of degree below `m` over GF(p), written in base `p`; the product is taken
    /// modulo the first monic polynomial of degree `m` without zero divisors.
    fn new(q: usize) -> Option<Field> {
        if !(2..=MAX_FIELD).contains(&q) {
            return None;
        }
        let p = (2..=q).find(|&p| q.is_multiple_of(p))?;
        let (mut m, mut r) = (0usize, q);
        while r.is_multiple_of(p) {
            r /= p;
            m += 1;
        }
        if r != 1 {
            return None;
        }
        let digits = |x: usize| -> Vec<usize> { (0..m).map(|i| x / p.pow(i as u32) % p).collect() };
        let number = |d: &[usize]| -> usize { d.iter().rev().fold(0, |a, &x| a * p + x) };
        let add: Vec<u32> = (0..q * q)
            .map(|i| {
                let (a, b) = (digits(i / q), digits(i % q));
                number(
                    &a.iter()
                        .zip(&b)
                        .map(|(x, y)| (x + y) % p)
                        .collect::<Vec<_>>(),
                ) as u32
            })
            .collect();
        // Candidate moduli x^m + (lower terms); m = 1 gives the integers modulo p.
        for lower in 0..q {
            let modulus = digits(lower);
            let times = |a: usize, b: usize| -> usize {
                let (a, b) = (digits(a), digits(b));
                let mut prod = vec![0usize; 2 * m];
                for i in 0..m {
                    for j in 0..m {
                        prod[i + j] = (prod[i + j] + a[i] * b[j]) % p;
                    }
                }
                // Reduce: x^m = -(lower terms).
                for d in (m..2 * m).rev() {
                    let c = prod[d];
                    prod[d] = 0;
                    for (i, &mi) in modulus.iter().enumerate() {
                        prod[d - m + i] = (prod[d - m + i] + c * (p - mi)) % p;
                    }
                }
                number(&prod[..m])
            };
            let mul: Vec<u32> = (0..q * q).map(|i| times(i / q, i % q) as u32).collect();
            let no_zero_divisor = (1..q).all(|a| (1..q).all(|b| mul[a * q + b] != 0));
            if no_zero_divisor {
                return Some(Field { q, add, mul });
            }
        }
        None
    }

    fn add(&self, a: u32, b: u32) -> u32 {
        self.add[a as usize * self.q + b as usize]
    }

    fn mul(&self, a: u32, b: u32) -> u32 {
        self.mul[a as usize * self.q + b as usize]
    }
}

/// Bush's orthogonal array OA(q^t; t, k, q) for `k ≤ q + 1` columns: `q^t × k` rows,
/// row-major, levels `0..q`, every t-tuple exactly once. `None` unless `q` is a prime power up
/// to 64, `2 ≤ t ≤ q` and `k ≤ q + 1`. With `k ≤ q` the constant polynomials give the `q`
/// constant rows.
pub fn orthogonal_array(q: usize, t: usize, k: usize) -> Option<Vec<u32>> {
    if t < 2 || t > q || k > q + 1 || q.checked_pow(t as u32)? > super::MAX_ROWS as usize {
        return None;
    }
    let field = Field::new(q)?;
    let n = q.pow(t as u32);
    let mut rows = Vec::with_capacity(n * k);
    let mut coef = vec![0u32; t];
    for r in 0..n {
        let mut x = r;
        for c in coef.iter_mut() {
            *c = (x % q) as u32;
            x /= q;
        }
        for col in 0..k {
            rows.push(if col == q {
                coef[t - 1]
            } else {
                // Horner's rule at the point `col`.
                coef.iter()
                    .rev()
                    .fold(0, |acc, &c| field.add(field.mul(acc, col as u32), c))
            });
        }
    }
    Some(rows)
}

/// The binary strength-2 array of the fewest rows for `k` columns, `n × k` row-major: the
/// least `n` with `C(n − 1, ⌈n/2⌉) ≥ k`, each column a distinct ⌈n/2⌉-subset of rows `1..n`
/// (Kleitman and Spencer, "Families of k-independent sets", Discrete Mathematics 6, 1973;
/// Katona 1973). Two such columns are incomparable sets that meet, and row 0 is all zeros, so
/// every pair of levels appears.
pub fn binary_pairs(k: usize) -> Vec<u32> {
    let choose =
        |n: usize, r: usize| (0..r).fold(1u128, |a, i| a * (n - i) as u128 / (i as u128 + 1));
    let mut n = 2;
    while choose(n - 1, n.div_ceil(2)) < k as u128 {
        n += 1;
    }
    let w = n.div_ceil(2);
    // The first k w-subsets of 1..n in lexicographic order.
    let mut subsets: Vec<Vec<usize>> = Vec::with_capacity(k);
    let mut s: Vec<usize> = (1..=w).collect();
    while subsets.len() < k {
        subsets.push(s.clone());
        // Next subset: the rightmost element that can grow does, the rest follow it.
        let Some(i) = (0..w).rev().find(|&i| s[i] < n - w + i) else {
            break;
        };
        s[i] += 1;
        for j in i + 1..w {
            s[j] = s[j - 1] + 1;
        }
    }
    let mut rows = vec![0u32; n * k];
    for (c, set) in subsets.iter().enumerate() {
        for &r in set {
            rows[r * k + c] = 1;
        }
    }
    rows
}

/// The product of a strength-2 array `a` (`n × ka`) and `b` (`m × kb`) over `v` levels: a
/// strength-2 array of `ka · kb` columns, column `(i, j)` taking `a`'s column `i` in the first
/// `n` rows and `b`'s column `j` in the rest; rows both parts share appear once.
pub fn product(a: &[u32], ka: usize, b: &[u32], kb: usize) -> Vec<u32> {
    let mut rows = Vec::new();
    for row in a.chunks(ka) {
        rows.push((0..ka * kb).map(|c| row[c / kb]).collect::<Vec<u32>>());
    }
    for row in b.chunks(kb) {
        rows.push((0..ka * kb).map(|c| row[c % kb]).collect());
    }
    distinct(rows)
}

/// Chateauneuf and Kreher's doubling: from a strength-3 array `a` and a strength-2 array `b`
/// over the same `k` columns and `v` levels, a strength-3 array of `2k` columns: the rows
/// `[x | x]` for `x` in `a`, and `[y | y + i mod v]` for `y` in `b` and `i` in `1..v`.
pub fn doubling(a: &[u32], b: &[u32], k: usize, v: u32) -> Vec<u32> {
    let mut rows = Vec::new();
    for row in a.chunks(k) {
        rows.push(row.iter().chain(row).copied().collect::<Vec<u32>>());
    }
    for row in b.chunks(k) {
        for i in 1..v {
            rows.push(
                row.iter()
                    .copied()
                    .chain(row.iter().map(|&x| (x + i) % v))
                    .collect(),
            );
        }
    }
    distinct(rows)
}

/// The rows, each once, in their first order, flattened.
fn distinct(rows: Vec<Vec<u32>>) -> Vec<u32> {
    let mut seen = HashSet::new();
    rows.into_iter()
        .filter(|r| seen.insert(r.clone()))
        .flatten()
        .collect()
}

/// The smallest of the constructions above that gives a strength-`t` array of `k` columns of
/// `v` levels each (the first `k` columns of a wider one), checked to cover every t-tuple;
/// `None` when none applies.
pub fn construct(v: u32, k: usize, t: usize) -> Option<CoveringArray> {
    let q = v as usize;
    let mut found: Vec<(Vec<u32>, usize)> = Vec::new();
    if v == 2 && t == 2 {
        found.push((binary_pairs(k), k));
    }
    if let Some(oa) = orthogonal_array(q, t, k) {
        found.push((oa, k));
    }
    if t == 2 && k > q + 1 {
        // a: the q columns with constant rows; b: as many columns as the product needs.
        let kb = k.div_ceil(q);
        if let (Some(a), Some(b)) = (orthogonal_array(q, 2, q), orthogonal_array(q, 2, kb)) {
            found.push((product(&a, q, &b, kb), q * kb));
        }
    }
    if k > q + 1 && t >= 2 {
        // Bush's array over the first q + 1 columns as IPOG's seed rows, the rest grown.
        if let Some(oa) = orthogonal_array(q, t, q + 1) {
            let seeds: Vec<Vec<Option<u32>>> = oa
                .chunks(q + 1)
                .map(|r| (0..k).map(|c| r.get(c).copied()).collect())
                .collect();
            let none = super::Constraints::default();
            if let Ok(a) = super::ipog_with(&vec![v; k], t, &none, &seeds) {
                found.push((a.rows, k));
            }
        }
    }
    if t == 3 && k > q + 1 {
        let half = k.div_ceil(2);
        if let (Some(a), Some(b)) = (orthogonal_array(q, 3, half), orthogonal_array(q, 2, half)) {
            found.push((doubling(&a, &b, half, v), 2 * half));
        }
    }
    found
        .into_iter()
        .map(|(rows, width)| {
            let rows: Vec<u32> = rows.chunks(width).flat_map(|r| r[..k].to_vec()).collect();
            CoveringArray {
                levels: vec![v; k],
                strength: t,
                rows,
            }
        })
        .filter(|a| {
            crate::coverage::kwise_coverage_rows(&a.levels, &a.rows, t, 0)
                .is_ok_and(|c| c.covered == c.total)
        })
        .min_by_key(CoveringArray::len)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covers(rows: &[u32], v: u32, k: usize, t: usize) -> bool {
        let c = crate::coverage::kwise_coverage_rows(&vec![v; k], rows, t, 0).unwrap();
        c.covered == c.total
    }

    #[test]
    fn the_fields_have_no_zero_divisors_and_others_are_refused() {
        for q in [2, 3, 4, 5, 7, 8, 9, 16, 25, 27] {
            let f = Field::new(q).unwrap_or_else(|| panic!("GF({q})"));
            for a in 1..q as u32 {
                assert!(
                    (1..q as u32).any(|b| f.mul(a, b) == 1),
                    "{a} has an inverse in GF({q})"
                );
            }
        }
        for q in [1, 6, 10, 12, 81] {
            assert!(Field::new(q).is_none(), "{q}");
        }
    }

    #[test]
    fn bushs_arrays_hold_every_tuple_exactly_once() {
        for (q, t) in [
            (2, 2),
            (3, 3),
            (4, 2),
            (4, 3),
            (5, 3),
            (5, 4),
            (7, 2),
            (8, 3),
            (9, 2),
        ] {
            let k = q + 1;
            let rows = orthogonal_array(q, t, k).unwrap();
            assert_eq!(rows.len(), q.pow(t as u32) * k);
            assert!(covers(&rows, q as u32, k, t), "OA({q}^{t}; {t}, {k}, {q})");
        }
        assert!(orthogonal_array(6, 2, 3).is_none());
        assert!(orthogonal_array(3, 4, 4).is_none());
        assert!(orthogonal_array(5, 2, 7).is_none());
    }

    #[test]
    fn the_binary_pair_arrays_are_the_smallest_there_are() {
        // CAN(2, k, 2) = the least n with C(n - 1, ceil(n / 2)) >= k: 4 rows up to 3 columns,
        // 5 up to 4, 6 up to 10, 7 up to 15, 8 up to 35.
        for (k, n) in [
            (2, 4),
            (3, 4),
            (4, 5),
            (10, 6),
            (11, 7),
            (15, 7),
            (35, 8),
            (36, 9),
        ] {
            let rows = binary_pairs(k);
            assert_eq!(rows.len() / k, n, "k = {k}");
            assert!(covers(&rows, 2, k, 2), "k = {k}");
        }
    }

    #[test]
    fn the_product_and_the_doubling_cover_their_tuples() {
        let a = orthogonal_array(5, 2, 5).unwrap();
        let p = product(&a, 5, &a, 5);
        assert_eq!(p.len() / 25, 45, "the five constant rows are shared");
        assert!(covers(&p, 5, 25, 2));
        let (a3, b2) = (
            orthogonal_array(5, 3, 5).unwrap(),
            orthogonal_array(5, 2, 5).unwrap(),
        );
        let d = doubling(&a3, &b2, 5, 5);
        assert_eq!(d.len() / 10, 125 + 4 * 25);
        assert!(covers(&d, 5, 10, 3));
        // A doubling over arrays that miss tuples misses tuples: the check is not vacuous.
        assert!(!covers(&doubling(&a3[..100 * 5], &b2, 5, 5), 5, 10, 3));
    }

    #[test]
    fn construct_picks_the_smallest_covering_start() {
        assert_eq!(construct(5, 20, 2).map(|a| a.len()), Some(45));
        assert_eq!(construct(5, 10, 3).map(|a| a.len()), Some(225));
        assert_eq!(construct(5, 6, 4).map(|a| a.len()), Some(625));
        assert_eq!(construct(6, 6, 3), None);
    }
}
