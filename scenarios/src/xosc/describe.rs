//! The text `paracosm-fuzz xosc` prints.

use std::fmt::Write;

use paracosm_generators::{Domain, Value};
use paracosm_openscenario::model::{
    Action, ConditionKind, EntityKind, EntityTest, LaneTarget, OffsetTarget, Position, Scenario,
    SpeedTarget, TrajectoryShape, Trigger,
};

use super::Inspection;

impl Inspection {
    /// The listing: the space, the grid, the entities, `Init`, the storyboard and the notes.
    pub fn text(&self) -> String {
        let s = &self.scenario;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} (OpenSCENARIO {}.{})",
            s.file, s.version.0, s.version.1
        );
        if let Some(r) = &s.road_network {
            let _ = writeln!(out, "road network: {}", r.item);
        }
        self.write_parameters(&mut out);
        write_entities(s, &mut out);
        write_storyboard(s, &mut out);
        for n in &s.notes {
            let _ = writeln!(out, "note: {}: {}", n.pos, n.text);
        }
        for l in &self.limits {
            let _ = writeln!(out, "note: {l}");
        }
        out
    }

    /// Writes the parameters (declared, with the domains of the open ones, and those of the
    /// value-set distributions) and the file's own grid or stochastic distribution.
    fn write_parameters(&self, out: &mut String) {
        let s = &self.scenario;
        let _ = writeln!(out, "parameters ({} declared):", s.params.len());
        for (d, v) in &s.params {
            let open = self.space.iter().find(|p| p.name == d.name);
            let _ = writeln!(
                out,
                "  {} = {}{}",
                d.name,
                v.to_text(),
                open.map_or(String::new(), |p| format!("   -> {}", domain(&p.domain)))
            );
        }
        for p in self
            .space
            .iter()
            .filter(|p| p.name.starts_with("value_set_"))
        {
            let _ = writeln!(
                out,
                "  {} (a ValueSetDistribution)   -> {}",
                p.name,
                domain(&p.domain)
            );
        }
        match self.grid_runs {
            Some(n) => {
                let _ = writeln!(out, "the file's own grid: {n} runs");
            }
            None if self.variation.is_some() => {
                let _ = writeln!(out, "the file's distribution is stochastic");
            }
            None => {}
        }
    }
}

/// Writes the entities (kind, size in m, controller) and their `Init` actions.
fn write_entities(s: &Scenario, out: &mut String) {
    let _ = writeln!(out, "entities:");
    for e in &s.entities {
        let kind = match &e.kind {
            EntityKind::Vehicle(c) => format!("vehicle ({c})"),
            EntityKind::Pedestrian(c) => format!("pedestrian ({c})"),
            EntityKind::MiscObject(c) => format!("object ({c})"),
        };
        let [l, w, h] = e.dimensions_m;
        let _ = writeln!(
            out,
            "  {}: {kind}, {l} x {w} x {h} m{}",
            e.name,
            match e.controllers.len() {
                0 => String::new(),
                1 => format!(", controller {}", e.controllers[0]),
                _ => format!(", controllers {}", e.controllers.join(", ")),
            }
        );
    }
    let _ = writeln!(out, "init:");
    for (e, a) in &s.init {
        let _ = writeln!(out, "  {}: {}", s.entities[*e].name, action(s, &a.action));
    }
    for a in &s.init_global {
        let _ = writeln!(out, "  the world: {}", action(s, &a.action));
    }
}

