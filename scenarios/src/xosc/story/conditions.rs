//! The storyboard's conditions (OpenSCENARIO 1.3 User Guide, "Conditions and triggers"):
//! each trigger's condition groups evaluated with edges and delays, the entity and value
//! conditions, and the ego's measures (headway, gap, distance to its lane's edge).

use std::collections::HashMap;

use super::*;

#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct Cond {
    pub(in crate::xosc::story) cond: m::Condition,
    /// Its value at its last evaluation; `None` before its first (its first evaluation, at
    /// the start of the simulation or when its element first waits, is no edge: a rising
    /// edge needs the condition seen false before it is seen true, as in esmini's
    /// `OSCCondition::CheckEdge`).
    pub(in crate::xosc::story) prev: Option<bool>,
    /// With a delay, its values over the last `delay` seconds as runs of one value (a
    /// condition that keeps its value for a minute holds one run, not 3,600 steps' values).
    pub(in crate::xosc::story) history: VecDeque<Run>,
    /// The time up to which its delayed values have been taken (s; −∞ while none has).
    pub(in crate::xosc::story) taken: f64,
    /// What it reads, found once when the storyboard is built
    /// ([`Storyboard::resolve_references`]): the elements an element-state condition names,
    /// the parameter a parameter condition reads (none when nothing is declared by its name);
    /// empty for the other kinds.
    pub(in crate::xosc::story) refs: Vec<usize>,
    /// The storyboard's count of transitions when it was last evaluated: an element-state
    /// condition reads the transitions its elements made since ([`elements::Change`]).
    pub(in crate::xosc::story) seen: u64,
    /// Whether it has been true since its element began to wait, for a storyboard whose
    /// conditions latch ([`Storyboard::carla`]).
    pub(in crate::xosc::story) latched: bool,
}

/// A run of evaluations of a delayed condition that gave one value: the first and last
/// evaluation's times (s) and the value.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct Run {
    first: f64,
    last: f64,
    value: bool,
}

impl Cond {
    /// A condition `cond` not yet evaluated.
    pub(in crate::xosc::story) fn new(cond: m::Condition) -> Cond {
        Cond {
            cond,
            prev: None,
            history: VecDeque::new(),
            taken: f64::NEG_INFINITY,
            refs: Vec::new(),
            seen: 0,
            latched: false,
        }
    }

    /// Records `value`, this step's (at `t`, s), and gives the delayed value: whether any
    /// value recorded between the last step's cut and this step's (`t − delay`) was true,
    /// taking each recorded step once.
    fn delayed(&mut self, t: f64, value: bool) -> bool {
        match self.history.back_mut() {
            Some(run) if run.value == value => run.last = t,
            _ => self.history.push_back(Run {
                first: t,
                last: t,
                value,
            }),
        }
        let cut = t - self.cond.delay_s + 1e-9;
        let mut out = false;
        while let Some(&run) = self.history.front() {
            if run.first > cut {
                break;
            }
            // The run's steps after the last cut and up to this one.
            out |= run.value && run.last > self.taken;
            if run.last > cut {
                break;
            }
            self.history.pop_front();
        }
        self.taken = cut;
        out
    }

    /// Forgets its delayed values and its latch: its element no longer waits, and its delay
    /// starts afresh when it waits again.
    pub(in crate::xosc::story) fn forget_delay(&mut self) {
        self.latched = false;
        self.history.clear();
        self.taken = f64::NEG_INFINITY;
    }
}

impl Storyboard {
    pub(in crate::xosc::story) fn evaluate(&mut self, k: usize, t: f64) -> bool {
        let mut any = false;
        let latch = self.carla;
        for g in 0..self.triggers[k].len() {
            let mut all = true;
            for c in 0..self.triggers[k][g].len() {
                let raw = self.condition(&self.triggers[k][g][c], t);
                let seq = self.seq;
                let cond = &mut self.triggers[k][g][c];
                cond.seen = seq;
                let edged = match cond.cond.edge {
                    _ if latch => raw,
                    Edge::None => raw,
                    Edge::Rising => raw && cond.prev == Some(false),
                    Edge::Falling => !raw && cond.prev == Some(true),
                    Edge::RisingOrFalling => cond.prev.is_some_and(|p| p != raw),
                };
                cond.prev = Some(raw);
                // With a delay, the condition's value `delay` seconds ago.
                let value = if cond.cond.delay_s > 0.0 {
                    cond.delayed(t, edged)
                } else {
                    edged
                };
                cond.latched |= latch && value;
                all &= value || cond.latched;
            }
            any |= all;
        }
        any
    }

