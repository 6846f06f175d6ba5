//! OpenDRIVE import: a `.xodr` document baked into a [`RoadMap`].
//!
//! The `xodr` crate parses the document and evaluates its geometry (line, arc, spiral, poly3,
//! paramPoly3 records, lane sections with width polynomials, lane offsets, junction
//! connections) into lane centre lines and a lane graph. This module adds what a testing
//! tool needs on top:
//!
//! - every element is checked against the OpenDRIVE schema's element names: an unknown one is
//!   an error naming its line;
//! - what paracosm does not use (elevation beyond flat, superelevation, signals, objects,
//!   lane borders, road marks, speed records...) is named in a warning, with a count and the
//!   first line;
//! - faults the crate would repair silently or with a warning (a dropped road or geometry, a
//!   lane link that does not meet, a road that does not exist) are errors, as are a lane
//!   width below zero and a gap between consecutive geometry records;
//! - lanes are sampled every 0.5 m of their road's reference line.

use std::collections::BTreeMap;
use std::sync::Arc;

use roxmltree::{Document, Node};

use super::map::{MapLane, MapRoad, RoadMap};

mod links;
mod numbers;
mod offsets;
mod overlaps;
mod recentre;

pub use links::{LINK_GAP_M, LINK_SILENT_M, SHORT_SECTION_M};
pub use numbers::{
    MAX_COORDINATE_M, MAX_CURVATURE_PER_M, MAX_LANES_PER_SIDE, MAX_LANE_WIDTH_M, MAX_ROAD_LENGTH_M,
};
pub use overlaps::{END_MARGIN_M, INSIDE_MARGIN_M};
pub use recentre::RESOLVED_M;

/// Largest distance between consecutive geometry records' end and start, m, and between a
/// baked centre line and its record's start, before the map is refused as having a gap.
pub const GEOMETRY_GAP_M: f64 = 0.01;

/// How far before its section's end a lane's last station is evaluated, m: below the `f32`
/// points' resolution, but past the crate's 1e-9 m tie, so the section's own `<laneOffset>`
/// applies there rather than one that starts with the next section.
const SECTION_END_M: f64 = 1e-6;

/// Largest step between a lane's stations, m.
pub const MAP_STEP_M: f64 = 0.5;

/// Most lane stations a map may bake into (all lanes together): about 250 km of lane.
pub const MAX_MAP_STATIONS: usize = 500_000;

/// An OpenDRIVE document that cannot be used, with where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{file}{}{}: {message}",
    .line.map(|l| format!(":{l}")).unwrap_or_default(),
    .column.filter(|_| line.is_some()).map(|c| format!(":{c}")).unwrap_or_default()
)]
pub struct MapError {
    /// The file, as the program names it.
    pub file: String,
    /// The 1-based line of the element at fault, where known.
    pub line: Option<u32>,
    /// The 1-based column of the element (or of the attribute's value) at fault, where known.
    pub column: Option<u32>,
    /// What is wrong, naming the element.
    pub message: String,
}

/// A map read from a document, with what it did not use.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The map.
    pub map: Arc<RoadMap>,
    /// One line per kind of element or record paracosm does not use (for example
    /// "12 <signal> elements (first at line 40): signals are not simulated").
    pub warnings: Vec<String>,
}

/// Elements paracosm bakes into the map.
const USED: &[&str] = &[
    "OpenDRIVE",
    "header",
    "geoReference",
    "offset",
    "road",
    "link",
    "predecessor",
    "successor",
    "planView",
    "geometry",
    "line",
    "arc",
    "spiral",
    "poly3",
    "paramPoly3",
    "lanes",
    "laneOffset",
    "laneSection",
    "left",
    "center",
    "right",
    "lane",
    "width",
    "junction",
    "connection",
    "laneLink",
    "elevationProfile",
    "lateralProfile",
];

