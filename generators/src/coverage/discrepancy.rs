use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::error::reserve_working;
use super::ordered_sum::ordered_sum;
use super::wrap_around::wrap_around_pair_sum;
use super::{check_unit_points, CoverageError};

/// The L2-type discrepancies of `scipy.stats.qmc.discrepancy`, with scipy's conventions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Discrepancy {
    /// Centered L2 discrepancy, squared (Hickernell, "A generalized discrepancy and quadrature
    /// error bound", Math. Comp. 67, 1998, eq. 3.7c):
    /// `CD² = (13/12)^d − 2/n Σ_i Π_k (1 + ½|z_ik| − ½ z_ik²)
    ///        + 1/n² Σ_i Σ_j Π_k (1 + ½|z_ik| + ½|z_jk| − ½|x_ik − x_jk|)`, `z = x − ½`.
    Centered,
    /// Wrap-around L2 discrepancy, squared (Hickernell 1998, eq. 3.8b):
    /// `WD² = −(4/3)^d + 1/n² Σ_i Σ_j Π_k (3/2 − |x_ik − x_jk| (1 − |x_ik − x_jk|))`.
    WrapAround,
    /// Mixture discrepancy, squared (Zhou, Fang, Ning, "Mixture discrepancy for quasi-random
    /// point sets", J. Complexity 29, 2013, eq. 4.1):
    /// `MD² = (19/12)^d − 2/n Σ_i Π_k (5/3 − ¼|z_ik| − ¼ z_ik²)
    ///        + 1/n² Σ_i Σ_j Π_k (15/8 − ¼|z_ik| − ¼|z_jk| − ¾|x_ik − x_jk| + ½|x_ik − x_jk|²)`.
    Mixture,
    /// L2-star discrepancy, square-rooted (Warnock's formula; Warnock, "Computational
    /// investigations of low-discrepancy point sets", 1972):
    /// `L2* = sqrt(3^−d − 2^(1−d)/n Σ_i Π_k (1 − x_ik²) + 1/n² Σ_i Σ_j Π_k (1 − max(x_ik, x_jk)))`.
    L2Star,
}

impl Discrepancy {
    /// Every kind, in the order of the CLI's `--metrics` names `cd, wd, md, l2star`.
    pub const ALL: [Discrepancy; 4] = [
        Discrepancy::Centered,
        Discrepancy::WrapAround,
        Discrepancy::Mixture,
        Discrepancy::L2Star,
    ];

    /// Short name: `cd`, `wd`, `md`, `l2star`.
    pub fn name(self) -> &'static str {
        match self {
            Discrepancy::Centered => "cd",
            Discrepancy::WrapAround => "wd",
            Discrepancy::Mixture => "md",
            Discrepancy::L2Star => "l2star",
        }
    }
}

