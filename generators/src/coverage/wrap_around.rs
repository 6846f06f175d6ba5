//! The wrap-around discrepancy's pair sum `Σ_i Σ_j P_ij`, `P_ij = Π_k (3/2 − t + t²)`,
//! `t = |x_ik − x_jk|` (Hickernell, "A generalized discrepancy and quadrature error bound",
//! Math. Comp. 67, 1998, eq. 3.8b), with the bits of scipy's loop: one accumulator, `i` outer,
//! `j` inner (all `j`, `j = i` included), each product multiplied in column order. Each
//! product is computed once for both of its places in that sequence, not twice.
//!
//! WD's product is symmetric bit for bit: `|a − b|` and `|b − a|` are the same float (IEEE 754
//! rounds `a − b` and `−(b − a)` alike), so `P_ij` and `P_ji` are the same operations on the
//! same numbers. The sequential sum cannot be split as it stands, but while the running sum
//! `s` stays in one binade `[2^e, 2^(e+1))`, `fl(s + v) = s + round_u(v)` with
//! `u = 2^(e−52)` for `v ≥ 0` that is not a tie (see `ordered_sum.rs`; Goldberg, "What every
//! computer scientist should know about floating-point arithmetic", 1991, §1.2). So when the
//! whole of row `i`'s additions stay in binade `e_i`, the row adds exactly
//! `T_i · u_i`, `T_i = Σ_j round(P_ij / u_i)`: integers, whose sum does not depend on order.
//!
//! The binades are not known before the sum is, so they are predicted:
//! 1. [`predict_binades`] estimates each row's sum from a sample of the points, adds the
//!    estimates up, and names a binade for the rows whose estimated start and end lie well
//!    inside one (a relative margin of [`MARGIN`]); the others are left without one.
//! 2. [`symmetric_units`] computes each unordered pair's product once, in parallel, and adds
//!    its rounded units to both rows' `T` (integer sums, so any thread count gives the same
//!    result), marking a row where one of its terms is a tie.
//! 3. [`assemble`] adds the rows in order: a row whose binade was named, without a tie, whose
//!    start `s` is really in that binade and whose end `s + T_i · u_i` is below the binade's
//!    top adds `T_i · u_i` exactly; any other row's products are computed again in order and
//!    added with [`ordered_sum`]. The terms are positive, so a row that starts and ends in
//!    the binade stayed in it throughout. A wrong prediction costs time, never a bit.
//!
//! Where most rows would have a tie (coarse dyadic grids), [`mostly_ties`] sees it before the
//! symmetric pass, and the caller adds the products as for CD and MD instead.

use rayon::prelude::*;

use super::ordered_sum::{ordered_sum, ROUND};

/// Points per register tile: each tile's products stay in registers over the `d` columns
/// (the AVX-512 symmetric kernel takes 32).
const LANES: usize = 16;
/// Points sampled to estimate each row's sum: 64 of every row's n products, 1.6% of the n²
/// at n = 4000.
const SAMPLES: usize = 64;
/// Relative safety margin around the estimated running sums: a row gets a predicted binade
/// only when `start · (1 − MARGIN)` and `end · (1 + MARGIN)` lie in the same binade.
const MARGIN: f64 = 0.005;
/// Rows whose products are computed at once, in parallel, in [`assemble`].
const BLOCK: usize = 64;

/// `Σ_i Σ_j P_ij` added left to right in scipy's order (see the module docs), for the `n × d`
/// row-major `points` in `[0, 1]` (`d >= 1`; checked by the caller, not here). The same bits on any thread count. `None` when a probe
/// finds the terms so often ties (see [`mostly_ties`]) that most rows would be added again
/// one term at a time: the symmetric pass would be wasted, and the caller is faster adding
/// every product in order.
pub(super) fn wrap_around_pair_sum(points: &[f64], d: usize) -> Option<f64> {
    // The caller (`discrepancy`) checked these: the bounds on the products rely on them.
    debug_assert!(d > 0 && points.len().is_multiple_of(d));
    debug_assert!(points.iter().all(|x| (0.0..=1.0).contains(x)));
    // On one of the pool's threads: each parallel step called from outside the pool would
    // hand its work to the pool and sleep until it is done.
    rayon::scope(|_| {
        let columns = columns(points, d);
        let binades = predict_binades(&columns, MARGIN);
        (!mostly_ties(&columns, &binades)).then(|| sum_with_binades(&columns, &binades).sum)
    })
}

/// The coordinates column by column: `columns[k][j] = x_jk`.
fn columns(points: &[f64], d: usize) -> Vec<Vec<f64>> {
    (0..d)
        .map(|k| points.iter().skip(k).step_by(d).copied().collect())
        .collect()
}

/// WD's factor for one coordinate, `3/2 − |a − b| + |a − b|²`, evaluated left to right as
/// scipy writes it (plain IEEE operations: Rust contracts nothing into a fused multiply-add).
#[inline(always)]
fn factor(a: f64, b: f64) -> f64 {
    let t = (a - b).abs();
    1.5 - t + t * t
}

