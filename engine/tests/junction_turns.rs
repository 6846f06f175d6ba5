//! Issue 48, requirement 2: junction turns as the file gives them. Every connection out of
//! the incoming lanes of three junctions of CARLA's towns (Town01's junction 43, Town03's
//! four-way junction 422 and the ten junctions of its roundabout) is a way out that a route
//! takes, by the connecting road's id and by the name of its angle where it has one; the route enters the connecting road and leaves it onto the road the file links
//! it to. At a T junction's stem the ways out are left and right, as on `TIntersection`.

use std::path::PathBuf;

use paracosm_engine::network::opendrive::{import, SHORT_SECTION_M};
use paracosm_engine::network::{RoadMap, RoadName, Turn};

fn town(name: &str) -> (String, RoadMap) {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/maps/carla")
        .join(format!("{name}.xodr"));
    let text = std::fs::read_to_string(p).unwrap();
    let map = import(name, &text).unwrap().map.as_ref().clone();
    (text, map)
}

/// One lane link of a junction connection, as the file gives it.
#[derive(Debug)]
struct Connection {
    junction: String,
    incoming: String,
    lane: i32,
    connecting: String,
    /// The road the connecting road leads onto, and whether the car enters it at its start.
    outgoing: (String, bool),
    /// Whether the incoming road meets the junction at its end (else its start).
    at_end: bool,
}

/// Every lane link of the junctions `ids` of the document `text`.
fn connections(text: &str, ids: &[&str]) -> Vec<Connection> {
    let doc = roxmltree::Document::parse(text).unwrap();
    let root = doc.root_element();
    let road = |id: &str| {
        root.children()
            .find(|n| n.has_tag_name("road") && n.attribute("id") == Some(id))
            .unwrap()
    };
    fn link<'a, 'i>(r: roxmltree::Node<'a, 'i>, tag: &str) -> Option<roxmltree::Node<'a, 'i>> {
        r.children()
            .find(|n| n.has_tag_name("link"))
            .and_then(|l| l.children().find(|n| n.has_tag_name(tag)))
    }
    let mut out = Vec::new();
    for j in root
        .children()
        .filter(|n| n.has_tag_name("junction") && ids.contains(&n.attribute("id").unwrap()))
    {
        let jid = j.attribute("id").unwrap();
        for c in j.children().filter(|n| n.has_tag_name("connection")) {
            let (incoming, connecting) = (
                c.attribute("incomingRoad").unwrap(),
                c.attribute("connectingRoad").unwrap(),
            );
            // The connecting road leaves by its far end.
            let far = if c.attribute("contactPoint") == Some("end") {
                "predecessor"
            } else {
                "successor"
            };
            let o = link(road(connecting), far).unwrap();
            let mut outgoing = (
                o.attribute("elementId").unwrap().to_owned(),
                o.attribute("contactPoint") == Some("start"),
            );
            // A road shorter than a millimetre (Town03's road 13 is 15 µm) has no lanes: the
            // car drives on through it onto the road it links to.
            while road(&outgoing.0)
                .attribute("length")
                .and_then(|l| l.parse::<f64>().ok())
                .is_some_and(|l| l < SHORT_SECTION_M)
            {
                let on = link(
                    road(&outgoing.0),
                    if outgoing.1 {
                        "successor"
                    } else {
                        "predecessor"
                    },
                )
                .unwrap();
                outgoing = (
                    on.attribute("elementId").unwrap().to_owned(),
                    on.attribute("contactPoint") == Some("start"),
                );
            }
            let at_end = link(road(incoming), "successor")
                .is_some_and(|s| s.attribute("elementId") == Some(jid));
            for l in c.children().filter(|n| n.has_tag_name("laneLink")) {
                out.push(Connection {
                    junction: jid.to_owned(),
                    incoming: incoming.to_owned(),
                    lane: l.attribute("from").unwrap().parse().unwrap(),
                    connecting: connecting.to_owned(),
                    outgoing: outgoing.clone(),
                    at_end,
                });
            }
        }
    }
    out
}

