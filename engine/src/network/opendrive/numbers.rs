//! The numbers and the structure of an OpenDRIVE document, checked before the `xodr` crate
//! bakes it: every numeric attribute paracosm or the crate reads is finite and in its range,
//! every id is unique where the schema says so, every `<geometry>` holds one record, and no
//! section holds more lanes than a road can.
//!
//! The ranges (documented in LANGUAGE.md, "The numbers a map may hold"):
//!
//! | attribute | range |
//! |---|---|
//! | `<road length>` | `(0, MAX_ROAD_LENGTH_M]` m |
//! | `<geometry length>` | `[0, MAX_ROAD_LENGTH_M]` m |
//! | `s`, `sOffset`, `elementS` | `[0, MAX_ROAD_LENGTH_M]` m |
//! | `<geometry x y>`, `<offset x y z>` | `|v| <= MAX_COORDINATE_M` m (then recentred, see `recentre.rs`) |
//! | `<arc curvature>`, `<spiral curvStart curvEnd>` | `|k| <= MAX_CURVATURE_PER_M` 1/m |
//! | `<lane id>`, `<laneLink from to>`, a lane's `<predecessor id>` | whole, `|id| <= MAX_LANES_PER_SIDE` |
//! | every other number (`hdg`, polynomial coefficients) | finite |

use std::collections::BTreeMap;

use roxmltree::Node;

use super::{MapError, Reader};

/// The longest road and geometry record, m: a road's stations are `f32` in the `xodr` crate
/// and lane strips are sampled every 0.5 m, so 100 km resolves to 4 mm (the same limit as a
/// program's `RoadSegment`).
pub const MAX_ROAD_LENGTH_M: f64 = 100_000.0;

/// The largest `|x|` or `|y|` a map may give before it is recentred, m: 10^9 m (beyond any
/// projected coordinate system on Earth).
pub const MAX_COORDINATE_M: f64 = 1e9;

/// The largest `|curvature|` of an arc or spiral, 1/m: a radius of 0.5 m, tighter than any
/// vehicle turns.
pub const MAX_CURVATURE_PER_M: f64 = 2.0;

/// The most lanes a section may have on one side of its reference line.
pub const MAX_LANES_PER_SIDE: i64 = 64;

/// The widest a lane may be anywhere along its `<width>` polynomials, m.
pub const MAX_LANE_WIDTH_M: f64 = 100.0;

/// What a numeric attribute must be.
#[derive(Clone, Copy)]
enum Rule {
    /// Any finite number.
    Finite,
    /// A station or offset along a road: `[0, MAX_ROAD_LENGTH_M]`.
    Station,
    /// A road's length: `(0, MAX_ROAD_LENGTH_M]`.
    RoadLength,
    /// A geometry record's length: `[0, MAX_ROAD_LENGTH_M]`.
    RecordLength,
    /// A coordinate: `|v| <= MAX_COORDINATE_M`.
    Coordinate,
    /// A curvature: `|k| <= MAX_CURVATURE_PER_M`.
    Curvature,
    /// A lane id: whole, `|id| <= MAX_LANES_PER_SIDE`.
    LaneId,
}

/// The numeric attributes of an element, by its name (and its parent's, for links).
fn rules(n: Node) -> &'static [(&'static str, Rule)] {
    use Rule::*;
    let parent = n.parent_element().map(|p| p.tag_name().name());
    match n.tag_name().name() {
        "offset" => &[
            ("x", Coordinate),
            ("y", Coordinate),
            ("z", Coordinate),
            ("hdg", Finite),
        ],
        "road" => &[("length", RoadLength)],
        // A lane's link names the lane by its id; a road's gives a station on the other road.
        "predecessor" | "successor" if parent == Some("link") && is_lane_link(n) => {
            &[("id", LaneId)]
        }
        "predecessor" | "successor" => &[("elementS", Station)],
        "geometry" => &[
            ("s", Station),
            ("x", Coordinate),
            ("y", Coordinate),
            ("hdg", Finite),
            ("length", RecordLength),
        ],
        "arc" => &[("curvature", Curvature)],
        "spiral" => &[("curvStart", Curvature), ("curvEnd", Curvature)],
        "poly3" => &[("a", Finite), ("b", Finite), ("c", Finite), ("d", Finite)],
        "paramPoly3" => &[
            ("aU", Finite),
            ("bU", Finite),
            ("cU", Finite),
            ("dU", Finite),
            ("aV", Finite),
            ("bV", Finite),
            ("cV", Finite),
            ("dV", Finite),
        ],
        "laneOffset" | "elevation" | "superelevation" | "crossfall" => &[
            ("s", Station),
            ("a", Finite),
            ("b", Finite),
            ("c", Finite),
            ("d", Finite),
        ],
        "laneSection" => &[("s", Station)],
        "lane" => &[("id", LaneId)],
        "width" => &[
            ("sOffset", Station),
            ("a", Finite),
            ("b", Finite),
            ("c", Finite),
            ("d", Finite),
        ],
        "laneLink" => &[("from", LaneId), ("to", LaneId)],
        _ => &[],
    }
}

