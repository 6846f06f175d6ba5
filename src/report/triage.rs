//! Where failures are, in words: a shallow decision tree fitted on a campaign's records names
//! the failure regions as rules (`walking_speed ≥ 2.1 m/s and trigger_distance < 9.8 m: 31 of
//! 33 failed`), and the parameters are ranked by how much they explain the outcome.
//!
//! The tree is CART with Gini impurity (Breiman et al., *Classification and Regression Trees*,
//! 1984), fitted by `linfa-trees` on the tests that passed or failed (errors have no verdict and
//! are left out), one feature per open parameter: a continuous parameter's value in its unit, a
//! discrete one's level index, then pruned by cost complexity (a split stays when it removes
//! more than 5 % of the smaller outcome's tests from the wrong side per leaf it adds). A rule
//! is the path to a leaf where most tests failed, with the bounds on each parameter merged. A parameter's importance is the tree's mean decrease in
//! impurity (Breiman 2001, "Random forests", §10): the Gini decrease of each split on it,
//! weighted by the share of tests reaching the split, normalised to sum to 1. Its association
//! with the robustness is Spearman's ρ for a continuous parameter and the correlation ratio η
//! of the robustness's ranks across levels for a discrete one.

use linfa::prelude::*;
use linfa_trees::{DecisionTree, SplitQuality, TreeNode};
use ndarray::{Array1, Array2};
use serde::{Deserialize, Serialize};

use paracosm_generators::{Domain, Param, ParamSpace, Value};

use crate::record::{RunRecord, Status};

/// The depth of the tree: a rule has at most this many conditions before bounds on one
/// parameter are merged, so a box over two parameters is one rule.
pub const MAX_DEPTH: usize = 5;

/// Fewer judged tests than this and no tree is fitted.
pub const MIN_TESTS: usize = 10;

/// The failure regions and the parameters' relevance of a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Triage {
    /// Tests the tree was fitted on: those that passed or failed (errors left out).
    pub tests: u64,
    /// How many of them failed.
    pub failed: u64,
    /// The tree's depth limit ([`MAX_DEPTH`]).
    pub max_depth: usize,
    /// The failure regions, most failures first: each leaf of the tree where most tests failed;
    /// when there is none but some test failed, the leaf with the highest failure rate.
    pub rules: Vec<Rule>,
    /// Every open parameter, most relevant first (importance, then |association|, then
    /// declaration order).
    pub ranking: Vec<Relevance>,
}

/// A region of the parameter space: the tests inside satisfy every condition.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rule {
    /// One condition per parameter the region bounds, in declaration order.
    pub conditions: Vec<Condition>,
    /// Tests inside that failed.
    pub failed: u64,
    /// Tests inside (passed or failed).
    pub tests: u64,
    /// The rule as a person reads it: `a ≥ 2.1 m/s and b < 9.8 m: 31 of 33 failed`.
    pub text: String,
}

/// A bound on one parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Condition {
    /// `lo ≤ value < hi` for a continuous parameter, in its unit; a missing side is unbounded.
    /// Bounds are the tree's splits, midway between two tests' values, so no test lies on one.
    Range {
        /// The parameter.
        param: String,
        /// Lower bound (inclusive), or none.
        lo: Option<f64>,
        /// Upper bound (exclusive), or none.
        hi: Option<f64>,
    },
    /// The value is one of `levels` (a discrete parameter), in declaration order.
    Levels {
        /// The parameter.
        param: String,
        /// The levels inside the region.
        levels: Vec<Value>,
    },
}

/// How much one parameter explains the outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Relevance {
    /// The parameter.
    pub param: String,
    /// The tree's mean decrease in impurity from splits on it, normalised over the parameters:
    /// in `[0, 1]`, 0 when the tree never splits on it.
    pub importance: f64,
    /// Spearman's ρ in `[-1, 1]` between the parameter and the robustness (continuous), or the
    /// correlation ratio η in `[0, 1]` of the robustness's ranks across its levels (discrete);
    /// over the tests with a finite robustness; `null` when it is undefined (fewer than 3 such
    /// tests, or no spread).
    pub association: Option<f64>,
    /// `"spearman"` or `"eta"`.
    pub association_kind: String,
}

/// One judged test: its feature vector and whether it failed.
struct Sample {
    x: Vec<f64>,
    fail: bool,
    robustness: f64,
}

