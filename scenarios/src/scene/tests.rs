use paracosm_engine::behaviour::ActorRef;
use paracosm_engine::rx::{Node, Value};
use paracosm_generators::{Param, ParamSpace, Point};

use super::*;
use crate::reference;

fn assignment(walking_speed: f64, trigger_distance: f64) -> Assignment {
    let space = ParamSpace::new(vec![
        Param::interval(reference::WALKING_SPEED, 0.5, 10.0, "m/s"),
        Param::interval(reference::TRIGGER_DISTANCE, 5.0, 60.0, "m"),
    ])
    .unwrap();
    let unit = |x: f64, lo: f64, hi: f64| (x - lo) / (hi - lo);
    space
        .decode(&Point {
            discrete: vec![],
            continuous: vec![
                unit(walking_speed, 0.5, 10.0),
                unit(trigger_distance, 5.0, 60.0),
            ],
        })
        .unwrap()
}

#[test]
fn a_scene_declared_in_rust_carries_its_sites_and_takes_values_by_name() {
    let scene = reference::scene(Scene::for_assignment(&assignment(3.0, 20.0))).unwrap();
    let names: Vec<_> = scene
        .params()
        .iter()
        .map(|p| p.name.clone().unwrap())
        .collect();
    assert_eq!(names, ["walking_speed", "trigger_distance"]);
    for p in scene.params() {
        assert!(
            p.site.file.ends_with("reference.rs") && p.site.line > 0,
            "{:?}",
            p.site
        );
        assert_eq!(p.site.variable.as_deref(), p.name.as_deref());
    }
    // The values by name, as the world reads them: the pedestrian's speed stream is the
    // walking speed.
    let world = scene.world().unwrap();
    let speed = world.pedestrians[0].speed;
    assert!(matches!(world.streams.nodes()[speed.0], Node::Const(Value::Num(v)) if v == 3.0));
    let actors: Vec<_> = scene
        .actors()
        .iter()
        .map(|a| (a.actor, a.site.variable.clone().unwrap()))
        .collect();
    assert_eq!(actors[0], (ActorRef::Ego, "v".to_owned()));
    assert!(matches!(actors[1], (ActorRef::Pedestrian(_), ref v) if v == "p"));
    let monitors: Vec<_> = scene
        .monitors()
        .map(|(m, s)| (m.name().to_owned(), s.line))
        .collect();
    assert_eq!(monitors.len(), 2);
    assert!(monitors.iter().all(|(_, line)| *line > 0));
    assert_eq!(scene.horizon_s(), reference::HORIZON_S);
    // Without values, each parameter takes its representative value (an interval's lower end).
    let probe = reference::scene(Scene::new(None)).unwrap();
    let speed = probe.world().unwrap().pedestrians[0].speed;
    let nodes = probe.world().unwrap().streams;
    assert!(matches!(nodes.nodes()[speed.0], Node::Const(Value::Num(v)) if v == 0.5));
}

#[test]
fn a_scene_refuses_what_it_cannot_hold_twice_or_out_of_order() {
    let mut scene = reference::scene(Scene::new(None)).unwrap();
    let light = scene.push(Node::Const(Value::Num(1.0)));
    let e = scene
        .set_environment(light, light, Site::of("x.star:3:1"))
        .unwrap_err();
    assert!(e.to_string().contains("reference.rs:"), "{e}");
    let e = scene.set_settings(TestSettings::default()).unwrap_err();
    assert!(matches!(e, SceneError::SecondSettings { .. }), "{e}");
    // A pedestrian declared but placed under another's handle.
    let first = scene.declare_pedestrian("a".into(), Site::of("x.star:4:1"));
    let _second = scene.declare_pedestrian("b".into(), Site::of("x.star:5:1"));
    let spec = scene.pedestrians().values().next().unwrap().clone();
    assert!(scene.place_pedestrian(_second, spec.clone()).is_err());
    assert!(scene.place_pedestrian(first, spec).is_ok());
    let spec = scene.pedestrians().values().next().unwrap().clone();
    assert!(scene.place_pedestrian(ActorRef::Ego, spec).is_err());
}

