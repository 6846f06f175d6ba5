//! An R-tree of a map's lane centre lines, holding runs of consecutive segments rather than
//! single ones: a 10 km road of 17 lanes has 340,000 segments at one station every
//! 0.5 m ([`super::opendrive::MAP_STEP_M`]), and the tree's bulk load sorts its items, so a
//! tree of runs of [`RUN`] segments costs about an eighth to build. A query unpacks the runs
//! near its point and keeps the very segments a tree of single segments would have given.

use rstar::primitives::Line;
use rstar::{Envelope, PointDistance, RTree, RTreeObject, AABB};

use super::map::MapLane;

/// Segments in a run (the last run of a lane may hold fewer).
pub(crate) const RUN: usize = 8;

/// Segments `first..end` of lane `lane` (segment `i` joins stations `i` and `i + 1`), with
/// the box around them.
#[derive(Debug, Clone)]
struct Run {
    lane: usize,
    first: usize,
    end: usize,
    envelope: AABB<[f64; 2]>,
}

impl RTreeObject for Run {
    type Envelope = AABB<[f64; 2]>;

    fn envelope(&self) -> AABB<[f64; 2]> {
        self.envelope
    }
}

/// A run's distance is its box's: never more than any of its segments' boxes' (a box holding
/// another is at most as far from any point, in floating point too, since the distance per
/// axis is a difference of the same coordinates), so a query that would reach a segment
/// reaches its run.
impl PointDistance for Run {
    fn distance_2(&self, p: &[f64; 2]) -> f64 {
        Envelope::distance_2(&self.envelope, p)
    }
}

/// The tree of runs of a map's lane centre lines (see the module documentation).
#[derive(Debug)]
pub(crate) struct CentreTree {
    tree: RTree<Run>,
}

impl CentreTree {
    /// The runs of every lane of `lanes` that `keep` accepts (by index).
    pub(crate) fn new(lanes: &[MapLane], keep: impl Fn(usize) -> bool) -> CentreTree {
        let mut runs = Vec::new();
        for (k, l) in lanes.iter().enumerate().filter(|(k, _)| keep(*k)) {
            let segments = l.centre.len().saturating_sub(1);
            let mut first = 0;
            while first < segments {
                let end = (first + RUN).min(segments);
                let envelope = AABB::from_points(&l.centre[first..=end]);
                runs.push(Run {
                    lane: k,
                    first,
                    end,
                    envelope,
                });
                first = end;
            }
        }
        CentreTree {
            tree: RTree::bulk_load(runs),
        }
    }

    /// The segments `(lane, i)` of the tree whose line from station `i` to `i + 1` of `lanes`
    /// (the lanes the tree was built from) lies within `sqrt(max_2)` m of `p` (world `[x, z]`),
    /// by the same test `rstar` applies to a tree of single segments
    /// ([`PointDistance::distance_2_if_less_or_equal`] of the segment's [`Line`]), in no
    /// particular order.
    pub(crate) fn within<'a>(
        &'a self,
        lanes: &'a [MapLane],
        p: [f64; 2],
        max_2: f64,
    ) -> impl Iterator<Item = (usize, usize)> + 'a {
        self.tree
            .locate_within_distance(p, max_2)
            .flat_map(move |run| {
                let c = &lanes[run.lane].centre;
                (run.first..run.end)
                    .filter(move |&i| {
                        Line::new(c[i], c[i + 1])
                            .distance_2_if_less_or_equal(&p, max_2)
                            .is_some()
                    })
                    .map(move |i| (run.lane, i))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstar::primitives::GeomWithData;

    /// A tree of runs gives the very segments a tree of single segments gives, on lanes that
    /// bend, cross and end at every point of a grid over them.
    #[test]
    fn runs_give_the_segments_single_segments_give() {
        let lane = |k: usize, n: usize| {
            let centre: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    let a = i as f64 * 0.05 + k as f64;
                    [
                        k as f64 * 3.0 + 20.0 * a.cos(),
                        20.0 * a.sin() + i as f64 * 0.1,
                    ]
                })
                .collect();
            MapLane::driving_for_tests((0..n).map(|i| i as f64 * 0.5).collect(), centre, 3.5)
        };
        let lanes: Vec<MapLane> = [(0, 130), (1, 9), (2, 2), (3, 17)]
            .into_iter()
            .map(|(k, n)| lane(k, n))
            .collect();
        let runs = CentreTree::new(&lanes, |_| true);
        let mut single = Vec::new();
        for (k, l) in lanes.iter().enumerate() {
            for i in 0..l.centre.len() - 1 {
                single.push(GeomWithData::new(
                    Line::new(l.centre[i], l.centre[i + 1]),
                    (k, i),
                ));
            }
        }
        let single = RTree::bulk_load(single);
        let mut checked = 0;
        for x in -30..40 {
            for z in -30..40 {
                let p = [x as f64 * 0.7, z as f64 * 0.7];
                for max_2 in [0.0, 1.0, 3.0625] {
                    let mut a: Vec<(usize, usize)> = runs.within(&lanes, p, max_2).collect();
                    let mut b: Vec<(usize, usize)> = single
                        .locate_within_distance(p, max_2)
                        .map(|s| s.data)
                        .collect();
                    a.sort_unstable();
                    b.sort_unstable();
                    assert_eq!(a, b, "at {p:?} within {max_2}");
                    checked += a.len();
                }
            }
        }
        assert!(checked > 1000, "{checked} segments found");
    }
}
