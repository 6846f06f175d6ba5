//! An ASAM OpenSCENARIO 1.2 document of one concrete test, written from the world the test
//! built and the states it went through (for `paracosm-fuzz export`).
//!
//! - **Entities.** The ego vehicle (`ego`), the NPC cars (`car1`, ...), the pedestrians
//!   (`pedestrian1`, ...) and the obstacles (`obstacle1`, ...), with their bounding boxes.
//!   A vehicle's position is its rear axle's centre (OpenSCENARIO's reference point of a
//!   vehicle, which esmini assumes), [`REAR_AXLE_SHARE`] of its length behind the centre of
//!   its footprint, and its bounding box lies ahead of it; a pedestrian's and an obstacle's is
//!   the centre of its footprint. OpenSCENARIO's `(x, y, z)` is paracosm's `(x, -z, y)`,
//!   headings agree.
//! - **Init.** Every entity is placed where the test starts it (`TeleportAction`); the ego and
//!   the cars get their initial speed (`AbsoluteTargetSpeed`). With [`EgoMotion::Route`], the
//!   ego gets its route as an `AssignRouteAction` (waypoints every 10 m) for a system under
//!   test to drive.
//! - **Story.** Each car follows the trajectory it drove in the test, timed (`Polyline`
//!   vertices at every step of the test, absolute time, written exactly: read back, each
//!   entity is where the test had it at every step), from the start; so does the ego with
//!   [`EgoMotion::Trajectory`] (the default): what the system under test did is in the file. Each pedestrian that walked starts
//!   on a `DistanceCondition`: when the ego comes within the distance at which it started
//!   walking in the test (its trigger, measured from the recording); it then follows its walk
//!   as a trajectory timed from that moment.
//! - **Stop.** At the test's horizon (`SimulationTimeCondition`).
//!
//! The header's date is the Unix epoch, so that one test always exports to the same bytes.

use paracosm_engine::Snapshot;
use paracosm_engine::{Size, WorldSpec};

use super::xml::El;

/// Longest distance between two waypoints of the ego's route, m.
pub const WAYPOINT_EVERY_M: f64 = 10.0;
/// How much farther than the recorded distance a pedestrian's trigger reaches, m: read
/// back, the ego's reference point is where it was, to the last bits, and the walk starts at
/// the step it started in the test, not one step later for a rounding.
pub const TRIGGER_SLACK_M: f64 = 1e-9;
/// How far behind the centre of a vehicle's footprint its rear axle lies, as a share of its
/// length (its front axle lies as far ahead).
pub const REAR_AXLE_SHARE: f64 = 0.3;

/// The rear axle's centre of a vehicle of `size` whose footprint's centre is at `p` (paracosm
/// world `[x, y, z]`, m) facing `h` (rad): its reference point in the file.
fn rear_axle(p: [f64; 3], h: f64, size: Size) -> [f64; 3] {
    let k = REAR_AXLE_SHARE * size.length_m;
    // Heading h points along (cos h, -sin h) in paracosm's (x, z).
    [p[0] - k * h.cos(), p[1], p[2] + k * h.sin()]
}

/// How the ego's motion is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EgoMotion {
    /// The trajectory it drove, timed (a vertex at every step): another simulator replays
    /// what the system under test did, and `paracosm-fuzz FILE.xosc --scripted-ego` replays
    /// the test itself.
    #[default]
    Trajectory,
    /// Its route as an `AssignRouteAction`, for another system under test to drive.
    Route,
}

/// What the export writes about one test: what it is, and what it went through.
pub struct Test<'a> {
    /// How the ego's motion is written.
    pub ego: EgoMotion,
    /// One line describing the test (campaign, id, verdict).
    pub description: String,
    /// The test's parameters, `(name, value as written)`, numbers first.
    pub params: Vec<(String, serde_json::Value)>,
    /// The road network's file, relative to the `.xosc`.
    pub network_file: String,
    /// The world as built.
    pub world: &'a WorldSpec,
    /// The states at the start and after every step.
    pub states: &'a [Snapshot],
    /// The test's horizon, s.
    pub horizon_s: f64,
    /// Where the network's origin lies in its file's coordinates, OpenDRIVE `[x, y]` m: a map
    /// far from the origin is simulated moved (`RoadMap::origin_m`), and the scenario's
    /// positions are written back in the file's own coordinates. `[0, 0]` for pieces.
    pub origin_m: [f64; 2],
}

