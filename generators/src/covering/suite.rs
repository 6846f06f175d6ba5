use crate::{Generator, GeneratorError, Halton, ParamSpace, Point};

use super::{ipog_with, random_kwise_rows, CoveringError};
use super::{random::draw_until_covered, Constraints};

/// How the discrete half of a [`CoveringSuite`] is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayKind {
    /// [`super::ipog`].
    Ipog,
    /// [`super::random_kwise_covering`] with δ = 0.01: Proposition 3.2's draws, then on
    /// until every t-tuple is covered.
    RandomKWise,
}

/// A (k, ε)-covering test suite for a mixed space (PARACOSM §3.2): a t-wise covering array
/// over the discrete parameters and, for each of its rows, a block of Halton points over the
/// continuous ones.
///
/// Row `r`'s block is Halton indices `r · m .. (r + 1) · m` (disjoint ranges, so no two blocks
/// repeat each other) with `m` points per row. Points come out interleaved, block position
/// major and row minor (row 0 point 0, row 1 point 0, ..., row 0 point 1, ...), so any prefix
/// of at least `rows` points covers every t-tuple and spreads evenly over the rows.
///
/// Over a constrained space each row takes the next of its Halton points that is valid with
/// its levels, so every round of `rows` points still gives each row a valid test.
#[derive(Debug, Clone)]
pub struct CoveringSuite {
    rows: Vec<Vec<u32>>,
    per_row: u64,
    /// Halton over the continuous coordinates only.
    halton: Halton,
    next: u64,
    name: &'static str,
    /// The space when it is constrained: its invalid points are passed over.
    constrained: Option<ParamSpace>,
    /// Per row, how many of its Halton points it has used.
    used: Vec<u64>,
    /// The stride of a row's points past the blocks: the least prime at least the number of
    /// rows that is no Halton base, so that the leaped sequence still fills the cube (a stride
    /// sharing a factor with a base fixes that coordinate's first digits; Kocis and Whiten,
    /// "Computational investigations of low-discrepancy sequences", ACM TOMS 23, 1997).
    leap: u64,
}

/// The least prime `p ≥ at_least` that is not among the first `bases` primes.
fn leap_prime(at_least: u64, bases: usize) -> u64 {
    let is_prime = |n: u64| {
        n >= 2
            && (2..)
                .take_while(|d| d * d <= n)
                .all(|d| !n.is_multiple_of(d))
    };
    let first: Vec<u64> = (2..).filter(|&n| is_prime(n)).take(bases).collect();
    (at_least.max(2)..)
        .find(|&n| is_prime(n) && !first.contains(&n))
        .expect("a prime")
}

/// The most of a row's Halton points a constrained suite tries for one valid test before it
/// gives the last (which [`crate::ValidOnly`] then skips).
const MAX_TRIES_PER_TEST: u64 = 10_000;

impl CoveringSuite {
    /// A suite of strength `t` over `space` with `per_row` continuous points for each array
    /// row (use [`CoveringSuite::per_row_for_budget`] or a Halton budget for a target ε).
    ///
    /// Over a constrained space the array covers every t-tuple of levels that some valid
    /// point holds and holds no combination the constraints forbid
    /// ([`ParamSpace::forbidden_levels`]), as PICT and ACTS do with constraints; the extra
    /// rows of a space without continuous parameters are valid combinations too. (Its
    /// continuous points may still break a constraint: [`crate::Strategy`] skips them.)
    ///
    /// # Errors
    /// [`CoveringError::Strength`] for `t` outside `1..=min(6, N_D)` when the space has
    /// discrete parameters; [`CoveringError::Forbidden`] when the forbidden combinations
    /// cannot be found ([`ParamSpace::forbidden_levels`]'s errors).
    pub fn new(
        space: &ParamSpace,
        t: usize,
        kind: ArrayKind,
        per_row: u64,
        seed: u64,
    ) -> Result<Self, CoveringError> {
        let levels = space.level_counts();
        let k = levels.len();
        let cons = space
            .forbidden_levels()
            .map_err(|e| CoveringError::Forbidden(e.to_string()))?
            .unwrap_or_default();
        let rows: Vec<Vec<u32>> = if k == 0 {
            vec![Vec::new()]
        } else {
            let a = match kind {
                ArrayKind::Ipog => ipog_with(&levels, t, &cons, &[])?,
                ArrayKind::RandomKWise => {
                    let m = random_kwise_rows(&levels, t, 0.01)?.rows as usize;
                    draw_until_covered(&levels, t, seed, 1 << 20, &cons, &[], m)?
                }
            };
            (0..a.len()).map(|r| a.row(r).to_vec()).collect()
        };
        let continuous = ParamSpace::unit_cube(space.continuous_dims());
        let mut rows = rows;
        let mut per_row = per_row.max(1);
        // Without continuous parameters a row's block would be the same test `per_row` times
        // (same values, same results): the budget past the array goes to other combinations
        // of levels instead, as long as there are any.
        if space.continuous_dims() == 0 && k > 0 && per_row > 1 {
            let target = rows.len() as u64 * per_row;
            // A random array may draw a row twice: here that is one test run twice.
            let mut kept = std::collections::HashSet::new();
            rows.retain(|r| kept.insert(r.clone()));
            extend_with_distinct_rows(&mut rows, &levels, target, seed, &cons);
            per_row = target.div_ceil(rows.len() as u64);
        }
        let leap = leap_prime(rows.len() as u64, space.continuous_dims());
        Ok(CoveringSuite {
            used: vec![0; rows.len()],
            rows,
            per_row,
            halton: Halton::new(&continuous),
            next: 0,
            leap,
            constrained: space.is_constrained().then(|| space.clone()),
            name: match kind {
                ArrayKind::Ipog => "ipog",
                ArrayKind::RandomKWise => "kwise",
            },
        })
    }