/// The feature of parameter `p` for a test: its value in its unit, or its level index.
fn feature(p: &Param, r: &RunRecord) -> Option<f64> {
    let params = r.params.as_ref()?;
    match &p.domain {
        Domain::Interval { .. } => params.real(&p.name),
        Domain::Levels(levels) => {
            let v = params.get(&p.name)?;
            levels.iter().position(|l| l == v).map(|i| i as f64)
        }
    }
}

/// A node of the fitted tree, with the samples that reach it counted by [`Tree::count`].
enum Tree {
    Leaf,
    Split {
        feature: usize,
        /// `x[feature] <= value` goes left.
        value: f64,
        /// The Gini decrease of the split, within the node.
        decrease: f64,
        left: Box<Tree>,
        right: Box<Tree>,
    },
}

impl Tree {
    fn of(node: &TreeNode<f64, usize>) -> Tree {
        if node.is_leaf() {
            return Tree::Leaf;
        }
        let (feature, value, decrease) = node.split();
        let children = node.children();
        match (children[0], children[1]) {
            (Some(l), Some(r)) => Tree::Split {
                feature,
                value,
                decrease,
                left: Box::new(Tree::of(l)),
                right: Box::new(Tree::of(r)),
            },
            _ => Tree::Leaf,
        }
    }
}

/// The tree pruned by cost complexity (Breiman et al. 1984, ch. 3): a split is kept only
/// when it removes more than `alpha` misclassified tests per leaf it adds, so that a region
/// is not cut into pieces by a few tests of the other outcome. `at` are the samples reaching
/// `tree`. Returns the pruned tree, its misclassified tests and its leaves.
fn prune(tree: Tree, samples: &[Sample], at: &[usize], alpha: f64) -> (Tree, usize, usize) {
    let failed = at.iter().filter(|&&i| samples[i].fail).count();
    let as_leaf = failed.min(at.len() - failed);
    match tree {
        Tree::Leaf => (Tree::Leaf, as_leaf, 1),
        Tree::Split {
            feature,
            value,
            decrease,
            left,
            right,
        } => {
            let (l, r): (Vec<usize>, Vec<usize>) =
                at.iter().partition(|&&i| samples[i].x[feature] <= value);
            let (left, el, nl) = prune(*left, samples, &l, alpha);
            let (right, er, nr) = prune(*right, samples, &r, alpha);
            let (errors, leaves) = (el + er, nl + nr);
            if (as_leaf as f64 - errors as f64) <= alpha * (leaves - 1) as f64 {
                (Tree::Leaf, as_leaf, 1)
            } else {
                let split = Tree::Split {
                    feature,
                    value,
                    decrease,
                    left: Box::new(left),
                    right: Box::new(right),
                };
                (split, errors, leaves)
            }
        }
    }
}

/// A bound on one feature along a path: `(feature, value, goes left)`.
type Step = (usize, f64, bool);

struct Walk<'a> {
    samples: &'a [Sample],
    importance: Vec<f64>,
    /// `(path, failed, tests)` per leaf.
    leaves: Vec<(Vec<Step>, u64, u64)>,
}

impl Walk<'_> {
    fn visit(&mut self, tree: &Tree, at: &[usize], path: &mut Vec<Step>) {
        match tree {
            Tree::Leaf => {
                let failed = at.iter().filter(|&&i| self.samples[i].fail).count() as u64;
                self.leaves.push((path.clone(), failed, at.len() as u64));
            }
            Tree::Split {
                feature,
                value,
                decrease,
                left,
                right,
            } => {
                self.importance[*feature] += decrease * at.len() as f64 / self.samples.len() as f64;
                let (l, r): (Vec<usize>, Vec<usize>) = at
                    .iter()
                    .partition(|&&i| self.samples[i].x[*feature] <= *value);
                path.push((*feature, *value, true));
                self.visit(left, &l, path);
                path.pop();
                path.push((*feature, *value, false));
                self.visit(right, &r, path);
                path.pop();
            }
        }
    }
}

