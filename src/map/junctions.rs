//! A map's `<junction>`s and their connections, read from the document's XML tree (which the
//! importer has checked), with the turn each connection is for read from the baked lane graph.

use paracosm_engine::network::RoadMap;
use roxmltree::{Document, Node};

/// One `<junction>` of a map.
#[derive(Debug, Clone, PartialEq)]
pub struct Junction {
    /// Its `<junction id>`.
    pub id: String,
    /// Its `name`, when it has one.
    pub name: Option<String>,
    /// Its connections, in the file's order.
    pub connections: Vec<Connection>,
}

/// One `<connection>` of a junction: a way from an incoming road, through a connecting road,
/// onto an outgoing road.
#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    /// Its `<connection id>`.
    pub id: String,
    /// The road traffic comes from (`incomingRoad`).
    pub incoming: String,
    /// The junction's road it drives along (`connectingRoad`; a direct junction's
    /// `linkedRoad`).
    pub connecting: String,
    /// The road it leaves onto: the connecting road's successor when it is entered at its
    /// start, its predecessor when entered at its end; `None` when that link names no road.
    pub outgoing: Option<String>,
    /// Where the connecting road is entered (`contactPoint`: `start` or `end`).
    pub contact: String,
    /// Its `<laneLink>`s: `(incoming lane id, connecting lane id)`.
    pub lane_links: Vec<(i32, i32)>,
    /// The turn a route names it by (`left`, `straight`, `right`, `uturn`, or `road:ID` where
    /// only its connecting road names it) and the heading change it makes (rad, positive to
    /// the left), from the first lane link whose incoming lane drives into the connecting road;
    /// `None` when no such lane does (the links lead against traffic).
    pub turn: Option<(String, f64)>,
}

/// Every `<junction>` of `doc`, in order, with the turns `map`'s lane graph gives them.
pub(super) fn read(map: &RoadMap, doc: &Document<'_>) -> Vec<Junction> {
    doc.root_element()
        .children()
        .filter(|n| n.has_tag_name("junction"))
        .map(|j| Junction {
            id: j.attribute("id").unwrap_or_default().to_owned(),
            name: j
                .attribute("name")
                .filter(|n| !n.trim().is_empty())
                .map(str::to_owned),
            connections: j
                .children()
                .filter(|c| c.has_tag_name("connection"))
                .map(|c| connection(map, doc, c))
                .collect(),
        })
        .collect()
}

/// The connection `c` of `doc`.
fn connection(map: &RoadMap, doc: &Document<'_>, c: Node<'_, '_>) -> Connection {
    let attr = |name: &str| c.attribute(name).unwrap_or_default().trim().to_owned();
    let connecting = c
        .attribute("connectingRoad")
        .or_else(|| c.attribute("linkedRoad"))
        .unwrap_or_default()
        .trim()
        .to_owned();
    let contact = attr("contactPoint");
    let lane_links: Vec<(i32, i32)> = c
        .children()
        .filter(|l| l.has_tag_name("laneLink"))
        .filter_map(|l| {
            let id = |a: &str| l.attribute(a).and_then(|v| v.trim().parse::<i32>().ok());
            Some((id("from")?, id("to")?))
        })
        .collect();
    let incoming = attr("incomingRoad");
    let turn = lane_links
        .iter()
        .find_map(|&(from, to)| turn(map, &incoming, from, &connecting, to));
    Connection {
        id: attr("id"),
        outgoing: outgoing(doc, &connecting, &contact),
        incoming,
        connecting,
        contact,
        lane_links,
        turn,
    }
}

/// The road a car leaves `connecting` onto, entered at `contact`: the `elementId` of its
/// `<successor>` (entered at its start) or `<predecessor>` (at its end) when that is a road.
fn outgoing(doc: &Document<'_>, connecting: &str, contact: &str) -> Option<String> {
    let road = doc
        .root_element()
        .children()
        .find(|n| n.has_tag_name("road") && n.attribute("id").map(str::trim) == Some(connecting))?;
    let far_end = if contact == "end" {
        "predecessor"
    } else {
        "successor"
    };
    road.children()
        .filter(|n| n.has_tag_name("link"))
        .flat_map(|l| l.children())
        .find(|n| n.has_tag_name(far_end))
        .filter(|n| {
            n.attribute("elementType")
                .is_none_or(|t| t.trim() == "road")
        })
        .and_then(|n| n.attribute("elementId"))
        .map(|id| id.trim().to_owned())
}

/// The turn (its name and heading change, rad) that lane `from` of road `incoming` makes
/// into lane `to` of road `connecting`, by the map's lane graph ([`RoadMap::ways_out`]).
fn turn(
    map: &RoadMap,
    incoming: &str,
    from: i32,
    connecting: &str,
    to: i32,
) -> Option<(String, f64)> {
    let road = |id: &str| map.roads.iter().position(|r| r.od_id == id);
    let (inc, con) = (road(incoming)?, road(connecting)?);
    map.lanes
        .iter()
        .enumerate()
        .filter(|(_, l)| l.road == inc && l.od_id == from)
        .flat_map(|(k, _)| map.ways_out(k))
        .find(|&(n, _, _)| map.lanes[n].road == con && map.lanes[n].od_id == to)
        .map(|(_, delta, t)| {
            let name = t.map_or_else(|| format!("road:{connecting}"), |t| t.to_string());
            (name, delta)
        })
}

impl Junction {
    /// Its lines of the listing: a header, then one line per connection.
    pub(super) fn lines(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "junction {}{}: {} connections",
            self.id,
            self.name
                .as_ref()
                .map(|n| format!(" \"{n}\""))
                .unwrap_or_default(),
            self.connections.len()
        )];
        lines.extend(self.connections.iter().map(|c| {
            let links: Vec<String> = c
                .lane_links
                .iter()
                .map(|(a, b)| format!("{a}:{b}"))
                .collect();
            format!(
                "  {} -> {} -> {}  contact {}  lanes {}  {}",
                c.incoming,
                c.connecting,
                c.outgoing.as_deref().unwrap_or("?"),
                if c.contact.is_empty() {
                    "-"
                } else {
                    &c.contact
                },
                if links.is_empty() {
                    "-".to_owned()
                } else {
                    links.join(",")
                },
                c.turn.as_ref().map_or_else(
                    || "no turn (its lanes lead against traffic)".to_owned(),
                    |(t, d)| format!("{t} ({:+.0}°)", d.to_degrees().round() + 0.0)
                ),
            )
        }));
        lines
    }
}