/// Writes the storyboard: each story's acts and events with their start triggers and
/// actions, then the stop trigger.
fn write_storyboard(s: &Scenario, out: &mut String) {
    for story in &s.stories {
        let _ = writeln!(out, "story {}:", story.name);
        for act in &story.acts {
            // An empty trigger (`<StartTrigger/>`) is none: the act starts at once.
            let start = act
                .start
                .as_ref()
                .filter(|t| !t.0.is_empty())
                .map_or("at once".to_string(), |t| trigger(s, t));
            let _ = writeln!(out, "  act {} starts {start}", act.name);
            for g in &act.groups {
                let actors: Vec<&str> = g
                    .actors
                    .iter()
                    .map(|&a| s.entities[a].name.as_str())
                    .collect();
                for m in &g.maneuvers {
                    for e in &m.events {
                        let when = e
                            .start
                            .as_ref()
                            .filter(|t| !t.0.is_empty())
                            .map_or("with its act".to_string(), |t| trigger(s, t));
                        let _ = writeln!(
                            out,
                            "    event {} ({}) starts {when}:",
                            e.name,
                            actors.join(", ")
                        );
                        for a in &e.actions {
                            let _ = writeln!(out, "      {}: {}", a.name, action(s, &a.action));
                        }
                    }
                }
            }
        }
    }
    // An empty stop trigger never fires.
    if let Some(t) = s.stop.as_ref().filter(|t| !t.0.is_empty()) {
        let _ = writeln!(out, "stops {}", trigger(s, t));
    }
}

fn domain(d: &Domain) -> String {
    match d {
        Domain::Interval { lo, hi } => format!("interval [{lo}, {hi}]"),
        Domain::Levels(l) => {
            let t: Vec<String> = l
                .iter()
                .map(|v| match v {
                    Value::Int(i) => i.to_string(),
                    Value::Real(r) => r.to_string(),
                    Value::Bool(b) => b.to_string(),
                    Value::Text(s) => s.clone(),
                })
                .collect();
            format!("{} levels {{{}}}", l.len(), t.join(", "))
        }
    }
}

fn name(s: &Scenario, e: usize) -> &str {
    s.entities.get(e).map_or("?", |e| e.name.as_str())
}

/// One line for a position.
fn position(s: &Scenario, p: &Position) -> String {
    match p {
        Position::Route { waypoints, at, .. } => {
            let on = match at {
                paracosm_openscenario::model::InRoute::Entity(e) => {
                    format!("where {} is", name(s, *e))
                }
                paracosm_openscenario::model::InRoute::Lane { path_s, lane, .. } => {
                    format!("{path_s} m along, lane {lane}")
                }
                paracosm_openscenario::model::InRoute::Road { path_s, t } => {
                    format!("{path_s} m along, {t} m across")
                }
            };
            format!("on a route of {} waypoints, {on}", waypoints.len())
        }
        Position::World { x, y, h } => format!(
            "world ({x}, {y}){}",
            h.map_or(String::new(), |h| format!(" heading {h} rad"))
        ),
        Position::RelativeWorld { entity, dx, dy, .. } => {
            format!("{} + ({dx}, {dy}) m", name(s, *entity))
        }
        Position::RelativeObject { entity, dx, dy, .. } => {
            format!("{dx} m ahead, {dy} m left of {}", name(s, *entity))
        }
        Position::Road { road, s: st, t, .. } => format!("road {road} s {st} t {t}"),
        Position::Trajectory { s: st, t, .. } => format!("{st} m along a trajectory, {t} m left"),
        Position::Lane {
            road,
            lane,
            s: st,
            offset,
            ..
        } => format!("road {road} lane {lane} s {st} offset {offset}"),
        Position::RelativeRoad { entity, ds, dt, .. } => {
            format!(
                "{ds} m along, {dt} m across the road from {}",
                name(s, *entity)
            )
        }
        Position::RelativeLane {
            entity,
            d_lane,
            ds,
            offset,
            ..
        } => {
            format!(
                "{ds} m along, {d_lane} lanes left of {} (offset {offset})",
                name(s, *entity)
            )
        }
    }
}