/// The discrepancy `kind` of `points` (`n × d`, row-major, values in `[0, 1]`), equal to
/// `scipy.stats.qmc.discrepancy(points, method=...)` bit for bit (checked against fixtures
/// made by scipy 1.17, `tests/scipy_discrepancy.rs`): CD, WD and MD are returned **squared**, L2-star
/// **square-rooted**, as scipy does. Formulas on [`Discrepancy`].
///
/// `O(d · n²)` time, `O(n · threads)` memory (WD keeps two `n`-long accumulators per piece of rayon's split). Products are computed in parallel (rayon), sums in
/// scipy's order, so the result is bit-identical on any thread count. WD's products are
/// symmetric, so each is computed once for its two places in that order (`wrap_around.rs`).
///
/// # Errors
/// [`CoverageError::Shape`] for `d = 0`, a ragged length or `n = 0`;
/// [`CoverageError::OutsideUnitCube`] for NaN or a value outside `[0, 1]`;
/// [`CoverageError::OutOfMemory`] when the pair sums' buffers (about `(2d + 130) × 8` bytes a
/// point) cannot be allocated.
pub fn discrepancy(points: &[f64], d: usize, kind: Discrepancy) -> Result<f64, CoverageError> {
    let n = check_unit_points(points, d)?;
    if n == 0 {
        return Err(CoverageError::Shape("the point set is empty".into()));
    }
    // The pair sums' columns (two of n per dimension) and two blocks of 64 rows of n.
    let per_point = (2 * d).saturating_add(130).saturating_mul(8);
    reserve_working("the discrepancy", n, d, per_point)?;
    let nf = n as f64;
    let df = d as f64;
    Ok(match kind {
        Discrepancy::Centered => {
            let s1 = single_sum(points, d, |x| {
                let z = (x - 0.5).abs();
                1.0 + 0.5 * z - 0.5 * z.powi(2)
            });
            // scipy: 1 + 0.5|a - 0.5| + 0.5|b - 0.5| - 0.5|a - b|, left to right.
            let s2 = pair_sum(
                points,
                d,
                Order::Flat,
                |a| 1.0 + 0.5 * (a - 0.5).abs(),
                |b| 0.5 * (b - 0.5).abs(),
                |ra, a, cb, b| ra + cb - 0.5 * (a - b).abs(),
            );
            (13.0f64 / 12.0).powf(df) - 2.0 / nf * s1 + 1.0 / (nf * nf) * s2
        }
        Discrepancy::WrapAround => {
            // scipy's loop, each symmetric product computed once (wrap_around.rs), unless
            // its terms are too often ties for that: then each product twice, here.
            let s = wrap_around_pair_sum(points, d).unwrap_or_else(|| {
                pair_sum(
                    points,
                    d,
                    Order::Flat,
                    |_| 0.0,
                    |_| 0.0,
                    |_, a, _, b| {
                        let t = (a - b).abs();
                        // scipy: 3/2 - |a - b| + |a - b|², left to right.
                        1.5 - t + t * t
                    },
                )
            });
            -(4.0f64 / 3.0).powf(df) + 1.0 / (nf * nf) * s
        }
        Discrepancy::Mixture => {
            let s1 = single_sum(points, d, |x| {
                let z = (x - 0.5).abs();
                5.0 / 3.0 - 0.25 * z - 0.25 * z.powi(2)
            });
            // scipy: 15/8 - 0.25|a - 0.5| - 0.25|b - 0.5| - 3/4|a - b| + 0.5|a - b|², left to right.
            let s2 = pair_sum(
                points,
                d,
                Order::Flat,
                |a| 15.0 / 8.0 - 0.25 * (a - 0.5).abs(),
                |b| 0.25 * (b - 0.5).abs(),
                |ra, a, cb, b| {
                    let t = (a - b).abs();
                    ra - cb - 0.75 * t + 0.5 * t.powi(2)
                },
            );
            (19.0f64 / 12.0).powf(df) - 2.0 / nf * s1 + 1.0 / (nf * nf) * s2
        }
        Discrepancy::L2Star => {
            let s1 = single_sum(points, d, |x| 1.0 - x.powi(2));
            let s2 = pair_sum(
                points,
                d,
                Order::ByRow,
                |_| 0.0,
                |_| 0.0,
                |_, a, _, b| 1.0 - a.max(b),
            );
            let one_div_n = 1.0 / nf;
            (3.0f64.powf(-df) - one_div_n * 2.0f64.powf(1.0 - df) * s1 + 1.0 / (nf * nf) * s2)
                .max(0.0)
                .sqrt()
        }
    })
}