/// The failure regions and relevance of `records` over `space`; `None` with fewer than
/// [`MIN_TESTS`] tests that passed or failed, or no open parameter.
pub fn triage(space: &ParamSpace, records: &[RunRecord]) -> Option<Triage> {
    let params = space.params();
    if params.is_empty() {
        return None;
    }
    let samples: Vec<Sample> = records
        .iter()
        .filter(|r| r.status != Status::Error)
        .filter_map(|r| {
            let x: Option<Vec<f64>> = params.iter().map(|p| feature(p, r)).collect();
            Some(Sample {
                x: x?,
                fail: r.status == Status::Fail,
                robustness: r.robustness(),
            })
        })
        .collect();
    if samples.len() < MIN_TESTS {
        return None;
    }
    let n = samples.len();
    let failed = samples.iter().filter(|s| s.fail).count() as u64;
    let all: Vec<usize> = (0..n).collect();
    let tree = if failed == 0 || failed == n as u64 {
        Tree::Leaf
    } else {
        // A split must explain at least 5 % of the smaller outcome's tests per added leaf
        // (and at least 2 tests).
        let smaller = failed.min(n as u64 - failed) as f64;
        let alpha = (0.05 * smaller).max(2.0);
        prune(fit(&samples, params.len())?, &samples, &all, alpha).0
    };
    let mut walk = Walk {
        samples: &samples,
        importance: vec![0.0; params.len()],
        leaves: Vec::new(),
    };
    walk.visit(&tree, &all, &mut Vec::new());
    let rules = failure_rules(params, walk.leaves);
    let ranking = relevance(params, &samples, &walk.importance);
    Some(Triage {
        tests: n as u64,
        failed,
        max_depth: MAX_DEPTH,
        rules,
        ranking,
    })
}

/// The rules of the failure regions among `leaves` (`(path, failed, tests)`): the leaves where
/// most tests failed, or else the one with the highest failure rate (then the most failures);
/// the most failures first, then the fewest passes.
fn failure_rules(params: &[Param], leaves: Vec<(Vec<Step>, u64, u64)>) -> Vec<Rule> {
    let mut leaves: Vec<_> = leaves
        .into_iter()
        .filter(|(_, f, t)| *t > 0 && *f > 0)
        .collect();
    let majority: Vec<_> = leaves
        .iter()
        .filter(|(_, f, t)| 2 * f > *t)
        .cloned()
        .collect();
    let chosen = if majority.is_empty() {
        // No region where most failed: the leaf with the highest failure rate, then the most
        // failures.
        leaves.sort_by(|a, b| {
            (b.1 as f64 / b.2 as f64)
                .total_cmp(&(a.1 as f64 / a.2 as f64))
                .then(b.1.cmp(&a.1))
        });
        leaves.into_iter().take(1).collect()
    } else {
        majority
    };
    let mut rules: Vec<Rule> = chosen
        .into_iter()
        .map(|(path, failed, tests)| rule(params, &path, failed, tests))
        .collect();
    rules.sort_by(|a, b| {
        b.failed
            .cmp(&a.failed)
            .then((a.tests - a.failed).cmp(&(b.tests - b.failed)))
    });
    rules
}

/// Every parameter's relevance, most relevant first: its share of the tree's `importance`,
/// then the size of its association with the outcome, then its order.
fn relevance(params: &[Param], samples: &[Sample], importance: &[f64]) -> Vec<Relevance> {
    let total: f64 = importance.iter().sum();
    let mut ranking: Vec<(usize, Relevance)> = params
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let discrete = matches!(p.domain, Domain::Levels(_));
            (
                j,
                Relevance {
                    param: p.name.clone(),
                    importance: if total > 0.0 {
                        importance[j] / total
                    } else {
                        0.0
                    },
                    association: association(samples, j, discrete),
                    association_kind: if discrete { "eta" } else { "spearman" }.into(),
                },
            )
        })
        .collect();
    ranking.sort_by(|(i, a), (j, b)| {
        b.importance
            .total_cmp(&a.importance)
            .then(
                b.association
                    .map_or(0.0, f64::abs)
                    .total_cmp(&a.association.map_or(0.0, f64::abs)),
            )
            .then(i.cmp(j))
    });
    ranking.into_iter().map(|(_, r)| r).collect()
}

/// Fits the tree: Gini, depth [`MAX_DEPTH`], leaves of at least 1 % of the tests (at least 3);
/// `None` when `linfa-trees` fails.
fn fit(samples: &[Sample], d: usize) -> Option<Tree> {
    let n = samples.len();
    let x = Array2::from_shape_fn((n, d), |(i, j)| samples[i].x[j]);
    let y: Array1<usize> = samples.iter().map(|s| usize::from(s.fail)).collect();
    let data = Dataset::new(x, y);
    let leaf = (n as f32 / 100.0).max(3.0);
    // The summary must not be lost to the learning library: a panic inside it (it asserts on
    // its inputs) is no triage, like an error.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        DecisionTree::params()
            .split_quality(SplitQuality::Gini)
            .max_depth(Some(MAX_DEPTH))
            .min_weight_leaf(leaf)
            .min_weight_split(2.0 * leaf)
            .fit(&data)
            .ok()
            .map(|model| Tree::of(model.root_node()))
    }))
    .ok()
    .flatten()
}