    /// Finds, once, what each condition reads by name ([`Cond::refs`]), so that a step's
    /// evaluation costs each condition what it names, not a search of the storyboard: a
    /// chain of 10,000 events each started by the one before is linear per step, not
    /// quadratic. An element is named as the storyboard check reads it (OpenSCENARIO 1.1+
    /// may qualify a name with its parents, `Event::Action`: the last part names it).
    pub(in crate::xosc::story) fn resolve_references(&mut self) {
        let mut elems: HashMap<(String, &str), Vec<usize>> = HashMap::new();
        for (i, e) in self.elems.iter().enumerate() {
            let key = (e.kind.name().to_ascii_lowercase(), e.name.as_str());
            elems.entry(key).or_default().push(i);
        }
        let mut params: HashMap<&str, usize> = HashMap::new();
        for (i, p) in self.params.iter().enumerate() {
            params.entry(p.name.as_str()).or_insert(i);
        }
        let mut variables: HashMap<&str, usize> = HashMap::new();
        for (i, v) in self.variables.iter().enumerate() {
            variables.entry(v.name.as_str()).or_insert(i);
        }
        let mut found: Vec<Vec<usize>> = Vec::new();
        for cond in self.triggers.iter().flatten().flatten() {
            found.push(match &cond.cond.kind {
                ConditionKind::ElementState {
                    element_type,
                    element,
                    ..
                } => {
                    let kind = element_type.to_ascii_lowercase();
                    let last = element.rsplit("::").next().unwrap_or(element);
                    let mut refs =
                        (elems.get(&(kind.clone(), element.as_str())).cloned()).unwrap_or_default();
                    if last != element {
                        refs.extend(elems.get(&(kind, last)).into_iter().flatten());
                    }
                    refs
                }
                ConditionKind::Parameter { name, .. } => {
                    params.get(name.as_str()).copied().into_iter().collect()
                }
                ConditionKind::Variable { name, .. } => {
                    variables.get(name.as_str()).copied().into_iter().collect()
                }
                _ => Vec::new(),
            });
        }
        for (cond, refs) in self.triggers.iter_mut().flatten().flatten().zip(found) {
            cond.refs = refs;
        }
    }

    pub(in crate::xosc::story) fn condition(&self, cond: &Cond, t: f64) -> bool {
        match &cond.cond.kind {
            ConditionKind::SimulationTime { rule, value } => rule.holds(t, *value),
            ConditionKind::ElementState { state, .. } => cond.refs.iter().any(|&i| {
                let e = &self.elems[i];
                // The transitions it made since this condition last read them, newest first.
                let since = e.changes.iter().rev().take_while(|c| c.seq >= cond.seen);
                let made = |what| since.clone().any(|c| c.what == what);
                let was = |phase| e.phase == phase || since.clone().any(|c| c.phase == phase);
                match state.as_str() {
                    "startTransition" => made(elements::Transition::Start),
                    "endTransition" => made(elements::Transition::End),
                    "stopTransition" => made(elements::Transition::Stop),
                    "skipTransition" => made(elements::Transition::Skip),
                    "completeState" => was(Phase::Complete),
                    "runningState" => was(Phase::Running),
                    "standbyState" => was(Phase::Standby),
                    _ => false,
                }
            }),
            ConditionKind::TrafficSignal { signal, state } => {
                self.signal_state(signal) == Some(state.as_str())
            }
            ConditionKind::Parameter { rule, value, .. }
            | ConditionKind::Variable { rule, value, .. } => {
                let store = if matches!(cond.cond.kind, ConditionKind::Variable { .. }) {
                    &self.variables
                } else {
                    &self.params
                };
                let Some(v) = cond.refs.first().map(|&i| &store[i].text) else {
                    return false;
                };
                match (v.trim().parse::<f64>(), value.trim().parse::<f64>()) {
                    (Ok(a), Ok(b)) => rule.holds(a, b),
                    _ => match rule {
                        Rule::Eq => v == value,
                        Rule::Ne => v != value,
                        _ => false,
                    },
                }
            }
            ConditionKind::Entity {
                entities,
                all,
                test,
            } => {
                // An entity out of the scenario is left out, as esmini's conditions skip an
                // inactive one; with none left the condition is false.
                let mut hits = entities
                    .iter()
                    .filter(|&&e| self.actors[e].present)
                    .map(|&e| self.entity_test(e, test))
                    .peekable();
                if hits.peek().is_none() {
                    false
                } else if *all {
                    hits.all(|h| h)
                } else {
                    hits.any(|h| h)
                }
            }
        }
    }