fn world_position(p: [f64; 3], h: f64) -> El {
    El::new("Position").child(
        El::new("WorldPosition")
            .exact("x", p[0])
            .exact("y", -p[2])
            .num("z", 0.0)
            .exact("h", h),
    )
}

/// A bounding box of `size` whose centre lies `ahead` m in front of the reference point.
fn bounding_box(size: Size, ahead: f64) -> El {
    El::new("BoundingBox")
        .child(
            El::new("Center")
                .num("x", ahead)
                .num("y", 0.0)
                .num("z", size.height_m / 2.0),
        )
        .child(
            El::new("Dimensions")
                .num("width", size.width_m)
                .num("length", size.length_m)
                .num("height", size.height_m),
        )
}

fn vehicle(name: &str, size: Size) -> El {
    let axle = |tag: &str, x: f64, steer: f64| {
        El::new(tag)
            .num("maxSteering", steer)
            .num("wheelDiameter", 0.7)
            .num("trackWidth", size.width_m - 0.2)
            .num("positionX", x)
            .num("positionZ", 0.35)
    };
    El::new("Vehicle")
        .attr("name", name)
        .attr("vehicleCategory", "car")
        .child(bounding_box(size, REAR_AXLE_SHARE * size.length_m))
        .child(
            El::new("Performance")
                .num("maxSpeed", 60.0)
                .num("maxAcceleration", 5.0)
                .num("maxDeceleration", 10.0),
        )
        .child(
            El::new("Axles")
                .child(axle(
                    "FrontAxle",
                    2.0 * REAR_AXLE_SHARE * size.length_m,
                    0.6,
                ))
                .child(axle("RearAxle", 0.0, 0.0)),
        )
        .child(El::new("Properties"))
}

fn private(entity: &str, actions: Vec<El>) -> El {
    El::new("Private").attr("entityRef", entity).children(
        actions
            .into_iter()
            .map(|a| El::new("PrivateAction").child(a)),
    )
}

fn teleport(p: [f64; 3], h: f64) -> El {
    El::new("TeleportAction").child(world_position(p, h))
}

fn speed(v: f64) -> El {
    El::new("LongitudinalAction").child(
        El::new("SpeedAction")
            .child(
                El::new("SpeedActionDynamics")
                    .attr("dynamicsShape", "step")
                    .num("value", 0.0)
                    .attr("dynamicsDimension", "time"),
            )
            .child(
                El::new("SpeedActionTarget").child(El::new("AbsoluteTargetSpeed").num("value", v)),
            ),
    )
}

fn condition(name: &str, edge: &str, inner: El) -> El {
    El::new("ConditionGroup").child(
        El::new("Condition")
            .attr("name", name)
            .num("delay", 0.0)
            .attr("conditionEdge", edge)
            .child(inner),
    )
}

fn time_condition(name: &str, edge: &str, rule: &str, t: f64) -> El {
    condition(
        name,
        edge,
        El::new("ByValueCondition").child(
            El::new("SimulationTimeCondition")
                .num("value", t)
                .attr("rule", rule),
        ),
    )
}