/// The rule of a leaf reached by `path`, its bounds merged per parameter.
fn rule(params: &[Param], path: &[Step], failed: u64, tests: u64) -> Rule {
    let mut conditions = Vec::new();
    for (j, p) in params.iter().enumerate() {
        let steps: Vec<&Step> = path.iter().filter(|s| s.0 == j).collect();
        if steps.is_empty() {
            continue;
        }
        match &p.domain {
            Domain::Interval { .. } => {
                let (mut lo, mut hi): (Option<f64>, Option<f64>) = (None, None);
                for &&(_, v, left) in &steps {
                    if left {
                        hi = Some(hi.map_or(v, |h| h.min(v)));
                    } else {
                        lo = Some(lo.map_or(v, |l| l.max(v)));
                    }
                }
                conditions.push(Condition::Range {
                    param: p.name.clone(),
                    lo,
                    hi,
                });
            }
            Domain::Levels(levels) => {
                let inside: Vec<Value> = levels
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| {
                        steps
                            .iter()
                            .all(|&&(_, v, left)| ((*i as f64) <= v) == left)
                    })
                    .map(|(_, l)| l.clone())
                    .collect();
                conditions.push(Condition::Levels {
                    param: p.name.clone(),
                    levels: inside,
                });
            }
        }
    }
    let text = describe(params, &conditions, failed, tests);
    Rule {
        conditions,
        failed,
        tests,
        text,
    }
}

/// Decimals that show a bound of a parameter spanning `span` to about 1/200 of it.
fn decimals(span: f64) -> usize {
    if span.is_finite() && span > 0.0 {
        (-(span / 200.0).log10()).ceil().clamp(0.0, 6.0) as usize
    } else {
        3
    }
}

/// The text of a rule: its conditions joined by `and`, then `failed of tests failed`.
fn describe(params: &[Param], conditions: &[Condition], failed: u64, tests: u64) -> String {
    let parts: Vec<String> = conditions
        .iter()
        .map(|c| match c {
            Condition::Range { param, lo, hi } => {
                let p = params.iter().find(|p| &p.name == param);
                let unit = p
                    .and_then(|p| p.unit.as_ref())
                    .map(|u| format!(" {u}"))
                    .unwrap_or_default();
                let span = match p.map(|p| &p.domain) {
                    Some(Domain::Interval { lo, hi }) => hi - lo,
                    _ => f64::NAN,
                };
                let k = decimals(span);
                match (lo, hi) {
                    (Some(l), Some(h)) => format!("{l:.k$} ≤ {param} < {h:.k$}{unit}"),
                    (Some(l), None) => format!("{param} ≥ {l:.k$}{unit}"),
                    (None, Some(h)) => format!("{param} < {h:.k$}{unit}"),
                    (None, None) => format!("any {param}"),
                }
            }
            Condition::Levels { param, levels } => match levels.as_slice() {
                [one] => format!("{param} = {one}"),
                many => format!(
                    "{param} ∈ {{{}}}",
                    many.iter()
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
        })
        .collect();
    let region = if parts.is_empty() {
        "all tests".to_owned()
    } else {
        parts.join(" and ")
    };
    format!("{region}: {failed} of {tests} failed")
}

/// Ranks of `v` from 1, ties given their average rank.
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut out = vec![0.0; v.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
            j += 1;
        }
        let r = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            out[k] = r;
        }
        i = j + 1;
    }
    out
}