/// Elements of the OpenDRIVE schema paracosm reads nothing from: `(name, why)`. Their
/// children are not checked.
const UNUSED: &[(&str, &str)] = &[
    ("signals", "traffic signals and signs are not simulated"),
    ("objects", "road objects are not simulated"),
    (
        "roadMark",
        "lane markings are drawn by paracosm's own rule, not the map's",
    ),
    (
        "border",
        "lane <border>s are baked by the xodr crate; paracosm has no test of them",
    ),
    (
        "speed",
        "speed limits are not read (each car's speed is the program's)",
    ),
    ("type", "road types are not read"),
    (
        "material",
        "lane materials are not read (a map has one friction)",
    ),
    ("access", "lane access rules are not read"),
    ("height", "lane heights are dropped: maps are flat"),
    ("rule", "lane rules are not read"),
    ("visibility", "lane visibility is not read"),
    ("surface", "OpenCRG surfaces are dropped: maps are flat"),
    ("railroad", "railways are not simulated"),
    ("controller", "signal controllers are not simulated"),
    (
        "priority",
        "junction priorities are not read (NPC cars do not yield)",
    ),
    ("controller", "junction controllers are not read"),
    ("crossPath", "junction cross paths are not read"),
    ("boundary", "junction boundaries are not read"),
    (
        "elevationGrid",
        "junction elevation grids are dropped: maps are flat",
    ),
    ("junctionGroup", "junction groups are not read"),
    ("station", "stations are not simulated"),
    ("neighbor", "road neighbours are not read"),
    ("userData", "user data is not read"),
    ("include", "includes are not read"),
    ("dataQuality", "data-quality records are not read"),
    ("shape", "lateral shapes are dropped: maps are flat"),
];

/// Profile records that are kept only when they say nothing: `(name, why when not)`.
const FLAT: &[(&str, &str)] = &[
    ("elevation", "elevation is dropped: maps are flat, at y = 0"),
    ("superelevation", "superelevation is dropped: maps are flat"),
    ("crossfall", "crossfall is dropped: maps are flat"),
];

/// `xodr` warnings that are faults of the map, refused rather than repaired.
const FAULTS: &[&str] = &[
    "RoadSkipped",
    "GeometryDropped",
    "LaneIdUnreadable",
    "LaneOnWrongSide",
    "LaneIdRepeated",
    "LaneDropped",
    "BorderCrossesInnerLane",
    "ConnectionDropped",
    "LaneLinkDropped",
    "JunctionLinkMissing",
    "RecordDropped",
    "RecordValueUnreadable",
    "LaneSectionDropped",
    "ContactPointMissing",
];

fn attr_f64(n: Node, name: &str) -> Option<f64> {
    n.attribute(name).and_then(|v| v.trim().parse::<f64>().ok())
}

struct Reader<'a> {
    file: &'a str,
    doc: &'a Document<'a>,
    /// Byte offset of each line's start: `roxmltree`'s `text_pos_at` walks the text from its
    /// start at every call, which was most of loading a town.
    line_starts: Vec<usize>,
}

impl<'a> Reader<'a> {
    fn new(file: &'a str, doc: &'a Document<'a>) -> Self {
        let text = doc.input_text();
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Reader {
            file,
            doc,
            line_starts,
        }
    }

    /// Line and column (from 1; columns in characters) of byte `offset`, as `text_pos_at`.
    fn pos_at(&self, offset: usize) -> (u32, u32) {
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let text = self.doc.input_text();
        let col = text
            .get(start..offset.min(text.len()))
            .map_or(1, |s| s.chars().count() + 1);
        (line as u32, col as u32)
    }

    fn line(&self, n: Node) -> u32 {
        self.pos_at(n.range().start).0
    }

    fn error(&self, n: Option<Node>, message: String) -> MapError {
        let pos = n.map(|n| self.pos_at(n.range().start));
        MapError {
            file: self.file.to_owned(),
            line: pos.map(|p| p.0),
            column: pos.map(|p| p.1),
            message,
        }
    }

    fn roads(&self) -> impl Iterator<Item = Node<'_, '_>> {
        self.doc
            .root_element()
            .children()
            .filter(|n| n.has_tag_name("road"))
    }

    fn road_node(&self, id: &str) -> Option<Node<'_, '_>> {
        self.roads().find(|n| n.attribute("id") == Some(id))
    }
}

