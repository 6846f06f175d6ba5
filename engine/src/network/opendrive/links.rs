//! The lane graph as the file gives it, read by paracosm from the document rather than taken
//! from the `xodr` crate, and the gaps its links cross, measured on the baked lanes.
//!
//! The crate (0.8) drops lane sections shorter than a millimetre and then reads the link of the
//! section before one as a link into the next road (CARLA's Town02, 04 and 05 have sections
//! of 0.1–0.3 mm), and its gap measure found links of Town03 and Town06 that meet 0.96 m and
//! 3.5 m apart (the latter at a section's end evaluated with the next section's `laneOffset`).
//! Here, as the OpenDRIVE standard (1.6, 1.7) has it:
//!
//! - a lane leaves by its travel end: a lane driven along `s` by its section's end, one driven
//!   against `s` by its start. Its `<successor>` (along `s`) or `<predecessor>` (against it)
//!   ids name the lanes of the next section of its road, or, at the road's end, of the road its
//!   road `<link>` names there, in that road's first section for `contactPoint="start"` (then
//!   driven along `s`) or its last for `"end"` (then driven against `s`);
//! - a road whose `<link>` names a junction there leads into every connection of that junction
//!   whose `incomingRoad` it is: each `<laneLink from to>` from the lane leads into lane `to`
//!   of the `connectingRoad` (`linkedRoad` in a direct junction) at the connection's
//!   `contactPoint`, either end;
//! - a lane section shorter than [`SHORT_SECTION_M`] bakes no lanes: a link into one of its
//!   lanes is followed on through it, by that lane's own links;
//! - a section ends where the next one starts, and its lanes' last stations are evaluated just
//!   before that `s`, with the section's own `laneOffset` and widths: a `laneOffset` record
//!   starting with the next section applies from there on (`sample_lane`).
//!
//! A link's gap is the shortest distance between the line across the lane where it leaves
//! (border to border) and the line across the next lane where it enters: a lane that splits
//! in two meets both along its border. A gap up to [`LINK_SILENT_M`] is silent; up to
//! [`LINK_GAP_M`] it is a warning with the gaps measured; beyond, the map is refused.

use std::collections::{BTreeMap, HashMap};

use roxmltree::Node;

use super::super::map::{MapLane, MapRoad, RoadMap};
use super::{attr_f64, MapError, Reader};

/// A lane section shorter than this bakes no lanes (as in the `xodr` crate), m: the lane graph
/// steps over it by its lanes' links.
pub const SHORT_SECTION_M: f64 = 1e-3;

/// The largest gap a lane link may cross without a word, m: where a lane leaves off and the
/// next begins, measured across both lanes from border to border. Links that meet are under
/// 1 cm apart on CARLA's and esmini's maps.
pub const LINK_SILENT_M: f64 = 0.1;

/// The largest gap a lane link may cross before the map is refused, m. A gap is a hole in the
/// driving surface that a car following the link crosses in a step or two: at 10 m/s, half a
/// metre is 0.05 s, during which `OffRoadMonitor` may read the ego as off the road.
pub const LINK_GAP_M: f64 = 0.5;

/// Which end of a road a link reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Contact {
    Start,
    End,
}

/// What a road's `<predecessor>` or `<successor>` names.
#[derive(Debug, Clone)]
enum Target {
    /// A road (index into [`Topology::roads`]) at one of its ends.
    Road(usize, Contact),
    /// A junction, by its `id`.
    Junction(String),
}

/// One `<laneSection>`: where it starts and ends along its road (m), and each lane's links
/// by lane id: `(predecessor ids, successor ids)`.
struct Section {
    start: f64,
    end: f64,
    lanes: HashMap<i32, (Vec<i32>, Vec<i32>)>,
}

/// One `<road>`: its lane sections in order of `s`, and its road links.
struct Road {
    sections: Vec<Section>,
    predecessor: Option<Target>,
    successor: Option<Target>,
}