/// Spearman's ρ of feature `j` with the robustness, or η across levels when `discrete`.
fn association(samples: &[Sample], j: usize, discrete: bool) -> Option<f64> {
    let finite: Vec<&Sample> = samples
        .iter()
        .filter(|s| s.robustness.is_finite())
        .collect();
    if finite.len() < 3 {
        return None;
    }
    let r = ranks(&finite.iter().map(|s| s.robustness).collect::<Vec<_>>());
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mr = mean(&r);
    let ss_total: f64 = r.iter().map(|x| (x - mr).powi(2)).sum();
    if ss_total <= 0.0 {
        return None;
    }
    let x: Vec<f64> = finite.iter().map(|s| s.x[j]).collect();
    if discrete {
        let mut groups: std::collections::BTreeMap<i64, (f64, usize)> = Default::default();
        for (xi, ri) in x.iter().zip(&r) {
            let g = groups.entry(*xi as i64).or_insert((0.0, 0));
            g.0 += ri;
            g.1 += 1;
        }
        let ss_between: f64 = groups
            .values()
            .map(|(s, k)| *k as f64 * (s / *k as f64 - mr).powi(2))
            .sum();
        Some((ss_between / ss_total).sqrt())
    } else {
        let q = ranks(&x);
        let mq = mean(&q);
        let ss_x: f64 = q.iter().map(|v| (v - mq).powi(2)).sum();
        if ss_x <= 0.0 {
            return None;
        }
        let cov: f64 = q.iter().zip(&r).map(|(a, b)| (a - mq) * (b - mr)).sum();
        Some(cov / (ss_x * ss_total).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_average_ties() {
        assert_eq!(ranks(&[3.0, 1.0, 3.0, 2.0]), vec![3.5, 1.0, 3.5, 2.0]);
    }

    #[test]
    fn decimals_follow_the_span() {
        assert_eq!(decimals(3.0), 2);
        assert_eq!(decimals(40.0), 1);
        assert_eq!(decimals(1000.0), 0);
    }

    /// Whether the test with assignment `a` lies in the rule's region.
    fn inside(rule: &Rule, a: &paracosm_generators::Assignment) -> bool {
        rule.conditions.iter().all(|c| match c {
            Condition::Range { param, lo, hi } => {
                let v = a.real(param).unwrap();
                lo.is_none_or(|l| v > l) && hi.is_none_or(|h| v <= h)
            }
            Condition::Levels { param, levels } => levels.contains(a.get(param).unwrap()),
        })
    }

    #[test]
    fn each_rule_counts_exactly_the_tests_in_its_region_and_regions_do_not_overlap() {
        use rand::{Rng, SeedableRng};
        let space = ParamSpace::new(vec![
            Param::interval("x", 0.0, 10.0, "m"),
            Param::interval("y", -5.0, 5.0, "m/s"),
            Param::levels(
                "w",
                vec![
                    Value::Text("dry".into()),
                    Value::Text("wet".into()),
                    Value::Bool(true),
                ],
            ),
        ])
        .unwrap();
        for seed in 0..5u64 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let records: Vec<RunRecord> = (0..400)
                .map(|id| {
                    let point = paracosm_generators::Point {
                        discrete: vec![rng.random_range(0..3)],
                        continuous: vec![rng.random::<f64>(), rng.random::<f64>()],
                    };
                    let a = space.decode(&point).unwrap();
                    let (x, y) = (a.real("x").unwrap(), a.real("y").unwrap());
                    // A noisy region: mostly x > 6 with y < 1, or the third level.
                    let fail = (x > 6.0 && y < 1.0) || (point.discrete[0] == 2 && x < 3.0);
                    let flip = rng.random::<f64>() < 0.05;
                    let status = match (fail != flip, id % 50 == 7) {
                        (_, true) => Status::Error,
                        (true, _) => Status::Fail,
                        (false, _) => Status::Pass,
                    };
                    RunRecord {
                        passive: Vec::new(),
                        campaign: None,
                        id,
                        seed: 0,
                        strategy: "random".into(),
                        params: Some(a),
                        point,
                        status,
                        monitors: vec![],
                        metrics: vec![],
                        error: None,
                        log: Vec::new(),
                        wall_ms: 0.0,
                    }
                })
                .collect();
            let t = triage(&space, &records).unwrap();
            let judged: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.status != Status::Error)
                .collect();
            assert_eq!(t.tests as usize, judged.len());
            assert!(!t.rules.is_empty());
            for r in &t.rules {
                let inside: Vec<&&RunRecord> = judged
                    .iter()
                    .filter(|rec| inside(r, rec.params.as_ref().unwrap()))
                    .collect();
                assert_eq!(inside.len() as u64, r.tests, "{}", r.text);
                let failed = inside
                    .iter()
                    .filter(|rec| rec.status == Status::Fail)
                    .count();
                assert_eq!(failed as u64, r.failed, "{}", r.text);
                assert!(2 * r.failed > r.tests, "a majority failed: {}", r.text);
            }
            for (i, a) in t.rules.iter().enumerate() {
                for b in &t.rules[i + 1..] {
                    let both = judged.iter().any(|rec| {
                        let p = rec.params.as_ref().unwrap();
                        inside(a, p) && inside(b, p)
                    });
                    assert!(!both, "{} overlaps {}", a.text, b.text);
                }
            }
            let sum: f64 = t.ranking.iter().map(|r| r.importance).sum();
            assert!((sum - 1.0).abs() < 1e-9);
        }
    }
}