/// Reads the OpenDRIVE document `text` (the contents of `file`).
///
/// # Errors
/// [`MapError`] naming the file, the element and its line, for XML that is not well formed,
/// a root that is not `<OpenDRIVE>`, an element the schema does not have, a road or junction
/// that a link or connection names but the document lacks, a lane width below zero, a gap
/// between geometry records, a fault the `xodr` crate reports, or a map too large to bake.
pub fn import(file: &str, text: &str) -> Result<Imported, MapError> {
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        MapError {
            file: file.to_owned(),
            line: Some(pos.row),
            column: Some(pos.col),
            message: format!("malformed XML: {e}"),
        }
    })?;
    let r = Reader::new(file, &doc);
    let root = doc.root_element();
    if !root.has_tag_name("OpenDRIVE") {
        return Err(r.error(
            Some(root),
            format!(
                "the root element is <{}>; an OpenDRIVE map's is <OpenDRIVE>",
                root.tag_name().name()
            ),
        ));
    }
    let mut warnings = check_elements(&r, root)?;
    numbers::check(&r, root)?;
    warnings.extend(numbers::lane_type_warnings(&r, root));
    warnings.extend(numbers::widthless_lane_warnings(&r, root));
    warnings.extend(check_references(&r)?);
    check_widths(&r)?;
    // A map far from the origin is moved to it, in its text, before anything evaluates it.
    let shift = recentre::shift(&r, root)?;
    let moved;
    let (doc, text) = match shift {
        Some(by) => {
            moved = recentre::apply(&doc, text, by);
            warnings.push(format!(
                "{file}: the map lies {:.1} km from the origin, where the f32 physics resolves {:.2} m; it is simulated moved by ({}, {}) m (exports write the file's own coordinates)",
                by[0].hypot(by[1]) / 1e3,
                f64::from(f32::EPSILON) * by[0].abs().max(by[1].abs()),
                -by[0],
                -by[1]
            ));
            let doc = Document::parse(&moved).map_err(|e| MapError {
                file: file.to_owned(),
                line: None,
                column: None,
                message: format!("the recentred map does not parse: {e}"),
            })?;
            (doc, moved.as_str())
        }
        None => (doc, text),
    };
    let r = Reader::new(file, &doc);
    let (net, provenance) = crate_bake(&r, text)?;
    warnings.extend(crate_warnings(&r, &provenance)?);
    check_self_links(&r, &net)?;
    check_gaps(&r, &net)?;
    let mut map = bake(&r, &net, &provenance)?;
    offsets::centre_offsets(&r, &mut map);
    map.origin_m = shift.unwrap_or([0.0, 0.0]);
    warnings.extend(links::link_and_check(&r, &mut map)?);
    warnings.extend(overlaps::check(&r, &map)?);
    Ok(Imported {
        map: Arc::new(map),
        warnings,
    })
}

/// The `xodr` crate's reading of `text`, the map `r` reads.
///
/// # Errors
/// A map the crate bakes no road of: at the first lane with neither width nor border where
/// that is why, else naming the crate's reason.
fn crate_bake(r: &Reader, text: &str) -> Result<(xodr::RoadNetwork, xodr::Provenance), MapError> {
    let (file, doc) = (r.file, r.doc);
    xodr::load_str_with_provenance(text).map_err(|e| {
        // A map whose every lane has neither width nor border has no lane to bake.
        match numbers::first_widthless_lane(doc.root_element()) {
            Some(lane) => r.error(
                Some(lane),
                format!(
                    "lane {} of road \"{}\" has neither <width> nor <border>: it is 0 m wide, and no lane of the map has a width, so there is no road surface (the xodr crate: {e})",
                    lane.attribute("id").unwrap_or("?"),
                    lane.ancestors()
                        .find(|a| a.has_tag_name("road"))
                        .and_then(|a| a.attribute("id"))
                        .unwrap_or("?")
                ),
            ),
            None => MapError {
                file: file.to_owned(),
                line: None,
                column: None,
                message: format!(
                    "the xodr crate could not bake the map ({e}): every road was skipped, for a reason paracosm's own checks do not name"
                ),
            },
        }
    })
}