    pub(in crate::xosc::story) fn entity_test(&self, e: usize, test: &EntityTest) -> bool {
        let st = &self.actors[e].state;
        // A test against an entity out of the scenario is false (esmini: "inactive").
        if other_entity(test).is_some_and(|o| !self.actors[o].present) {
            return false;
        }
        match test {
            // Undefined (the reference behind, or the entity standing; not closing in) is
            // false whatever the rule, as esmini has it: an "infinite" headway must not
            // satisfy `greaterThan`.
            EntityTest::TimeHeadway(g) => {
                let d = self.measured_gap(e, g);
                d >= 0.0 && st.speed > 1e-9 && g.rule.holds(d / st.speed, g.value)
            }
            EntityTest::TimeToCollision(g) => {
                let (long, _, closing) = self.gap(e, g);
                long >= 0.0 && closing > 1e-9 && g.rule.holds(long / closing, g.value)
            }
            EntityTest::RelativeDistance(g) => g.rule.holds(self.measured_gap(e, g).abs(), g.value),
            EntityTest::Distance(g) => self
                .distance_to_position(e, &g.position, g.freespace, (&g.kind, &g.frame))
                .is_some_and(|d| g.rule.holds(d, g.value)),
            EntityTest::TimeToPosition(g) => self
                .distance_to_position(e, &g.position, g.freespace, (&g.kind, &g.frame))
                .filter(|d| d.abs() >= 1e-6 && st.speed.abs() >= 1e-6)
                .map(|d| d / st.speed)
                .is_some_and(|ttc| ttc >= 0.0 && g.rule.holds(ttc, g.value)),
            EntityTest::ReachPosition {
                position,
                tolerance,
            } => {
                let at = paracosm_openscenario::Pos {
                    file: String::new(),
                    line: 0,
                    col: 0,
                };
                self.resolve(position, &at)
                    .is_ok_and(|(p, _)| (p.x - st.pose.x).hypot(p.y - st.pose.y) <= *tolerance)
            }
            EntityTest::Speed { rule, value } => rule.holds(st.speed, *value),
            EntityTest::RelativeSpeed {
                entity,
                rule,
                value,
            } => rule.holds(st.speed - self.actors[*entity].state.speed, *value),
            EntityTest::Acceleration { rule, value } => rule.holds(st.accel, *value),
            EntityTest::Standstill(d) => st.still_s >= *d - 1e-9,
            EntityTest::TraveledDistance(d) => st.travelled_m >= *d,
            EntityTest::EndOfRoad(d) => st.at_end_s.is_some_and(|s| s >= *d - 1e-9),
            EntityTest::Offroad(d) => st.offroad_s.is_some_and(|s| s > *d + 1e-9),
            // Touching in the engine's world (a campaign's contacts), or bounding boxes that
            // overlap, as esmini's `Object::Collision` finds it (scripted entities the
            // engine does not collide, and the storyboard run alone).
            EntityTest::Collision(other) => match other {
                Some(o) => (st.collided && self.touching(e, *o)) || self.overlapping(e, *o),
                None => {
                    st.collided
                        || (0..self.actors.len())
                            .any(|o| o != e && self.actors[o].present && self.overlapping(e, o))
                }
            },
            EntityTest::CollisionByType(kind) => (0..self.actors.len()).any(|o| {
                o != e
                    && self.actors[o].present
                    && self.actors[o].object_type == kind
                    && ((st.collided && self.touching(e, o)) || self.overlapping(e, o))
            }),
            EntityTest::RelativeClearance(c) => self.clear(e, c),
            EntityTest::Angle(a) => self
                .heading_in(e, &a.frame)
                .is_some_and(|h| within_angle(h, a)),
            EntityTest::RelativeAngle { entity, test: a } => {
                // In the other entity's frame: the difference of the two world headings.
                let frame = if a.frame == "entity" {
                    "world"
                } else {
                    &a.frame
                };
                match (self.heading_in(e, frame), self.heading_in(*entity, frame)) {
                    (Some(h), Some(r)) => within_angle(h - r, a),
                    _ => false,
                }
            }
        }
    }

