//! An OpenDRIVE 1.6 document written from a paracosm road network (for `paracosm-fuzz
//! export`; ASAM OpenDRIVE 1.6, "Roads", "Lanes", "Junctions").
//!
//! - Each segment, `Arc` and `Clothoid` is one road (`<road id>` = its piece index + 1) with
//!   one geometry record (`line`, `arc`, `spiral`) from its port `ONE`, and one lane section:
//!   driving lanes of 3.5 m (`-1..=-n/2` right of the reference line, driving along it, and
//!   `1..=n/2` left) and a 2 m sidewalk outside them each side. Connected roads are linked
//!   road to road, lane to lane.
//! - Each junction piece (T, cross, roundabout) is a `<junction>` whose connecting roads are
//!   its lane paths, one one-lane road per path (`<road id>` = 1000·(index + 1) + n) made of
//!   `line` records between the path's points (0.5–2 m apart), with a lane offset of 1.75 m so
//!   that the reference line is the lane's centre; the plaza around them, the
//!   roundabout's island and the curbs are not written (OpenDRIVE has no plaza).
//!
//! paracosm's `(x, z)` is OpenDRIVE's `(x, -y)`, so headings agree.

use paracosm_engine::network::{LanePath, Network, PieceKind, LANE_WIDTH_M, SIDEWALK_WIDTH_M};
use paracosm_engine::PieceId;

use super::xml::El;

/// Why a network cannot be written as OpenDRIVE.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum XodrError {
    /// The network holds an OpenDRIVE map: its own file is exported instead, and a network
    /// that mixes one with pieces of the program cannot be.
    #[error(
        "{0} is an OpenDRIVE map: its own file is exported, and a network that mixes it with pieces of the program cannot be"
    )]
    Map(String),
    /// A road piece of a kind this writer does not know (its type name).
    #[error("no OpenDRIVE road for a {0}")]
    UnknownRoad(&'static str),
}

/// The `<road id>` of road piece `i` (by piece index).
pub fn road_id(i: usize) -> String {
    (i + 1).to_string()
}

/// The `<junction id>` of junction piece `i`.
pub fn junction_id(i: usize) -> String {
    (i + 1).to_string()
}

fn geometry(s: f64, x: f64, y: f64, hdg: f64, length: f64, shape: El) -> El {
    El::new("geometry")
        .num("s", s)
        .num("x", x)
        .num("y", y)
        .num("hdg", hdg)
        .num("length", length)
        .child(shape)
}

fn lane(id: i32, kind: &str, width: f64, pred: Option<i32>, succ: Option<i32>) -> El {
    let mut e = El::new("lane")
        .attr("id", id)
        .attr("type", kind)
        .attr("level", "false");
    if pred.is_some() || succ.is_some() {
        let mut link = El::new("link");
        if let Some(p) = pred {
            link = link.child(El::new("predecessor").attr("id", p));
        }
        if let Some(s) = succ {
            link = link.child(El::new("successor").attr("id", s));
        }
        e = e.child(link);
    }
    e.child(
        El::new("width")
            .attr("sOffset", 0)
            .num("a", width)
            .attr("b", 0)
            .attr("c", 0)
            .attr("d", 0),
    )
}

/// A road's `<predecessor>` or `<successor>` (`tag`): road piece `other`, met at its port
/// `port` (`ONE` is its start).
fn road_link(tag: &str, other: usize, port: usize) -> El {
    El::new(tag)
        .attr("elementType", "road")
        .attr("elementId", road_id(other))
        .attr("contactPoint", if port == 0 { "start" } else { "end" })
}

/// A lane section's centre lane, lane 0.
fn centre_lane() -> El {
    El::new("center").child(
        El::new("lane")
            .attr("id", 0)
            .attr("type", "none")
            .attr("level", "false"),
    )
}

/// What is at the other side of port `port` of piece `piece`: `(piece, its port)`.
fn across(network: &Network, piece: usize, port: usize) -> Option<(usize, usize)> {
    network.links().iter().find_map(|l| {
        if l.a == (PieceId(piece), port) {
            Some((l.b.0 .0, l.b.1))
        } else if l.b == (PieceId(piece), port) {
            Some((l.a.0 .0, l.a.1))
        } else {
            None
        }
    })
}