/// The crate's warnings about the map `r` reads, as paracosm words them: its faults are
/// errors; what it reads otherwise than written, warnings; what paracosm reads itself (link
/// gaps) or reads as the crate does (lanes without width), nothing.
///
/// # Errors
/// The first fault, at its road.
fn crate_warnings(r: &Reader, provenance: &xodr::Provenance) -> Result<Vec<String>, MapError> {
    let mut warnings = Vec::new();
    for w in &provenance.warnings {
        let debug = format!("{w:?}");
        let variant = debug.split([' ', '{', '(']).next().unwrap_or("");
        let road = debug
            .split("road_id: \"")
            .nth(1)
            .and_then(|t| t.split('"').next());
        let node = road.and_then(|id| r.road_node(id));
        // A lane with neither `<width>` nor `<border>` is 0 m wide, and the crate, which drops
        // it and stacks the lanes outside it on the lane inside, bakes the same surface: a
        // warning names it (`numbers::widthless_lane_warnings`).
        if let xodr::Warning::LaneDropped {
            road_id,
            section,
            lane,
        } = w
        {
            if widthless(r, road_id, *section, *lane) {
                continue;
            }
        }
        if FAULTS.contains(&variant) {
            return Err(r.error(
                node,
                format!(
                    "{}{w}",
                    road.map(|id| format!("<road id=\"{id}\">: "))
                        .unwrap_or_default()
                ),
            ));
        }
        // The crate's link gaps come from its own reading of the links; paracosm reads and
        // measures them itself (`links.rs`).
        if !w.is_ignored() && variant != "LinkGap" {
            let done = if variant == "RoadLengthMismatch" {
                ": the road is baked to its length, its last geometry running on (as \
                 libOpenDRIVE and the xodr crate read it)"
            } else {
                ""
            };
            warnings.push(format!("{w}{done}"));
        }
    }
    Ok(warnings)
}

/// Whether lane `lane` of lane section `section` (zero-based, in the document's order) of road
/// `road_id` has neither `<width>` nor `<border>`.
fn widthless(r: &Reader, road_id: &str, section: usize, lane: i32) -> bool {
    let Some(road) = r.road_node(road_id) else {
        return false;
    };
    road.descendants()
        .filter(|n| n.has_tag_name("laneSection"))
        .nth(section)
        .and_then(|sec| {
            sec.descendants().find(|n| {
                n.has_tag_name("lane")
                    && n.attribute("id")
                        .and_then(|id| id.trim().parse::<i32>().ok())
                        == Some(lane)
            })
        })
        .is_some_and(|n| {
            !n.children()
                .any(|c| c.has_tag_name("width") || c.has_tag_name("border"))
        })
}

/// Walks the tree: unknown elements are errors; unused ones and non-flat profiles, warnings.
fn check_elements(r: &Reader, root: Node) -> Result<Vec<String>, MapError> {
    // name -> (count, first line, why)
    let mut unused: BTreeMap<String, (usize, u32, &str)> = BTreeMap::new();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        for c in n.children().filter(Node::is_element) {
            let name = c.tag_name().name();
            // A road's <type> holds <speed>; a lane's <link> its predecessors: both known.
            if let Some((_, why)) = UNUSED.iter().find(|(u, _)| *u == name) {
                // An empty container (`<signals/>`, `<objects></objects>`) says nothing.
                let says = c.attributes().len() > 0 || c.children().any(|x| x.is_element());
                if says {
                    let e = unused.entry(name.to_owned()).or_insert((0, r.line(c), why));
                    e.0 += 1;
                }
                continue;
            }
            if let Some((_, why)) = FLAT.iter().find(|(f, _)| *f == name) {
                let sloped = ["b", "c", "d"]
                    .iter()
                    .any(|k| attr_f64(c, k).is_some_and(|v| v != 0.0))
                    || (name != "elevation" && attr_f64(c, "a").is_some_and(|v| v != 0.0));
                if sloped {
                    let e = unused.entry(name.to_owned()).or_insert((0, r.line(c), why));
                    e.0 += 1;
                }
                continue;
            }
            if !USED.contains(&name) {
                return Err(r.error(
                    Some(c),
                    format!(
                        "<{name}> (inside <{}>) is not an OpenDRIVE element",
                        n.tag_name().name()
                    ),
                ));
            }
            stack.push(c);
        }
    }
    let mut out: Vec<(u32, String)> = unused
        .into_iter()
        .map(|(name, (count, line, why))| {
            (
                line,
                format!(
                    "{}:{line}: {count} <{name}> element{} ignored: {why}",
                    r.file,
                    if count == 1 { "" } else { "s" }
                ),
            )
        })
        .collect();
    out.sort();
    Ok(out.into_iter().map(|(_, w)| w).collect())
}