    /// Points per row so that `rows × m >= budget`: `m = ceil(budget / rows)`.
    pub fn per_row_for_budget(rows: usize, budget: u64) -> u64 {
        budget.div_ceil(rows.max(1) as u64).max(1)
    }

    /// Rows of the covering array (1 when the space has no discrete parameter).
    pub fn rows(&self) -> usize {
        self.rows.len()
    }

    /// Total points: `rows × per_row`.
    pub fn len(&self) -> u64 {
        self.rows.len() as u64 * self.per_row
    }

    /// Whether the suite has no point (never: at least one row and one point per row).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Point `j` in the interleaved order. Past [`CoveringSuite::len`] (a constrained space
    /// whose invalid points are skipped asks for more) the rows take turns again, each with
    /// Halton points past every block: `len + (i - m) · L + r` for row `r`'s `i`-th point, `L`
    /// the least prime at least the number of rows that is no Halton base.
    pub fn point(&self, j: u64) -> Point {
        let rows = self.rows.len() as u64;
        self.draw((j % rows) as usize, j / rows)
    }

    /// Row `r`'s `i`-th point.
    fn draw(&self, r: usize, i: u64) -> Point {
        let index = if i < self.per_row {
            r as u64 * self.per_row + i
        } else {
            self.len() + (i - self.per_row) * self.leap + r as u64
        };
        let h = self.halton.point(index);
        Point {
            discrete: self.rows[r].clone(),
            continuous: h.continuous,
        }
    }
}

/// Appends to `rows` rows of `levels` that none of them repeats, drawn from
/// `ChaCha8Rng::seed_from_u64(seed)`, until there are `target` rows or every combination of
/// levels is there: all the others in a seeded random order when they are few (at most
/// 2^20), else random rows not seen yet; none that `cons` forbids.
fn extend_with_distinct_rows(
    rows: &mut Vec<Vec<u32>>,
    levels: &[u32],
    target: u64,
    seed: u64,
    cons: &Constraints,
) {
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    let total = levels
        .iter()
        .try_fold(1u64, |n, &v| n.checked_mul(u64::from(v)))
        .unwrap_or(u64::MAX);
    let mut seen: std::collections::HashSet<Vec<u32>> = rows.iter().cloned().collect();
    let want = target.min(total).saturating_sub(seen.len() as u64);
    if want == 0 {
        return;
    }
    // Its own stream: the array's draws (random k-wise) come from the seed itself.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6469_7374_696e_6374);
    if total <= 1 << 20 {
        let mut others: Vec<Vec<u32>> = (0..total)
            .map(|mut i| {
                levels
                    .iter()
                    .rev()
                    .map(|&v| {
                        let cell = (i % u64::from(v)) as u32;
                        i /= u64::from(v);
                        cell
                    })
                    .collect::<Vec<u32>>()
                    .into_iter()
                    .rev()
                    .collect()
            })
            .filter(|r: &Vec<u32>| !seen.contains(r) && !cons.violated_by(r))
            .collect();
        others.shuffle(&mut rng);
        rows.extend(others.into_iter().take(want as usize));
    } else {
        // (A constrained space of this size is refused by `forbidden_levels`.)
        let goal = target.min(total);
        while (seen.len() as u64) < goal {
            let r: Vec<u32> = levels.iter().map(|&v| rng.random_range(0..v)).collect();
            if !cons.violated_by(&r) && seen.insert(r.clone()) {
                rows.push(r);
            }
        }
    }
}