/// `P_ij` for the point `i` with coordinates `own` and the point `j`, multiplied in column
/// order from 1, as scipy does.
#[inline(always)]
fn product(columns: &[Vec<f64>], own: &[f64], j: usize) -> f64 {
    columns
        .iter()
        .zip(own)
        .fold(1.0, |p, (x, &a)| p * factor(a, x[j]))
}

/// `[P_ij; W]` for `j = start..start + W`: the same operations as [`product`] for each lane,
/// columns outermost so that the compiler keeps the tile in vector registers.
#[inline(always)]
fn tile<const W: usize>(columns: &[Vec<f64>], own: &[f64], start: usize) -> [f64; W] {
    let mut p = [1.0; W];
    for (x, &a) in columns.iter().zip(own) {
        let xs: &[f64; W] = x[start..start + W].try_into().expect("a full tile");
        for l in 0..W {
            p[l] *= factor(a, xs[l]);
        }
    }
    p
}

/// `(bits, gap)` for `q` in `[0, 2^52)`: `bits` is the bit pattern of `q + 2^52`, which is
/// `2^52`'s pattern plus `round(q)` (to nearest, ties to even): adding `2^52` puts `q` where
/// the floats are the integers. `gap = |q − round(q)|` is exact, and `½` exactly when `q` is
/// a tie, which the running sum would round by its own last bit. Summing the patterns and
/// subtracting `2^52`'s once per term at the end, and taking the largest gap, costs fewer
/// operations per term than the integers and a tie flag.
#[inline(always)]
fn round_units(q: f64) -> (u64, f64) {
    let r = q + ROUND;
    (r.to_bits(), (q - (r - ROUND)).abs())
}

/// The larger of `a` and `b`, for the gaps of [`round_units`], which are never NaN: one
/// vector instruction, where `f64::max`'s NaN rule takes three.
#[inline(always)]
fn larger(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// `1/u = 2^(52−e)` for the binade `[2^e, 2^(e+1))` whose biased exponent is `biased`, when
/// its integer sums are safe, else 0 (no prediction). Safe means: `u` is a normal number and
/// the binade's top is finite (`52 < biased < 2046`, as `ordered_sum` asks), and every WD
/// product, at most `bound`, is below `min(2^51, 2^62 / n)` units. Then each term is in the
/// range where [`round_units`] is exact, and a row's `n` terms, each below that many units
/// plus ½, add up to less than `2^62 + n/2 < 2^64`, so the row's units are known exactly from
/// a sum of [`round_units`]'s patterns that wraps around `2^64`, whatever the order.
fn unit_inverse(biased: u64, bound: f64, n: usize) -> f64 {
    if biased <= 52 || biased >= 2046 {
        return 0.0;
    }
    let inverse = f64::from_bits((2098 - biased) << 52); // 2^(1075 − biased): exact
    let limit = (ROUND / 2.0).min(ROUND * 1024.0 / n as f64); // min(2^51, 2^62/n)
    if bound * inverse < limit {
        inverse
    } else {
        0.0
    }
}

/// An upper bound on every WD product in `d` dimensions: each factor is at most `3/2` before
/// rounding (`3/2 − t + t² ≤ 3/2` for `t` in `[0, 1]`), and the `3d` roundings of a product
/// and `powi`'s own (a relative `3d · 2^−53` and `2 log2(d) · 2^−53`) add far less than the
/// 1% allowed here. Infinite when `1.5^d` overflows: then no row is predicted.
fn product_bound(d: usize) -> f64 {
    1.5f64.powi(d.min(i32::MAX as usize) as i32) * 1.01
}

/// For each row, the biased exponent of the binade the running sum is predicted to stay in
/// during that row, or 0 when no binade is predicted. Each row's sum `Σ_j P_ij` is estimated
/// from about [`SAMPLES`] evenly spaced points `j`, scaled up to `n`; the estimates' prefix
/// sums are the running sum at each row's start and end. A row is given the binade only when
/// both, widened by the relative `margin` (`start · (1 − margin)`, `end · (1 + margin)`), lie
/// in it. The estimates may be wrong (at random or on purpose); [`assemble`] checks each row.
fn predict_binades(columns: &[Vec<f64>], margin: f64) -> Vec<u64> {
    let n = columns.first().map_or(0, Vec::len);
    let stride = (n / SAMPLES).max(1);
    let sample: Vec<Vec<f64>> = columns
        .iter()
        .map(|x| x.iter().skip(stride / 2).step_by(stride).copied().collect())
        .collect();
    let scale = n as f64 / sample[0].len().max(1) as f64;
    let estimates: Vec<f64> = (0..n)
        .into_par_iter()
        .map_init(Vec::new, |own: &mut Vec<f64>, i| {
            own.clear();
            own.extend(columns.iter().map(|x| x[i]));
            sampled_sum(&sample, own) * scale
        })
        .collect();
    let mut start = 0.0;
    estimates
        .iter()
        .map(|&e| {
            let end = start + e;
            let (low, high) = (start * (1.0 - margin), end * (1.0 + margin));
            start = end;
            let biased = low.to_bits() >> 52;
            if low > 0.0 && low.is_finite() && high.to_bits() >> 52 == biased {
                biased
            } else {
                0
            }
        })
        .collect()
}

/// Whether the symmetric pass would be wasted: no probed row has a usable prediction, or a
/// row's terms are expected to hold a tie at its predicted binade: the products of
/// about [`SAMPLES`] rows with about [`SAMPLES`] points each, at the row's scale, are ties at
/// a rate of at least `1/n`. A product `P = m · 2^k` (`m` odd) is a tie at one scale only,
/// `u = 2^(k+1)`, so ties are rare for products with full mantissas, and common on coarse
/// grids (all `x` multiples of 1/8 in d = 8: nearly every row has one). Such a row's integer sum is
/// useless and its products are computed again, so a set where most rows have a tie is better
/// added without the symmetric pass.
fn mostly_ties(columns: &[Vec<f64>], binades: &[u64]) -> bool {
    let n = binades.len();
    let stride = (n / SAMPLES).max(1);
    let bound = product_bound(columns.len());
    let (mut probes, mut ties) = (0, 0);
    for i in (stride / 2..n).step_by(stride) {
        let inverse = unit_inverse(binades[i], bound, n);
        if inverse == 0.0 {
            continue;
        }
        let own: Vec<f64> = columns.iter().map(|x| x[i]).collect();
        for j in (0..n).step_by(stride) {
            probes += 1;
            ties += usize::from(round_units(product(columns, &own, j) * inverse).1 == 0.5);
        }
    }
    // No probed row with a usable prediction (products too large for any binade, as when
    // `1.5^d` overflows): the symmetric pass could step no row either.
    probes == 0 || ties * n >= probes
}

/// What [`sum_with_binades`] did: the sum, and how many rows took each way.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Summary {
    /// `Σ_i Σ_j P_ij`, with the bits of scipy's loop.
    sum: f64,
    /// Rows added as one integer step `T_i · u_i`.
    stepped: usize,
    /// Rows whose products were computed again and added in order: no prediction, a tie, or
    /// a prediction that turned out wrong.
    reordered: usize,
}