    /// Whether the lanes `c` names around entity `e` are clear (esmini's
    /// `TrigByRelativeClearance`): no other entity (of `c.entities`, or any) stands from
    /// `c.backward_m` behind to `c.forward_m` ahead along the road (between reference
    /// points, or boxes with `freespace`) in a lane whose `<lane id>` differs from `e`'s
    /// by a count in `c.ranges` (the centre lane skipped; one of the other direction only
    /// with `opposite_lanes`), and a driving lane exists at `e`'s station with an id that
    /// differs from `e`'s by such a count (of `e`'s side only without `opposite_lanes`).
    /// False when `e` is on no lane.
    fn clear(&self, e: usize, c: &paracosm_openscenario::model::Clearance) -> bool {
        let Some(la) = self.actors[e].state.lane else {
            return false;
        };
        let in_range =
            |d: i64| c.ranges.is_empty() || c.ranges.iter().any(|&(a, b)| (a..=b).contains(&d));
        let (ida, road) = self.roads.ids(la.lane);
        let max_m = c.forward_m.max(c.backward_m);
        // One gap, its entity set for each other entity in turn.
        let mut g = Gap {
            entity: e,
            rule: Rule::Lt,
            value: 0.0,
            freespace: c.freespace,
            frame: "road".into(),
            kind: "longitudinal".into(),
        };
        for o in 0..self.actors.len() {
            if o == e
                || !self.actors[o].present
                || (!c.entities.is_empty() && !c.entities.contains(&o))
            {
                continue;
            }
            let Some(lb) = self.actors[o].state.lane else {
                continue;
            };
            g.entity = o;
            let (ds, _, _) = self.road_gap(e, &g);
            if !ds.is_finite() || (!c.freespace && ds.abs() >= max_m) {
                continue;
            }
            if ds < -c.backward_m || ds > c.forward_m {
                continue;
            }
            let idb = self.roads.ids(lb.lane).0;
            let opposite = idb.signum() != ida.signum();
            let mut d = i64::from(idb) - i64::from(ida);
            if opposite {
                d = (d.abs() - 1) * d.signum();
            }
            if in_range(d) && (c.opposite_lanes || !opposite) {
                return false;
            }
        }
        // The lanes counted from e's own (by id, as esmini counts them) exist where it is.
        self.roads.driving_ids_at(road, la.s).any(|id| {
            let d = i64::from(id) - i64::from(ida);
            in_range(d) && (c.opposite_lanes || id.signum() == ida.signum())
        })
    }

    /// Entity `e`'s heading in `frame` (rad): `world` its heading; `entity` 0; `road` its
    /// heading less the direction of increasing `s` where it is; `lane` less its lane's
    /// direction of travel there (esmini's `TrigByAngle`). `None` off every lane in the
    /// road's and lane's frames.
    fn heading_in(&self, e: usize, frame: &str) -> Option<f64> {
        let st = &self.actors[e].state;
        match frame {
            "world" => Some(st.pose.h),
            "entity" => Some(0.0),
            _ => {
                let lp = LanePos {
                    rev: false,
                    ..st.lane?
                };
                let reference = if frame == "road" {
                    self.roads.along_heading(&lp)
                } else {
                    self.roads.travel_heading(&lp)
                };
                Some(st.pose.h - reference)
            }
        }
    }