#[test]
fn a_scene_without_an_ego_builds_no_world_and_says_so() {
    let scene = Scene::new(None);
    let e = scene.world().unwrap_err();
    assert_eq!(e.kind, LoadErrorKind::Worlds);
    assert!(e.message.contains("AutonomousVehicle"), "{}", e.message);
}

/// The scene model sits at the bottom (issue "One front-end contract"): no file of `scene/`
/// refers to the runner, the scenario built around a scene, or a front end (the language,
/// OpenSCENARIO, the Rust reference study) outside comments and tests.
#[test]
fn the_scene_model_imports_no_runner_and_no_front_end() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/scene");
    let above = [
        "crate::runner",
        "crate::scenario",
        "crate::lang",
        "crate::xosc",
        "crate::reference",
        "crate::Scenario",
    ];
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.file_name().is_some_and(|n| n == "tests.rs") {
            continue;
        }
        files += 1;
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for a in above {
                assert!(
                    !code.contains(a),
                    "{}:{}: the scene model refers to `{a}`: {line}",
                    path.display(),
                    i + 1
                );
            }
        }
    }
    assert!(files >= 7, "{files} files read");
}

/// A declaration for the binding tests: `name`, a `[0, 1)` interval, declared at line `line`.
fn decl(name: Option<&str>, line: u32, over_time: OverTime) -> ParamDecl {
    ParamDecl {
        name: name.map(str::to_owned),
        domain: paracosm_generators::Domain::Interval { lo: 0.0, hi: 1.0 },
        unit: None,
        over_time,
        site: Site {
            file: "p.star".into(),
            line,
            col: 5,
            variable: None,
        },
    }
}

/// Every front end binds by name: a parameter takes the value given under its own name, or
/// under the name it stands under (a program's `x = VarInterval(...)`) when it is declared
/// where the front end first saw it; another place, an unknown name or a value of the other
/// kind (a level for a parameter that varies over time) gives the representative value.
#[test]
fn a_scene_binds_values_by_name_whatever_the_declaration_order() {
    let level = |x: f64| ParamValue::Level(paracosm_generators::Value::Real(x));
    let given = GivenValues::new([
        ("speed".to_owned(), level(0.25)),
        ("gap".to_owned(), level(0.75)),
        ("fog".to_owned(), level(0.5)),
    ])
    .standing(std::sync::Arc::from(vec![
        (decl(None, 1, OverTime::Constant).site, "gap".to_owned()),
        (decl(None, 2, OverTime::Constant).site, "fog".to_owned()),
    ]));
    let mut scene = Scene::new(Some(given));
    // Declared in another order than given: each finds its own.
    let (gap, k) = scene.declare_param(decl(None, 1, OverTime::Constant));
    assert_eq!((gap, k), (level(0.75), 0));
    let (speed, _) = scene.declare_param(decl(Some("speed"), 9, OverTime::Constant));
    assert_eq!(speed, level(0.25));
    // Declared second but somewhere else than the front end saw: not `fog`'s value.
    let (moved, _) = scene.declare_param(decl(None, 7, OverTime::Constant));
    assert_eq!(
        moved,
        level(0.0),
        "the representative of [0, 1) is its low end"
    );
    let (unknown, _) = scene.declare_param(decl(Some("rain"), 3, OverTime::Constant));
    assert_eq!(
        unknown,
        representative(&decl(Some("rain"), 3, OverTime::Constant), 15.0)
    );
    let over = decl(Some("gap"), 4, OverTime::Piecewise(3));
    let (stream, _) = scene.declare_param(over.clone());
    assert_eq!(stream, representative(&over, scene.horizon_s()));
    assert_eq!(scene.param_value(1), Some(level(0.25)));
    assert!(scene.has_values());
}
