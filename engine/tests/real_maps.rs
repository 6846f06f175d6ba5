//! Issue 48, requirement 1: maps nobody here wrote load. CARLA's seven towns and esmini's maps
//! (`tests/data/maps/`, see PROVENANCE.md there) are read, and each map's roads, lane counts
//! per lane section and road lengths equal a plain XML reading of the file; every lane link
//! meets (no gap warning), and the lane graph steps over lane sections shorter than a
//! millimetre by the file's own links. The two esmini maps with faults are refused, naming
//! them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use paracosm_engine::network::opendrive::{import, Imported, SHORT_SECTION_M};
use paracosm_engine::network::RoadMap;

fn maps(folder: &str) -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/maps")
        .join(folder);
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xodr"))
        .collect();
    out.sort();
    out
}

fn num(n: roxmltree::Node, k: &str) -> f64 {
    n.attribute(k).map_or(0.0, |v| v.trim().parse().unwrap())
}

/// What a plain reading of the file says: by road id, its `length` and, by lane section (in
/// order of `s`), the number of lanes with a width somewhere, for the sections of a
/// millimetre or more.
fn plain(text: &str) -> BTreeMap<String, (f64, BTreeMap<usize, usize>)> {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mut out = BTreeMap::new();
    for road in doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("road"))
    {
        let length = num(road, "length");
        let mut sections: Vec<roxmltree::Node> = road
            .descendants()
            .filter(|n| n.has_tag_name("laneSection"))
            .collect();
        sections.sort_by(|a, b| num(*a, "s").total_cmp(&num(*b, "s")));
        let mut lanes = BTreeMap::new();
        for (k, sec) in sections.iter().enumerate() {
            let end = sections.get(k + 1).map_or(length, |n| num(*n, "s"));
            if end - num(*sec, "s") < SHORT_SECTION_M {
                continue;
            }
            let wide = sec
                .descendants()
                .filter(|n| n.has_tag_name("lane") && n.attribute("id") != Some("0"))
                .filter(|lane| {
                    lane.children()
                        .filter(|w| w.has_tag_name("width"))
                        .any(|w| ["a", "b", "c", "d"].iter().any(|c| num(w, c) != 0.0))
                })
                .count();
            if wide > 0 {
                lanes.insert(k, wide);
            }
        }
        if !lanes.is_empty() {
            out.insert(road.attribute("id").unwrap().to_owned(), (length, lanes));
        }
    }
    out
}

/// The same figures from the baked map.
fn baked(map: &RoadMap) -> BTreeMap<String, (f64, BTreeMap<usize, usize>)> {
    let mut out: BTreeMap<String, (f64, BTreeMap<usize, usize>)> = BTreeMap::new();
    for l in &map.lanes {
        let road = &map.roads[l.road];
        *out.entry(road.od_id.clone())
            .or_insert((road.length_m, BTreeMap::new()))
            .1
            .entry(l.section)
            .or_default() += 1;
    }
    out
}

/// Checks one map that loads; returns its road count.
fn check(path: &Path) -> usize {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let text = std::fs::read_to_string(path).unwrap();
    let t = std::time::Instant::now();
    let Imported { map, warnings } =
        import(&name, &text).unwrap_or_else(|e| panic!("{name} is refused: {e}"));
    let took = t.elapsed();
    let (want, got) = (plain(&text), baked(&map));
    assert_eq!(map.roads.len(), want.len(), "{name}: road count");
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>(),
        "{name}: road ids"
    );
    for (id, (length, sections)) in &want {
        let (baked_length, baked_sections) = &got[id];
        assert!(
            (baked_length - length).abs() <= 1e-9 * length.max(1.0),
            "{name}: road {id} is {baked_length} m long, the file says {length}"
        );
        assert_eq!(
            baked_sections, sections,
            "{name}: road {id}: lanes per section (section index: lanes)"
        );
    }
    // Every lane's stations span its section, and every link meets.
    for l in &map.lanes {
        assert!(l.s.len() >= 2, "{name}: a lane with {} stations", l.s.len());
    }
    let gaps: Vec<&String> = warnings
        .iter()
        .filter(|w| w.contains("lane link"))
        .collect();
    assert!(gaps.is_empty(), "{name}: {gaps:?}");
    println!(
        "{name}: {} roads, {} lanes, {} lane links, loaded in {took:.1?}",
        map.roads.len(),
        map.lanes.len(),
        map.lanes.iter().map(|l| l.successors.len()).sum::<usize>()
    );
    map.roads.len()
}