fn is_road(kind: &PieceKind) -> bool {
    kind.road_length_m().is_some()
}

/// The document for `network`.
///
/// # Errors
/// [`XodrError::Map`] for a network holding an OpenDRIVE map (its own file is exported
/// instead), [`XodrError::UnknownRoad`] for a piece kind this writer does not know.
pub fn write(network: &Network, name: &str) -> Result<String, XodrError> {
    let mut root = El::new("OpenDRIVE").child(
        El::new("header")
            .attr("revMajor", 1)
            .attr("revMinor", 6)
            .attr("name", name)
            .attr("version", "1.0")
            .attr("vendor", "paracosm"),
    );
    let mut junctions = Vec::new();
    for (i, p) in network.pieces().iter().enumerate() {
        let kind = &p.kind;
        if let PieceKind::Map { .. } = kind {
            return Err(XodrError::Map(p.name.clone()));
        }
        if is_road(kind) {
            root = root.child(road(network, i)?);
        } else {
            let (roads, junction) = junction(network, i);
            root = root.children(roads);
            junctions.push(junction);
        }
    }
    Ok(root.children(junctions).document())
}

/// The road of segment or curve `i`.
fn road(network: &Network, i: usize) -> Result<El, XodrError> {
    let p = &network.pieces()[i];
    let kind = &p.kind;
    let length = kind.road_length_m().expect("a road piece");
    let shape = match kind {
        PieceKind::Segment { .. } => El::new("line"),
        PieceKind::Arc {
            radius_m,
            angle_rad,
            ..
        } => El::new("arc").num("curvature", angle_rad.signum() / radius_m),
        PieceKind::Clothoid {
            curv_start,
            curv_end,
            ..
        } => El::new("spiral")
            .num("curvStart", *curv_start)
            .num("curvEnd", *curv_end),
        other => return Err(XodrError::UnknownRoad(other.type_name())),
    };
    // Port ONE sits at the piece's local origin, the road heading along local +x.
    let [x, z] = p.pose.apply([0.0, 0.0]);
    let plan = El::new("planView").child(geometry(0.0, x, -z, p.pose.heading_rad, length, shape));
    let half = (kind.lanes() / 2) as i32;
    // Links at each end: the element across, and how lane ids map (a lane keeps its id across
    // an end-to-start joint; it changes sign where two starts or two ends meet).
    let mut link = El::new("link");
    let mut lane_map: [Option<(bool, bool)>; 2] = [None, None]; // (is road, flips)
    for (port, tag) in [(0usize, "predecessor"), (1, "successor")] {
        if let Some((other, other_port)) = across(network, i, port) {
            let o = &network.pieces()[other];
            if is_road(&o.kind) {
                link = link.child(road_link(tag, other, other_port));
                lane_map[port] = Some((true, port == other_port));
            } else {
                link = link.child(
                    El::new(tag)
                        .attr("elementType", "junction")
                        .attr("elementId", junction_id(other)),
                );
            }
        }
    }
    let linked = |id: i32, port: usize| match lane_map[port] {
        Some((true, flips)) => Some(if flips { -id } else { id }),
        _ => None,
    };
    let side = |sign: i32| {
        let mut lanes: Vec<El> = (1..=half)
            .map(|k| {
                let id = sign * k;
                lane(id, "driving", LANE_WIDTH_M, linked(id, 0), linked(id, 1))
            })
            .collect();
        let id = sign * (half + 1);
        lanes.push(lane(
            id,
            "sidewalk",
            SIDEWALK_WIDTH_M,
            linked(id, 0),
            linked(id, 1),
        ));
        if sign > 0 {
            lanes.reverse(); // OpenDRIVE lists left lanes from the outside in.
        }
        lanes
    };
    let section = El::new("laneSection")
        .attr("s", 0)
        .child(El::new("left").children(side(1)))
        .child(centre_lane())
        .child(El::new("right").children(side(-1)));
    Ok(El::new("road")
        .attr("name", &p.name)
        .num("length", length)
        .attr("id", road_id(i))
        .attr("junction", "-1")
        .child(link)
        .child(plan)
        .child(El::new("lanes").child(section)))
}