    /// The longitudinal and lateral distances from entity `e` to `g`'s entity in `e`'s frame
    /// (m; between bounding boxes with `freespace`, between reference points otherwise) and
    /// the speed at which `e` closes in on it along its heading (m/s).
    pub(in crate::xosc::story) fn gap(&self, e: usize, g: &Gap) -> (f64, f64, f64) {
        if g.frame == "road" || g.frame == "lane" {
            return self.road_gap(e, g);
        }
        let (a, b) = (&self.actors[e], &self.actors[g.entity]);
        let h = a.state.pose.h;
        let (c, s) = (h.cos(), h.sin());
        let centre = |x: &Actor| {
            let p = x.state.pose;
            let (cc, ss) = (p.h.cos(), p.h.sin());
            (
                p.x + cc * x.centre_m[0] - ss * x.centre_m[1],
                p.y + ss * x.centre_m[0] + cc * x.centre_m[1],
            )
        };
        let (pa, pb) = if g.freespace {
            (centre(a), centre(b))
        } else {
            (
                (a.state.pose.x, a.state.pose.y),
                (b.state.pose.x, b.state.pose.y),
            )
        };
        let (dx, dy) = (pb.0 - pa.0, pb.1 - pa.1);
        let mut long = dx * c + dy * s;
        let mut lat = -dx * s + dy * c;
        if g.freespace {
            // Half the extent of each box along and across `e`'s heading.
            let rel = b.state.pose.h - h;
            let half_long_b = 0.5 * (b.size_m[0] * rel.cos().abs() + b.size_m[1] * rel.sin().abs());
            let half_lat_b = 0.5 * (b.size_m[0] * rel.sin().abs() + b.size_m[1] * rel.cos().abs());
            let shrink = |d: f64, half: f64| d.signum() * (d.abs() - half).max(0.0);
            long = shrink(long, a.size_m[0] / 2.0 + half_long_b);
            lat = shrink(lat, a.size_m[1] / 2.0 + half_lat_b);
        }
        let vb = b.state.speed * (b.state.pose.h - h).cos();
        let closing = if long >= 0.0 {
            a.state.speed - vb
        } else {
            vb - a.state.speed
        };
        (long, lat, closing)
    }

    /// The distance from entity `e` to the entity `g` names, m, as `g.kind` measures it (esmini's
    /// `Object::Distance`): along (`longitudinal`) or across (`lateral`) in `g.frame`; the
    /// euclidean distance in whatever frame (`euclidianDistance`, the default) is the straight
    /// distance between the reference points (between the boxes with `freespace`), negative
    /// when the other is not ahead along `e`'s heading (esmini's `getRelativeDistance`).
    fn measured_gap(&self, e: usize, g: &Gap) -> f64 {
        match g.kind.as_str() {
            "longitudinal" => self.gap(e, g).0,
            "lateral" => self.gap(e, g).1,
            _ => {
                let straight = Gap {
                    frame: "entity".into(),
                    ..g.clone()
                };
                let (long, lat, _) = self.gap(e, &straight);
                let sign = if long > 0.0 { 1.0 } else { -1.0 };
                sign * long.hypot(lat)
            }
        }
    }

    /// The distance from entity `e` to `position` where it is now, m, as a
    /// `DistanceCondition` measures it (`kind` and `frame`, from its box with `freespace`):
    /// in the entity's frame ([`Storyboard::distance_to_point`]) or along the roads
    /// ([`Storyboard::road_distance_to`]); `None` for a position that does not resolve.
    pub(in crate::xosc::story) fn distance_to_position(
        &self,
        e: usize,
        position: &Position,
        freespace: bool,
        (kind, frame): (&str, &str),
    ) -> Option<f64> {
        let at = paracosm_openscenario::Pos {
            file: String::new(),
            line: 0,
            col: 0,
        };
        let (p, lp) = self.resolve(position, &at).ok()?;
        Some(if frame == "entity" {
            self.distance_to_point(e, [p.x, p.y], freespace, kind)
        } else {
            self.road_distance_to(e, lp, freespace, kind)
        })
    }

    /// The distance from entity `e` to the point `p` (`[x, y]` m), as `kind` measures it in
    /// `e`'s frame (`longitudinal`, `lateral`, else euclidean): from its reference point, or
    /// with `freespace` from its bounding box (0 inside it). OpenSCENARIO `DistanceCondition`.
    pub(in crate::xosc::story) fn distance_to_point(
        &self,
        e: usize,
        p: [f64; 2],
        freespace: bool,
        kind: &str,
    ) -> f64 {
        let a = &self.actors[e];
        let pose = a.state.pose;
        let (c, s) = (pose.h.cos(), pose.h.sin());
        let (dx, dy) = (p[0] - pose.x, p[1] - pose.y);
        let (mut long, mut lat) = (dx * c + dy * s, -dx * s + dy * c);
        if freespace {
            long = ((long - a.centre_m[0]).abs() - a.size_m[0] / 2.0).max(0.0);
            lat = ((lat - a.centre_m[1]).abs() - a.size_m[1] / 2.0).max(0.0);
        }
        match kind {
            "longitudinal" => long.abs(),
            "lateral" => lat.abs(),
            _ => long.hypot(lat),
        }
    }