/// The attributes an element cannot do without (the schema's `use="required"` among those
/// paracosm or the `xodr` crate reads).
fn required(name: &str) -> &'static [&'static str] {
    match name {
        "road" => &["id", "length"],
        "geometry" => &["s", "x", "y", "hdg", "length"],
        "arc" => &["curvature"],
        "spiral" => &["curvStart", "curvEnd"],
        "laneSection" => &["s"],
        "lane" => &["id", "type"],
        "width" => &["sOffset", "a"],
        "junction" => &["id"],
        _ => &[],
    }
}

/// Whether a `<predecessor>`/`<successor>` sits in a lane's `<link>` (not a road's).
fn is_lane_link(n: Node) -> bool {
    n.parent_element()
        .and_then(|l| l.parent_element())
        .is_some_and(|p| p.has_tag_name("lane"))
}

impl Reader<'_> {
    /// An error at attribute `name` of `n` (its value's line and column).
    pub(super) fn at_attribute(&self, n: Node, name: &str, message: String) -> MapError {
        let pos = n
            .attribute_node(name)
            .map_or(n.range().start, |a| a.range_value().start);
        let (line, column) = self.pos_at(pos);
        MapError {
            file: self.file.to_owned(),
            line: Some(line),
            column: Some(column),
            message,
        }
    }
}

/// Checks every numeric attribute (see the module documentation), every `<geometry>`'s
/// record, the lane counts and the ids.
///
/// # Errors
/// The first attribute out of its range, a geometry without exactly one record, a section
/// with more than [`MAX_LANES_PER_SIDE`] lanes on a side, or an id used twice, naming the
/// element and its line and column.
pub(super) fn check(r: &Reader, root: Node) -> Result<(), MapError> {
    for n in root.descendants().filter(Node::is_element) {
        check_values(r, n)?;
        check_children(r, n)?;
    }
    let roads: Vec<Node> = root.children().filter(|c| c.has_tag_name("road")).collect();
    unique(r, &roads, "id", "road id", "")?;
    for road in &roads {
        check_road(r, *road)?;
    }
    let junctions: Vec<Node> = root
        .children()
        .filter(|c| c.has_tag_name("junction"))
        .collect();
    unique(r, &junctions, "id", "junction id", "")?;
    Ok(())
}

/// Checks element `n`'s own attributes: those OpenDRIVE requires are there, and each numeric
/// attribute is in its range ([`judge`]).
///
/// # Errors
/// The first missing or out-of-range attribute, naming the element and its line and column.
fn check_values(r: &Reader, n: Node) -> Result<(), MapError> {
    let name = n.tag_name().name();
    if let Some(missing) = required(name).iter().find(|a| n.attribute(**a).is_none()) {
        let road = n
            .ancestors()
            .find(|a| a.has_tag_name("road"))
            .and_then(|a| a.attribute("id"))
            .map(|id| format!(" of road \"{id}\""))
            .unwrap_or_default();
        return Err(r.error(
            Some(n),
            format!("<{name}>{road} has no `{missing}`, which OpenDRIVE requires"),
        ));
    }
    for &(attr, rule) in rules(n) {
        let Some(text) = n.attribute(attr) else {
            continue;
        };
        if let Err(why) = judge(text.trim(), rule) {
            let road = n
                .ancestors()
                .find(|a| a.has_tag_name("road"))
                .and_then(|a| a.attribute("id"))
                .map(|id| format!(" of road \"{id}\""))
                .unwrap_or_default();
            return Err(r.at_attribute(
                n,
                attr,
                format!("<{name} {attr}=\"{text}\">{road}: {why}"),
            ));
        }
    }
    Ok(())
}

