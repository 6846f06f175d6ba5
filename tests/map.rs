//! `paracosm-fuzz map`: the listing of a map's roads and junctions, its drawings, and its
//! refusals; and the system under test named in `summary.json` and `report.html`.

use std::path::{Path, PathBuf};

mod common;
use common::{expect_code, fuzz};

/// The shipped OpenDRIVE maps, `scenarios/maps/*.xodr`.
fn shipped_maps() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/maps");
    let mut maps: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xodr"))
        .collect();
    maps.sort();
    assert!(maps.len() >= 3, "{maps:?}");
    maps
}

/// The `<road id>`s of the file, in order, and its number of `<connection>`s, read as plain
/// XML.
fn roads_in(path: &Path) -> (Vec<String>, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let root = doc.root_element();
    let roads = root
        .children()
        .filter(|n| n.has_tag_name("road"))
        .map(|n| n.attribute("id").unwrap().to_owned())
        .collect();
    let connections = root
        .children()
        .filter(|n| n.has_tag_name("junction"))
        .flat_map(|j| j.children())
        .filter(|n| n.has_tag_name("connection"))
        .count();
    (roads, connections)
}

#[test]
fn map_lists_every_road_and_connection_of_each_shipped_map_and_draws_it() {
    let dir = tempfile::tempdir().unwrap();
    for path in shipped_maps() {
        let stem = path.file_stem().unwrap().to_str().unwrap();
        let (png, svg) = (
            dir.path().join(format!("{stem}.png")),
            dir.path().join(format!("{stem}.svg")),
        );
        let o = fuzz(&[
            "map",
            path.to_str().unwrap(),
            "--png",
            png.to_str().unwrap(),
            "--svg",
            svg.to_str().unwrap(),
        ]);
        expect_code(&o, 0);
        let stdout = String::from_utf8(o.stdout).unwrap();
        let (roads, connections) = roads_in(&path);
        // One line per road, in the file's order.
        let listed: Vec<&str> = stdout
            .lines()
            .filter_map(|l| l.strip_prefix("road "))
            .map(|l| l.split_whitespace().next().unwrap())
            .collect();
        assert_eq!(listed, roads, "{stem}: {stdout}");
        assert!(
            stdout.contains(&format!(
                "{} road{}",
                roads.len(),
                if roads.len() == 1 { "" } else { "s" }
            )),
            "{stem}: {stdout}"
        );
        let connection_lines = stdout
            .lines()
            .filter(|l| l.starts_with("  ") && l.contains(" -> "))
            .count();
        assert_eq!(connection_lines, connections, "{stem}: {stdout}");
        // Every road line gives a length and at least one lane section with a driving lane.
        for line in stdout.lines().filter(|l| l.starts_with("road ")) {
            assert!(line.contains(" m  junction "), "{line}");
            assert!(line.contains(":driving"), "{line}");
        }
        assert!(
            stdout.contains(&format!("wrote: {}, {}", png.display(), svg.display())),
            "{stdout}"
        );
        let image = image::open(&png).unwrap();
        assert!(image.width() >= 800 && image.height() >= 800, "{stem}");
        let svg_text = std::fs::read_to_string(&svg).unwrap();
        assert!(
            svg_text.len() > 10_000 && svg_text.contains("<svg"),
            "{stem}"
        );
        // Each road outside a junction is labelled with its id.
        assert!(
            svg_text.contains(&format!(">\n{}\n</text>", roads[0])),
            "{stem}"
        );
    }
}