/// A `FollowTrajectoryAction`'s trajectory `shape` as the listing says it.
fn trajectory(s: &Scenario, shape: &TrajectoryShape) -> String {
    match shape {
        TrajectoryShape::Polyline(vertices) => format!(
            "follow a polyline of {} vertices to {}",
            vertices.len(),
            vertices
                .last()
                .map_or(String::new(), |(_, p)| position(s, p))
        ),
        TrajectoryShape::Clothoid {
            start,
            curvature,
            curvature_prime,
            length,
            ..
        } => format!(
            "follow a clothoid of {length} m, curvature {curvature} 1/m changing by \
             {curvature_prime} 1/m2, from {}",
            start
                .as_ref()
                .map_or("where it is".to_owned(), |p| position(s, p))
        ),
        TrajectoryShape::ClothoidSpline {
            start, segments, ..
        } => spline(s, start, segments),
        TrajectoryShape::Nurbs { order, points, .. } => format!(
            "follow a NURBS of order {order} over {} control points to {}",
            points.len(),
            points
                .last()
                .map_or(String::new(), |(_, _, p)| position(s, p))
        ),
    }
}

/// A clothoid spline from `start` (where the entity is when none) as the listing says it.
fn spline(s: &Scenario, start: &Option<Position>, segments: &[[f64; 4]]) -> String {
    format!(
        "follow a clothoid spline of {} segments, {} m, from {}",
        segments.len(),
        segments.iter().map(|g| g[2]).sum::<f64>(),
        start
            .as_ref()
            .map_or("where it is".to_owned(), |p| position(s, p))
    )
}

/// A `SpeedProfileAction` as the listing says it.
fn speed_profile(s: &Scenario, p: &paracosm_openscenario::model::SpeedProfile) -> String {
    format!(
        "speed profile through {} ({}{})",
        p.entries
            .iter()
            .map(|(t, v)| match t {
                Some(t) => format!("{v} m/s after {t} s"),
                None => format!("{v} m/s"),
            })
            .collect::<Vec<_>>()
            .join(", "),
        if p.follow { "follow" } else { "position" },
        p.entity.map_or(String::new(), |r| format!(
            ", relative to {}'s speed",
            name(s, r)
        ))
    )
}

/// A `SynchronizeAction` as the listing says it.
fn synchronize(s: &Scenario, y: &paracosm_openscenario::model::Synchronize) -> String {
    format!(
        "arrive at {} when {} arrives at {}",
        position(s, &y.target),
        name(s, y.master),
        position(s, &y.master_target)
    )
}

/// One line for an action.
fn action(s: &Scenario, a: &Action) -> String {
    match a {
        Action::Speed { target, dynamics } => {
            let t = match target {
                SpeedTarget::Absolute(v) => format!("{v} m/s"),
                SpeedTarget::Relative {
                    entity,
                    value,
                    factor: true,
                    ..
                } => format!("{value} x {}'s speed", name(s, *entity)),
                SpeedTarget::Relative { entity, value, .. } => {
                    format!("{}'s speed + {value} m/s", name(s, *entity))
                }
            };
            format!(
                "speed to {t} ({:?} by {:?} {})",
                dynamics.shape, dynamics.dimension, dynamics.value
            )
        }
        Action::LaneChange {
            target, dynamics, ..
        } => {
            let t = match target {
                LaneTarget::Absolute(l) => format!("lane {l}"),
                LaneTarget::Relative { entity, lanes } => {
                    format!("{lanes} lanes left of {}'s", name(s, *entity))
                }
            };
            format!(
                "lane change to {t} ({:?} by {:?} {})",
                dynamics.shape, dynamics.dimension, dynamics.value
            )
        }
        Action::LaneOffset { target, .. } => match target {
            OffsetTarget::Absolute(v) => format!("lane offset to {v} m"),
            OffsetTarget::Relative { entity, value } => {
                format!("lane offset to {}'s + {value} m", name(s, *entity))
            }
        },
        Action::LongitudinalDistance {
            entity,
            distance_m,
            time_gap_s,
            ..
        } => match (distance_m, time_gap_s) {
            (Some(d), _) => format!("keep {d} m behind {}", name(s, *entity)),
            (_, Some(t)) => format!("keep {t} s behind {}", name(s, *entity)),
            _ => String::new(),
        },
        Action::LateralDistance {
            entity,
            distance_m,
            displacement,
            ..
        } => match distance_m {
            Some(d) => format!("keep {d} m beside {} ({displacement})", name(s, *entity)),
            None => format!("keep its distance beside {}", name(s, *entity)),
        },
        Action::Teleport(p) => format!("at {}", position(s, p)),
        Action::AcquirePosition(p) => format!("route to {}", position(s, p)),
        Action::Trailer(Some(k)) => format!("hitch {}", name(s, *k)),
        Action::Trailer(None) => "unhitch its trailer".to_string(),
        Action::Nothing => "nothing (an empty action)".to_string(),
        Action::TrafficSignalState { signal, state } => {
            format!("traffic signal {signal:?} to {state:?}")
        }
        Action::Synchronize(y) => synchronize(s, y),
        Action::SpeedProfile(p) => speed_profile(s, p),
        Action::FollowTrajectory { shape, .. } => trajectory(s, shape),
        Action::AssignRoute { waypoints } => format!(
            "route through {} waypoints to {}",
            waypoints.len(),
            waypoints
                .last()
                .map_or(String::new(), |(p, _)| position(s, p))
        ),
        Action::ActivateController { .. } => "the system under test takes over".into(),
        Action::AddEntity {
            entity,
            position: p,
        } => {
            format!("{} enters at {}", name(s, *entity), position(s, p))
        }
        Action::DeleteEntity { entity } => format!("{} leaves the scenario", name(s, *entity)),
        Action::AssignController { .. }
        | Action::OverrideController
        | Action::Environment(_)
        | Action::Appearance(_)
        | Action::Visibility { .. }
        | Action::SetValue { .. }
        | Action::ModifyValue { .. } => not_motion(a),
    }
}

