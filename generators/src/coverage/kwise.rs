use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::CoverageError;
use crate::{Domain, ParamSpace, Point, Value};

/// The largest strength `t` the estimators accept.
pub const MAX_STRENGTH: usize = 6;

/// One t-tuple that no test covers: `(parameter name, value)` pairs in declaration order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissingTuple {
    /// The tuple's values, by parameter.
    pub values: Vec<(String, Value)>,
}

/// k-wise (t-wise) combinatorial coverage of the discrete parameters at one strength
/// (PARACOSM §3.1; Kuhn, Kacker, Lei, "Introduction to Combinatorial Testing", 2013).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KWiseCoverage {
    /// The strength `t`.
    pub strength: usize,
    /// t-tuples (a choice of `t` parameters and one level for each) that some test covers.
    pub covered: u64,
    /// All t-tuples: `Σ over t-subsets S of Π_{i∈S} v_i`, with `v_i` the level counts; over
    /// a constrained space, those some valid point holds (`forbidden` left out).
    pub total: u64,
    /// Over a constrained space, the t-tuples no valid point holds
    /// ([`crate::ParamSpace::forbidden_levels`]): not counted in `total`, never missing.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub forbidden: u64,
    /// `covered / total` in `[0, 1]` (`1` when there are no tuples).
    pub fraction: f64,
    /// Up to the requested number of uncovered tuples, in lexicographic order of parameter
    /// subsets, then of levels.
    pub missing: Vec<MissingTuple>,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// Every `t`-subset of `0..k`, in lexicographic order (empty unless `1 <= t <= k`).