/// One junction `<connection>`: the incoming and connecting roads (indices), the end of the
/// connecting road it enters, and its lane links `(from, to)`.
struct Connection {
    incoming: usize,
    connecting: usize,
    contact: Contact,
    lanes: Vec<(i32, i32)>,
}

/// A lane of the document, driven one way: its road (index), section (index in order of
/// `s`), `<lane id>`, and whether it is driven along `s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Way {
    road: usize,
    section: usize,
    lane: i32,
    forward: bool,
}

/// A document's roads, lane sections, links and junction connections.
pub(super) struct Topology {
    roads: Vec<Road>,
    by_id: HashMap<String, usize>,
    junctions: HashMap<String, Vec<Connection>>,
}

fn contact(n: Node) -> Contact {
    match n.attribute("contactPoint") {
        Some("end") => Contact::End,
        _ => Contact::Start,
    }
}

/// A lane's `<link>` ids: `(predecessors, successors)`.
fn lane_links(lane: Node) -> (Vec<i32>, Vec<i32>) {
    let Some(link) = lane.children().find(|n| n.has_tag_name("link")) else {
        return (Vec::new(), Vec::new());
    };
    let ids = |tag: &str| {
        link.children()
            .filter(|n| n.has_tag_name(tag))
            .filter_map(|n| n.attribute("id")?.trim().parse::<i32>().ok())
            .collect()
    };
    (ids("predecessor"), ids("successor"))
}

/// A road's lane sections, in order of `s` (a stable sort: as the `xodr` crate numbers
/// them), each ending where the next starts or at the road's `length`.
fn sections(road: Node) -> Vec<Section> {
    let length = attr_f64(road, "length").unwrap_or(0.0);
    let mut nodes: Vec<(f64, Node)> = road
        .children()
        .filter(|n| n.has_tag_name("lanes"))
        .flat_map(|l| l.children().filter(|n| n.has_tag_name("laneSection")))
        .map(|n| (attr_f64(n, "s").unwrap_or(0.0), n))
        .collect();
    nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let starts: Vec<f64> = nodes.iter().map(|(s, _)| *s).collect();
    nodes
        .iter()
        .enumerate()
        .map(|(k, (start, n))| {
            let lanes = n
                .descendants()
                .filter(|l| l.has_tag_name("lane"))
                .filter_map(|l| {
                    let id = l.attribute("id")?.trim().parse::<i32>().ok()?;
                    Some((id, lane_links(l)))
                })
                .collect();
            Section {
                start: *start,
                end: starts.get(k + 1).copied().unwrap_or(length).min(length),
                lanes,
            }
        })
        .collect()
}

/// Each lane section's start along its road (m, in order of `s`, as the `xodr` crate numbers
/// sections) and the road's `length` (m), by road id.
pub(super) fn section_starts(r: &Reader) -> BTreeMap<String, (Vec<f64>, f64)> {
    r.roads()
        .map(|road| {
            let starts = sections(road).iter().map(|s| s.start).collect();
            (
                road.attribute("id").unwrap_or("").to_owned(),
                (starts, attr_f64(road, "length").unwrap_or(0.0)),
            )
        })
        .collect()
}

