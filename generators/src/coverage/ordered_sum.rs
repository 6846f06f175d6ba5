//! A left-to-right floating-point sum that gives the bits of `for v in values { s += v }`
//! without waiting for each addition in turn.
//!
//! scipy adds the `n²` products of the CD, WD and MD discrepancies into one accumulator, and
//! these discrepancies are small differences of large sums, so only that exact order
//! reproduces scipy's value to 1e-12. Done naively, the `n²` dependent additions take one
//! addition latency each (about 4 cycles), which bounds the whole computation.
//!
//! The idea: while the running sum `s` stays in one binade `[2^e, 2^(e+1))`, every float
//! there is a multiple of its unit in the last place `u = 2^(e−52)`, so for `v ≥ 0` the
//! rounded sum `fl(s + v)` is exactly `s + round_u(v)`, where `round_u` rounds `v` to the
//! nearest multiple of `u` (IEEE 754 round-to-nearest; Goldberg, "What every computer
//! scientist should know about floating-point arithmetic", 1991, §1.2 on ulps). The rounded
//! terms are integers in units of `u`, and integer addition is associative, so a chunk of
//! terms can be rounded and added in any order, in vector lanes. The shortcut is exact when
//! the chunk keeps `s` inside the binade, every term is `≥ 0`, no term lies exactly halfway
//! between two multiples of `u` (then round-half-to-even would depend on the running sum's
//! last bit). A chunk that breaks any of these is added one term at a time, as before; that
//! happens about once per binade crossed.

/// Values per chunk: the unit of the exact shortcut and of the one-at-a-time fallback.
const CHUNK: usize = 1024;
/// `2^52`: adding then subtracting it rounds a value in `[0, 2^52)` to the nearest integer
/// (ties to even), in the current rounding mode (round-to-nearest).
pub(super) const ROUND: f64 = 4_503_599_627_370_496.0;
/// `2^51` units: a larger term is refused, so a chunk's integer sum stays below
/// `CHUNK · 2^51 = 2^61` and cannot overflow.
const TERM_LIMIT: f64 = 2_251_799_813_685_248.0;

/// `total + values[0] + values[1] + …`, added left to right in IEEE 754 double precision
/// with round-to-nearest: the same bits as the plain loop, for any values (NaN, infinities,
/// negative numbers and zeros included; such chunks take the plain loop).
pub(crate) fn ordered_sum(mut total: f64, values: &[f64]) -> f64 {
    for chunk in values.chunks(CHUNK) {
        total = match within_binade(total, chunk) {
            Some(t) => t,
            None => plain_sum(total, chunk),
        };
    }
    total
}

/// The plain loop: one rounded addition after another.
fn plain_sum(total: f64, values: &[f64]) -> f64 {
    values.iter().fold(total, |s, &v| s + v)
}

/// `Some(fl(…fl(s + v0) + v1 …))` when the shortcut described in the module docs is exact
/// for this chunk, `None` when the chunk must be added one term at a time.
fn within_binade(s: f64, chunk: &[f64]) -> Option<f64> {
    // A positive normal `s` whose ulp is normal too, and whose next binade is finite.
    let biased = s.to_bits() >> 52;
    if s.is_nan() || s <= 0.0 || biased <= 52 || biased >= 2046 {
        return None;
    }
    let ulp = f64::from_bits((biased - 52) << 52);
    let top = f64::from_bits((biased + 1) << 52);
    let per_ulp = 1.0 / ulp; // a power of two: exact
    let (units, exact) = units_of(chunk, per_ulp);
    if !exact {
        return None;
    }
    // `top − s` is exact (both are multiples of `ulp` in `[0, 2^(e+1)]`) and at most
    // `2^e = 2^52 · ulp`. Below 2^52, `units` converts to `f64` exactly and `step` (a
    // power-of-two multiple of it) is exact, so the test is exact and `s + step` stays in the
    // binade, a representable multiple of `ulp`. From 2^52 on, rounding is monotone, so
    // `step ≥ 2^e` and the chunk is refused.
    let step = units as f64 * ulp;
    (step < top - s).then_some(s + step)
}

