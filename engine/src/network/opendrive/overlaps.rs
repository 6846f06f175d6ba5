//! Roads that overlap where the map says nothing of it: two roads outside any junction whose
//! lanes lie on each other (a crossing without a junction, or one road drawn twice), and a
//! road whose lanes come back over themselves.
//!
//! A point of a lane, sampled about every metre, *lies on* another lane when it is inside that
//! lane's strip by more than [`INSIDE_MARGIN_M`]. Points within [`END_MARGIN_M`] of either
//! lane's ends are not judged, so that roads meeting end to end (linked or through a junction
//! whose roads are short) are not taken for overlaps. Maps are flat in paracosm, so a bridge
//! over another road is an overlap too: a crossing is a warning (naming both roads, their
//! lines and the point); a road over itself is an error, unless its `<elevationProfile>`
//! rises (a spiral ramp), when it is a warning.

use std::collections::{BTreeMap, BTreeSet};

use rstar::primitives::Line;
use rstar::PointDistance;

use super::super::centre_tree::CentreTree;
use super::{MapError, Reader, RoadMap};

/// How far inside another lane's strip a point must be to count as on it, m.
pub const INSIDE_MARGIN_M: f64 = 0.25;

/// How close to a lane's ends a point may be and not be judged, m.
pub const END_MARGIN_M: f64 = 2.0;

/// How far apart along one road two points must be for one to lie on the other's lane as a
/// fold of the road (rather than as its neighbour lane), m.
const SELF_GAP_M: f64 = 30.0;

/// The most crossings named one by one; the rest are counted.
const NAMED: usize = 5;

/// Pairs of roads `(smaller, larger)` whose lanes lie on each other: the first point found
/// (world `[x, z]`, m) and how many stations did.
type Crossings = BTreeMap<(usize, usize), ([f64; 2], usize)>;

/// Checks `map` (see the module documentation).
///
/// # Errors
/// A flat road whose lanes lie on themselves, naming the road, its line and the point.
pub(super) fn check(r: &Reader, map: &RoadMap) -> Result<Vec<String>, MapError> {
    let Some(widest) = widest(map) else {
        return Ok(Vec::new());
    };
    let tree = CentreTree::new(&map.lanes, |l| judged(map, l));
    let links = linked(map);
    let reach = widest / 2.0;
    let (crossings, folds) = overlaps(map, &tree, &links, reach);
    let line = |road: usize| {
        r.road_node(&map.roads[road].od_id)
            .map(|n| r.line(n).to_string())
            .unwrap_or_else(|| "?".into())
    };
    let mut warnings = Vec::new();
    for road in folds {
        let id = &map.roads[road].od_id;
        let rises = r.road_node(id).is_some_and(|n| {
            n.descendants()
                .filter(|e| e.has_tag_name("elevation"))
                .any(|e| {
                    ["b", "c", "d"].iter().any(|k| {
                        e.attribute(*k)
                            .and_then(|v| v.trim().parse::<f64>().ok())
                            .is_some_and(|v| v != 0.0)
                    })
                })
        });
        let message = format!(
            "road \"{id}\" (line {}) comes back over itself: its lanes lie on each other more than {SELF_GAP_M} m apart along it",
            line(road)
        );
        if rises {
            warnings.push(format!(
                "{}: {message}; it rises, but maps are flat in paracosm, so its levels meet",
                r.file
            ));
        } else {
            return Err(r.error(r.road_node(id), message));
        }
    }
    let total = crossings.len();
    for ((a, b), (p, _)) in crossings.into_iter().take(NAMED) {
        warnings.push(format!(
            "{}: roads \"{}\" (line {}) and \"{}\" (line {}) overlap at ({:.1}, {:.1}) outside any junction: both are simulated on one flat plane, and their cars do not yield to each other",
            r.file,
            map.roads[a].od_id,
            line(a),
            map.roads[b].od_id,
            line(b),
            p[0] + map.origin_m[0],
            -p[1] + map.origin_m[1],
        ));
    }
    if total > NAMED {
        warnings.push(format!(
            "{}: {} more pairs of roads overlap outside any junction",
            r.file,
            total - NAMED
        ));
    }
    Ok(warnings)
}

/// Whether lane `l` of `map` is checked: a driving lane outside any junction.
fn judged(map: &RoadMap, l: usize) -> bool {
    let lane = &map.lanes[l];
    lane.drivable && map.roads[lane.road].junction.is_none()
}

/// The widest checked lane's width ([`judged`]) at the start of any of its segments, m;
/// `None` where no checked lane has a segment.
fn widest(map: &RoadMap) -> Option<f64> {
    let mut widest = None;
    for (l, lane) in map.lanes.iter().enumerate() {
        if !judged(map, l) {
            continue;
        }
        for i in 0..lane.centre.len().saturating_sub(1) {
            widest = Some(widest.unwrap_or(0.0f64).max(lane.width[i]));
        }
    }
    widest
}

/// Where the checked lanes lie on each other, from each lane's stations (one a metre, away
/// from its ends) to the segments of `tree` within `reach` metres: the pairs of different
/// roads `(smaller, larger)` not linked to each other (`links`), each with the first point
/// found (world `[x, z]`, m) and how many were; and the roads that fold over themselves
/// (their lanes lie on each other more than [`SELF_GAP_M`] apart along the road).
fn overlaps(
    map: &RoadMap,
    tree: &CentreTree,
    links: &BTreeSet<(usize, usize)>,
    reach: f64,
) -> (Crossings, BTreeSet<usize>) {
    // (road, road) -> (point, count); the first point found.
    let mut crossings: Crossings = BTreeMap::new();
    let mut folds: BTreeSet<usize> = BTreeSet::new();
    for (l, lane) in map.lanes.iter().enumerate() {
        if !judged(map, l) {
            continue;
        }
        let (first, last) = lane.s_range();
        let mut next_s = f64::NEG_INFINITY;
        for (i, p) in lane.centre.iter().enumerate() {
            let s = lane.s[i];
            if s < next_s || s - first < END_MARGIN_M || last - s < END_MARGIN_M {
                continue;
            }
            next_s = s + 1.0;
            for (m, j) in tree.within(&map.lanes, *p, reach * reach) {
                let other = &map.lanes[m];
                let (o_first, o_last) = other.s_range();
                let t = other.s[j];
                if t - o_first < END_MARGIN_M || o_last - other.s[j + 1] < END_MARGIN_M {
                    continue;
                }
                let half = other.width[j].min(other.width[j + 1]) / 2.0;
                if Line::new(other.centre[j], other.centre[j + 1])
                    .distance_2(p)
                    .sqrt()
                    > half - INSIDE_MARGIN_M
                {
                    continue;
                }
                let (a, b) = (lane.road, other.road);
                if a == b {
                    if (s - t).abs() > SELF_GAP_M {
                        folds.insert(a);
                    }
                    continue;
                }
                if links.contains(&(a.min(b), a.max(b))) {
                    continue;
                }
                let e = crossings.entry((a.min(b), a.max(b))).or_insert((*p, 0));
                e.1 += 1;
            }
        }
    }
    (crossings, folds)
}

/// The pairs of roads `(smaller, larger)` where a lane of one leads into a lane of the other.
fn linked(map: &RoadMap) -> BTreeSet<(usize, usize)> {
    let mut out = BTreeSet::new();
    for l in &map.lanes {
        for &n in &l.successors {
            let (a, b) = (l.road, map.lanes[n].road);
            out.insert((a.min(b), a.max(b)));
        }
    }
    out
}