/// The pair sum, using `binades` (as from [`predict_binades`], any values allowed) to add the
/// rows whose prediction holds as integer steps.
fn sum_with_binades(columns: &[Vec<f64>], binades: &[u64]) -> Summary {
    let n = binades.len();
    let bound = product_bound(columns.len());
    let inverses: Vec<f64> = binades.iter().map(|&b| unit_inverse(b, bound, n)).collect();
    let (units, tied) = symmetric_units(columns, &inverses);
    assemble(columns, binades, &inverses, &units, &tied)
}

/// For every row `i`, `(T_i, tied_i)`: `T_i = Σ_j round(P_ij · inverses[i])` over all `j`,
/// and whether one of these terms is a tie (see [`round_units`]). Rows with
/// `inverses[i] = 0` get meaningless values and are not used. Each pair `i < j` is computed once,
/// for both rows. Wrapping integer sums and maxima only, so the split among threads cannot
/// change the result; [`unit_inverse`] keeps each row's units below `2^64`, so they are the
/// sum of the patterns minus `2^52`'s pattern once per term, modulo `2^64`.
fn symmetric_units(columns: &[Vec<f64>], inverses: &[f64]) -> (Vec<u64>, Vec<bool>) {
    let n = inverses.len();
    let zeros = || (vec![0u64; n], vec![0.0; n]);
    // Row p and row n − 1 − p together: n − 1 pairs per task, whatever p.
    // At most about 4 pieces per thread, each with its two n-long accumulators.
    let min_len = (n.div_ceil(2) / (4 * rayon::current_num_threads())).max(1);
    let (bits, gaps) = (0..n.div_ceil(2))
        .into_par_iter()
        .with_min_len(min_len)
        .fold(
            || (zeros(), Vec::new()),
            |((mut bits, mut gaps), mut own), p| {
                let pair = [p, n - 1 - p];
                // The middle row of an odd n is its own partner.
                let rows = if p == n - 1 - p {
                    &pair[..1]
                } else {
                    &pair[..]
                };
                for &i in rows {
                    own.clear();
                    own.extend(columns.iter().map(|x| x[i]));
                    let (b, g) = symmetric_row(columns, &own, i, inverses, &mut bits, &mut gaps);
                    bits[i] = bits[i].wrapping_add(b);
                    gaps[i] = larger(g, gaps[i]);
                }
                ((bits, gaps), own)
            },
        )
        .map(|(acc, _)| acc)
        .reduce(zeros, |(mut bits, mut gaps), (b, g)| {
            for (a, b) in bits.iter_mut().zip(b) {
                *a = a.wrapping_add(b);
            }
            for (a, b) in gaps.iter_mut().zip(g) {
                *a = larger(b, *a);
            }
            (bits, gaps)
        });
    // Each row got exactly n terms (i from the rows above it, n − i from its own), each with
    // 2^52's pattern added.
    let offset = ROUND.to_bits().wrapping_mul(n as u64);
    let units = bits.iter().map(|b| b.wrapping_sub(offset)).collect();
    (units, gaps.iter().map(|&g| g == 0.5).collect())
}