    /// As [`Storyboard::gap`], in road coordinates (`coordinateSystem="road"`, 1.0's
    /// `alongRoute`; `lane` along its lanes, the same stations): `e`'s longitudinal distance
    /// to the other entity is the roads' stations between them along the lanes, ahead in
    /// `e`'s direction of travel (over the lanes' successors into other roads, behind when
    /// the other entity leads to `e`), the lateral the difference of their `t` (left of `e`'s
    /// direction), each between reference points or, with `freespace`, between the boxes
    /// (half their lengths and widths off). NaN (every comparison false) when either entity
    /// is on no lane or no lanes lead from one to the other.
    fn road_gap(&self, e: usize, g: &Gap) -> (f64, f64, f64) {
        let (a, b) = (&self.actors[e], &self.actors[g.entity]);
        let nan = (f64::NAN, f64::NAN, f64::NAN);
        let (Some(la), Some(lb)) = (a.state.lane, b.state.lane) else {
            return nan;
        };
        let Some((mut long, mut lat)) = self.road_offsets(la, lb) else {
            return nan;
        };
        if g.freespace {
            // The gap between the boxes' extents in road coordinates, their corners each
            // taken to the road (esmini's `FreeSpaceDistanceObjectRoadLane`); on different
            // roads, the reference points' offsets less half the boxes.
            let road = self.roads.ids(la.lane).1;
            let dir = if la.along_s(&self.roads) { 1.0 } else { -1.0 };
            match (
                self.box_on_road(a, road, dir),
                self.box_on_road(b, road, dir),
            ) {
                (Some((sa, ta)), Some((sb, tb))) => {
                    let gap = |p: (f64, f64), q: (f64, f64)| {
                        if q.0 > p.1 {
                            q.0 - p.1
                        } else if p.0 > q.1 {
                            -(p.0 - q.1)
                        } else {
                            0.0
                        }
                    };
                    long = gap(sa, sb);
                    lat = gap(ta, tb);
                }
                _ => {
                    long += b.centre_m[0] - a.centre_m[0];
                    let shrink = |d: f64, half: f64| d.signum() * (d.abs() - half).max(0.0);
                    long = shrink(long, (a.size_m[0] + b.size_m[0]) / 2.0);
                    lat = shrink(lat, (a.size_m[1] + b.size_m[1]) / 2.0);
                }
            }
        }
        let vb = b.state.speed * (b.state.pose.h - a.state.pose.h).cos();
        let closing = if long >= 0.0 {
            a.state.speed - vb
        } else {
            vb - a.state.speed
        };
        (long, lat, closing)
    }

    /// The extent of entity `x`'s bounding box on road `road` (an index of the map's roads):
    /// the least and greatest station and `t` of its corners, each times `dir` (so that they
    /// grow in the direction of travel measured from); `None` when a corner is on no lane of
    /// that road.
    fn box_on_road(&self, x: &Actor, road: usize, dir: f64) -> Option<((f64, f64), (f64, f64))> {
        let p = x.state.pose;
        let key = (
            [p.x.to_bits(), p.y.to_bits(), p.h.to_bits(), dir.to_bits()],
            road,
            x.size_m.map(f64::to_bits),
            x.centre_m.map(f64::to_bits),
        );
        if let Some(b) = self.boxes.borrow().iter().find(|b| b.key == key) {
            return b.extent;
        }
        let extent = self.box_on_road_now(x, road, dir);
        let mut boxes = self.boxes.borrow_mut();
        if boxes.len() == BOXES_KEPT {
            boxes.remove(0);
        }
        boxes.push(BoxOnRoad { key, extent });
        extent
    }