/// Roads and junctions that junction connections name must exist. A road's `<link>` to a
/// road or junction the map lacks leads nowhere: the road ends there (as esmini reads it),
/// with a warning naming the link and its line.
fn check_references(r: &Reader) -> Result<Vec<String>, MapError> {
    let mut warnings = Vec::new();
    let root = r.doc.root_element();
    let has = |tag: &str, id: &str| {
        root.children()
            .any(|n| n.has_tag_name(tag) && n.attribute("id") == Some(id))
    };
    for road in r.roads() {
        let rid = road.attribute("id").unwrap_or("?");
        for link in road.children().filter(|n| n.has_tag_name("link")) {
            for end in link.children().filter(Node::is_element) {
                let (Some(kind), Some(id)) =
                    (end.attribute("elementType"), end.attribute("elementId"))
                else {
                    continue;
                };
                if (kind == "road" || kind == "junction") && !has(kind, id) {
                    warnings.push(format!(
                        "{}:{}: <{}> of road \"{rid}\" names {kind} \"{id}\", which the map does not have: the road ends there",
                        r.file,
                        r.line(end),
                        end.tag_name().name()
                    ));
                }
            }
        }
    }
    for j in root.children().filter(|n| n.has_tag_name("junction")) {
        let jid = j.attribute("id").unwrap_or("?");
        for c in j.children().filter(|n| n.has_tag_name("connection")) {
            for key in ["incomingRoad", "connectingRoad", "linkedRoad"] {
                if let Some(id) = c.attribute(key) {
                    if !has("road", id) {
                        return Err(r.error(
                            Some(c),
                            format!(
                                "<connection> of junction \"{jid}\" names {key} \"{id}\", which the map does not have"
                            ),
                        ));
                    }
                }
            }
        }
    }
    Ok(warnings)
}