/// `(Σ round(v · per_ulp), exact)`: the chunk's terms rounded to integers in units of the
/// ulp, summed, and whether every term is in `[0, 2^51)` units (no NaN) and none is a tie. Chooses the widest vectors the CPU has; the result is the same.
fn units_of(chunk: &[f64], per_ulp: f64) -> (u64, bool) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F, checked just above.
        return unsafe { units_of_avx512(chunk, per_ulp) };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { units_of_avx2(chunk, per_ulp) };
    }
    units_of_portable(chunk, per_ulp)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn units_of_avx512(chunk: &[f64], per_ulp: f64) -> (u64, bool) {
    units_of_portable(chunk, per_ulp)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn units_of_avx2(chunk: &[f64], per_ulp: f64) -> (u64, bool) {
    units_of_portable(chunk, per_ulp)
}

#[inline(always)]
fn units_of_portable(chunk: &[f64], per_ulp: f64) -> (u64, bool) {
    // Integer reductions, which the compiler vectorises (a float sum it must keep in order).
    let mut sum = 0u64;
    let mut refused = 0u64;
    for &v in chunk {
        let q = v * per_ulp; // exact: a power-of-two scaling of a normal number
                             // For q in [0, 2^52), q + 2^52 lies in [2^52, 2^53), where floats are the integers:
                             // it is rounded to nearest (ties to even), and its mantissa bits are round(q).
        let r = q + ROUND;
        let k = r - ROUND;
        // `q − k` is exact (|q − k| ≤ ½); ±½ is a tie. The range test also refuses NaN.
        let bad = !(0.0..TERM_LIMIT).contains(&q) | ((q - k).abs() == 0.5);
        refused += u64::from(bad);
        sum = sum.wrapping_add(r.to_bits().wrapping_sub(ROUND.to_bits()));
    }
    (sum, refused == 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn same(total: f64, values: &[f64]) {
        let fast = ordered_sum(total, values);
        let plain = plain_sum(total, values);
        assert_eq!(
            fast.to_bits(),
            plain.to_bits(),
            "{fast:e} against {plain:e} from {total:e}"
        );
    }

    #[test]
    fn discrepancy_sized_sums_take_the_shortcut_and_keep_every_bit() {
        // Products like WD's in d = 8 ([1.25^8, 1.5^8]) over 2^20 terms: the running sum
        // crosses about 20 binades, and most chunks must take the shortcut.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let v: Vec<f64> = (0..1 << 20)
            .map(|_| rng.random_range(5.96..25.63))
            .collect();
        same(0.0, &v);
        let shortcuts = {
            let mut s = 0.0;
            let mut taken = 0;
            for c in v.chunks(CHUNK) {
                s = match within_binade(s, c) {
                    Some(t) => {
                        taken += 1;
                        t
                    }
                    None => plain_sum(s, c),
                };
            }
            taken
        };
        assert!(shortcuts > v.len() / CHUNK * 9 / 10, "{shortcuts}");
    }

    #[test]
    fn ties_zeros_negatives_and_non_finite_values_fall_back() {
        // A running sum of 2^30 has ulp 2^-22: halfway values are ties.
        let big = (1u64 << 30) as f64;
        let half = 2f64.powi(-23);
        let mut v = vec![1.0 + half; 3000];
        same(big, &v);
        same(big + 2f64.powi(-22), &v);
        v[5] = 0.0;
        v[6] = -0.0;
        same(big, &v);
        v[700] = -3.5;
        same(big, &v);
        v[1500] = f64::NAN;
        assert!(ordered_sum(big, &v).is_nan());
        v[1500] = f64::INFINITY;
        same(big, &v);
        // A crossing into the next binade within a chunk, and a start at zero and negative.
        same(big * 2.0 - 10.0, &vec![0.75; 2048]);
        same(0.0, &vec![1e-300; 5000]);
        same(-5.0, &vec![0.1; 5000]);
        // Terms of 2^52 units and more, and sums of 2^52 units and more.
        same(1.0, &vec![1e10; 5000]);
        same(big, &[2f64.powi(29); 3]);
        same(big, &[2f64.powi(26) + 2f64.powi(-20); 16]);
    }

    proptest! {
        #[test]
        fn any_values_give_the_plain_loops_bits(
            start in prop_oneof![Just(0.0), 0.0..1e12, -1e3..1e3],
            scale in prop_oneof![Just(1.0), 1e-6..1e6],
            raw in prop::collection::vec(prop_oneof![0.0..30.0, -1.0..1.0, Just(0.5)], 0..5000),
        ) {
            let values: Vec<f64> = raw.iter().map(|v| v * scale).collect();
            same(start, &values);
        }
    }
}