impl Topology {
    /// Reads the roads, their lane sections and links, and the junctions' connections.
    pub(super) fn read(r: &Reader) -> Topology {
        let nodes: Vec<Node> = r.roads().collect();
        let by_id: HashMap<String, usize> = nodes
            .iter()
            .enumerate()
            .map(|(k, n)| (n.attribute("id").unwrap_or("").to_owned(), k))
            .collect();
        let target = |road: Node, tag: &str| {
            let link = road.children().find(|n| n.has_tag_name("link"))?;
            let end = link.children().find(|n| n.has_tag_name(tag))?;
            // A link part way along a road (a virtual junction's `elementS`) is no road's end.
            if end.attribute("elementS").is_some() {
                return None;
            }
            let id = end.attribute("elementId")?;
            match end.attribute("elementType") {
                Some("junction") => Some(Target::Junction(id.to_owned())),
                _ => Some(Target::Road(*by_id.get(id)?, contact(end))),
            }
        };
        let roads = nodes
            .iter()
            .map(|&n| Road {
                sections: sections(n),
                predecessor: target(n, "predecessor"),
                successor: target(n, "successor"),
            })
            .collect();
        let mut junctions: HashMap<String, Vec<Connection>> = HashMap::new();
        let root = r.doc.root_element();
        for j in root.children().filter(|n| n.has_tag_name("junction")) {
            let key = if j.attribute("type") == Some("direct") {
                "linkedRoad"
            } else {
                "connectingRoad"
            };
            let conns = j
                .children()
                .filter(|n| n.has_tag_name("connection"))
                .filter_map(|c| {
                    let road = |k: &str| by_id.get(c.attribute(k)?).copied();
                    Some(Connection {
                        incoming: road("incomingRoad")?,
                        connecting: road(key)?,
                        contact: contact(c),
                        lanes: c
                            .children()
                            .filter(|n| n.has_tag_name("laneLink"))
                            .filter_map(|l| {
                                let id = |k: &str| l.attribute(k)?.trim().parse::<i32>().ok();
                                Some((id("from")?, id("to")?))
                            })
                            .collect(),
                    })
                });
            junctions
                .entry(j.attribute("id").unwrap_or("").to_owned())
                .or_default()
                .extend(conns);
        }
        Topology {
            roads,
            by_id,
            junctions,
        }
    }

    /// The lane `lane` of road `road` entered at `at`: in its first section, driven along `s`,
    /// from its start; in its last, driven against `s`, from its end.
    fn entered(&self, road: usize, at: Contact, lane: i32) -> Option<Way> {
        let n = self.roads[road].sections.len();
        let (section, forward) = match at {
            Contact::Start => (0, true),
            Contact::End => (n.checked_sub(1)?, false),
        };
        self.roads[road].sections[section]
            .lanes
            .contains_key(&lane)
            .then_some(Way {
                road,
                section,
                lane,
                forward,
            })
    }

    /// The lanes a car leaving `w` by its travel end drives into (see the module
    /// documentation).
    fn next(&self, w: Way) -> Vec<Way> {
        let road = &self.roads[w.road];
        let Some((pred, succ)) = road.sections[w.section].lanes.get(&w.lane) else {
            return Vec::new();
        };
        let ids = if w.forward { succ } else { pred };
        let within = if w.forward {
            (w.section + 1 < road.sections.len()).then_some(w.section + 1)
        } else {
            w.section.checked_sub(1)
        };
        if let Some(section) = within {
            return ids
                .iter()
                .filter(|id| road.sections[section].lanes.contains_key(id))
                .map(|&lane| Way { section, lane, ..w })
                .collect();
        }
        let target = if w.forward {
            &road.successor
        } else {
            &road.predecessor
        };
        match target {
            None => Vec::new(),
            Some(Target::Road(to, at)) => ids
                .iter()
                .filter_map(|&id| self.entered(*to, *at, id))
                .collect(),
            Some(Target::Junction(j)) => self
                .junctions
                .get(j)
                .into_iter()
                .flatten()
                .filter(|c| c.incoming == w.road)
                .flat_map(|c| {
                    c.lanes
                        .iter()
                        .filter(|(from, _)| *from == w.lane)
                        .filter_map(|&(_, to)| self.entered(c.connecting, c.contact, to))
                })
                .collect(),
        }
    }