/// Every lane `<width>` polynomial stays at or above zero over its stretch.
fn check_widths(r: &Reader) -> Result<(), MapError> {
    for road in r.roads() {
        let rid = road.attribute("id").unwrap_or("?");
        let length = attr_f64(road, "length").unwrap_or(0.0);
        let Some(lanes) = road.children().find(|n| n.has_tag_name("lanes")) else {
            continue;
        };
        let sections: Vec<Node> = lanes
            .children()
            .filter(|n| n.has_tag_name("laneSection"))
            .collect();
        for (k, sec) in sections.iter().enumerate() {
            let s0 = attr_f64(*sec, "s").unwrap_or(0.0);
            let s1 = sections
                .get(k + 1)
                .and_then(|n| attr_f64(*n, "s"))
                .unwrap_or(length);
            let span = (s1 - s0).max(0.0);
            for lane in sec.descendants().filter(|n| n.has_tag_name("lane")) {
                let widths: Vec<Node> = lane
                    .children()
                    .filter(|n| n.has_tag_name("width"))
                    .collect();
                for (i, w) in widths.iter().enumerate() {
                    let from = attr_f64(*w, "sOffset").unwrap_or(0.0);
                    let to = widths
                        .get(i + 1)
                        .and_then(|n| attr_f64(*n, "sOffset"))
                        .unwrap_or(span);
                    let c: Vec<f64> = ["a", "b", "c", "d"]
                        .iter()
                        .map(|k| attr_f64(*w, k).unwrap_or(0.0))
                        .collect();
                    for j in 0..=16 {
                        let ds = (to - from).max(0.0) * f64::from(j) / 16.0;
                        let v = c[0] + ds * (c[1] + ds * (c[2] + ds * c[3]));
                        if v > MAX_LANE_WIDTH_M {
                            return Err(r.error(
                                Some(*w),
                                format!(
                                    "<width> of lane {} on road \"{rid}\" reaches {v:.3e} m at {:.2} m into its stretch; a lane is at most {MAX_LANE_WIDTH_M} m wide",
                                    lane.attribute("id").unwrap_or("?"),
                                    ds
                                ),
                            ));
                        }
                        if v < -1e-9 {
                            return Err(r.error(
                                Some(*w),
                                format!(
                                    "<width> of lane {} on road \"{rid}\" is negative: {v:.3} m at {:.2} m into its stretch",
                                    lane.attribute("id").unwrap_or("?"),
                                    ds
                                ),
                            ));
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Each geometry record starts where the one before it ends (to [`GEOMETRY_GAP_M`]).
fn check_gaps(r: &Reader, net: &xodr::RoadNetwork) -> Result<(), MapError> {
    for road in r.roads() {
        let rid = road.attribute("id").unwrap_or("?");
        let Some(baked) = net.road_by_od_id(rid) else {
            continue;
        };
        let Some(plan) = road.children().find(|n| n.has_tag_name("planView")) else {
            continue;
        };
        let geoms: Vec<Node> = plan
            .children()
            .filter(|n| n.has_tag_name("geometry"))
            .collect();
        for g in geoms.iter().skip(1) {
            let (Some(s), Some(x), Some(y)) =
                (attr_f64(*g, "s"), attr_f64(*g, "x"), attr_f64(*g, "y"))
            else {
                continue;
            };
            let before = net.road_point(xodr::RoadPosition {
                road: baked.id(),
                s: (s - 1e-6).max(0.0),
                t: 0.0,
            });
            if let Some(p) = before {
                let gap = (f64::from(p.x) - x).hypot(f64::from(p.y) - y);
                // f32 points: allow their rounding at the coordinates' size.
                let tolerance =
                    GEOMETRY_GAP_M + 4.0 * f64::from(f32::EPSILON) * x.abs().max(y.abs());
                if gap > tolerance {
                    return Err(r.error(
                        Some(*g),
                        format!(
                            "<geometry s=\"{s}\"> of road \"{rid}\" starts {gap:.3} m from where the record before it ends ({:.3}, {:.3}): a gap in the reference line",
                            p.x, p.y
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A road linked to itself (a ring) must close: its end meets its start.
fn check_self_links(r: &Reader, net: &xodr::RoadNetwork) -> Result<(), MapError> {
    for road in r.roads() {
        let rid = road.attribute("id").unwrap_or("?");
        let Some(link) = road.children().find(|n| n.has_tag_name("link")) else {
            continue;
        };
        for end in link.children().filter(Node::is_element) {
            if end.attribute("elementType") != Some("road")
                || end.attribute("elementId") != Some(rid)
            {
                continue;
            }
            let which = end.tag_name().name();
            let here = if which == "successor" { "end" } else { "start" };
            let there = end.attribute("contactPoint").unwrap_or("?");
            if there == here {
                return Err(r.error(
                    Some(end),
                    format!("road \"{rid}\" is its own {which} at its {here}, the end it leaves from: a road cannot lead into itself there"),
                ));
            }
            let Some(baked) = net.road_by_od_id(rid) else {
                continue;
            };
            let at = |s: f64| {
                net.road_point(xodr::RoadPosition {
                    road: baked.id(),
                    s,
                    t: 0.0,
                })
            };
            let (Some(a), Some(b)) = (at(0.0), at(baked.length())) else {
                continue;
            };
            let gap = (f64::from(a.x) - f64::from(b.x)).hypot(f64::from(a.y) - f64::from(b.y));
            if gap > 10.0 * GEOMETRY_GAP_M {
                return Err(r.error(
                    Some(end),
                    format!(
                        "road \"{rid}\" is its own {which}, but its end ({:.2}, {:.2}) is {gap:.2} m from its start ({:.2}, {:.2}): only a closed ring may lead into itself",
                        b.x, b.y, a.x, a.y
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Samples every permanent lane every [`MAP_STEP_M`] of its road.
fn bake(
    r: &Reader,
    net: &xodr::RoadNetwork,
    provenance: &xodr::Provenance,
) -> Result<RoadMap, MapError> {
    let mut roads: Vec<MapRoad> = Vec::new();
    let mut road_index: BTreeMap<String, usize> = BTreeMap::new();
    // Section ranges from the document: road id -> starts, and the road's length.
    let sections = links::section_starts(r);
    let mut lanes: Vec<MapLane> = Vec::new();
    let mut stations = 0usize;
    for p in &provenance.lanes {
        if p.layer != xodr::Layer::Permanent {
            continue;
        }
        let Some(lane) = net.lane(p.lane) else {
            continue;
        };
        let Some((starts, length)) = sections.get(&p.road_id) else {
            continue;
        };
        let s0 = starts.get(p.section).copied().unwrap_or(0.0);
        let s1 = starts.get(p.section + 1).copied().unwrap_or(*length);
        if s1.partial_cmp(&s0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let road = *road_index.entry(p.road_id.clone()).or_insert_with(|| {
            let baked = net.road_by_od_id(&p.road_id);
            roads.push(MapRoad {
                od_id: p.road_id.clone(),
                length_m: baked.map_or(*length, xodr::Road::length),
                junction: baked.and_then(|b| b.junction().map(str::to_owned)),
            });
            roads.len() - 1
        });
        let n = ((s1 - s0) / MAP_STEP_M).ceil().max(1.0) as usize;
        stations += n + 1;
        if stations > MAX_MAP_STATIONS {
            return Err(r.error(
                None,
                format!(
                    "the map is too large: more than {MAX_MAP_STATIONS} lane stations at one every {MAP_STEP_M} m"
                ),
            ));
        }
        let (ss, centre, width) = sample_lane(r, net, p, lane, (s0, s1), n)?;
        if ss.len() < 2 || width.iter().all(|w| *w <= 0.0) {
            continue;
        }
        lanes.push(MapLane {
            road,
            section: p.section,
            od_id: p.od_id,
            kind: lane.kind.as_str().to_owned(),
            drivable: lane.kind.is_drivable(),
            forward: lane.direction != xodr::Direction::Backward,
            s: ss,
            centre,
            width,
            t: Vec::new(),
            successors: Vec::new(),
        });
    }
    if !lanes.iter().any(|l| l.drivable) {
        return Err(r.error(None, "the map has no driving lane".into()));
    }
    let signals = r
        .doc
        .descendants()
        .filter(|n| n.has_tag_name("signal"))
        .map(|n| {
            let text = |a: &str| n.attribute(a).unwrap_or("").to_owned();
            (text("id"), text("name"))
        })
        .collect();
    Ok(RoadMap {
        source: r.file.to_owned(),
        origin_m: [0.0, 0.0],
        roads,
        lanes,
        signals,
    })
}

/// The width of `lane` wherever it is read (m), when it has one width all along: no width
/// profile, or a profile of one nonzero finite value, whose interpolation gives that value's
/// bits at any distance (`w + (w − w)·t`); `None` for a width that varies.
fn one_width(lane: &xodr::Lane) -> Option<f64> {
    match lane.widths.first() {
        None => Some(f64::from(lane.width_at(0.0))),
        Some(&w)
            if w != 0.0
                && w.is_finite()
                && lane.widths.iter().all(|v| v.to_bits() == w.to_bits()) =>
        {
            Some(f64::from(lane.width_at(0.0)))
        }
        Some(_) => None,
    }
}

/// A lane's stations: each one's `s` (m), the lane's centre there (world `[x, z]`, m) and its
/// width (m).
type Stations = (Vec<f64>, Vec<[f64; 2]>, Vec<f64>);

/// The `n + 1` stations of lane `lane` (`p`) from `s0` to `s1` (m, its section's range),
/// evenly spread: each station's `s` (m), the lane's centre there (world `[x, z]`, m) and
/// its width (m, `>= 0`). A station where the lane has no point is left out.
///
/// # Errors
/// A lane whose centre or width is not finite at a station.
fn sample_lane(
    r: &Reader,
    net: &xodr::RoadNetwork,
    p: &xodr::LaneProvenance,
    lane: &xodr::Lane,
    (s0, s1): (f64, f64),
    n: usize,
) -> Result<Stations, MapError> {
    let (mut ss, mut centre, mut width) = (Vec::new(), Vec::new(), Vec::new());
    let one_width = one_width(lane);
    for i in 0..=n {
        let s = if i == n {
            s1
        } else {
            s0 + (s1 - s0) * i as f64 / n as f64
        };
        // The last station is the section's own: its lane offset and widths just before the
        // next section starts, where a `<laneOffset>` record starting with that section
        // takes over (the crate would evaluate `s1` with it).
        let at = xodr::LanePosition {
            lane: p.lane,
            s: if i == n { s1 - SECTION_END_M } else { s },
            offset: 0.0,
        };
        let Some(c) = net.lane_point(at) else {
            continue;
        };
        // The distance along the lane is read only for a width that varies: the crate sums
        // the lane from its start for each (`centerline_s`), so every station would cost the
        // lane's length. Where `lane_point` has a point, `centerline_s` has a distance.
        let w = match one_width {
            Some(w) => w,
            None => match net.centerline_s(at) {
                Some(cs) => f64::from(lane.width_at(cs)),
                None => continue,
            },
        };
        if !(c.x.is_finite() && c.y.is_finite() && w.is_finite()) {
            return Err(r.error(
                r.road_node(&p.road_id),
                format!(
                    "lane {} of road \"{}\" is not finite at s = {s:.2} m",
                    p.od_id, p.road_id
                ),
            ));
        }
        ss.push(s);
        centre.push([f64::from(c.x), -f64::from(c.y)]);
        width.push(w.max(0.0));
    }
    Ok((ss, centre, width))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where a lane has one width ([`one_width`]), the crate's width at the distance along
    /// the lane gives the same bits at every station, so reading that distance (a sum over
    /// the lane from its start) can be left out without changing the map.
    #[test]
    fn a_lane_of_one_width_has_its_bits_at_every_distance_along_it() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let (mut one, mut varying) = (0, 0);
        for file in [
            "tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_straight.xodr",
            "tests/data/maps/esmini/lane_width_and_offset.xodr",
            "tests/data/maps/esmini/multi_intersections.xodr",
            "tests/data/maps/carla/Town07.xodr",
        ] {
            let text = std::fs::read_to_string(root.join(file)).unwrap();
            let (net, provenance) = xodr::load_str_with_provenance(&text).unwrap();
            for p in &provenance.lanes {
                let Some(lane) = net.lane(p.lane) else {
                    continue;
                };
                let Some(w) = one_width(lane) else {
                    varying += 1;
                    continue;
                };
                let length = net
                    .road_by_od_id(&p.road_id)
                    .map_or(0.0, xodr::Road::length);
                for k in 0..=40 {
                    let at = xodr::LanePosition {
                        lane: p.lane,
                        s: length * f64::from(k) / 40.0,
                        offset: 0.0,
                    };
                    if let Some(cs) = net.centerline_s(at) {
                        assert_eq!(
                            f64::from(lane.width_at(cs)).to_bits(),
                            w.to_bits(),
                            "{file}: road {} lane {} at s = {}",
                            p.road_id,
                            p.od_id,
                            at.s
                        );
                        one += 1;
                    }
                }
            }
        }
        // Both kinds were met: lanes of one width checked, lanes whose width varies left to
        // the distance along them.
        assert!(
            one > 1000 && varying > 0,
            "{one} stations, {varying} varying lanes"
        );
    }
}
