use serde::Serialize;

/// A cell not yet given a level.
pub(crate) const OPEN: u32 = u32::MAX;

/// Forbidden combinations: partial assignments `(column, level)` that no row may contain
/// (PICT's constraints in their simplest form: `IF [A] = "x" THEN [B] <> "y"` forbids
/// `{A = x, B = y}`).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Constraints {
    forbidden: Vec<Vec<(usize, u32)>>,
}

impl Constraints {
    /// The constraints forbidding each of `forbidden` (each a list of `(column, level)`;
    /// order does not matter, duplicates are dropped).
    pub fn new(forbidden: Vec<Vec<(usize, u32)>>) -> Self {
        let mut forbidden: Vec<Vec<(usize, u32)>> = forbidden
            .into_iter()
            .map(|mut f| {
                f.sort_unstable();
                f.dedup();
                f
            })
            .collect();
        forbidden.sort();
        forbidden.dedup();
        Constraints { forbidden }
    }

    /// Whether there is no constraint.
    pub fn is_empty(&self) -> bool {
        self.forbidden.is_empty()
    }

    /// The forbidden combinations, each sorted by column.
    pub fn forbidden(&self) -> &[Vec<(usize, u32)>] {
        &self.forbidden
    }

    /// The same constraints with column `c` renamed `position[c]`.
    pub(crate) fn renamed(&self, position: &[usize]) -> Constraints {
        Constraints::new(
            self.forbidden
                .iter()
                .map(|f| f.iter().map(|&(c, v)| (position[c], v)).collect())
                .collect(),
        )
    }

    /// Whether `row` (open cells allowed) already contains a forbidden combination in full.
    pub fn violated_by(&self, row: &[u32]) -> bool {
        self.forbidden
            .iter()
            .any(|f| f.iter().all(|&(c, v)| c < row.len() && row[c] == v))
    }

    /// `row` with its open cells filled so that no forbidden combination holds, or `None` if
    /// no such completion exists. Columns outside every constraint take level 0; the others
    /// are searched depth first, lowest levels first. `levels` has the level counts of the
    /// columns of `row`.
    pub fn complete(&self, levels: &[u32], row: &[u32]) -> Option<Vec<u32>> {
        let mut out = row.to_vec();
        if self.violated_by(&out) {
            return None;
        }
        let mut free: Vec<usize> = self
            .forbidden
            .iter()
            .flatten()
            .map(|&(c, _)| c)
            .filter(|&c| c < out.len() && out[c] == OPEN)
            .collect();
        free.sort_unstable();
        free.dedup();
        if self.search(levels, &mut out, &free) {
            for cell in &mut out {
                if *cell == OPEN {
                    *cell = 0;
                }
            }
            Some(out)
        } else {
            None
        }
    }

    fn search(&self, levels: &[u32], row: &mut [u32], free: &[usize]) -> bool {
        let Some((&c, rest)) = free.split_first() else {
            return true;
        };
        for v in 0..levels[c] {
            row[c] = v;
            // Only combinations that mention `c` can have become complete.
            let bad = self
                .forbidden
                .iter()
                .filter(|f| f.iter().any(|&(fc, _)| fc == c))
                .any(|f| f.iter().all(|&(fc, fv)| row[fc] == fv));
            if !bad && self.search(levels, row, rest) {
                return true;
            }
        }
        row[c] = OPEN;
        false
    }

    /// Whether the partial assignment `cells` extends to a full row of `levels` that breaks no
    /// constraint.
    pub fn completable(&self, levels: &[u32], cells: &[(usize, u32)]) -> bool {
        if self.is_empty() {
            return true;
        }
        let mut row = vec![OPEN; levels.len()];
        for &(c, v) in cells {
            row[c] = v;
        }
        self.complete(levels, &row).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn completion_avoids_forbidden_combinations_and_reports_impossible_ones() {
        // A = 0 forbids B = 0 and B = 1; B has two levels, so A = 0 is impossible.
        let c = Constraints::new(vec![vec![(0, 0), (1, 0)], vec![(1, 1), (0, 0)]]);
        let levels = [2, 2, 3];
        assert!(!c.completable(&levels, &[(0, 0)]));
        assert!(c.completable(&levels, &[(0, 1)]));
        let row = c.complete(&levels, &[OPEN, OPEN, 2]).unwrap();
        assert_eq!(row, [1, 0, 2]);
        assert!(c.violated_by(&[0, 1, 0]));
        assert!(!c.violated_by(&[0, OPEN, 0]));
        assert_eq!(c.forbidden().len(), 2);
    }
}
