use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{
    dispersion, kwise_coverage, CoverageError, Dispersion, DispersionOptions, KWiseCoverage,
};
use crate::{ParamSpace, Point};

/// Whether a mixed test set is (k, ε)-covering (PARACOSM §3.1), with the evidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KEpsilonCovering {
    /// The strength `k` of condition 1.
    pub k: usize,
    /// The dispersion bound `ε` of condition 2, in `[0, 1]` (unit-cube volume).
    pub epsilon: f64,
    /// Condition 1: k-wise coverage of the discrete parameters, `None` without any.
    pub kwise: Option<KWiseCoverage>,
    /// Number of distinct discrete vectors `t_D` among the tests.
    pub groups: usize,
    /// Condition 2's worst case: the discrete vector (level indices) whose tests' continuous
    /// parts have the largest dispersion, and that dispersion. `None` without continuous
    /// parameters.
    pub worst_group: Option<(Vec<u32>, Dispersion)>,
    /// `Some(true)` covering, `Some(false)` not, `None` undecided (a dispersion bracket
    /// straddles `ε`).
    pub covering: Option<bool>,
}

/// Decides whether `points` are (k, ε)-covering for `space` (PARACOSM §3.1): (1) every k-tuple
/// of discrete levels appears in some test, and (2) for every discrete vector `t_D` in the
/// set, the continuous parts `{t_C | (t_D, t_C) ∈ A}` have dispersion at most `ε`.
///
/// Condition 1 is vacuous without discrete parameters and condition 2 without continuous
/// ones. When a group's dispersion is only bracketed (see [`dispersion`]), the answer is
/// decided only if the bracket lies on one side of `ε`.
///
/// # Errors
/// [`CoverageError`] for a strength outside `1..=min(6, N_D)` (when `N_D > 0`), points that do
/// not fit the space, or `ε` outside `[0, 1]`.
pub fn k_epsilon_covering(
    space: &ParamSpace,
    points: &[Point],
    k: usize,
    epsilon: f64,
    options: &DispersionOptions,
) -> Result<KEpsilonCovering, CoverageError> {
    if !(0.0..=1.0).contains(&epsilon) {
        return Err(CoverageError::Shape(format!(
            "ε = {epsilon} is not a volume in [0, 1]"
        )));
    }
    let nd = space.level_counts().len();
    let nc = space.continuous_dims();
    let kwise = if nd > 0 {
        Some(kwise_coverage(space, points, k, 20)?)
    } else {
        None
    };
    let mut groups: BTreeMap<Vec<u32>, Vec<f64>> = BTreeMap::new();
    for p in points {
        if p.continuous.len() != nc {
            return Err(CoverageError::Shape(format!(
                "a point has {} continuous coordinates, the space has {nc}",
                p.continuous.len()
            )));
        }
        groups
            .entry(p.discrete.clone())
            .or_default()
            .extend_from_slice(&p.continuous);
    }
    let mut worst: Option<(Vec<u32>, Dispersion)> = None;
    if nc > 0 {
        for (key, coords) in &groups {
            let d = dispersion(coords, nc, options)?;
            if worst.as_ref().is_none_or(|(_, w)| d.upper > w.upper) {
                worst = Some((key.clone(), d));
            }
        }
    }
    let kwise_ok = kwise.as_ref().is_none_or(|c| c.covered == c.total);
    let covering = match &worst {
        _ if !kwise_ok => Some(false),
        None => Some(true),
        Some((_, d)) if d.upper <= epsilon => Some(true),
        Some((_, d)) if d.lower > epsilon => Some(false),
        Some(_) => None,
    };
    Ok(KEpsilonCovering {
        k,
        epsilon,
        kwise,
        groups: groups.len(),
        worst_group: worst,
        covering,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Generator, Halton, Param, Value};

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::levels("a", vec![Value::Int(0), Value::Int(1)]),
            Param::levels("b", vec![Value::Int(0), Value::Int(1)]),
            Param::interval("x", 0.0, 1.0, "1"),
        ])
        .unwrap()
    }

    /// Every discrete row gets the same 64 Halton points in x.
    fn design(rows: &[[u32; 2]]) -> Vec<Point> {
        let one = ParamSpace::new(vec![Param::interval("x", 0.0, 1.0, "1")]).unwrap();
        let xs = Halton::new(&one).ask(64).unwrap();
        rows.iter()
            .flat_map(|r| {
                xs.iter().map(move |p| Point {
                    discrete: r.to_vec(),
                    continuous: p.continuous.clone(),
                })
            })
            .collect()
    }

    #[test]
    fn full_pairs_and_fine_groups_are_covering() {
        let pts = design(&[[0, 0], [0, 1], [1, 0], [1, 1]]);
        // 64 van der Corput points: largest gap 1/64.
        let r = k_epsilon_covering(&space(), &pts, 2, 1.0 / 64.0, &DispersionOptions::default())
            .unwrap();
        assert_eq!(r.covering, Some(true));
        assert_eq!(r.groups, 4);
        assert_eq!(r.worst_group.as_ref().unwrap().1.upper, 1.0 / 64.0);
        let tight =
            k_epsilon_covering(&space(), &pts, 2, 0.01, &DispersionOptions::default()).unwrap();
        assert_eq!(tight.covering, Some(false));
    }

    #[test]
    fn a_missing_pair_is_not_covering_and_is_named() {
        let pts = design(&[[0, 0], [0, 1], [1, 0]]);
        let r = k_epsilon_covering(&space(), &pts, 2, 0.5, &DispersionOptions::default()).unwrap();
        assert_eq!(r.covering, Some(false));
        let missing = &r.kwise.unwrap().missing;
        assert_eq!(missing.len(), 1);
        assert_eq!(
            missing[0].values,
            vec![
                ("a".to_owned(), Value::Int(1)),
                ("b".to_owned(), Value::Int(1))
            ]
        );
    }
}