/// `acc[j] *= Π_k term(row(x_ik), x_ik, col(x_jk), x_jk)` for every `j`: the inner kernel.
///
/// On x86-64 the same code is compiled twice more, with 8-wide (AVX-512F) and 4-wide (AVX2)
/// vectors, and the widest the CPU has is chosen at run time. Only plain IEEE operations are involved (no fused multiply-add), so both
/// versions give the same bits.
fn row_products<R, T>(
    acc: &mut [f64],
    columns: &[(Vec<f64>, Vec<f64>)],
    i: usize,
    row: &R,
    term: &T,
) where
    R: Fn(f64) -> f64,
    T: Fn(f64, f64, f64, f64) -> f64,
{
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F, checked just above.
        unsafe { row_products_avx512(acc, columns, i, row, term) };
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        unsafe { row_products_avx2(acc, columns, i, row, term) };
        return;
    }
    row_products_portable(acc, columns, i, row, term);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn row_products_avx512<R, T>(
    acc: &mut [f64],
    columns: &[(Vec<f64>, Vec<f64>)],
    i: usize,
    row: &R,
    term: &T,
) where
    R: Fn(f64) -> f64,
    T: Fn(f64, f64, f64, f64) -> f64,
{
    row_products_portable(acc, columns, i, row, term);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_products_avx2<R, T>(
    acc: &mut [f64],
    columns: &[(Vec<f64>, Vec<f64>)],
    i: usize,
    row: &R,
    term: &T,
) where
    R: Fn(f64) -> f64,
    T: Fn(f64, f64, f64, f64) -> f64,
{
    row_products_portable(acc, columns, i, row, term);
}

#[inline(always)]
fn row_products_portable<R, T>(
    acc: &mut [f64],
    columns: &[(Vec<f64>, Vec<f64>)],
    i: usize,
    row: &R,
    term: &T,
) where
    R: Fn(f64) -> f64,
    T: Fn(f64, f64, f64, f64) -> f64,
{
    // Tiles of LANES points: each tile's products stay in registers over the d columns,
    // instead of a pass over `acc` per column. Each product is still multiplied in column
    // order, so the bits do not change.
    const LANES: usize = 16;
    let own: Vec<(f64, f64)> = columns.iter().map(|(x, _)| (x[i], row(x[i]))).collect();
    let full = acc.len() / LANES * LANES;
    let (tiles, rest) = acc.split_at_mut(full);
    for (t, tile) in tiles.chunks_exact_mut(LANES).enumerate() {
        let start = t * LANES;
        let mut p = [0.0; LANES];
        p.copy_from_slice(tile);
        for ((x, c), &(a, ra)) in columns.iter().zip(&own) {
            let xs: &[f64; LANES] = x[start..start + LANES].try_into().expect("a full tile");
            let cs: &[f64; LANES] = c[start..start + LANES].try_into().expect("a full tile");
            for l in 0..LANES {
                p[l] *= term(ra, a, cs[l], xs[l]);
            }
        }
        tile.copy_from_slice(&p);
    }
    for ((x, c), &(a, ra)) in columns.iter().zip(&own) {
        for ((p, &b), &cb) in rest.iter_mut().zip(&x[full..]).zip(&c[full..]) {
            *p *= term(ra, a, cb, b);
        }
    }
}

/// `Σ_i Π_k f(x_ik)`, in row order.
fn single_sum(points: &[f64], d: usize, f: impl Fn(f64) -> f64) -> f64 {
    points
        .chunks_exact(d)
        .map(|r| r.iter().map(|&a| f(a)).product::<f64>())
        .sum()
}

/// How [`pair_sum`] adds the products, following scipy's code for each discrepancy.
#[derive(Clone, Copy, PartialEq)]
enum Order {
    /// One accumulator over `i`, then `j` (scipy's CD and MD loops; its WD loop too, which
    /// `wrap_around.rs` computes with half the products).
    Flat,
    /// A sum per row `i`, then the rows added in order (scipy's L2-star loop).
    ByRow,
}

/// `Σ_i Σ_j Π_k term(row(x_ik), x_ik, col(x_jk), x_jk)`, added in scipy's order (`order`).
/// `row` and `col` precompute the parts of the term that depend on one point only; they must
/// reproduce scipy's left-to-right evaluation exactly.
///
/// These discrepancies are small differences of large sums, so the summation order shows in
/// the tenth digit; keeping scipy's order is what makes the results equal scipy's. The
/// products of a block of rows are computed in parallel on columns (a slice loop the compiler
/// vectorises) while the previous block is being added, and the additions always run in the
/// same sequence (`Order::Flat` through [`ordered_sum`], which gives the plain loop's bits
/// several additions at a time), so the result does not depend on the thread count.
fn pair_sum(
    points: &[f64],
    d: usize,
    order: Order,
    row: impl Fn(f64) -> f64 + Sync,
    col: impl Fn(f64) -> f64 + Sync,
    term: impl Fn(f64, f64, f64, f64) -> f64 + Sync,
) -> f64 {
    const BLOCK: usize = 64;
    let n = points.len() / d;
    let columns: Vec<(Vec<f64>, Vec<f64>)> = (0..d)
        .map(|k| {
            let x: Vec<f64> = points.iter().skip(k).step_by(d).copied().collect();
            let c = x.iter().map(|&v| col(v)).collect();
            (x, c)
        })
        .collect();
    let compute = |start: usize, buf: &mut Vec<Vec<f64>>| {
        let rows = (n - start).min(BLOCK);
        buf[..rows].par_iter_mut().enumerate().for_each(|(r, acc)| {
            let i = start + r;
            acc.fill(1.0);
            row_products(acc, &columns, i, &row, &term);
        });
        rows
    };
    // The same additions in the same order as scipy's one accumulator, without waiting for
    // each in turn.
    let add = |buf: &[Vec<f64>], total: &mut f64| {
        for acc in buf {
            *total = ordered_sum(*total, acc);
        }
    };
    if order == Order::ByRow {
        // Row sums are independent: compute them all in parallel, add them in row order.
        let sums: Vec<f64> = (0..n)
            .into_par_iter()
            .map_init(Vec::new, |acc: &mut Vec<f64>, i| {
                acc.clear();
                acc.resize(n, 1.0);
                row_products(acc, &columns, i, &row, &term);
                // Each row's sum starts at zero and crosses a binade every few hundred
                // terms, where `ordered_sum` would add each chunk twice: the plain loop.
                acc.iter().fold(0.0, |s, &v| s + v)
            })
            .collect();
        let mut total = 0.0;
        for s in sums {
            total += s;
        }
        return total;
    }
    // The whole pipeline runs on one of the pool's threads: a `join` called from outside the
    // pool would hand each block to the pool and wait for it, sleeping and waking every time.
    rayon::scope(|_| {
        let mut current = vec![vec![0.0; n]; BLOCK.min(n).max(1)];
        let mut next = current.clone();
        let mut total = 0.0;
        let mut rows = if n > 0 { compute(0, &mut current) } else { 0 };
        let mut start = 0;
        while rows > 0 {
            let next_start = start + rows;
            let (next_rows, ()) = rayon::join(
                || {
                    if next_start < n {
                        compute(next_start, &mut next)
                    } else {
                        0
                    }
                },
                || add(&current[..rows], &mut total),
            );
            std::mem::swap(&mut current, &mut next);
            rows = next_rows;
            start = next_start;
        }
        total
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_centred_point_matches_the_closed_forms() {
        // Values scipy gives for the single point x = 0.5 in d = 1.
        let p = [0.5];
        let close = |a: f64, b: f64| (a - b).abs() < 1e-15;
        assert!(close(
            discrepancy(&p, 1, Discrepancy::Centered).unwrap(),
            1.0 / 12.0
        ));
        assert!(close(
            discrepancy(&p, 1, Discrepancy::WrapAround).unwrap(),
            1.0 / 6.0
        ));
        assert!(close(
            discrepancy(&p, 1, Discrepancy::Mixture).unwrap(),
            0.125
        ));
        assert!(close(
            discrepancy(&p, 1, Discrepancy::L2Star).unwrap(),
            (1.0f64 / 12.0).sqrt()
        ));
    }

    fn sample(n: usize, d: usize) -> Vec<f64> {
        // A fixed irrational-rotation lattice: deterministic, no RNG needed.
        (0..n * d)
            .map(|k| ((k as f64 + 1.0) * 0.754_877_666_246_692_7).fract())
            .collect()
    }

    #[test]
    fn same_bits_on_one_thread_and_on_many() {
        let x = sample(300, 5);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let three = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        for k in Discrepancy::ALL {
            let a = one.install(|| discrepancy(&x, 5, k).unwrap());
            let b = three.install(|| discrepancy(&x, 5, k).unwrap());
            assert_eq!(a.to_bits(), b.to_bits(), "{}", k.name());
        }
    }

    #[test]
    fn vector_and_portable_kernels_agree_bit_for_bit() {
        let x = sample(97, 3);
        let columns: Vec<(Vec<f64>, Vec<f64>)> = (0..3)
            .map(|k| {
                let c: Vec<f64> = x.iter().skip(k).step_by(3).copied().collect();
                let z = c.iter().map(|v| 0.5 * (v - 0.5).abs()).collect();
                (c, z)
            })
            .collect();
        let row = |a: f64| 1.0 + 0.5 * (a - 0.5).abs();
        let term = |ra: f64, a: f64, cb: f64, b: f64| ra + cb - 0.5 * (a - b).abs();
        for i in [0, 50, 96] {
            let mut fast = vec![1.0; 97];
            let mut plain = vec![1.0; 97];
            row_products(&mut fast, &columns, i, &row, &term);
            row_products_portable(&mut plain, &columns, i, &row, &term);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&plain));
            // The tiled kernel against the definition, one point at a time, columns in order
            // (97 points: six full tiles of 16 and a remainder of 1).
            let definition: Vec<f64> = (0..97)
                .map(|j| {
                    let mut p = 1.0;
                    for (x, c) in &columns {
                        p *= term(row(x[i]), x[i], c[j], x[j]);
                    }
                    p
                })
                .collect();
            assert_eq!(bits(&plain), bits(&definition));
            // Each vector width the CPU has, not only the one chosen.
            #[cfg(target_arch = "x86_64")]
            for (wide, kernel) in [
                (
                    std::arch::is_x86_feature_detected!("avx2"),
                    row_products_avx2::<_, _> as unsafe fn(&mut [f64], _, _, &_, &_),
                ),
                (
                    std::arch::is_x86_feature_detected!("avx512f"),
                    row_products_avx512::<_, _>,
                ),
            ] {
                if wide {
                    let mut v = vec![1.0; 97];
                    // SAFETY: the CPU has the kernel's feature, checked in `wide`.
                    unsafe { kernel(&mut v, &columns, i, &row, &term) };
                    assert_eq!(bits(&v), bits(&plain));
                }
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(discrepancy(&[], 2, Discrepancy::Centered).is_err());
        assert!(discrepancy(&[0.1, 0.2, 0.3], 2, Discrepancy::Centered).is_err());
        assert!(matches!(
            discrepancy(&[0.1, 0.2, 0.3, f64::NAN], 2, Discrepancy::Mixture),
            Err(CoverageError::OutsideUnitCube {
                row: 1,
                column: 1,
                ..
            })
        ));
    }
}