#[test]
fn every_listed_driving_lane_is_found_by_on_lane_at_its_sections_ends_and_middle() {
    for path in shipped_maps() {
        let listing = paracosm::map::read(&path).unwrap();
        let text = listing.text();
        let mut checked = 0;
        for road in &listing.roads {
            for section in &road.sections {
                let [a, b] = section.s_m;
                assert!(0.0 <= a && a < b && b <= road.length_m + 1e-9, "{text}");
                for lane in section.lanes.iter().filter(|l| l.drivable) {
                    for s in [a, (a + b) / 2.0, b] {
                        let found = listing.map.lane_at(&road.id, lane.id, s);
                        assert!(found.is_ok(), "{} {} {s}: {found:?}", road.id, lane.id);
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 0, "{}", path.display());
    }
}

#[test]
fn the_junction_map_lists_its_turns_by_the_angle_they_make() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/maps/junction.xodr");
    let listing = paracosm::map::read(&path).unwrap();
    assert_eq!(listing.junctions.len(), 1);
    let turns: Vec<&str> = listing.junctions[0]
        .connections
        .iter()
        .map(|c| c.turn.as_ref().map(|(t, _)| t.as_str()).unwrap_or("none"))
        .collect();
    for t in ["left", "straight", "right"] {
        assert_eq!(turns.iter().filter(|x| **x == t).count(), 4, "{turns:?}");
    }
    // Each connecting road leaves onto a road outside the junction.
    for c in &listing.junctions[0].connections {
        let out = c.outgoing.as_deref().unwrap();
        assert!(["1", "2", "3", "4"].contains(&out), "{c:?}");
        assert_ne!(out, c.incoming, "{c:?}");
    }
}

#[test]
fn a_map_that_does_not_load_exits_2_naming_the_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "broken.xodr",
            &b"<OpenDRIVE>\n  <header/>\n  <road id=\"1\" length=\"10\">\n</OpenDRIVE>\n"[..],
            ":4:1",
        ),
        (
            "unknown.xodr",
            &b"<OpenDRIVE>\n  <header/>\n  <roadd id=\"1\"/>\n</OpenDRIVE>\n"[..],
            ":3:3",
        ),
        ("empty.xodr", &b""[..], ":1:1"),
        ("not_utf8.xodr", &b"<OpenDRIVE>\xff</OpenDRIVE>"[..], ""),
    ];
    for (name, text, at) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let o = fuzz(&["map", path.to_str().unwrap()]);
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.starts_with("paracosm-fuzz: error: ")
                && stderr.contains(&format!("{}{at}", path.display())),
            "{name}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(o.stdout.is_empty(), "{name}");
    }
    // A file that is not there, a folder, and a drawing onto a device: bad input too.
    let map = shipped_maps().remove(0);
    for args in [
        vec![
            "map".to_owned(),
            dir.path().join("missing.xodr").display().to_string(),
        ],
        vec!["map".to_owned(), dir.path().display().to_string()],
        vec![
            "map".to_owned(),
            map.display().to_string(),
            "--png".to_owned(),
            "/dev/null".to_owned(),
        ],
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = fuzz(&args);
        expect_code(&o, 2);
        assert!(!String::from_utf8_lossy(&o.stderr).contains("panicked"));
    }
    // A drawing into a missing folder, or over the map it draws (spelt another way, or
    // through a link): refused before the map is read, the error first, the map unchanged.
    let copy = dir.path().join("m.xodr");
    std::fs::copy(&map, &copy).unwrap();
    let link = dir.path().join("link.png");
    std::os::unix::fs::symlink(&copy, &link).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let spelt = dir.path().join(".").join("m.xodr");
    for (option, out, says) in [
        (
            "--png",
            dir.path().join("missing/sub/m.png"),
            "does not exist",
        ),
        ("--svg", spelt.clone(), "is the input"),
        ("--png", spelt, "is the input"),
        ("--png", link, "a symbolic link"),
    ] {
        let o = fuzz(&["map", copy.to_str().unwrap(), option, out.to_str().unwrap()]);
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.starts_with("paracosm-fuzz: error: ") && stderr.contains(says),
            "{option} {}: {stderr}",
            out.display()
        );
        assert_eq!(
            std::fs::read(&copy).unwrap(),
            before,
            "the map is unchanged"
        );
    }
}

/// The `sut` object of `dir/summary.json`, and the text of `dir/report.html`.
fn sut_of(dir: &Path) -> (serde_json::Value, String) {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let page = std::fs::read_to_string(dir.join("report.html")).unwrap();
    (summary["sut"].clone(), page)
}

#[test]
fn summary_and_report_name_the_system_under_test() {
    let dir = tempfile::tempdir().unwrap();
    let (builtin, external) = (dir.path().join("builtin"), dir.path().join("external"));
    let o = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "3",
        "--out",
        builtin.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .contains("system under test: aeb (built in, the scenario's)"),
        "{o:?}"
    );
    let (sut, page) = sut_of(&builtin);
    assert_eq!(
        sut,
        serde_json::json!({"kind": "builtin", "name": "aeb", "chosen_by": "scenario"})
    );
    assert!(
        page.contains("<title>pedestrian-crossing under aeb: "),
        "the page's title"
    );
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/python/paracosm_sut.py");
    let command = format!("python3 {}", script.display());
    let o = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "2",
        "--out",
        external.to_str().unwrap(),
        "--sut-cmd",
        &command,
    ]);
    expect_code(&o, 0);
    let (sut, page) = sut_of(&external);
    assert_eq!(sut["kind"], "command");
    assert_eq!(sut["name"], command.as_str());
    assert_eq!(sut["chosen_by"], "--sut-cmd");
    assert!(
        page.contains(&format!(" under {command}: ")),
        "the page's title"
    );
    // `report` rereads the folder and names it again; a summary written before the field
    // existed still reads.
    let o = fuzz(&["report", external.to_str().unwrap()]);
    expect_code(&o, 0);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains(&format!(
            "system under test: external command `{command}` (--sut-cmd)"
        )),
        "{o:?}"
    );
    let path = builtin.join("summary.json");
    let mut old: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    old.as_object_mut().unwrap().remove("sut");
    std::fs::write(&path, serde_json::to_string_pretty(&old).unwrap()).unwrap();
    let read = paracosm::report::summary::Summary::read(&builtin).unwrap();
    assert_eq!(read.sut, None);
}

#[test]
fn report_on_map_draws_each_test_where_its_parameters_put_an_actor() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("junction");
    let o = fuzz(&[
        "opendrive-junction",
        "--budget",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    common::ran(&o);
    let o = fuzz(&["report", out.to_str().unwrap(), "--on-map"]);
    common::ran(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    // `oncoming_at` is where the oncoming car starts along road 1: it is the actor drawn.
    assert!(
        stdout.contains("on the road map: where Car oncoming"),
        "{stdout}"
    );
    for f in ["failure_map-road.png", "failure_map-road.svg"] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len > 10_000, "{f}: {len} bytes");
    }
    let svg = std::fs::read_to_string(out.join("failure_map-road.svg")).unwrap();
    assert!(
        svg.contains("pass (") && svg.contains("fail ("),
        "the legend"
    );
    // No parameter of pedestrian-crossing moves an actor's start: refused, exit 2.
    let plain = dir.path().join("crossing");
    let o = fuzz(&[
        "pedestrian-crossing",
        "--budget",
        "5",
        "--out",
        plain.to_str().unwrap(),
    ]);
    common::ran(&o);
    let o = fuzz(&["report", plain.to_str().unwrap(), "--on-map"]);
    expect_code(&o, 2);
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .contains("no parameter of pedestrian-crossing places an actor"),
        "{o:?}"
    );
}