    /// [`Storyboard::box_on_road`], computed.
    fn box_on_road_now(
        &self,
        x: &Actor,
        road: usize,
        dir: f64,
    ) -> Option<((f64, f64), (f64, f64))> {
        let p = x.state.pose;
        let (c, s) = (p.h.cos(), p.h.sin());
        let (mut sr, mut tr) = (
            (f64::INFINITY, f64::NEG_INFINITY),
            (f64::INFINITY, f64::NEG_INFINITY),
        );
        for (u, v) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            let lx = x.centre_m[0] + u * x.size_m[0] / 2.0;
            let ly = x.centre_m[1] + v * x.size_m[1] / 2.0;
            let (cx, cy) = (p.x + c * lx - s * ly, p.y + s * lx + c * ly);
            let lp = self.roads.anchor(cx, cy)?;
            if self.roads.ids(lp.lane).1 != road {
                return None;
            }
            let t = self.roads.t_of(&lp).ok()?;
            let (sv, tv) = (lp.s * dir, t * dir);
            sr = (sr.0.min(sv), sr.1.max(sv));
            tr = (tr.0.min(tv), tr.1.max(tv));
        }
        Some((sr, tr))
    }

    /// Where lane position `lb` is from `la` in road coordinates: the roads' stations
    /// between them along the lanes (ahead in `la`'s direction of travel positive) and the
    /// difference of their `t` (left of that direction positive); `None` when no lanes lead
    /// from one to the other.
    pub(in crate::xosc::story) fn road_offsets(
        &self,
        la: LanePos,
        lb: LanePos,
    ) -> Option<(f64, f64)> {
        let (Ok(ta), Ok(tb)) = (self.roads.t_of(&la), self.roads.t_of(&lb)) else {
            return None;
        };
        let dir = if la.along_s(&self.roads) { 1.0 } else { -1.0 };
        let ahead = LanePos { d: 0.0, ..la };
        let b0 = LanePos { d: 0.0, ..lb };
        // The shortest way over the lanes, either way round: `b` ahead of `e`, or `e` ahead
        // of `b` (then `b` is behind, the distance negative).
        let shortest = |from: LanePos, to: LanePos, flip_from: bool| {
            [false, true]
                .into_iter()
                .flat_map(|r1| [false, true].map(|r2| (r1, r2)))
                .filter(|(r1, _)| flip_from || !*r1)
                .filter_map(|(r1, r2)| {
                    let f = LanePos {
                        rev: from.rev != r1,
                        ..from
                    };
                    let t = LanePos { rev: r2, ..to };
                    self.roads.route_between(&f, &t).map(|(_, d)| d)
                })
                .filter(|d| *d >= 0.0)
                .fold(f64::INFINITY, f64::min)
        };
        let long = if self.roads.ids(la.lane).1 == self.roads.ids(lb.lane).1 {
            (lb.s - la.s) * dir
        } else {
            let fwd = shortest(ahead, b0, false);
            let bwd = shortest(b0, ahead, true);
            match (fwd.is_finite(), bwd.is_finite()) {
                (false, false) => return None,
                _ if fwd <= bwd => fwd,
                _ => -bwd,
            }
        };
        Some((long, (tb - ta) * dir))
    }

    /// A `DistanceCondition`'s distance in road coordinates from entity `e` to lane position
    /// `to` ([`Storyboard::road_offsets`]; with `freespace`, from its bounding box); NaN
    /// when either is on no lane or no lanes lead between them.
    fn road_distance_to(&self, e: usize, to: Option<LanePos>, freespace: bool, kind: &str) -> f64 {
        let a = &self.actors[e];
        let (Some(la), Some(lb)) = (a.state.lane, to) else {
            return f64::NAN;
        };
        let Some((mut long, mut lat)) = self.road_offsets(la, lb) else {
            return f64::NAN;
        };
        if freespace {
            long = ((long - a.centre_m[0]).abs() - a.size_m[0] / 2.0).max(0.0);
            lat = ((lat - a.centre_m[1]).abs() - a.size_m[1] / 2.0).max(0.0);
        }
        match kind {
            "longitudinal" => long.abs(),
            "lateral" => lat.abs(),
            _ => long.hypot(lat),
        }
    }

    /// Whether the bounding boxes of `a` and `b` touch (within 5 cm).
    pub(in crate::xosc::story) fn touching(&self, a: usize, b: usize) -> bool {
        let g = Gap {
            entity: b,
            rule: Rule::Lt,
            value: 0.0,
            freespace: true,
            frame: "entity".into(),
            kind: "euclidianDistance".into(),
        };
        let (long, lat, _) = self.gap(a, &g);
        long.abs() <= 0.05 && lat.abs() <= 0.05
    }

    /// Whether the bounding boxes of entities `a` and `b` overlap seen from above (esmini's
    /// `Object::Collision`: [`paracosm_engine::placement::boxes_overlap`]). A tow and the
    /// trailer hitched to it never do: coupled, their boxes overlap at the hitch, and the
    /// engine does not collide them either (esmini would find them colliding).
    pub(in crate::xosc::story) fn overlapping(&self, a: usize, b: usize) -> bool {
        if self.actors[a].trailer == Some(b) || self.actors[b].trailer == Some(a) {
            return false;
        }
        let ground = |i: usize| {
            let x = &self.actors[i];
            let p = x.state.pose;
            let (s, c) = p.h.sin_cos();
            (
                [
                    p.x + c * x.centre_m[0] - s * x.centre_m[1],
                    p.y + s * x.centre_m[0] + c * x.centre_m[1],
                ],
                p.h,
                [x.size_m[0], x.size_m[1]],
            )
        };
        paracosm_engine::placement::boxes_overlap(ground(a), ground(b))
    }

    /// The R157-style measures of entity `e`: its time headway (s) and following distance (m,
    /// between bounding boxes) to the nearest entity ahead of it in its lane (within the two
    /// half-widths sideways), `inf` with none; and the distance from its box's side to its
    /// lane's nearer edge (m, negative once over it; `nan` off every lane).
    pub fn measures(&self, e: usize) -> (f64, f64, f64) {
        let a = &self.actors[e];
        let mut gap_m = f64::INFINITY;
        for (j, b) in self.actors.iter().enumerate() {
            if j == e || !b.present {
                continue;
            }
            let g = Gap {
                entity: j,
                rule: Rule::Lt,
                value: 0.0,
                freespace: true,
                frame: "entity".into(),
                kind: "longitudinal".into(),
            };
            let (long, lat, _) = self.gap(e, &g);
            if long >= 0.0 && lat == 0.0 {
                gap_m = gap_m.min(long);
            }
        }
        let headway_s = if a.state.speed > 1e-9 {
            gap_m / a.state.speed
        } else {
            f64::INFINITY
        };
        let edge_m = match a.state.lane {
            Some(lp) => {
                let w = self.roads.lane_width(lp.lane, lp.s);
                w / 2.0 - lp.d.abs() - a.size_m[1] / 2.0
            }
            None => f64::NAN,
        };
        (headway_s, gap_m, edge_m)
    }
}