/// Follows every connection of `cs` on `map` by its connecting road's id and, where it has
/// one, by its name. Returns how many were followed by id and by
/// name.
fn follow_all(map: &RoadMap, cs: &[Connection]) -> (usize, usize) {
    let (mut by_id, mut by_name) = (0, 0);
    for c in cs {
        let length = map
            .roads
            .iter()
            .find(|r| r.od_id == c.incoming)
            .unwrap()
            .length_m;
        // A few centimetres before the incoming road's end at the junction.
        let s = if c.at_end { length - 0.05 } else { 0.05 };
        let Ok(k) = map.lane_at(&c.incoming, c.lane, s) else {
            panic!("{c:?}: no lane {} at s = {s}", c.lane)
        };
        if !map.lanes[k].drivable {
            continue;
        }
        assert_eq!(
            map.lanes[k].forward, c.at_end,
            "{c:?}: driven toward the junction"
        );
        // A lane with one way out takes it without using a turn of the route.
        let ways = map.ways_out(k);
        let fork = ways.len() > 1;
        let check = |turn: Turn| {
            let turns = if fork { vec![turn] } else { vec![] };
            let lanes = map
                .route_lanes(k, s, &turns, 300.0)
                .unwrap_or_else(|e| panic!("{c:?} by {turn}: {e}"));
            let road = |k: usize| map.roads[map.lanes[k].road].od_id.as_str();
            assert_eq!(road(lanes[1]), c.connecting, "{c:?} by {turn}: {lanes:?}");
            let Some(&out) = lanes[1..].iter().find(|&&n| road(n) != c.connecting) else {
                panic!("{c:?} by {turn}: the route ends in the junction")
            };
            assert_eq!(road(out), c.outgoing.0, "{c:?} by {turn}");
            assert_eq!(map.lanes[out].forward, c.outgoing.1, "{c:?} by {turn}");
        };
        check(Turn::Road(RoadName::new(&c.connecting).unwrap()));
        by_id += 1;
        let Some(&(_, _, name)) = ways
            .iter()
            .find(|w| map.roads[map.lanes[w.0].road].od_id == c.connecting)
        else {
            panic!("{c:?}: not among the ways out {ways:?}")
        };
        if let Some(name) = name {
            check(name);
            by_name += 1;
        }
    }
    (by_id, by_name)
}

#[test]
fn every_connection_of_town01_s_junction_43_is_a_turn_the_route_takes() {
    let (text, map) = town("Town01");
    let cs = connections(&text, &["43"]);
    assert_eq!(cs.len(), 6);
    let (by_id, by_name) = follow_all(&map, &cs);
    assert_eq!((by_id, by_name), (6, 6));
    // Road 0, lane -1: straight on by road 50, left by road 56 (xodr 0.8's lane graph has
    // both; paracosm named the turns where the connecting roads' first sections end, and
    // offered "straight" alone).
    let k = map.lane_at("0", -1, 36.0).unwrap();
    let names = |k: usize| {
        let mut w: Vec<(String, String)> = map
            .ways_out(k)
            .iter()
            .map(|w| {
                (
                    w.2.unwrap().name(),
                    map.roads[map.lanes[w.0].road].od_id.clone(),
                )
            })
            .collect();
        w.sort();
        w
    };
    assert_eq!(
        names(k),
        [
            ("left".to_owned(), "56".to_owned()),
            ("straight".to_owned(), "50".to_owned())
        ]
    );
    // Road 16 is the T's stem: left and right, no straight, as on a TIntersection.
    let stem = map.lane_at("16", 1, 0.05).unwrap();
    assert_eq!(
        names(stem),
        [
            ("left".to_owned(), "45".to_owned()),
            ("right".to_owned(), "58".to_owned())
        ]
    );
    let e = map
        .route(stem, 0.05, &[Turn::Straight], 100.0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("turn 1 (\"straight\") is not possible")
            && e.contains("\"left\" (road:45, +90°)")
            && e.contains("\"right\" (road:58, -90°)"),
        "{e}"
    );
}

#[test]
fn every_connection_of_town03_s_four_way_junction_and_roundabout_is_a_turn_the_route_takes() {
    let (text, map) = town("Town03");
    let cs = connections(&text, &["422"]);
    assert_eq!(cs.len(), 18, "{cs:#?}");
    let (by_id, by_name) = follow_all(&map, &cs);
    println!("junction 422: {by_id} lane links followed by road id, {by_name} by name");
    assert_eq!((by_id, by_name), (18, 16));
    // The roundabout: ten junctions where its arms meet the ring.
    let ring = [
        "524", "575", "584", "594", "678", "685", "695", "731", "751", "831",
    ];
    let cs = connections(&text, &ring);
    let (by_id, by_name) = follow_all(&map, &cs);
    println!(
        "roundabout: {} lane links, {by_id} followed by road id, {by_name} by name",
        cs.len()
    );
    assert_eq!((cs.len(), by_id, by_name), (44, 44, 44));
    for j in ring {
        assert!(cs.iter().any(|c| c.junction == j), "junction {j}");
    }
}