    /// The baked lanes a car leaving `w` drives into (`baked`: baked lane index by road,
    /// section and lane id), stepping through the lanes of sections shorter than
    /// [`SHORT_SECTION_M`], each lane once, with whether the link enters it driving along `s`.
    fn next_baked(
        &self,
        w: Way,
        baked: &HashMap<(usize, usize, i32), usize>,
    ) -> Vec<(usize, bool)> {
        let mut out = Vec::new();
        // A ring's lane may lead into itself: `w` is not counted as seen.
        let mut seen = Vec::new();
        let mut stack = self.next(w);
        while let Some(n) = stack.pop() {
            if seen.contains(&n) {
                continue;
            }
            seen.push(n);
            if let Some(&k) = baked.get(&(n.road, n.section, n.lane)) {
                if !out.contains(&(k, n.forward)) {
                    out.push((k, n.forward));
                }
                continue;
            }
            let s = &self.roads[n.road].sections[n.section];
            if s.end - s.start < SHORT_SECTION_M {
                stack.extend(self.next(n));
            }
        }
        out.sort_unstable();
        out
    }

    /// Sets each baked lane's successors: every baked lane a car leaving its travel end
    /// drives into, drivable or not. Returns the links that enter a lane against the way it
    /// is driven, `(from, to)` lane indices, which are left out.
    pub(super) fn link(&self, lanes: &mut [MapLane], roads: &[MapRoad]) -> Vec<(usize, usize)> {
        let road_of: Vec<Option<usize>> = roads
            .iter()
            .map(|r| self.by_id.get(&r.od_id).copied())
            .collect();
        let baked: HashMap<(usize, usize, i32), usize> = lanes
            .iter()
            .enumerate()
            .filter_map(|(k, l)| Some(((road_of[l.road]?, l.section, l.od_id), k)))
            .collect();
        let mut wrong_way = Vec::new();
        for k in 0..lanes.len() {
            let l = &lanes[k];
            let Some(road) = road_of[l.road] else {
                continue;
            };
            let w = Way {
                road,
                section: l.section,
                lane: l.od_id,
                forward: l.forward,
            };
            let mut to = Vec::new();
            for (n, forward) in self.next_baked(w, &baked) {
                if lanes[n].forward == forward {
                    to.push(n);
                } else {
                    wrong_way.push((k, n));
                }
            }
            lanes[k].successors = to;
        }
        wrong_way
    }
}

/// A lane link that crosses a gap: the lanes it joins (indices), the gap (m) and where the
/// first lane leaves off (world `[x, z]`, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Gap {
    /// The lane the link leaves (index into the map's lanes).
    pub from: usize,
    /// The lane it leads into.
    pub to: usize,
    /// The gap, m.
    pub gap_m: f64,
    /// Where `from` leaves off, world `[x, z]` m.
    pub at: [f64; 2],
}

/// The line across lane `l` from border to border at its station `i`, world `[x, z]` m.
fn across(l: &MapLane, i: usize) -> [[f64; 2]; 2] {
    let (c, r, h) = (l.centre[i], l.right(i), l.width[i] / 2.0);
    [
        [c[0] - h * r[0], c[1] - h * r[1]],
        [c[0] + h * r[0], c[1] + h * r[1]],
    ]
}

/// The distance from `p` to the segment `s`, m.
fn to_segment(p: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let u = if len2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - u * d[0]).hypot(p[1] - a[1] - u * d[1])
}