/// Checks what element `n` holds: a `<geometry>` one record, a `<laneSection>` at most
/// [`MAX_LANES_PER_SIDE`] lanes a side with unique ids, a `<planView>` a geometry, a
/// `<junction>` connections with unique ids.
///
/// # Errors
/// The first problem, naming the element and its line and column.
fn check_children(r: &Reader, n: Node) -> Result<(), MapError> {
    let name = n.tag_name().name();
    if name == "geometry" {
        let records: Vec<Node> = n.children().filter(Node::is_element).collect();
        if records.len() != 1 {
            return Err(r.error(
                Some(n),
                format!(
                    "<geometry s=\"{}\"> of road \"{}\" holds {} records; it holds exactly one of <line>, <arc>, <spiral>, <poly3>, <paramPoly3>",
                    n.attribute("s").unwrap_or("?"),
                    road_id(n),
                    records.len()
                ),
            ));
        }
    }
    if name == "laneSection" {
        for side in n
            .children()
            .filter(|c| c.has_tag_name("left") || c.has_tag_name("right"))
        {
            let count = side.children().filter(|c| c.has_tag_name("lane")).count();
            if count as i64 > MAX_LANES_PER_SIDE {
                return Err(r.error(
                    Some(side),
                    format!(
                        "<{}> of the section at s = {} of road \"{}\" has {count} lanes; a side has at most {MAX_LANES_PER_SIDE}",
                        side.tag_name().name(),
                        n.attribute("s").unwrap_or("?"),
                        road_id(n)
                    ),
                ));
            }
        }
        let lanes: Vec<Node> = n.descendants().filter(|c| c.has_tag_name("lane")).collect();
        let place = format!(
            " in the section at s = {} of road \"{}\"",
            n.attribute("s").unwrap_or("?"),
            road_id(n)
        );
        unique(r, &lanes, "id", "lane id", &place)?;
    }
    if name == "planView" && !n.children().any(|c| c.has_tag_name("geometry")) {
        return Err(r.error(
            Some(n),
            format!(
                "<planView> of road \"{}\" has no <geometry>: the road has no reference line",
                road_id(n)
            ),
        ));
    }
    if name == "junction" {
        let connections: Vec<Node> = n
            .children()
            .filter(|c| c.has_tag_name("connection"))
            .collect();
        unique(
            r,
            &connections,
            "id",
            "connection id",
            &format!(" in junction \"{}\"", n.attribute("id").unwrap_or("?")),
        )?;
    }
    Ok(())
}

/// Checks `<road>` `road`: it has a lane section with a lane besides the centre lane, a
/// `<planView>`, and no record starting past its end ([`check_stations`]).
///
/// # Errors
/// The first problem, naming the road and its line and column.
fn check_road(r: &Reader, road: Node) -> Result<(), MapError> {
    let sections: Vec<Node> = road
        .children()
        .filter(|c| c.has_tag_name("lanes"))
        .flat_map(|l| l.children().filter(|c| c.has_tag_name("laneSection")))
        .collect();
    if sections.is_empty() {
        return Err(r.error(
            Some(road),
            format!(
                "<road id=\"{}\"> has no <lanes> with a <laneSection>: it has no lane",
                road_id(road)
            ),
        ));
    }
    let lanes = sections
        .iter()
        .flat_map(|s| s.descendants())
        .filter(|c| c.has_tag_name("lane") && c.attribute("id").is_some_and(|id| id.trim() != "0"))
        .count();
    if lanes == 0 {
        return Err(r.error(
            Some(road),
            format!(
                "<road id=\"{}\"> has no lane besides its centre lane 0",
                road_id(road)
            ),
        ));
    }
    if !road.children().any(|c| c.has_tag_name("planView")) {
        return Err(r.error(
            Some(road),
            format!(
                "<road id=\"{}\"> has no <planView>: the road has no reference line",
                road_id(road)
            ),
        ));
    }
    check_stations(r, road)?;
    Ok(())
}