/// Row `i`'s share of [`symmetric_units`]: for each `j > i`, `P_ij` once, its
/// [`round_units`] at row `i`'s scale summed into the returned `(bits, gap)` (the sum of the
/// patterns and the largest gap) and at row `j`'s scale into `bits[j]`, `gaps[j]`; then the
/// diagonal `P_ii`, for row `i` only (scipy adds it once). Chooses the widest vectors the CPU
/// has; the result is the same.
fn symmetric_row(
    columns: &[Vec<f64>],
    own: &[f64],
    i: usize,
    inverses: &[f64],
    bits: &mut [u64],
    gaps: &mut [f64],
) -> (u64, f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F, checked just above.
        return unsafe { symmetric_row_avx512(columns, own, i, inverses, bits, gaps) };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { symmetric_row_avx2(columns, own, i, inverses, bits, gaps) };
    }
    symmetric_row_portable::<LANES>(columns, own, i, inverses, bits, gaps)
}

/// [`symmetric_row`], compiled with AVX-512F (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn symmetric_row_avx512(
    columns: &[Vec<f64>],
    own: &[f64],
    i: usize,
    inverses: &[f64],
    bits: &mut [u64],
    gaps: &mut [f64],
) -> (u64, f64) {
    // Four 8-lane vectors per tile: with 32 vector registers, more work in flight.
    symmetric_row_portable::<32>(columns, own, i, inverses, bits, gaps)
}

/// [`symmetric_row`], compiled with AVX2 (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn symmetric_row_avx2(
    columns: &[Vec<f64>],
    own: &[f64],
    i: usize,
    inverses: &[f64],
    bits: &mut [u64],
    gaps: &mut [f64],
) -> (u64, f64) {
    symmetric_row_portable::<LANES>(columns, own, i, inverses, bits, gaps)
}

/// [`symmetric_row`]'s body, `W` points per tile: plain IEEE operations in a loop shape the
/// compiler vectorises, inlined into each variant so that it is compiled with that variant's
/// features.
#[inline(always)]
fn symmetric_row_portable<const W: usize>(
    columns: &[Vec<f64>],
    own: &[f64],
    i: usize,
    inverses: &[f64],
    bits: &mut [u64],
    gaps: &mut [f64],
) -> (u64, f64) {
    let n = inverses.len();
    let inverse = inverses[i];
    let mut row_bits = [0u64; W];
    let mut row_gaps = [0.0f64; W];
    let mut start = i + 1;
    while start + W <= n {
        let p = tile::<W>(columns, own, start);
        let lane_inverses: &[f64; W] = inverses[start..start + W].try_into().unwrap();
        let lane_bits: &mut [u64; W] = (&mut bits[start..start + W]).try_into().unwrap();
        let lane_gaps: &mut [f64; W] = (&mut gaps[start..start + W]).try_into().unwrap();
        for l in 0..W {
            let (b, g) = round_units(p[l] * inverse);
            row_bits[l] = row_bits[l].wrapping_add(b);
            row_gaps[l] = larger(g, row_gaps[l]);
            let (b, g) = round_units(p[l] * lane_inverses[l]);
            lane_bits[l] = lane_bits[l].wrapping_add(b);
            lane_gaps[l] = larger(g, lane_gaps[l]);
        }
        start += W;
    }
    let mut sum = row_bits.iter().fold(0u64, |a, &b| a.wrapping_add(b));
    let mut gap = row_gaps.iter().fold(0.0, |a, &b| larger(b, a));
    for j in start..n {
        let p = product(columns, own, j);
        let (b, g) = round_units(p * inverse);
        sum = sum.wrapping_add(b);
        gap = larger(g, gap);
        let (b, g) = round_units(p * inverses[j]);
        bits[j] = bits[j].wrapping_add(b);
        gaps[j] = larger(g, gaps[j]);
    }
    let (b, g) = round_units(product(columns, own, i) * inverse);
    (sum.wrapping_add(b), larger(g, gap))
}

/// `Σ_j P_ij` over the points of `sample` (columns, as [`columns`] gives), in any order: an
/// estimate only. Chooses the widest vectors the CPU has.
fn sampled_sum(sample: &[Vec<f64>], own: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F, checked just above.
        return unsafe { sampled_sum_avx512(sample, own) };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { sampled_sum_avx2(sample, own) };
    }
    sampled_sum_portable(sample, own)
}

/// [`sampled_sum`], compiled with AVX-512F (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn sampled_sum_avx512(sample: &[Vec<f64>], own: &[f64]) -> f64 {
    sampled_sum_portable(sample, own)
}