/// The `<planView>` of a junction's lane path, and its length: the path's own lines and arcs
/// (`LanePath::curve`), so a simulator reading the map drives the same G1 curve; the polyline
/// where a path has none.
fn path_plan(path: &LanePath) -> (El, f64) {
    let mut plan = El::new("planView");
    let mut s = 0.0;
    for (pose, line) in &path.curve {
        if line.length_m < 1e-6 {
            continue;
        }
        let shape = if line.curv_start == 0.0 {
            El::new("line")
        } else {
            El::new("arc").num("curvature", line.curv_start)
        };
        plan = plan.child(geometry(
            s,
            pose.x,
            -pose.z,
            pose.heading_rad,
            line.length_m,
            shape,
        ));
        s += line.length_m;
    }
    for w in path.points.windows(2).filter(|_| path.curve.is_empty()) {
        let (a, b) = (w[0], w[1]);
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        if length < 1e-6 {
            continue;
        }
        let hdg = (-(b[1] - a[1])).atan2(b[0] - a[0]);
        plan = plan.child(geometry(s, a[0], -a[1], hdg, length, El::new("line")));
        s += length;
    }
    (plan, s)
}

/// The connecting roads and the `<junction>` of junction piece `i`.
fn junction(network: &Network, i: usize) -> (Vec<El>, El) {
    let p = &network.pieces()[i];
    let mut roads = Vec::new();
    let mut junction = El::new("junction")
        .attr("id", junction_id(i))
        .attr("name", &p.name);
    for (n, path) in network.lane_paths(PieceId(i)).iter().enumerate() {
        let id = 1000 * (i + 1) + n;
        let (plan, s) = path_plan(path);
        let j = path.entry.1 as i32;
        // Where the path comes from and goes to: the road across each port, and the lane
        // there (a lane driving into the junction from a road's end is -j; from its start, j).
        let from =
            across(network, i, path.entry.0).filter(|(o, _)| is_road(&network.pieces()[*o].kind));
        let to =
            across(network, i, path.exit.0).filter(|(o, _)| is_road(&network.pieces()[*o].kind));
        let mut link = El::new("link");
        let mut pred = None;
        let mut succ = None;
        if let Some((o, port)) = from {
            link = link.child(road_link("predecessor", o, port));
            pred = Some(if port == 1 { -j } else { j });
        }
        if let Some((o, port)) = to {
            link = link.child(road_link("successor", o, port));
            succ = Some(if port == 0 { -j } else { j });
        }
        roads.push(
            El::new("road")
                .attr("name", format!("{} path {n}", p.name))
                .num("length", s)
                .attr("id", id)
                .attr("junction", junction_id(i))
                .child(link)
                .child(plan)
                .child(
                    El::new("lanes")
                        // The reference line is the path itself: the lane's centre.
                        .child(
                            El::new("laneOffset")
                                .attr("s", 0)
                                .num("a", LANE_WIDTH_M / 2.0)
                                .attr("b", 0)
                                .attr("c", 0)
                                .attr("d", 0),
                        )
                        .child(
                            El::new("laneSection")
                                .attr("s", 0)
                                .child(centre_lane())
                                .child(El::new("right").child(lane(
                                    -1,
                                    "driving",
                                    LANE_WIDTH_M,
                                    pred,
                                    succ,
                                ))),
                        ),
                ),
        );
        if let (Some((o, _)), Some(from_lane)) = (from, pred) {
            junction = junction.child(
                El::new("connection")
                    .attr("id", n)
                    .attr("incomingRoad", road_id(o))
                    .attr("connectingRoad", id)
                    .attr("contactPoint", "start")
                    .child(El::new("laneLink").attr("from", from_lane).attr("to", -1)),
            );
        }
    }
    (roads, junction)
}