/// The shortest distance between two segments in the plane, m: 0 where they cross.
fn between(p: [[f64; 2]; 2], q: [[f64; 2]; 2]) -> f64 {
    let side = |[a, b]: [[f64; 2]; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let crosses = side(p, q[0]) * side(p, q[1]) < 0.0 && side(q, p[0]) * side(q, p[1]) < 0.0;
    if crosses {
        return 0.0;
    }
    [
        to_segment(p[0], q),
        to_segment(p[1], q),
        to_segment(q[0], p),
        to_segment(q[1], p),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Every lane link of `lanes` whose lanes are more than [`LINK_SILENT_M`] apart where one
/// leaves off and the next begins, measured across both from border to border.
pub(super) fn gaps(lanes: &[MapLane]) -> Vec<Gap> {
    let mut out = Vec::new();
    for (k, l) in lanes.iter().enumerate() {
        let exit = if l.forward { l.s.len() - 1 } else { 0 };
        for &n in &l.successors {
            let m = &lanes[n];
            let entry = if m.forward { 0 } else { m.s.len() - 1 };
            let gap_m = between(across(l, exit), across(m, entry));
            if gap_m > LINK_SILENT_M {
                out.push(Gap {
                    from: k,
                    to: n,
                    gap_m,
                    at: l.centre[exit],
                });
            }
        }
    }
    out
}

/// `road "id" lane L (section k)` for lane `k` of `map`.
fn name(map: &RoadMap, k: usize) -> String {
    let l = &map.lanes[k];
    format!(
        "road \"{}\" lane {} (section {})",
        map.roads[l.road].od_id, l.od_id, l.section
    )
}

/// Links the lanes of `map` as the document `r` gives them (see the module documentation),
/// keeping the drivable successors of each, and checks the links' gaps. Returns the warnings:
/// links across gaps over [`LINK_SILENT_M`], links into lanes driven the other way (left out).
///
/// # Errors
/// A [`MapError`] at the road whose lane a link leaves, for a link across a gap over
/// [`LINK_GAP_M`], naming both lanes, the gap and where.
pub(super) fn link_and_check(r: &Reader, map: &mut RoadMap) -> Result<Vec<String>, MapError> {
    let topology = Topology::read(r);
    let wrong_way = topology.link(&mut map.lanes, &map.roads);
    let drivable: Vec<bool> = map.lanes.iter().map(|l| l.drivable).collect();
    for l in &mut map.lanes {
        l.successors.retain(|&n| drivable[n]);
    }
    let file = |p: [f64; 2]| (p[0] + map.origin_m[0], -p[1] + map.origin_m[1]);
    let mut warnings = Vec::new();
    let gaps = gaps(&map.lanes);
    if let Some(g) = gaps.iter().max_by(|a, b| a.gap_m.total_cmp(&b.gap_m)) {
        let (x, y) = file(g.at);
        if g.gap_m > LINK_GAP_M {
            return Err(r.error(
                r.road_node(&map.roads[map.lanes[g.from].road].od_id),
                format!(
                    "{} links to {}, but they are {:.2} m apart where one leaves off and the other begins, at ({x:.2}, {y:.2}): a lane link may cross at most {LINK_GAP_M} m",
                    name(map, g.from),
                    name(map, g.to),
                    g.gap_m
                ),
            ));
        }
        let least = gaps.iter().map(|g| g.gap_m).fold(f64::INFINITY, f64::min);
        let span = if format!("{least:.2}") == format!("{:.2}", g.gap_m) {
            format!("{least:.2}")
        } else {
            format!("{least:.2}–{:.2}", g.gap_m)
        };
        warnings.push(format!(
            "{}: {} lane link{} cross{} a gap of {span} m (over {LINK_SILENT_M} m, at most {LINK_GAP_M} m), the widest from {} to {} at ({x:.2}, {y:.2}); cars drive across it",
            r.file,
            gaps.len(),
            if gaps.len() == 1 { "" } else { "s" },
            if gaps.len() == 1 { "es" } else { "" },
            name(map, g.from),
            name(map, g.to),
        ));
    }
    let wrong_way: Vec<&(usize, usize)> = wrong_way
        .iter()
        .filter(|(a, b)| drivable[*a] && drivable[*b])
        .collect();
    if let Some(&&(a, b)) = wrong_way.first() {
        warnings.push(format!(
            "{}: {} lane link{} lead{} into a lane driven the other way, the first from {} to {}; not followed",
            r.file,
            wrong_way.len(),
            if wrong_way.len() == 1 { "" } else { "s" },
            if wrong_way.len() == 1 { "s" } else { "" },
            name(map, a),
            name(map, b),
        ));
    }
    Ok(warnings)
}