/// One line for an action that moves no entity (a controller's assignment or override, the
/// environment, an entity's appearance or visibility, a parameter or variable).
fn not_motion(a: &Action) -> String {
    match a {
        Action::AssignController {
            controller, kind, ..
        } => format!(
            "assign controller {controller}{}{}",
            kind.as_ref().map_or(String::new(), |k| format!(" ({k})")),
            if a.hands_over() { ", active" } else { "" }
        ),
        Action::OverrideController => "override nothing (every value inactive)".into(),
        Action::Environment(e) => environment(e),
        Action::Appearance(what) => format!("{what} (not modelled)"),
        Action::Visibility {
            graphics,
            traffic,
            sensors,
        } => format!("visible: graphics {graphics}, traffic {traffic}, sensors {sensors}"),
        Action::SetValue { name, value, .. } => format!("{name} = {}", value.to_text()),
        Action::ModifyValue {
            name, multiply, by, ..
        } => format!("{name} {} {by}", if *multiply { "*=" } else { "+=" }),
        _ => String::new(),
    }
}

/// One line for an `EnvironmentAction`'s environment: the parts it gives.
fn environment(e: &paracosm_openscenario::model::Environment) -> String {
    let mut parts = Vec::new();
    if let Some((secs, animation)) = e.time_of_day {
        let running = if animation { ", running" } else { "" };
        parts.push(format!(
            "time of day {:02}:{:02}{running}",
            (secs / 3600.0) as u32,
            ((secs % 3600.0) / 60.0) as u32
        ));
    }
    if let Some((lux, elevation)) = e.sun {
        parts.push(format!("sun {lux} lx at {elevation} rad"));
    }
    if let Some(v) = e.fog_visual_range_m {
        parts.push(format!("fog, visual range {v} m"));
    }
    if let Some((kind, mm)) = &e.precipitation {
        parts.push(format!("{kind} {mm} mm/h"));
    }
    if let Some(f) = e.friction_scale {
        parts.push(format!("road friction x {f}"));
    }
    format!("environment: {}", parts.join(", "))
}

/// One line for a trigger: `when A and B, or C`.
fn trigger(s: &Scenario, t: &Trigger) -> String {
    let groups: Vec<String> =
        t.0.iter()
            .map(|g| {
                g.iter()
                    .map(|c| {
                        let delay = if c.delay_s > 0.0 {
                            format!(" (then {} s later)", c.delay_s)
                        } else {
                            String::new()
                        };
                        format!("{}{delay}", condition(s, &c.kind))
                    })
                    .collect::<Vec<_>>()
                    .join(" and ")
            })
            .collect();
    format!("when {}", groups.join(", or "))
}