#[test]
fn every_carla_town_loads_with_the_file_s_roads_lanes_and_lengths() {
    let towns = maps("carla");
    let names: Vec<String> = towns
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        ["Town01", "Town02", "Town03", "Town04", "Town05", "Town06", "Town07"]
    );
    let roads: Vec<usize> = towns.iter().map(|p| check(p)).collect();
    assert!(roads.iter().all(|&n| n > 60), "{roads:?}");
}

/// esmini's maps with faults of their own, which load (as esmini and libOpenDRIVE read them)
/// with a warning naming the fault: a link to a road the map lacks leads nowhere, and a road
/// longer than its plan view is baked to its length, its last geometry running on.
const WARNED: &[(&str, &str)] = &[
    (
        "stationary_objects.xodr",
        "<successor> of road \"0\" names road \"1\", which the map does not have",
    ),
    (
        "straight_road.xodr",
        "length 2000.000 m, but its <planView> ends at 500.000 m",
    ),
];

#[test]
fn esmini_s_maps_load_with_the_file_s_roads_lanes_and_lengths() {
    let mut loaded = 0;
    for path in maps("esmini") {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if let Some((_, phrase)) = WARNED.iter().find(|(f, _)| *f == name) {
            let text = std::fs::read_to_string(&path).unwrap();
            let warnings = import(&name, &text).unwrap().warnings;
            assert!(
                warnings.iter().any(|w| w.contains(phrase)),
                "{name}: {warnings:?}"
            );
        }
        check(&path);
        loaded += 1;
    }
    assert_eq!(loaded, 76, "every esmini map loads");
    println!(
        "{loaded} esmini maps load; {} of them with a fault named",
        WARNED.len()
    );
}

/// A lane's `(road id, section, lane id)`.
fn key(map: &RoadMap, k: usize) -> (String, usize, i32) {
    let l = &map.lanes[k];
    (map.roads[l.road].od_id.clone(), l.section, l.od_id)
}

#[test]
fn links_step_over_sub_millimetre_sections_and_section_ends_keep_their_own_lane_offset() {
    let load = |town: &str| {
        let path = maps("carla")
            .into_iter()
            .find(|p| p.file_stem().unwrap() == town)
            .unwrap();
        import(town, &std::fs::read_to_string(path).unwrap())
            .unwrap()
            .map
    };
    let successors = |map: &RoadMap, road: &str, section: usize, lane: i32| {
        let k = (0..map.lanes.len())
            .find(|&k| key(map, k) == (road.to_owned(), section, lane))
            .unwrap();
        let mut to: Vec<_> = map.lanes[k]
            .successors
            .iter()
            .map(|&n| key(map, n))
            .collect();
        to.sort();
        to
    };
    // Town02, road 294: its first section is 0.11 mm long; lane 1 (driven against s) leaves
    // through it into lane -1 of road 6, as that section's link says (xodr 0.8 read lane 1,
    // 42.5 m away).
    let town02 = load("Town02");
    assert_eq!(successors(&town02, "294", 1, 1), [("6".to_owned(), 0, -1)]);
    // Town03, road 14 into junction 685: lane -4 enters connecting road 691 through its
    // 4.5 µm first section, whose link takes it to lane -3.
    let town03 = load("Town03");
    assert_eq!(
        successors(&town03, "14", 0, -4),
        [("686".to_owned(), 1, -4), ("691".to_owned(), 1, -3)]
    );
    // Town06, road 98: section 8's lane -1 ends where section 9 starts with a lane offset
    // 7 m further left; it ends 1.75 m right of the reference line, where lane -3 of section
    // 9 begins.
    let town06 = load("Town06");
    let lane = |section: usize, id: i32| {
        (0..town06.lanes.len())
            .find(|&k| key(&town06, k) == ("98".to_owned(), section, id))
            .unwrap()
    };
    let (a, b) = (&town06.lanes[lane(8, -1)], &town06.lanes[lane(9, -3)]);
    let (end, start) = (a.centre[a.centre.len() - 1], b.centre[0]);
    let apart = (end[0] - start[0]).hypot(end[1] - start[1]);
    assert!(
        apart < 0.01,
        "{apart} m between section 8's end and section 9's start"
    );
    assert_eq!(successors(&town06, "98", 8, -1), [("98".to_owned(), 9, -3)]);
}