/// [`sampled_sum`], compiled with AVX2 (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sampled_sum_avx2(sample: &[Vec<f64>], own: &[f64]) -> f64 {
    sampled_sum_portable(sample, own)
}

/// [`sampled_sum`]'s body: plain IEEE operations in a loop shape the compiler vectorises,
/// inlined into each variant so that it is compiled with that variant's features.
#[inline(always)]
fn sampled_sum_portable(sample: &[Vec<f64>], own: &[f64]) -> f64 {
    let m = sample.first().map_or(0, Vec::len);
    let mut lanes = [0.0; LANES];
    let mut start = 0;
    while start + LANES <= m {
        let p: [f64; LANES] = tile(sample, own, start);
        for l in 0..LANES {
            lanes[l] += p[l];
        }
        start += LANES;
    }
    (start..m).fold(lanes.iter().sum(), |s, j| s + product(sample, own, j))
}

/// `out[j] = P_ij` for every `j`, each computed as [`product`] does. Chooses the widest
/// vectors the CPU has; the products are the same.
fn full_row(columns: &[Vec<f64>], i: usize, out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F, checked just above.
        unsafe { full_row_avx512(columns, i, out) };
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        unsafe { full_row_avx2(columns, i, out) };
        return;
    }
    full_row_portable(columns, i, out);
}

/// [`full_row`], compiled with AVX-512F (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn full_row_avx512(columns: &[Vec<f64>], i: usize, out: &mut [f64]) {
    full_row_portable(columns, i, out);
}

/// [`full_row`], compiled with AVX2 (the caller checks that the CPU has it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn full_row_avx2(columns: &[Vec<f64>], i: usize, out: &mut [f64]) {
    full_row_portable(columns, i, out);
}

/// [`full_row`]'s body: plain IEEE operations in a loop shape the compiler vectorises,
/// inlined into each variant so that it is compiled with that variant's features.
#[inline(always)]
fn full_row_portable(columns: &[Vec<f64>], i: usize, out: &mut [f64]) {
    let own: Vec<f64> = columns.iter().map(|x| x[i]).collect();
    let full = out.len() / LANES * LANES;
    let (tiles, rest) = out.split_at_mut(full);
    for (t, chunk) in tiles.chunks_exact_mut(LANES).enumerate() {
        chunk.copy_from_slice(&tile::<LANES>(columns, &own, t * LANES));
    }
    for (j, p) in rest.iter_mut().enumerate() {
        *p = product(columns, &own, full + j);
    }
}

/// `s + T · u` when that is exactly what adding row's terms one at a time to `s` gives: `s`
/// is a positive float in the binade with biased exponent `biased` (which has a normal ulp
/// `u` and a finite top), and `s + T · u` is below the binade's top. Then every partial sum
/// stays in the binade (the terms are positive), where each addition adds its term rounded to
/// a multiple of `u`, which is what `T` counts (ties excluded by the caller). `None`
/// otherwise. The same exact-step argument as `ordered_sum`'s `within_binade`.
fn step(s: f64, biased: u64, units: u64) -> Option<f64> {
    if s.is_nan() || s <= 0.0 || s.to_bits() >> 52 != biased || biased <= 52 || biased >= 2046 {
        return None;
    }
    let ulp = f64::from_bits((biased - 52) << 52);
    let top = f64::from_bits((biased + 1) << 52);
    // `top − s` is exact (Sterbenz: s ≥ top/2) and at most 2^52 ulps. Below 2^53, `units`
    // converts exactly and `step` is exact; from 2^53 on the conversion is monotone, so
    // `step ≥ 2^53 · ulp > top − s` and the row is refused. So `s + step < top` is decided
    // exactly, and then `s + step` is a multiple of `ulp` in the binade: exact too.
    let step = units as f64 * ulp;
    (step < top - s).then_some(s + step)
}