/// A timed trajectory of `(t, position, heading)`, `absolute` or relative to the action's
/// start.
fn follow(name: &str, points: &[(f64, [f64; 3], f64)], absolute: bool) -> El {
    let vertices = points.iter().map(|(t, p, h)| {
        El::new("Vertex")
            .exact("time", *t)
            .child(world_position(*p, *h))
    });
    El::new("RoutingAction").child(
        El::new("FollowTrajectoryAction")
            .child(
                El::new("TrajectoryRef").child(
                    El::new("Trajectory")
                        .attr("name", name)
                        .attr("closed", "false")
                        .child(El::new("Shape").child(El::new("Polyline").children(vertices))),
                ),
            )
            .child(
                El::new("TimeReference").child(
                    El::new("Timing")
                        .attr(
                            "domainAbsoluteRelative",
                            if absolute { "absolute" } else { "relative" },
                        )
                        .num("scale", 1.0)
                        .num("offset", 0.0),
                ),
            )
            .child(El::new("TrajectoryFollowingMode").attr("followingMode", "position")),
    )
}

fn maneuver_group(entity: &str, event: El) -> El {
    El::new("ManeuverGroup")
        .attr("maximumExecutionCount", 1)
        .attr("name", entity)
        .child(
            El::new("Actors")
                .attr("selectTriggeringEntities", "false")
                .child(El::new("EntityRef").attr("entityRef", entity)),
        )
        .child(El::new("Maneuver").attr("name", entity).child(event))
}

fn event(name: &str, action: El, trigger: El) -> El {
    El::new("Event")
        .attr("name", name)
        .attr("priority", "override")
        .attr("maximumExecutionCount", 1)
        .child(
            El::new("Action")
                .attr("name", name)
                .child(El::new("PrivateAction").child(action)),
        )
        .child(El::new("StartTrigger").child(trigger))
}

/// A simulated world position `[x, y, z]` in the file's frame, where the network's origin lies
/// at `origin` (OpenDRIVE y is -z).
fn in_file(origin: [f64; 2], p: [f64; 3]) -> [f64; 3] {
    [p[0] + origin[0], p[1], p[2] - origin[1]]
}

/// The document.
pub fn write(test: &Test<'_>) -> String {
    let frames: Vec<&Snapshot> = test.states.iter().collect();
    let Some(first) = test.states.first() else {
        return String::new();
    };
    let params = parameter_declarations(&test.params);
    let entities = entities(test.world);
    let init = init(test, first);
    let story = story(test, &frames, first);
    El::new("OpenSCENARIO")
        .child(
            El::new("FileHeader")
                .attr("revMajor", 1)
                .attr("revMinor", 2)
                .attr("date", "1970-01-01T00:00:00")
                .attr("description", &test.description)
                .attr("author", "paracosm"),
        )
        .child(params)
        .child(El::new("CatalogLocations"))
        .child(
            El::new("RoadNetwork").child(El::new("LogicFile").attr("filepath", &test.network_file)),
        )
        .child(El::new("Entities").children(entities))
        .child(
            El::new("Storyboard")
                .child(El::new("Init").child(El::new("Actions").children(init)))
                .child(story)
                .child(El::new("StopTrigger").child(time_condition(
                    "horizon",
                    "rising",
                    "greaterThan",
                    test.horizon_s,
                ))),
        )
        .document()
}

/// The test's parameters: numbers as `double`, the others as `string`.
fn parameter_declarations(params: &[(String, serde_json::Value)]) -> El {
    El::new("ParameterDeclarations").children(params.iter().map(|(n, v)| {
        let (kind, value) = match v {
            serde_json::Value::Number(x) => ("double", x.to_string()),
            serde_json::Value::String(s) => ("string", s.clone()),
            other => ("string", other.to_string()),
        };
        El::new("ParameterDeclaration")
            .attr("name", n)
            .attr("parameterType", kind)
            .attr("value", value)
    }))
}