impl Generator for CoveringSuite {
    fn name(&self) -> &'static str {
        self.name
    }

    /// The next `n` points; past [`CoveringSuite::len`] as [`CoveringSuite::point`] says.
    /// Over a constrained space, each row's next valid point.
    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let end = self.next + n as u64;
        let Some(space) = self.constrained.clone() else {
            let pts = (self.next..end).map(|j| self.point(j)).collect();
            self.next = end;
            return Ok(pts);
        };
        let rows = self.rows.len() as u64;
        let tries = if space.continuous_dims() == 0 {
            1
        } else {
            MAX_TRIES_PER_TEST
        };
        let mut pts = Vec::with_capacity(n);
        for j in self.next..end {
            let r = (j % rows) as usize;
            let mut p = self.draw(r, self.used[r]);
            self.used[r] += 1;
            for _ in 1..tries {
                if space.is_valid(&p)? {
                    break;
                }
                p = self.draw(r, self.used[r]);
                self.used[r] += 1;
            }
            pts.push(p);
        }
        self.next = end;
        Ok(pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::kwise_coverage;
    use crate::{Param, Value};

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::levels("a", vec![Value::Int(0), Value::Int(1), Value::Int(2)]),
            Param::interval("x", 0.0, 1.0, "1"),
            Param::levels("b", vec![Value::Int(0), Value::Int(1)]),
            Param::levels("c", vec![Value::Int(0), Value::Int(1)]),
            Param::interval("y", 0.0, 1.0, "1"),
        ])
        .unwrap()
    }

    #[test]
    fn any_prefix_of_rows_points_covers_every_pair_and_blocks_differ() {
        let s = space();
        let mut suite = CoveringSuite::new(&s, 2, ArrayKind::Ipog, 16, 0).unwrap();
        let rows = suite.rows();
        let pts = suite.ask(rows * 16).unwrap();
        let c = kwise_coverage(&s, &pts[..rows], 2, 0).unwrap();
        assert_eq!(c.covered, c.total);
        // Blocks use disjoint Halton ranges: no continuous part repeats across rows.
        let mut seen: Vec<Vec<u64>> = pts
            .iter()
            .map(|p| p.continuous.iter().map(|x| x.to_bits()).collect())
            .collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), pts.len());
        // Each row's block is the Halton points r·m .. (r+1)·m.
        let h = Halton::new(&ParamSpace::unit_cube(2));
        assert_eq!(pts[1].continuous, h.point(16).continuous);
        // Past the blocks (a constrained space's skipped points ask for more), row 0 takes
        // the first Halton point after every block.
        let next = suite.ask(1).unwrap();
        assert_eq!(next[0].continuous, h.point(suite.len()).continuous);
        assert_eq!(next[0].discrete, pts[0].discrete);
    }

    /// Without continuous parameters, the budget past the array runs other combinations of
    /// levels, each once, before any repeats; the array's rows come first.
    #[test]
    fn a_discrete_space_gets_distinct_tests_past_the_array() {
        let s = ParamSpace::new(
            (0..7)
                .map(|i| Param::levels(&format!("s{i}"), vec![Value::Int(0), Value::Int(1)]))
                .collect(),
        )
        .unwrap();
        for kind in [ArrayKind::Ipog, ArrayKind::RandomKWise] {
            let array = CoveringSuite::new(&s, 2, kind, 1, 0).unwrap();
            let rows = array.rows();
            for budget in [60u64, 128, 300] {
                let per_row = CoveringSuite::per_row_for_budget(rows, budget);
                let mut suite = CoveringSuite::new(&s, 2, kind, per_row, 0).unwrap();
                let pts = suite.ask(budget as usize).unwrap();
                let distinct: std::collections::HashSet<&Vec<u32>> =
                    pts.iter().map(|p| &p.discrete).collect();
                assert_eq!(distinct.len() as u64, budget.min(128), "{kind:?} {budget}");
                let c = kwise_coverage(&s, &pts[..rows], 2, 0).unwrap();
                assert_eq!(c.covered, c.total, "{kind:?} {budget}");
            }
        }
    }

    #[test]
    fn value_stability_first_points() {
        let mut suite = CoveringSuite::new(&space(), 2, ArrayKind::Ipog, 4, 0).unwrap();
        let p = suite.ask(2).unwrap();
        assert_eq!(p[0].discrete, [0, 0, 0]);
        assert_eq!(p[0].continuous, [0.0, 0.0]);
        // Row 1 starts at Halton index 4: (γ_2(4), γ_3(4)) = (1/8, 4/9).
        assert_eq!(p[1].discrete, PINNED_ROW1);
        assert_eq!(p[1].continuous, [1.0 / 8.0, 4.0 / 9.0]);
    }

    const PINNED_ROW1: [u32; 3] = [0, 1, 1];

    #[test]
    fn per_row_for_budget_rounds_up() {
        assert_eq!(CoveringSuite::per_row_for_budget(9, 100), 12);
        assert_eq!(CoveringSuite::per_row_for_budget(0, 5), 5);
    }
}