/// The other entity a test measures against, if it names one.
fn other_entity(test: &EntityTest) -> Option<usize> {
    match test {
        EntityTest::TimeHeadway(g)
        | EntityTest::TimeToCollision(g)
        | EntityTest::RelativeDistance(g) => Some(g.entity),
        EntityTest::RelativeSpeed { entity, .. } | EntityTest::RelativeAngle { entity, .. } => {
            Some(*entity)
        }
        EntityTest::Collision(other) => *other,
        _ => None,
    }
}

/// Whether heading `h` (rad) lies within `a.tolerance` of `a.angle`: their difference taken
/// into `[0, π]`, below the tolerance plus 1e-6 rad (esmini's `GetAbsAngleDifference` and
/// `SMALL_NUMBER`).
fn within_angle(h: f64, a: &paracosm_openscenario::model::AngleTest) -> bool {
    paracosm_engine::network::roads::wrap(h - a.angle).abs() < a.tolerance + 1e-6
}

/// How many box extents [`Storyboard::box_on_road`] keeps: the boxes of a step's entities.
const BOXES_KEPT: usize = 16;

/// The extent on a road of an entity's box at one pose ([`Storyboard::box_on_road`]): the
/// key is the pose's and the direction's bits, the road, and the box's size and centre.
#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct BoxOnRoad {
    key: ([u64; 4], usize, [u64; 3], [u64; 3]),
    extent: Option<((f64, f64), (f64, f64))>,
}