/// The scenario objects: the ego, the cars, the pedestrians and the obstacles of `w`.
fn entities(w: &WorldSpec) -> Vec<El> {
    let mut entities = vec![El::new("ScenarioObject")
        .attr("name", "ego")
        .child(vehicle("ego", w.ego.vehicle.size))];
    // A car not in this test (`enabled` false) is not in the file either.
    for (i, c) in w.cars.iter().enumerate().filter(|(_, c)| c.enabled) {
        entities.push(
            El::new("ScenarioObject")
                .attr("name", format!("car{}", i + 1))
                .child(vehicle(&format!("car{} ({})", i + 1, c.color), c.size)),
        );
    }
    for i in 0..w.pedestrians.len() {
        let name = format!("pedestrian{}", i + 1);
        entities.push(
            El::new("ScenarioObject").attr("name", &name).child(
                El::new("Pedestrian")
                    .attr("name", &name)
                    .num("mass", 75.0)
                    .attr("pedestrianCategory", "pedestrian")
                    .child(bounding_box(Size::PEDESTRIAN, 0.0))
                    .child(El::new("Properties")),
            ),
        );
    }
    for (i, o) in w.obstacles.iter().enumerate() {
        let name = format!("obstacle{}", i + 1);
        entities.push(
            El::new("ScenarioObject").attr("name", &name).child(
                El::new("MiscObject")
                    .attr("name", &name)
                    .num("mass", 500.0)
                    .attr("miscObjectCategory", "obstacle")
                    .child(bounding_box(o.size, 0.0))
                    .child(El::new("Properties")),
            ),
        );
    }
    entities
}

/// Init: where everything starts (`first`), the ego's and the cars' speeds, the ego's route.
fn init(test: &Test<'_>, first: &Snapshot) -> Vec<El> {
    let w = test.world;
    let g = |p: [f64; 3]| in_file(test.origin_m, p);
    let mut init = Vec::new();
    let ego = &first.ego;
    let ego_size = w.ego.vehicle.size;
    let mut ego_actions = vec![
        teleport(
            g(rear_axle(ego.pos_m, ego.heading_rad, ego_size)),
            ego.heading_rad,
        ),
        speed(w.ego.initial_speed_mps),
    ];
    if test.ego == EgoMotion::Route && w.ego.route.len() >= 2 {
        ego_actions.push(assign_route(&w.ego.route, test.origin_m));
    }
    init.push(private("ego", ego_actions));
    for (i, c) in first.cars.iter().enumerate() {
        if !w.cars[i].enabled {
            continue;
        }
        init.push(private(
            &format!("car{}", i + 1),
            vec![
                teleport(
                    g(rear_axle(c.pos_m, c.heading_rad, w.cars[i].size)),
                    c.heading_rad,
                ),
                // The speed of its first step (a car's speed is measured over a step, and
                // the first state has none yet): the storyboard starts its trajectory one
                // step after the start, and moves it at this speed until then.
                speed(first_step_speed(test, i).unwrap_or(c.speed_mps)),
            ],
        ));
    }
    for (i, p) in first.pedestrians.iter().enumerate() {
        let s = &w.pedestrians[i];
        let h = (-(s.target[2] - s.start[2])).atan2(s.target[0] - s.start[0]);
        init.push(private(
            &format!("pedestrian{}", i + 1),
            vec![teleport(g(p.pos_m), h)],
        ));
    }
    for (i, o) in first.obstacles.iter().enumerate() {
        init.push(private(
            &format!("obstacle{}", i + 1),
            vec![teleport(g(o.base_m), o.heading_rad)],
        ));
    }
    init
}

/// How fast car `i` moved over the test's first step, m/s; `None` for a test without one.
fn first_step_speed(test: &Test<'_>, i: usize) -> Option<f64> {
    let (a, b) = (test.states.first()?, test.states.get(1)?);
    let (p, q) = (a.cars.get(i)?.pos_m, b.cars.get(i)?.pos_m);
    let dt = b.t_s - a.t_s;
    (dt > 0.0).then(|| (q[0] - p[0]).hypot(q[2] - p[2]) / dt)
}

/// The ego's route (at least 2 points) as an `AssignRouteAction`: waypoints at the first
/// point, one every [`WAYPOINT_EVERY_M`], and the last, each heading along the route there.
fn assign_route(route: &[[f64; 2]], origin: [f64; 2]) -> El {
    let waypoints = route_waypoints(route);
    El::new("RoutingAction").child(
        El::new("AssignRouteAction").child(
            El::new("Route")
                .attr("name", "ego route")
                .attr("closed", "false")
                .children(waypoints.iter().map(|&(q, h)| {
                    El::new("Waypoint")
                        .attr("routeStrategy", "shortest")
                        .child(world_position(in_file(origin, [q[0], 0.0, q[1]]), h))
                })),
        ),
    )
}