/// The lane types of OpenDRIVE 1.4 to 1.8.
const LANE_TYPES: &[&str] = &[
    "none",
    "driving",
    "stop",
    "shoulder",
    "biking",
    "sidewalk",
    "walking",
    "border",
    "restricted",
    "parking",
    "bidirectional",
    "median",
    "curb",
    "special1",
    "special2",
    "special3",
    "roadWorks",
    "tram",
    "rail",
    "entry",
    "exit",
    "offRamp",
    "onRamp",
    "connectingRamp",
    "slipLane",
    "HOV",
    "bus",
    "taxi",
    "mwyEntry",
    "mwyExit",
];

/// One warning naming the lane types that OpenDRIVE does not have (with a count and the first
/// line): such a lane is taken as not drivable.
pub(super) fn lane_type_warnings(r: &Reader, root: Node) -> Vec<String> {
    let mut unknown: BTreeMap<&str, (usize, u32)> = BTreeMap::new();
    for lane in root.descendants().filter(|n| n.has_tag_name("lane")) {
        if let Some(t) = lane.attribute("type") {
            if !LANE_TYPES.iter().any(|k| k.eq_ignore_ascii_case(t.trim())) {
                let e = unknown.entry(t).or_insert((0, r.line(lane)));
                e.0 += 1;
            }
        }
    }
    unknown
        .into_iter()
        .map(|(t, (count, line))| {
            format!(
                "{}:{line}: {count} lane{} of type \"{t}\", which OpenDRIVE does not have: taken as not drivable",
                r.file,
                if count == 1 { "" } else { "s" }
            )
        })
        .collect()
}

/// One warning for the lanes (other than a centre lane) with neither `<width>` nor
/// `<border>`: the schema lets a lane leave both out (ASAM's own `SampleDatabase.xodr` does),
/// and such a lane is 0 m wide, as the `xodr` crate, esmini and libOpenDRIVE read it: it
/// takes no room, and no entity can stand on it (a position on it is refused where it is
/// read).
pub(super) fn widthless_lane_warnings(r: &Reader, root: Node) -> Vec<String> {
    let widthless: Vec<Node> = root.descendants().filter(|n| widthless(*n)).collect();
    let Some(first) = widthless.first() else {
        return Vec::new();
    };
    let count = widthless.len();
    vec![format!(
        "{}:{}: {count} lane{} with neither <width> nor <border> (first: lane {} of road \"{}\"): taken as 0 m wide, as esmini and libOpenDRIVE read {}",
        r.file,
        r.line(*first),
        if count == 1 { "" } else { "s" },
        first.attribute("id").unwrap_or("?"),
        road_id(*first),
        if count == 1 { "it" } else { "them" },
    )]
}

/// The first lane (other than a centre lane) with neither `<width>` nor `<border>`.
pub(super) fn first_widthless_lane<'a, 'i>(root: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    root.descendants().find(|n| widthless(*n))
}

/// Whether `n` is a lane (other than a centre lane) with neither `<width>` nor `<border>`.
fn widthless(n: Node) -> bool {
    n.has_tag_name("lane")
        && n.attribute("id").is_some_and(|id| id.trim() != "0")
        && !n
            .children()
            .any(|c| c.has_tag_name("width") || c.has_tag_name("border"))
}

