//! Each baked lane's centre offset from its road's reference line (OpenDRIVE's `t`), from
//! the road's `<laneOffset>` records and the baked widths of the lanes between the centre and
//! lane 0 (ASAM OpenDRIVE 1.8, 9.3 "Lane offset" and 9.5.1 "Lane width"): how far a lane
//! drifts across its road, which the motion along a lane leaves out as esmini's does.

use std::collections::BTreeMap;

use super::{attr_f64, Reader};
use crate::network::map::{MapLane, RoadMap};

/// One `<laneOffset>` record: from station `s` (m), `a + b·ds + c·ds² + d·ds³` (m).
type Cubic = [f64; 5];

/// The `<laneOffset>` records of every road of `r`, by road id, in order of `s`.
fn lane_offsets(r: &Reader) -> BTreeMap<String, Vec<Cubic>> {
    r.roads()
        .map(|road| {
            let mut records: Vec<Cubic> = road
                .children()
                .filter(|n| n.has_tag_name("lanes"))
                .flat_map(|lanes| lanes.children().filter(|n| n.has_tag_name("laneOffset")))
                .map(|n| {
                    let v = |k: &str| attr_f64(n, k).filter(|x| x.is_finite()).unwrap_or(0.0);
                    [v("s"), v("a"), v("b"), v("c"), v("d")]
                })
                .collect();
            records.sort_by(|x, y| x[0].total_cmp(&y[0]));
            (road.attribute("id").unwrap_or("").to_owned(), records)
        })
        .collect()
}

/// The lane offset at station `s` (m): the last record starting at or before `s`, 0 before
/// the first (the standard's default).
fn offset_at(records: &[Cubic], s: f64) -> f64 {
    let k = records.partition_point(|r| r[0] <= s);
    if k == 0 {
        return 0.0;
    }
    let [s0, a, b, c, d] = records[k - 1];
    let ds = s - s0;
    a + ds * (b + ds * (c + ds * d))
}

/// The width of `lane` at station `s` (m), linear between its stations, held past its ends.
fn width_at(lane: &MapLane, s: f64) -> f64 {
    let i = lane.s.partition_point(|&x| x <= s);
    if i == 0 {
        return lane.width[0];
    }
    if i >= lane.s.len() {
        return lane.width[lane.width.len() - 1];
    }
    let (s0, s1) = (lane.s[i - 1], lane.s[i]);
    let u = if s1 > s0 { (s - s0) / (s1 - s0) } else { 0.0 };
    lane.width[i - 1] + u * (lane.width[i] - lane.width[i - 1])
}

/// Fills every lane's [`MapLane::t`] of `map`, read from `r`: at each station, the road's
/// lane offset plus (lanes left of lane 0) or less (right) the widths of the lanes of its
/// section between it and lane 0 and half its own.
pub(super) fn centre_offsets(r: &Reader, map: &mut RoadMap) {
    let offsets = lane_offsets(r);
    // The lanes of each road section, by their OpenDRIVE ids.
    let mut sections: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
    for (k, l) in map.lanes.iter().enumerate() {
        sections.entry((l.road, l.section)).or_default().push(k);
    }
    let none = Vec::new();
    let mut ts = Vec::with_capacity(map.lanes.len());
    for l in &map.lanes {
        let records = offsets.get(&map.roads[l.road].od_id).unwrap_or(&none);
        let inner: Vec<&MapLane> = sections[&(l.road, l.section)]
            .iter()
            .map(|&j| &map.lanes[j])
            .filter(|o| o.od_id.signum() == l.od_id.signum() && o.od_id.abs() < l.od_id.abs())
            .collect();
        let side = f64::from(l.od_id.signum());
        let t =
            l.s.iter()
                .zip(&l.width)
                .enumerate()
                .map(|(i, (&s, &w))| {
                    // A lane of the same section has the same stations but where the crate gave
                    // no point: its width is read at the station's index, else found by `s`.
                    let between: f64 = inner
                        .iter()
                        .map(|o| match o.s.get(i) {
                            Some(&os) if os == s => o.width[i],
                            _ => width_at(o, s),
                        })
                        .sum();
                    offset_at(records, s) + side * (between + w / 2.0)
                })
                .collect();
        ts.push(t);
    }
    for (l, t) in map.lanes.iter_mut().zip(ts) {
        l.t = t;
    }
}

#[cfg(test)]
mod tests {
    /// On esmini's `soderleden.xodr` the ramp (road 5) carries its lane from 1.75 m left of
    /// its reference line to 1.75 m right of it by a cubic `<laneOffset>` (its lane −1, 3.5 m
    /// wide, from `t` = 0 to −3.5 m); the main road (road 0, a lane offset of 3.5 m) has its
    /// lane −2 at −1.75 m all along.
    #[test]
    fn a_lanes_centre_offset_follows_the_lane_offset_and_the_widths_inside_it() {
        let path = format!(
            "{}/../tests/data/xosc/esmini/xodr/soderleden.xodr",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let map = super::super::import(&path, &text).unwrap().map;
        let lane = |road: &str, id: i32| {
            map.lanes
                .iter()
                .find(|l| map.roads[l.road].od_id == road && l.od_id == id && l.section == 0)
                .unwrap()
        };
        let ramp = lane("5", -1);
        assert_eq!(ramp.t.len(), ramp.s.len());
        assert!(ramp.t[0].abs() < 1e-9, "{}", ramp.t[0]);
        assert!(
            (ramp.t[ramp.t.len() - 1] + 3.5).abs() < 1e-3,
            "{:?}",
            ramp.t.last()
        );
        let main = lane("0", -2);
        assert!(main.t.iter().all(|t| (t + 1.75).abs() < 1e-9));
        let left = lane("0", 1);
        assert!(
            left.t.iter().all(|t| (t - 3.65).abs() < 1e-6),
            "{:?}",
            left.t.first()
        );
    }
}