/// The waypoints of a route of at least 2 points, `(point, heading)`.
fn route_waypoints(route: &[[f64; 2]]) -> Vec<([f64; 2], f64)> {
    // Indices of the route's points that become waypoints: the first, one every
    // WAYPOINT_EVERY_M, the last.
    let mut picked = vec![0];
    let mut walked = 0.0;
    for (i, pair) in route.windows(2).enumerate() {
        walked += (pair[1][0] - pair[0][0]).hypot(pair[1][1] - pair[0][1]);
        if walked >= WAYPOINT_EVERY_M {
            picked.push(i + 1);
            walked = 0.0;
        }
    }
    if picked.last() != Some(&(route.len() - 1)) {
        picked.push(route.len() - 1);
    }
    // Each waypoint heads along the route there (a simulator matches a waypoint to the
    // lane of that direction): toward the next distinct point, the last from the one
    // before it.
    let heading = |i: usize| {
        let ahead = route[i + 1..].iter().find(|q| **q != route[i]);
        let behind = route[..i].iter().rev().find(|q| **q != route[i]);
        let (a, b) = match (ahead, behind) {
            (Some(n), _) => (route[i], *n),
            (None, Some(p)) => (*p, route[i]),
            (None, None) => return 0.0,
        };
        (-(b[1] - a[1])).atan2(b[0] - a[0])
    };
    picked.iter().map(|&i| (route[i], heading(i))).collect()
}

/// The story: cars (and with [`EgoMotion::Trajectory`] the ego) drive their trajectories;
/// pedestrians walk when the ego comes near.
fn story(test: &Test<'_>, frames: &[&Snapshot], first: &Snapshot) -> El {
    let w = test.world;
    let g = |p: [f64; 3]| in_file(test.origin_m, p);
    let mut groups = Vec::new();
    if test.ego == EgoMotion::Trajectory {
        let points: Vec<(f64, [f64; 3], f64)> = frames
            .iter()
            .map(|s| {
                let p = rear_axle(s.ego.pos_m, s.ego.heading_rad, w.ego.vehicle.size);
                (s.t_s, g(p), s.ego.heading_rad)
            })
            .collect();
        groups.push(maneuver_group(
            "ego",
            event(
                "ego drives",
                follow("ego as driven", &points, true),
                time_condition("start", "none", "greaterOrEqual", 0.0),
            ),
        ));
    }
    for i in (0..w.cars.len()).filter(|&i| w.cars[i].enabled) {
        let name = format!("car{}", i + 1);
        let points: Vec<(f64, [f64; 3], f64)> = frames
            .iter()
            .filter_map(|s| {
                s.cars.get(i).map(|c| {
                    let p = rear_axle(c.pos_m, c.heading_rad, w.cars[i].size);
                    (s.t_s, g(p), c.heading_rad)
                })
            })
            .collect();
        groups.push(maneuver_group(
            &name,
            event(
                &format!("{name} drives"),
                follow(&format!("{name} as driven"), &points, true),
                time_condition("start", "none", "greaterOrEqual", 0.0),
            ),
        ));
    }
    for i in 0..w.pedestrians.len() {
        groups.extend(pedestrian_group(test, frames, first, i));
    }
    if groups.is_empty() {
        // An act holds at least one group: the ego's, with nothing to do.
        groups.push(
            El::new("ManeuverGroup")
                .attr("maximumExecutionCount", 1)
                .attr("name", "ego")
                .child(
                    El::new("Actors")
                        .attr("selectTriggeringEntities", "false")
                        .child(El::new("EntityRef").attr("entityRef", "ego")),
                ),
        );
    }
    El::new("Story").attr("name", "test").child(
        El::new("Act")
            .attr("name", "actors")
            .children(groups)
            .child(El::new("StartTrigger").child(time_condition(
                "start",
                "none",
                "greaterOrEqual",
                0.0,
            ))),
    )
}