/// Two straight roads along x, one lane each way, the second starting `gap` m past the
/// first's end, their lanes linked end to end.
fn linked_with_gap(gap: f64) -> String {
    let road = |id: &str, x: f64, link: &str, to: &str| {
        format!(
            r#"  <road length="100" id="{id}" junction="-1"><link>{link}</link>
    <planView><geometry s="0" x="{x}" y="0" hdg="0" length="100"><line/></geometry></planView>
    <lanes><laneSection s="0">
      <left><lane id="1" type="driving"><link><{to} id="1"/></link><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></left>
      <center><lane id="0" type="none"/></center>
      <right><lane id="-1" type="driving"><link><{to} id="-1"/></link><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></right>
    </laneSection></lanes>
  </road>
"#
        )
    };
    format!(
        "<OpenDRIVE>\n  <header revMajor=\"1\" revMinor=\"6\"/>\n{}{}</OpenDRIVE>\n",
        road(
            "1",
            0.0,
            r#"<successor elementType="road" elementId="2" contactPoint="start"/>"#,
            "successor"
        ),
        road(
            "2",
            100.0 + gap,
            r#"<predecessor elementType="road" elementId="1" contactPoint="end"/>"#,
            "predecessor"
        ),
    )
}

#[test]
fn a_lane_link_across_a_gap_is_a_warning_up_to_half_a_metre_and_refused_beyond() {
    // 5 cm: silent, and linked both ways.
    let Imported { map, warnings } = import("meet.xodr", &linked_with_gap(0.05)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let linked = |map: &RoadMap| {
        let mut pairs: Vec<_> = (0..map.lanes.len())
            .flat_map(|k| map.lanes[k].successors.iter().map(move |&n| (k, n)))
            .map(|(k, n)| (key(map, k), key(map, n)))
            .collect();
        pairs.sort();
        pairs
    };
    let both = [
        (("1".to_owned(), 0, -1), ("2".to_owned(), 0, -1)),
        (("2".to_owned(), 0, 1), ("1".to_owned(), 0, 1)),
    ];
    assert_eq!(linked(&map), both);
    // 30 cm: a warning with the gaps measured; the links are kept.
    let Imported { map, warnings } = import("near.xodr", &linked_with_gap(0.3)).unwrap();
    assert_eq!(linked(&map), both);
    let all = warnings.join("\n");
    assert!(
        all.contains(
            "near.xodr: 2 lane links cross a gap of 0.30 m (over 0.1 m, at most 0.5 m), the widest \
             from road \"2\" lane 1 (section 0) to road \"1\" lane 1 (section 0) at (100.30, 1.75)"
        ),
        "{all}"
    );
    // 2 m: refused, naming both lanes, the gap and where.
    let e = import("apart.xodr", &linked_with_gap(2.0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("apart.xodr:")
            && e.contains("links to")
            && e.contains("but they are 2.00 m apart where one leaves off and the other begins")
            && e.contains("a lane link may cross at most 0.5 m"),
        "{e}"
    );
}

#[test]
fn the_documented_link_tolerances_are_the_code_s() {
    use paracosm_engine::network::opendrive::{LINK_GAP_M, LINK_SILENT_M};
    let read = |f: &str| {
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(f))
            .unwrap()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    let maps = read("docs/maps.md");
    for says in [
        format!("Up to {LINK_SILENT_M} m (`LINK_SILENT_M`) a gap is silent"),
        format!("up to {LINK_GAP_M} m (`LINK_GAP_M`) the map loads with a warning"),
    ] {
        assert!(maps.contains(&says), "docs/maps.md: {says}");
    }
    let language = read("LANGUAGE.md");
    let says = format!(
        "more than {LINK_GAP_M} m apart where one leaves off and the next begins (measured across both lanes from border to border; from {LINK_SILENT_M} m to {LINK_GAP_M} m it is a warning"
    );
    assert!(language.contains(&says), "LANGUAGE.md: {says}");
}