fn condition(s: &Scenario, c: &ConditionKind) -> String {
    match c {
        ConditionKind::SimulationTime { rule, value } => format!("time {rule:?} {value} s"),
        ConditionKind::ElementState {
            element_type,
            element,
            state,
        } => format!("{element_type} {element} {state}"),
        ConditionKind::Parameter { name, rule, value } => format!("${name} {rule:?} {value}"),
        ConditionKind::TrafficSignal { signal, state } => {
            format!("traffic signal {signal:?} shows {state:?}")
        }
        ConditionKind::Variable { name, rule, value } => {
            format!("variable {name} {rule:?} {value}")
        }
        ConditionKind::Entity { entities, test, .. } => {
            let who: Vec<&str> = entities.iter().map(|&e| name(s, e)).collect();
            format!("{}: {}", who.join("/"), entity_test(s, test))
        }
    }
}

/// What an entity condition's `test` asks, in words.
fn entity_test(s: &Scenario, test: &EntityTest) -> String {
    match test {
        EntityTest::TimeHeadway(g) => format!(
            "headway to {} {:?} {} s",
            name(s, g.entity),
            g.rule,
            g.value
        ),
        EntityTest::TimeToCollision(g) => format!(
            "time to collision with {} {:?} {} s",
            name(s, g.entity),
            g.rule,
            g.value
        ),
        EntityTest::RelativeDistance(g) => format!(
            "{} distance to {} {:?} {} m",
            g.kind,
            name(s, g.entity),
            g.rule,
            g.value
        ),
        EntityTest::ReachPosition {
            position: p,
            tolerance,
        } => format!("within {tolerance} m of {}", position(s, p)),
        EntityTest::Distance(g) => format!(
            "{} distance{} to {} in {} coordinates {:?} {} m",
            g.kind,
            if g.freespace { " from its box" } else { "" },
            position(s, &g.position),
            g.frame,
            g.rule,
            g.value
        ),
        EntityTest::TimeToPosition(g) => format!(
            "time to {} {:?} {} s",
            position(s, &g.position),
            g.rule,
            g.value
        ),
        EntityTest::Speed { rule, value } => format!("speed {rule:?} {value} m/s"),
        EntityTest::RelativeSpeed {
            entity,
            rule,
            value,
        } => format!(
            "speed relative to {} {rule:?} {value} m/s",
            name(s, *entity)
        ),
        EntityTest::Acceleration { rule, value } => {
            format!("acceleration {rule:?} {value} m/s2")
        }
        EntityTest::Standstill(d) => format!("still for {d} s"),
        EntityTest::TraveledDistance(d) => format!("travelled {d} m"),
        EntityTest::EndOfRoad(d) => format!("past the road's end for {d} s"),
        EntityTest::Offroad(d) => format!("off the road for more than {d} s"),
        EntityTest::Collision(Some(e)) => format!("touches {}", name(s, *e)),
        EntityTest::Collision(None) => "touches anything".into(),
        EntityTest::CollisionByType(kind) => format!("touches any {kind}"),
        EntityTest::RelativeClearance(c) => format!(
            "clear of {} from {} m behind to {} m ahead in lanes {}{}",
            if c.entities.is_empty() {
                "every entity".to_owned()
            } else {
                c.entities
                    .iter()
                    .map(|&e| name(s, e))
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            c.backward_m,
            c.forward_m,
            if c.ranges.is_empty() {
                "any".to_owned()
            } else {
                c.ranges
                    .iter()
                    .map(|(a, b)| format!("{a}..{b}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            if c.opposite_lanes { ", either way" } else { "" }
        ),
        EntityTest::Angle(a) => format!(
            "heading in {} coordinates within {} rad of {} rad",
            a.frame, a.tolerance, a.angle
        ),
        EntityTest::RelativeAngle { entity, test: a } => format!(
            "heading less {}'s in {} coordinates within {} rad of {} rad",
            name(s, *entity),
            a.frame,
            a.tolerance,
            a.angle
        ),
    }
}