/// Pedestrian `i`'s walk, started when the ego comes within the distance at which it started
/// walking in the test; `None` when it never walked (or walked for less than two frames).
fn pedestrian_group(
    test: &Test<'_>,
    frames: &[&Snapshot],
    first: &Snapshot,
    i: usize,
) -> Option<El> {
    let w = test.world;
    let name = format!("pedestrian{}", i + 1);
    let Some(started) = test
        .states
        .iter()
        .find_map(|s| s.pedestrians.get(i).and_then(|p| p.triggered_at_s))
    else {
        // It never walked, or a script placed it (an OpenSCENARIO storyboard's): what it did
        // is a trajectory from the start, as a car's, when it moved at all.
        return placed_pedestrian_group(test, frames, first, i);
    };
    let at = test
        .states
        .iter()
        .find(|s| s.t_s >= started - 1e-9)
        .unwrap_or(first);
    let start = w.pedestrians[i].start;
    // From the ego's reference point, its rear axle, as a simulator measures it.
    let ego = rear_axle(at.ego.pos_m, at.ego.heading_rad, w.ego.vehicle.size);
    let d = (ego[0] - start[0]).hypot(ego[2] - start[2]);
    let target = w.pedestrians[i].target;
    let h = (-(target[2] - start[2])).atan2(target[0] - start[0]);
    let walk: Vec<(f64, [f64; 3], f64)> = frames
        .iter()
        .filter(|s| s.t_s >= started - 1e-9)
        .filter_map(|s| s.pedestrians.get(i).map(|p| (s.t_s - started, p.pos_m, h)))
        .collect();
    if walk.len() < 2 {
        return None;
    }
    let trigger = condition(
        &format!("ego within {d:.2} m"),
        "rising",
        El::new("ByEntityCondition")
            .child(
                El::new("TriggeringEntities")
                    .attr("triggeringEntitiesRule", "any")
                    .child(El::new("EntityRef").attr("entityRef", "ego")),
            )
            .child(
                El::new("EntityCondition").child(
                    El::new("DistanceCondition")
                        .attr("freespace", "false")
                        .attr("rule", "lessOrEqual")
                        .exact("value", d + TRIGGER_SLACK_M)
                        .attr("relativeDistanceType", "euclidianDistance")
                        .attr("coordinateSystem", "entity")
                        .child(world_position(in_file(test.origin_m, start), h)),
                ),
            ),
    );
    Some(maneuver_group(
        &name,
        event(
            &format!("{name} walks"),
            follow(&format!("{name} as walked"), &walk, false),
            trigger,
        ),
    ))
}

/// Pedestrian `i`'s motion as a trajectory timed from the start, facing the way it moved
/// from its first to its last position; `None` when it stayed where it started.
fn placed_pedestrian_group(
    test: &Test<'_>,
    frames: &[&Snapshot],
    first: &Snapshot,
    i: usize,
) -> Option<El> {
    let name = format!("pedestrian{}", i + 1);
    let at = |s: &Snapshot| s.pedestrians.get(i).map(|p| p.pos_m);
    let (start, end) = (at(first)?, frames.iter().rev().find_map(|s| at(s))?);
    if start == end && frames.iter().all(|s| at(s).is_none_or(|p| p == start)) {
        return None;
    }
    let h = (-(end[2] - start[2])).atan2(end[0] - start[0]);
    let points: Vec<(f64, [f64; 3], f64)> = frames
        .iter()
        .filter_map(|s| at(s).map(|p| (s.t_s, in_file(test.origin_m, p), h)))
        .collect();
    Some(maneuver_group(
        &name,
        event(
            &format!("{name} moves"),
            follow(&format!("{name} as placed"), &points, true),
            time_condition("start", "none", "greaterOrEqual", 0.0),
        ),
    ))
}