/// Adds the rows in order (see the module docs): each row with a usable prediction as one
/// exact step, every other row's products, computed again, with [`ordered_sum`]. The rows
/// known in advance to need their products (no prediction, or a tie) are computed in
/// parallel blocks of [`BLOCK`]; a row whose prediction fails only here is computed with the
/// [`BLOCK`] − 1 rows after it, in parallel, and those rows use these products when their
/// own step fails too.
fn assemble(
    columns: &[Vec<f64>],
    binades: &[u64],
    inverses: &[f64],
    units: &[u64],
    tied: &[bool],
) -> Summary {
    let n = binades.len();
    let known = |i: usize| inverses[i] == 0.0 || tied[i];
    let mut summary = Summary {
        sum: 0.0,
        stepped: 0,
        reordered: 0,
    };
    let mut buffers = vec![vec![0.0; n]; BLOCK.min(n)];
    // Rows computed after a prediction failed here, and their products.
    let mut spare = vec![vec![0.0; n]; BLOCK.min(n)];
    let mut spare_rows = 0..0;
    let mut next = 0;
    while next < n {
        let rows: Vec<usize> = (next..n).filter(|&i| known(i)).take(BLOCK).collect();
        buffers[..rows.len()]
            .par_iter_mut()
            .zip(&rows)
            .for_each(|(out, &i)| full_row(columns, i, out));
        let end = if rows.len() == BLOCK {
            rows[BLOCK - 1] + 1
        } else {
            n
        };
        let mut computed = rows.iter().zip(&buffers).peekable();
        for i in next..end {
            let s = summary.sum;
            summary.sum = if let Some((_, products)) = computed.next_if(|&(&r, _)| r == i) {
                summary.reordered += 1;
                ordered_sum(s, products)
            } else if let Some(t) = step(s, binades[i], units[i]) {
                summary.stepped += 1;
                t
            } else {
                summary.reordered += 1;
                if !spare_rows.contains(&i) {
                    // One wrong estimate shifts the running estimate of the rows after it:
                    // their predictions tend to fail too, so the next rows are computed
                    // together, in parallel, rather than one at a time.
                    spare_rows = i..(i + BLOCK).min(n);
                    spare[..spare_rows.len()]
                        .par_iter_mut()
                        .zip(spare_rows.clone())
                        .for_each(|(out, r)| full_row(columns, r, out));
                }
                ordered_sum(s, &spare[i - spare_rows.start])
            };
        }
        next = end;
    }
    summary
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The definition: scipy's loop, one accumulator, `i` outer, `j` inner.
    fn plain(points: &[f64], d: usize) -> f64 {
        let n = points.len() / d;
        let mut s = 0.0;
        for i in 0..n {
            for j in 0..n {
                let mut p = 1.0;
                for k in 0..d {
                    let t = (points[i * d + k] - points[j * d + k]).abs();
                    p *= 1.5 - t + t * t;
                }
                s += p;
            }
        }
        s
    }

    fn random(n: usize, d: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n * d).map(|_| rng.random::<f64>()).collect()
    }

    fn halton(n: usize, d: usize) -> Vec<f64> {
        let primes = crate::first_primes(d);
        (0..n as u64)
            .flat_map(|i| {
                primes
                    .iter()
                    .map(move |&q| crate::radical_inverse(i + 1, q))
            })
            .collect()
    }

    /// Values `k/8`: products on a coarse dyadic grid, so that many terms are ties.
    fn dyadic(n: usize, d: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n * d)
            .map(|_| f64::from(rng.random_range(0..=8u8)) / 8.0)
            .collect()
    }

    /// Checks the bits against the definition and returns how the rows were added.
    fn same_bits(points: &[f64], d: usize) -> Summary {
        let columns = columns(points, d);
        let summary = sum_with_binades(&columns, &predict_binades(&columns, MARGIN));
        let expected = plain(points, d);
        assert_eq!(
            summary.sum.to_bits(),
            expected.to_bits(),
            "{:e} against {expected:e}, {summary:?}",
            summary.sum
        );
        if let Some(sum) = wrap_around_pair_sum(points, d) {
            assert_eq!(sum.to_bits(), expected.to_bits());
        }
        summary
    }

    /// The sampled points (indices `stride/2 + k·stride`) far from all the others: every
    /// row's estimate is off, so most predictions fail when the rows are added (found by a
    /// review).
    fn biased_sample(n: usize, d: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let stride = (n / SAMPLES).max(1);
        (0..n)
            .flat_map(|i| {
                let centre = if i % stride == stride / 2 { 0.75 } else { 0.25 };
                (0..d)
                    .map(|_| centre + rng.random_range(-0.01..0.01))
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    #[test]
    fn products_too_large_for_any_prediction_are_left_to_the_caller() {
        // 1.25^1800 overflows: no row can be stepped, so the symmetric pass is not run.
        assert!(wrap_around_pair_sum(&random(70, 1800, 3), 1800).is_none());
        assert!(wrap_around_pair_sum(&random(70, 8, 3), 8).is_some());
    }

    #[test]
    fn failed_predictions_are_added_again_in_blocks_with_the_same_bits() {
        for (n, d) in [(700, 4), (1300, 8)] {
            let summary = same_bits(&biased_sample(n, d, 2), d);
            assert!(summary.reordered > n / 2, "{summary:?}");
        }
    }

    #[test]
    fn random_points_give_the_loops_bits_and_mostly_take_the_step() {
        for (n, d, seed) in [(1000, 8, 1), (1237, 8, 2), (777, 1, 3), (500, 5, 4)] {
            let summary = same_bits(&random(n, d, seed), d);
            assert_eq!(summary.stepped + summary.reordered, n);
            // Most rows are predicted and added as one step (only d = 1's few rows per
            // binade are near a crossing more often).
            assert!(summary.stepped > n * 4 / 5, "{n} × {d}: {summary:?}");
        }
    }

    #[test]
    fn halton_points_give_the_loops_bits() {
        for (n, d) in [(1024, 8), (999, 3), (600, 1)] {
            let summary = same_bits(&halton(n, d), d);
            assert!(summary.stepped > n / 2, "{summary:?}");
        }
    }

    #[test]
    fn tiny_and_ragged_sizes_give_the_loops_bits() {
        for n in [1, 2, 3, 15, 16, 17, 31, 33, 47, 65, 130] {
            for d in [1, 2, 8] {
                same_bits(&random(n, d, n as u64), d);
                same_bits(&halton(n, d), d);
            }
        }
    }

    #[test]
    fn ties_and_repeated_points_give_the_loops_bits() {
        // On the grid k/8 every factor is a multiple of 2^-6 and products have few bits,
        // so terms are often exactly halfway between two multiples of a row's ulp.
        let mut tied = 0;
        for (n, d, seed) in [(700, 1, 5), (700, 2, 6), (900, 3, 7), (400, 8, 8)] {
            let x = dyadic(n, d, seed);
            let columns = columns(&x, d);
            let binades = predict_binades(&columns, MARGIN);
            let inverses: Vec<f64> = binades
                .iter()
                .map(|&b| unit_inverse(b, product_bound(d), n))
                .collect();
            let (_, ties) = symmetric_units(&columns, &inverses);
            tied += ties.iter().filter(|&&t| t).count();
            same_bits(&x, d);
        }
        assert!(
            tied > 100,
            "only {tied} rows with a tie: the test does not test ties"
        );
        // One point repeated, and a few points each repeated many times.
        same_bits(&[0.25, 0.5, 0.75].repeat(600), 3);
        let few = random(7, 4, 9);
        same_bits(&few.repeat(150), 4);
    }

    #[test]
    fn sets_where_most_rows_have_a_tie_are_left_to_the_caller() {
        let (n, d) = (2000, 8);
        let tied_rows = |x: &[f64]| {
            let columns = columns(x, d);
            let binades = predict_binades(&columns, MARGIN);
            let inverses: Vec<f64> = binades
                .iter()
                .map(|&b| unit_inverse(b, product_bound(d), n))
                .collect();
            let tied = symmetric_units(&columns, &inverses).1;
            (
                tied.iter().filter(|&&t| t).count(),
                mostly_ties(&columns, &binades),
            )
        };
        // On the grid k/8 in d = 8, nearly every row has a tie: the probe sees it.
        let grid = dyadic(n, d, 15);
        let (tied, probed) = tied_rows(&grid);
        assert!(tied > n * 9 / 10 && probed, "{tied} {probed}");
        assert_eq!(wrap_around_pair_sum(&grid, d), None);
        let wd = |x: &[f64]| -(4.0f64 / 3.0).powi(8) + 1.0 / (n * n) as f64 * plain(x, d);
        let ours = crate::coverage::discrepancy(&grid, d, crate::coverage::Discrepancy::WrapAround);
        assert_eq!(ours.unwrap().to_bits(), wd(&grid).to_bits());
        // Random and Halton points have a few such rows, and take the symmetric pass.
        for x in [random(n, d, 16), halton(n, d)] {
            let (tied, probed) = tied_rows(&x);
            assert!(tied < n / 100 && !probed, "{tied} {probed}");
            let ours =
                crate::coverage::discrepancy(&x, d, crate::coverage::Discrepancy::WrapAround);
            assert_eq!(ours.unwrap().to_bits(), wd(&x).to_bits());
        }
    }

    #[test]
    fn wrong_predictions_cost_time_not_bits() {
        let d = 8;
        let x = random(900, d, 10);
        let columns = columns(&x, d);
        let expected = plain(&x, d).to_bits();
        let good = predict_binades(&columns, MARGIN);
        // No margin at all: the rows near a binade crossing are predicted, some wrongly.
        let bare = sum_with_binades(&columns, &predict_binades(&columns, 0.0));
        assert_eq!(bare.sum.to_bits(), expected);
        // One binade too high or too low for every third row, or for all of them.
        for shift in [1i64, -1] {
            for every in [1, 3] {
                let wrong: Vec<u64> = good
                    .iter()
                    .enumerate()
                    .map(|(i, &b)| {
                        if i % every == 0 && b != 0 {
                            b.saturating_add_signed(shift)
                        } else {
                            b
                        }
                    })
                    .collect();
                let summary = sum_with_binades(&columns, &wrong);
                assert_eq!(summary.sum.to_bits(), expected, "{shift} every {every}");
                assert!(summary.reordered >= 900 / every - 50, "{summary:?}");
            }
        }
        // Every row given the final binade, or one binade for the first half and one for
        // the second; or out-of-range exponents.
        let last = good.iter().rev().find(|&&b| b != 0).copied().unwrap();
        for wrong in [
            vec![last; 900],
            (0..900).map(|i| last - u64::from(i < 450)).collect(),
            vec![1; 900],
            vec![2045; 900],
            vec![u64::MAX; 900],
        ] {
            let summary = sum_with_binades(&columns, &wrong);
            assert_eq!(summary.sum.to_bits(), expected, "{summary:?}");
        }
    }

    #[test]
    fn rows_that_cross_into_the_next_binade_are_refused() {
        // Each row given the binade its true start is in (from the plain loop): right for
        // most rows, but the rows during which the sum crosses into the next binade must be
        // caught by the test against the binade's top.
        let (n, d) = (900, 8);
        let x = random(n, d, 14);
        let columns = columns(&x, d);
        let mut s = 0.0f64;
        let mut starts = Vec::new();
        for i in 0..n {
            starts.push(s.to_bits() >> 52);
            let own: Vec<f64> = columns.iter().map(|c| c[i]).collect();
            for j in 0..n {
                s += product(&columns, &own, j);
            }
        }
        let crossings = starts.windows(2).filter(|w| w[0] != w[1]).count();
        assert!(crossings >= 10, "{crossings}");
        let summary = sum_with_binades(&columns, &starts);
        assert_eq!(summary.sum.to_bits(), s.to_bits(), "{summary:?}");
        assert!(summary.reordered >= crossings, "{summary:?}");
        assert!(summary.stepped >= n - 2 * crossings - 10, "{summary:?}");
    }

    #[test]
    fn binades_whose_integer_sums_could_wrap_are_refused() {
        // 2^62 / n units per term at most: for n = 4096, 2^50 units, so a product bound of
        // 2^10 allows binades from 2^(10 + 52 − 50) = 2^12 up, exclusive.
        let n = 4096;
        let bound = 1024.0;
        let biased = |e: i64| (e + 1023) as u64;
        assert_eq!(unit_inverse(biased(12), bound, n), 0.0);
        assert_eq!(unit_inverse(biased(13), bound, n), 2f64.powi(52 - 13));
        // For few points, 2^51 units: from 2^(10 + 1) up.
        assert_eq!(unit_inverse(biased(11), bound, 3), 0.0);
        assert_eq!(unit_inverse(biased(12), bound, 3), 2f64.powi(52 - 12));
        // A subnormal ulp, an infinite top, and products that overflow.
        assert_eq!(unit_inverse(52, 1.0, 3), 0.0);
        assert_ne!(unit_inverse(53, 1e-300, 3), 0.0);
        assert_eq!(unit_inverse(2046, 1.0, 3), 0.0);
        assert_eq!(unit_inverse(biased(100), product_bound(2000), 3), 0.0);
    }

    #[test]
    fn same_bits_on_one_thread_and_on_three() {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let three = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        for (x, d) in [(random(1500, 8, 11), 8), (dyadic(801, 2, 12), 2)] {
            let a = one.install(|| wrap_around_pair_sum(&x, d)).unwrap();
            let b = three.install(|| wrap_around_pair_sum(&x, d)).unwrap();
            assert_eq!(a.to_bits(), b.to_bits());
            assert_eq!(a.to_bits(), plain(&x, d).to_bits());
        }
    }

    #[test]
    fn vector_and_portable_kernels_agree() {
        let d = 5;
        let x = random(203, d, 13);
        let columns = columns(&x, d);
        let inverses: Vec<f64> = predict_binades(&columns, MARGIN)
            .iter()
            .map(|&b| unit_inverse(b, product_bound(d), 203))
            .collect();
        let own: Vec<f64> = columns.iter().map(|c| c[7]).collect();
        type Kernel<'a> = &'a dyn Fn(&mut [u64], &mut [f64]) -> (u64, f64);
        let run = |kernel: Kernel| {
            let (mut bits, mut gaps) = (vec![0; 203], vec![0.0; 203]);
            let row = kernel(&mut bits, &mut gaps);
            (row, bits, gaps)
        };
        let portable =
            run(&|u, t| symmetric_row_portable::<LANES>(&columns, &own, 7, &inverses, u, t));
        assert_eq!(
            run(&|u, t| symmetric_row(&columns, &own, 7, &inverses, u, t)),
            portable
        );
        let mut full = vec![0.0; 203];
        full_row(&columns, 7, &mut full);
        let mut reference = vec![0.0; 203];
        full_row_portable(&columns, 7, &mut reference);
        let bits = |v: &[f64]| v.iter().map(|p| p.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&full), bits(&reference));
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2, checked just above.
                let avx2 =
                    run(&|u, t| unsafe { symmetric_row_avx2(&columns, &own, 7, &inverses, u, t) });
                assert_eq!(avx2, portable);
            }
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F, checked just above.
                let avx512 = run(&|u, t| unsafe {
                    symmetric_row_avx512(&columns, &own, 7, &inverses, u, t)
                });
                assert_eq!(avx512, portable);
            }
        }
        // The products themselves are the definition's.
        for (j, p) in reference.iter().enumerate() {
            let mut q = 1.0;
            for k in 0..d {
                let t = (x[7 * d + k] - x[j * d + k]).abs();
                q *= 1.5 - t + t * t;
            }
            assert_eq!(p.to_bits(), q.to_bits());
        }
    }
}