/// Geometry records and lane sections start within their road's length.
fn check_stations(r: &Reader, road: Node) -> Result<(), MapError> {
    let Some(length) = road
        .attribute("length")
        .and_then(|v| v.trim().parse::<f64>().ok())
    else {
        return Ok(());
    };
    let tolerance = super::GEOMETRY_GAP_M;
    let starts = road
        .descendants()
        .filter(|n| n.has_tag_name("geometry") || n.has_tag_name("laneSection"));
    for n in starts {
        if let Some(s) = n.attribute("s").and_then(|v| v.trim().parse::<f64>().ok()) {
            if s > length + tolerance {
                return Err(r.at_attribute(
                    n,
                    "s",
                    format!(
                        "<{} s=\"{s}\"> of road \"{}\" starts past the road's end (length {length} m)",
                        n.tag_name().name(),
                        road_id(road)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The id of the road holding `n` (or `n` itself), for messages.
fn road_id<'a>(n: Node<'a, '_>) -> &'a str {
    n.ancestors()
        .find(|a| a.has_tag_name("road"))
        .and_then(|a| a.attribute("id"))
        .unwrap_or("?")
}

/// Refuses a value of `attr` that two of `nodes` share, naming both lines: "`what` "id" is
/// used twice`place`".
fn unique(r: &Reader, nodes: &[Node], attr: &str, what: &str, place: &str) -> Result<(), MapError> {
    let mut seen: BTreeMap<String, Node> = BTreeMap::new();
    for n in nodes {
        let Some(id) = n.attribute(attr) else {
            continue;
        };
        // Lane ids compare as numbers ("-1" and "-01" are one lane).
        let key = id
            .trim()
            .parse::<i64>()
            .map_or_else(|_| id.trim().to_owned(), |v| v.to_string());
        if let Some(first) = seen.get(&key) {
            return Err(r.at_attribute(
                *n,
                attr,
                format!(
                    "{what} \"{id}\" is used twice{place} (first at line {}): ids must be unique",
                    r.line(*first)
                ),
            ));
        }
        seen.insert(key, *n);
    }
    Ok(())
}

/// How an attribute's text breaks its [`Rule`].
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq)]
enum Broken {
    /// A lane id that is not a whole number.
    #[error("a lane id is a whole number")]
    LaneIdNotWhole,
    /// A lane id farther than [`MAX_LANES_PER_SIDE`] from the centre lane.
    #[error(
        "a lane id is at most {MAX_LANES_PER_SIDE} from the centre lane 0 (a section has at most {MAX_LANES_PER_SIDE} lanes a side)"
    )]
    LaneIdTooFar,
    /// Text that is not a number.
    #[error("not a number")]
    NotANumber,
    /// A number that is not finite.
    #[error("not finite")]
    NotFinite,
    /// A number outside `[lo, hi]` (`(lo, hi]` when `open_lo`), in `unit`.
    #[error("out of range: it must lie in {}{lo}, {hi}] {unit}", if *.open_lo { "(" } else { "[" })]
    OutOfRange {
        lo: f64,
        hi: f64,
        open_lo: bool,
        unit: &'static str,
    },
}

/// Why `text` breaks `rule`, if it does.
fn judge(text: &str, rule: Rule) -> Result<(), Broken> {
    if let Rule::LaneId = rule {
        let Ok(id) = text.parse::<i64>() else {
            return Err(Broken::LaneIdNotWhole);
        };
        if id.abs() > MAX_LANES_PER_SIDE {
            return Err(Broken::LaneIdTooFar);
        }
        return Ok(());
    }
    let Ok(v) = text.parse::<f64>() else {
        return Err(Broken::NotANumber);
    };
    if !v.is_finite() {
        return Err(Broken::NotFinite);
    }
    let within = |lo: f64, hi: f64, open_lo: bool, unit: &'static str| {
        let low_ok = if open_lo { v > lo } else { v >= lo };
        if low_ok && v <= hi {
            Ok(())
        } else {
            Err(Broken::OutOfRange {
                lo,
                hi,
                open_lo,
                unit,
            })
        }
    };
    match rule {
        Rule::Finite | Rule::LaneId => Ok(()),
        // Generated maps write `s="-1e-15"`: a station a rounding below 0 is 0.
        Rule::Station if (-super::GEOMETRY_GAP_M..0.0).contains(&v) => Ok(()),
        Rule::Station => within(0.0, MAX_ROAD_LENGTH_M, false, "m"),
        Rule::RoadLength => within(
            0.0,
            MAX_ROAD_LENGTH_M,
            true,
            "m (a road is at most 100 km long)",
        ),
        Rule::RecordLength => within(0.0, MAX_ROAD_LENGTH_M, false, "m"),
        Rule::Coordinate => within(-MAX_COORDINATE_M, MAX_COORDINATE_M, false, "m"),
        Rule::Curvature => within(
            -MAX_CURVATURE_PER_M,
            MAX_CURVATURE_PER_M,
            false,
            "1/m (a radius of at least 0.5 m)",
        ),
    }
}
