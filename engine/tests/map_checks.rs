//! Hostile input, second round, requirement 2: OpenDRIVE maps are validated like programs.
//! A map far from the origin is recentred (and bakes to the same lanes); roads that overlap
//! outside a junction are named in a warning; a road that folds over itself is refused, one
//! that closes into a ring is not. The refusals with their messages are the corpus
//! `tests/bad_inputs/maps/` (run by the root crate's `bad_inputs` test).

use std::path::PathBuf;

use paracosm_engine::network::opendrive::{import, RESOLVED_M};

fn shipped(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios/maps")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

/// `text` with every `<geometry>`'s `x` and `y` moved by `by`, OpenDRIVE m.
fn moved(text: &str, by: [f64; 2]) -> String {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mut edits = Vec::new();
    for g in doc.descendants().filter(|n| n.has_tag_name("geometry")) {
        for (k, name) in ["x", "y"].into_iter().enumerate() {
            let a = g.attribute_node(name).unwrap();
            let v: f64 = a.value().parse().unwrap();
            edits.push((a.range_value(), format!("{}", v + by[k])));
        }
    }
    let mut out = text.to_owned();
    edits.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
    for (r, v) in edits {
        out.replace_range(r, &v);
    }
    out
}

#[test]
fn a_map_far_from_the_origin_bakes_to_the_same_lanes_as_at_the_origin() {
    for name in ["bend.xodr", "junction.xodr", "roundabout.xodr"] {
        let text = shipped(name);
        let near = import(name, &text).unwrap();
        assert_eq!(near.map.origin_m, [0.0, 0.0], "{name} lies near the origin");
        for by in [[1e8, 0.0], [-3.5e6, 7.25e5], [0.0, RESOLVED_M * 3.0]] {
            let far = import(name, &moved(&text, by)).unwrap();
            let all = far.warnings.join("\n");
            assert!(
                all.contains("it is simulated moved by"),
                "{name} {by:?}: {all}"
            );
            let o = far.map.origin_m;
            assert_eq!(near.map.lanes.len(), far.map.lanes.len(), "{name}");
            let mut worst: f64 = 0.0;
            for (a, b) in near.map.lanes.iter().zip(&far.map.lanes) {
                assert_eq!(a.s.len(), b.s.len());
                for (p, q) in a.centre.iter().zip(&b.centre) {
                    // World [x, z] = OpenDRIVE [x, -y].
                    let back = [q[0] + o[0] - by[0], q[1] - (o[1] - by[1])];
                    worst = worst.max((p[0] - back[0]).hypot(p[1] - back[1]));
                }
                for (w, v) in a.width.iter().zip(&b.width) {
                    assert!((w - v).abs() < 1e-4, "{name} width {w} vs {v}");
                }
            }
            println!("{name} moved by {by:?}: origin {o:?}, lane centres at most {worst:.2e} m from the map at the origin");
            assert!(worst < 1e-3, "{name} {by:?}: {worst} m");
            // The moved map lies within the resolved square.
            for l in &far.map.lanes {
                for p in &l.centre {
                    assert!(p[0].abs() < RESOLVED_M && p[1].abs() < RESOLVED_M);
                }
            }
        }
    }
}

#[test]
fn a_map_wider_than_the_physics_resolves_is_refused_with_its_span() {
    // Two copies of the bend 200 km apart: no shift brings both within 65.5 km of the origin.
    let text = shipped("bend.xodr");
    let far = moved(&text, [2e5, 0.0]).replace("id=\"1\" junction", "id=\"2\" junction");
    let road_far = &far[far.find("<road").unwrap()..far.rfind("</road>").unwrap() + 7];
    let both = text.replace("</OpenDRIVE>", &format!("{road_far}\n</OpenDRIVE>"));
    let e = import("wide.xodr", &both).unwrap_err().to_string();
    assert!(e.contains("the map spans 200.4 km"), "{e}");
    assert!(
        e.contains("the f32 physics resolves 1 cm only within 65.5 km of the origin"),
        "{e}"
    );
}

/// A straight road `id` from `(x, y)` along heading `hdg` rad, `length` m, one lane each way.
fn straight(id: &str, x: f64, y: f64, hdg: f64, length: f64, link: &str) -> String {
    format!(
        r#"  <road name="r{id}" length="{length}" id="{id}" junction="-1"><link>{link}</link>
    <planView><geometry s="0" x="{x}" y="{y}" hdg="{hdg}" length="{length}"><line/></geometry></planView>
    <lanes><laneSection s="0">
      <left><lane id="1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></left>
      <center><lane id="0" type="none" level="false"/></center>
      <right><lane id="-1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></right>
    </laneSection></lanes>
  </road>
"#
    )
}

fn document(roads: &[String]) -> String {
    format!(
        "<OpenDRIVE>\n  <header revMajor=\"1\" revMinor=\"6\" name=\"t\"/>\n{}</OpenDRIVE>\n",
        roads.concat()
    )
}

#[test]
fn roads_that_cross_without_a_junction_are_named_in_a_warning() {
    let map = document(&[
        straight("1", 0.0, 0.0, 0.0, 100.0, ""),
        straight("2", 50.0, -50.0, std::f64::consts::FRAC_PI_2, 100.0, ""),
    ]);
    let all = import("cross.xodr", &map).unwrap().warnings.join("\n");
    assert!(
        all.contains("cross.xodr: roads \"1\" (line 3) and \"2\" (line 11) overlap at ("),
        "{all}"
    );
    assert!(all.contains("outside any junction"), "{all}");
    // The point named lies at the crossing (50, 0), within the lanes' width.
    let at = all.split("overlap at (").nth(1).unwrap();
    let xy: Vec<f64> = at
        .split(')')
        .next()
        .unwrap()
        .split(", ")
        .map(|v| v.parse().unwrap())
        .collect();
    assert!((xy[0] - 50.0).abs() < 4.0 && xy[1].abs() < 4.0, "{xy:?}");
}

#[test]
fn a_road_drawn_twice_is_named_in_a_warning() {
    let map = document(&[
        straight("1", 0.0, 0.0, 0.0, 100.0, ""),
        straight("7", 20.0, 0.5, 0.0, 60.0, ""),
    ]);
    let all = import("twice.xodr", &map).unwrap().warnings.join("\n");
    assert!(
        all.contains("roads \"1\" (line 3) and \"7\" (line 11) overlap"),
        "{all}"
    );
}

#[test]
fn roads_that_meet_end_to_end_or_run_side_by_side_are_not_overlaps() {
    // Linked end to end, at an angle.
    let linked = document(&[
        straight(
            "1",
            0.0,
            0.0,
            0.0,
            100.0,
            r#"<successor elementType="road" elementId="2" contactPoint="start"/>"#,
        ),
        straight(
            "2",
            100.0,
            0.0,
            0.3,
            80.0,
            r#"<predecessor elementType="road" elementId="1" contactPoint="end"/>"#,
        ),
    ]);
    assert!(import("linked.xodr", &linked).unwrap().warnings.is_empty());
    // Parallel roads whose outer edges touch (7 m apart, each 3.5 m either side).
    let beside = document(&[
        straight("1", 0.0, 0.0, 0.0, 100.0, ""),
        straight("2", 0.0, 7.0, 0.0, 100.0, ""),
    ]);
    let w = import("beside.xodr", &beside).unwrap().warnings;
    assert!(w.is_empty(), "{w:?}");
    // The shipped maps, with their junctions and roundabout.
    for name in ["bend.xodr", "junction.xodr", "roundabout.xodr"] {
        let w = import(name, &shipped(name)).unwrap().warnings;
        assert!(w.is_empty(), "{name}: {w:?}");
    }
}

/// One road of one arc of `length` m and curvature `k` 1/m, linked to itself when `ring`, with
/// `elevation` inside the road.
fn arc_road(length: f64, k: f64, ring: bool, elevation: &str) -> String {
    let link = if ring {
        r#"<successor elementType="road" elementId="1" contactPoint="start"/><predecessor elementType="road" elementId="1" contactPoint="end"/>"#
    } else {
        ""
    };
    format!(
        r#"<OpenDRIVE><header revMajor="1" revMinor="6" name="t"/>
  <road name="r" length="{length}" id="1" junction="-1"><link>{link}</link>
    <planView><geometry s="0" x="0" y="0" hdg="0" length="{length}"><arc curvature="{k}"/></geometry></planView>{elevation}
    <lanes><laneSection s="0">
      <center><lane id="0" type="none" level="false"/></center>
      <right><lane id="-1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></right>
    </laneSection></lanes>
  </road>
</OpenDRIVE>"#
    )
}

#[test]
fn a_ring_road_that_is_its_own_successor_is_accepted_and_a_fold_is_not() {
    let tau = std::f64::consts::TAU;
    // A closed circle of 200 m.
    let ring = import("ring.xodr", &arc_road(200.0, tau / 200.0, true, "")).unwrap();
    assert!(ring.warnings.is_empty(), "{:?}", ring.warnings);
    // The same circle run on for 60 m more comes back over itself.
    let e = import("fold.xodr", &arc_road(260.0, tau / 200.0, false, ""))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("fold.xodr:2:3: road \"1\" (line 2) comes back over itself"),
        "{e}"
    );
    // A ramp that rises as it turns is flattened: a warning, not a refusal.
    let rises = r#"
    <elevationProfile><elevation s="0" a="0" b="0.05" c="0" d="0"/></elevationProfile>"#;
    let ramp = import("ramp.xodr", &arc_road(260.0, tau / 200.0, false, rises)).unwrap();
    let all = ramp.warnings.join("\n");
    assert!(
        all.contains("comes back over itself") && all.contains("it rises"),
        "{all}"
    );
    // A ring that does not close is refused.
    let e = import("open.xodr", &arc_road(150.0, tau / 200.0, true, ""))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("road \"1\" is its own successor, but its end"),
        "{e}"
    );
}