pub fn subsets(k: usize, t: usize) -> Vec<Vec<usize>> {
    if t == 0 || t > k {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut subset: Vec<usize> = (0..t).collect();
    loop {
        out.push(subset.clone());
        if !next_subset(&mut subset, k, 0) {
            return out;
        }
    }
}

/// `Π_{i∈S} v_i` for every t-subset `S` of the parameters, in lexicographic order of subsets:
/// the number of t-tuples each subset contributes. Empty unless `1 <= t <= levels.len()`.
pub fn subset_products(levels: &[u32], t: usize) -> Vec<f64> {
    let k = levels.len();
    if t == 0 || t > k {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut subset: Vec<usize> = (0..t).collect();
    loop {
        out.push(subset.iter().map(|&c| f64::from(levels[c])).product());
        if !next_subset(&mut subset, k, 0) {
            return out;
        }
    }
}

/// Counts of [`kwise_coverage_rows`]: missing tuples as `(column, level)` pairs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RawKWise {
    /// Covered t-tuples.
    pub covered: u64,
    /// All t-tuples.
    pub total: u64,
    /// Up to `max_missing` uncovered tuples as `(column, level)` pairs, columns increasing.
    pub missing: Vec<Vec<(usize, u32)>>,
}

/// t-wise coverage of the discrete parameters of `points` in `space` at strength `t`,
/// reporting at most `max_missing` uncovered tuples by name and value.
///
/// Exact: every t-subset of parameters gets a bitset over its `Π v_i` level combinations,
/// filled in one pass over the rows. Time `O(C(k, t) · n · t)`, memory one bitset per worker;
/// parallel over subsets with rayon, and deterministic whatever the thread count.
///
/// Over a constrained space ([`ParamSpace::with_constraints`]) only the t-tuples that some
/// valid point holds count: those the constraints forbid are left out of `total` and of the
/// missing ones, and counted in `forbidden` (a `t`-tuple of levels is coverable when it
/// extends to a combination of levels [`ParamSpace::forbidden_levels`] allows).
///
/// # Errors
/// [`CoverageError::Strength`] unless `1 <= t <= min(6, k)` with `k` discrete parameters;
/// [`CoverageError::LevelOutOfRange`] / [`CoverageError::Shape`] for points that do not fit;
/// [`CoverageError::Constraints`] when the forbidden combinations of a constrained space
/// cannot be found.
pub fn kwise_coverage(
    space: &ParamSpace,
    points: &[Point],
    t: usize,
    max_missing: usize,
) -> Result<KWiseCoverage, CoverageError> {
    let discrete: Vec<_> = space.discrete().collect();
    let levels: Vec<u32> = space.level_counts();
    let k = levels.len();
    let mut rows = Vec::with_capacity(points.len() * k);
    for (r, p) in points.iter().enumerate() {
        if p.discrete.len() != k {
            return Err(CoverageError::Shape(format!(
                "row {r} has {} level indices, the space has {k} discrete parameters",
                p.discrete.len()
            )));
        }
        rows.extend_from_slice(&p.discrete);
    }
    let mut raw = kwise_coverage_rows(&levels, &rows, t, max_missing)?;
    let mut forbidden = 0;
    let cons = space
        .forbidden_levels()
        .map_err(|e| CoverageError::Constraints(e.to_string()))?;
    if let Some(cons) = cons.filter(|c| !c.is_empty()) {
        (raw, forbidden) = valid_tuples(&levels, &rows, t, max_missing, &cons);
    }
    let missing = raw
        .missing
        .into_iter()
        .map(|tuple| MissingTuple {
            values: tuple
                .into_iter()
                .map(|(c, l)| {
                    let p = discrete[c];
                    let v = match &p.domain {
                        Domain::Levels(ls) => ls[l as usize].clone(),
                        Domain::Interval { .. } => unreachable!("discrete() yields levels only"),
                    };
                    (p.name.clone(), v)
                })
                .collect(),
        })
        .collect();
    Ok(KWiseCoverage {
        strength: t,
        covered: raw.covered,
        total: raw.total,
        forbidden,
        fraction: if raw.total == 0 {
            1.0
        } else {
            raw.covered as f64 / raw.total as f64
        },
        missing,
    })
}

/// [`kwise_coverage`] on raw data: `levels` has the `k` level counts, `rows` is `n × k`
/// row-major level indices.
///
/// # Errors
/// As [`kwise_coverage`]; [`CoverageError::TooManyTuples`] if the count overflows 64 bits.
pub fn kwise_coverage_rows(
    levels: &[u32],
    rows: &[u32],
    t: usize,
    max_missing: usize,
) -> Result<RawKWise, CoverageError> {
    let k = levels.len();
    let max = MAX_STRENGTH.min(k);
    if t == 0 || t > max {
        return Err(CoverageError::Strength {
            t,
            max,
            discrete: k,
        });
    }
    if !rows.len().is_multiple_of(k) {
        return Err(CoverageError::Shape(format!(
            "{} level indices do not form rows of {k}",
            rows.len()
        )));
    }
    let n = rows.len() / k;
    // Column-major copy: the inner loop walks one column per subset member.
    let mut columns = vec![Vec::with_capacity(n); k];
    for (i, &l) in rows.iter().enumerate() {
        let c = i % k;
        if l >= levels[c] {
            return Err(CoverageError::LevelOutOfRange {
                row: i / k,
                column: c,
                level: l,
                levels: levels[c],
            });
        }
        columns[c].push(l);
    }

    let per_first: Vec<Result<RawKWise, CoverageError>> = (0..=k - t)
        .into_par_iter()
        .map(|first| {
            let mut acc = RawKWise {
                covered: 0,
                total: 0,
                missing: Vec::new(),
            };
            let mut subset: Vec<usize> = (first..first + t).collect();
            let mut bits: Vec<u64> = Vec::new();
            loop {
                cover_subset(levels, &columns, &subset, max_missing, &mut bits, &mut acc)
                    .ok_or(CoverageError::TooManyTuples { t })?;
                if !next_subset(&mut subset, k, 1) {
                    break;
                }
            }
            Ok(acc)
        })
        .collect();

    let mut out = RawKWise {
        covered: 0,
        total: 0,
        missing: Vec::new(),
    };
    for part in per_first {
        let part = part?;
        out.covered += part.covered;
        out.total = out
            .total
            .checked_add(part.total)
            .ok_or(CoverageError::TooManyTuples { t })?;
        let room = max_missing - out.missing.len();
        out.missing.extend(part.missing.into_iter().take(room));
    }
    Ok(out)
}

/// The t-wise coverage of `rows` (`n × k` row-major, levels already checked) counting only the
/// tuples `cons` leaves coverable, and the number of forbidden tuples.
pub(crate) fn valid_tuples(
    levels: &[u32],
    rows: &[u32],
    t: usize,
    max_missing: usize,
    cons: &crate::covering::Constraints,
) -> (RawKWise, u64) {
    let k = levels.len();
    let mut out = RawKWise {
        covered: 0,
        total: 0,
        missing: Vec::new(),
    };
    let mut forbidden = 0;
    for cols in subsets(k, t) {
        let size: usize = cols.iter().map(|&c| levels[c] as usize).product();
        let index = |row: &[u32]| {
            cols.iter()
                .fold(0usize, |a, &c| a * levels[c] as usize + row[c] as usize)
        };
        let mut seen = vec![false; size];
        for row in rows.chunks_exact(k) {
            seen[index(row)] = true;
        }
        for (idx, &s) in seen.iter().enumerate() {
            let mut rest = idx;
            let mut cells = vec![(0usize, 0u32); t];
            for (slot, &c) in cells.iter_mut().zip(&cols).rev() {
                *slot = (c, (rest % levels[c] as usize) as u32);
                rest /= levels[c] as usize;
            }
            if !cons.completable(levels, &cells) {
                forbidden += 1;
                continue;
            }
            out.total += 1;
            if s {
                out.covered += 1;
            } else if out.missing.len() < max_missing {
                out.missing.push(cells);
            }
        }
    }
    (out, forbidden)
}

/// Advances `subset` (increasing indices below `k`) to the next subset in lexicographic order
/// that keeps its first `fixed` elements. Returns false when there is none.
fn next_subset(subset: &mut [usize], k: usize, fixed: usize) -> bool {
    let t = subset.len();
    let mut i = t;
    while i > fixed {
        i -= 1;
        if subset[i] < k - (t - i) {
            subset[i] += 1;
            for j in i + 1..t {
                subset[j] = subset[j - 1] + 1;
            }
            return true;
        }
    }
    false
}

/// Marks the level combinations of `subset` seen in the rows; adds the counts and up to
/// `max_missing` missing tuples to `acc`. `None` on overflow.
fn cover_subset(
    levels: &[u32],
    columns: &[Vec<u32>],
    subset: &[usize],
    max_missing: usize,
    bits: &mut Vec<u64>,
    acc: &mut RawKWise,
) -> Option<()> {
    // Mixed radix: the last member varies fastest.
    let mut strides = vec![0u64; subset.len()];
    let mut size: u64 = 1;
    for (i, &c) in subset.iter().enumerate().rev() {
        strides[i] = size;
        size = size.checked_mul(u64::from(levels[c]))?;
    }
    // Each row's combination index, one subset member at a time (a vectorisable loop).
    let n = columns.first().map_or(0, Vec::len);
    let mut index = vec![0u64; n];
    for (i, &c) in subset.iter().enumerate() {
        for (slot, &l) in index.iter_mut().zip(&columns[c]) {
            *slot += u64::from(l) * strides[i];
        }
    }
    acc.total = acc.total.checked_add(size)?;
    let tuple = |idx: u64| -> Vec<(usize, u32)> {
        subset
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, ((idx / strides[i]) % u64::from(levels[c])) as u32))
            .collect()
    };
    // A bitset of the subset's tuples while it is small beside the rows; past that (levels of
    // 2^20 make 2^40 pairs, a 137 GB bitset), the rows' sorted distinct indices: the same
    // counts and the same first missing tuples, in memory proportional to the rows.
    if size <= 64 * (n as u64).max(1 << 16) {
        let words = usize::try_from(size.div_ceil(64)).ok()?;
        bits.clear();
        bits.resize(words, 0);
        for idx in index {
            bits[(idx / 64) as usize] |= 1 << (idx % 64);
        }
        let covered: u64 = bits.iter().map(|w| u64::from(w.count_ones())).sum();
        acc.covered += covered;
        if acc.missing.len() < max_missing && covered < size {
            for idx in 0..size {
                if bits[(idx / 64) as usize] & (1 << (idx % 64)) == 0 {
                    acc.missing.push(tuple(idx));
                    if acc.missing.len() == max_missing {
                        break;
                    }
                }
            }
        }
    } else {
        index.sort_unstable();
        index.dedup();
        let covered = index.len() as u64;
        acc.covered += covered;
        // The smallest indices no row holds: walk up from 0, skipping the rows' own.
        let mut held = index.iter().peekable();
        let mut idx = 0u64;
        while acc.missing.len() < max_missing && idx < size {
            if held.next_if_eq(&&idx).is_none() {
                acc.missing.push(tuple(idx));
            }
            idx += 1;
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Param;
    use proptest::prelude::*;

    /// Brute force: enumerate every t-subset and every level combination, scan all rows.
    fn brute(levels: &[u32], rows: &[Vec<u32>], t: usize) -> (u64, u64) {
        let k = levels.len();
        let mut covered = 0;
        let mut total = 0;
        let mut subset: Vec<usize> = (0..t).collect();
        loop {
            let combos: u64 = subset.iter().map(|&c| u64::from(levels[c])).product();
            total += combos;
            for idx in 0..combos {
                let mut rest = idx;
                let mut want = vec![0u32; t];
                for i in (0..t).rev() {
                    want[i] = (rest % u64::from(levels[subset[i]])) as u32;
                    rest /= u64::from(levels[subset[i]]);
                }
                if rows
                    .iter()
                    .any(|r| subset.iter().zip(&want).all(|(&c, &w)| r[c] == w))
                {
                    covered += 1;
                }
            }
            // next subset, any first element
            let mut i = t;
            loop {
                if i == 0 {
                    return (covered, total);
                }
                i -= 1;
                if subset[i] < k - (t - i) {
                    subset[i] += 1;
                    for j in i + 1..t {
                        subset[j] = subset[j - 1] + 1;
                    }
                    break;
                }
            }
        }
    }

    #[test]
    fn a_known_pairwise_array_covers_every_pair() {
        // The L4(2^3) orthogonal array covers all 12 pairs of 3 binary factors.
        let rows = [0, 0, 0, 0, 1, 1, 1, 0, 1, 1, 1, 0];
        let c = kwise_coverage_rows(&[2, 2, 2], &rows, 2, 10).unwrap();
        assert_eq!((c.covered, c.total), (12, 12));
        assert!(c.missing.is_empty());
        let c3 = kwise_coverage_rows(&[2, 2, 2], &rows, 3, 2).unwrap();
        assert_eq!((c3.covered, c3.total), (4, 8));
        // (0,0,1) is the first of the missing triples.
        assert_eq!(c3.missing[0], vec![(0, 0), (1, 0), (2, 1)]);
        assert_eq!(c3.missing.len(), 2);
    }

    #[test]
    fn missing_tuples_are_named_by_parameter_and_value() {
        let space = ParamSpace::new(vec![
            Param::levels("lanes", vec![Value::Int(2), Value::Int(4)]),
            Param::interval("fog", 0.0, 1.0, "1"),
            Param::levels(
                "colour",
                vec![Value::Text("red".into()), Value::Text("white".into())],
            ),
        ])
        .unwrap();
        let pts = vec![
            Point {
                discrete: vec![0, 0],
                continuous: vec![0.1],
            },
            Point {
                discrete: vec![1, 1],
                continuous: vec![0.2],
            },
        ];
        let c = kwise_coverage(&space, &pts, 2, 5).unwrap();
        assert_eq!((c.covered, c.total), (2, 4));
        assert_eq!(c.fraction, 0.5);
        assert_eq!(
            c.missing[0].values,
            vec![
                ("lanes".to_owned(), Value::Int(2)),
                ("colour".to_owned(), Value::Text("white".into()))
            ]
        );
        let one = kwise_coverage(&space, &pts, 1, 5).unwrap();
        assert_eq!((one.covered, one.total), (4, 4));
    }

    #[test]
    fn columns_with_many_levels_count_the_rows_distinct_tuples() {
        // 3,000 × 3,000 pairs: past the bitset's limit for 500 rows, so the sorted path runs.
        // Its counts and first missing tuples are those of a set of the rows' pairs.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let levels = [3000u32, 3000, 2];
        let mut rows = Vec::new();
        for i in 0..500u32 {
            // Repeats, and the first few combinations held, so that missing ones are skipped.
            let r = if i < 40 {
                [0, i / 2, i % 2]
            } else {
                [
                    rng.random_range(0..3000),
                    rng.random_range(0..3000),
                    rng.random_range(0..2),
                ]
            };
            rows.extend(r);
        }
        let got = kwise_coverage_rows(&levels, &rows, 2, 30).unwrap();
        let mut covered = 0u64;
        let mut missing = Vec::new();
        for (a, b) in [(0usize, 1usize), (0, 2), (1, 2)] {
            let held: std::collections::HashSet<(u32, u32)> =
                rows.chunks_exact(3).map(|r| (r[a], r[b])).collect();
            covered += held.len() as u64;
            for x in 0..levels[a] {
                for y in 0..levels[b] {
                    if missing.len() < 30 && !held.contains(&(x, y)) {
                        missing.push(vec![(a, x), (b, y)]);
                    }
                }
            }
        }
        assert_eq!(got.covered, covered);
        assert_eq!(got.total, 3000 * 3000 + 2 * 3000 * 2);
        assert_eq!(got.missing, missing);
        assert_eq!(got.missing[0], vec![(0, 0), (1, 20)]);
    }

    #[test]
    fn subset_products_list_every_subset() {
        assert_eq!(subset_products(&[2, 3, 4], 2), [6.0, 8.0, 12.0]);
        assert_eq!(subset_products(&[2, 3, 4], 3), [24.0]);
        assert!(subset_products(&[2, 3], 3).is_empty());
    }

    #[test]
    fn bad_strengths_and_levels_are_errors() {
        assert!(matches!(
            kwise_coverage_rows(&[2, 2], &[0, 0], 3, 0),
            Err(CoverageError::Strength { t: 3, max: 2, .. })
        ));
        assert!(kwise_coverage_rows(&[2, 2], &[0, 0], 0, 0).is_err());
        assert_eq!(
            kwise_coverage_rows(&[2, 2], &[0, 0, 1, 2], 1, 0),
            Err(CoverageError::LevelOutOfRange {
                row: 1,
                column: 1,
                level: 2,
                levels: 2
            })
        );
    }

    proptest! {
        #[test]
        fn matches_brute_force(
            levels in prop::collection::vec(1u32..4, 1..6),
            seed_rows in prop::collection::vec(prop::collection::vec(0u32..100, 6), 0..12),
            t in 1usize..4,
        ) {
            let k = levels.len();
            prop_assume!(t <= k);
            let rows: Vec<Vec<u32>> = seed_rows
                .iter()
                .map(|r| (0..k).map(|c| r[c] % levels[c]).collect())
                .collect();
            let flat: Vec<u32> = rows.concat();
            let fast = kwise_coverage_rows(&levels, &flat, t, usize::MAX).unwrap();
            let (covered, total) = brute(&levels, &rows, t);
            prop_assert_eq!((fast.covered, fast.total), (covered, total));
            prop_assert_eq!(fast.missing.len() as u64, total - covered);
        }
    }
}
