//! How the world and the stream graph meet: probes (physics outputs as streams), sinks
//! (actions on actors), a graph builder, and the paper's pedestrian behaviour.

use crate::rx::{Func, Graph, Node, RxError, StreamId, Value};

/// An object whose outputs a probe reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Actor {
    /// The ego vehicle.
    Ego,
    /// Pedestrian `i`, in [`crate::WorldSpec::pedestrians`] order.
    Pedestrian(u32),
    /// NPC car `i`, in [`crate::WorldSpec::cars`] order.
    Car(u32),
}

/// What a probe reads from its actor, each step (paper §2: `rxout pos, vel, ...`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// Position `[x, y, z]` in metres (the ego's chassis centre, a pedestrian's feet, a car's
    /// ground point).
    Pos,
    /// Velocity `[x, y, z]` in m/s.
    Vel,
    /// Heading in rad.
    Heading,
    /// Speed in m/s (signed along the heading for the ego).
    Speed,
    /// Contact: `true` while the actor touches the ego vehicle (for the ego: touches any
    /// actor).
    Collision,
    /// `true` from the step the actor first touched anything solid (the ego, a car, a
    /// pedestrian, an obstacle) to the end of the test.
    Collided,
    /// The smallest distance from the actor's body to any other solid body (the ego, a car
    /// in the test, a pedestrian, an obstacle), m; `0` while touching, `inf` with nothing
    /// else in the world.
    Separation,
}

const OUTPUTS: [Output; 7] = [
    Output::Pos,
    Output::Vel,
    Output::Heading,
    Output::Speed,
    Output::Collision,
    Output::Collided,
    Output::Separation,
];

/// The probe number of `output` of `actor`, for [`Node::Probe`].
pub fn probe(actor: Actor, output: Output) -> u32 {
    let o = OUTPUTS.iter().position(|&x| x == output).expect("listed") as u32;
    let a = match actor {
        Actor::Ego => 0,
        Actor::Pedestrian(i) => 1 + 2 * i,
        Actor::Car(i) => 2 + 2 * i,
    };
    a * 8 + o
}

/// The inverse of [`probe`].
pub fn decode_probe(p: u32) -> (Actor, Output) {
    let (a, o) = (p / 8, p % 8);
    let actor = match a {
        0 => Actor::Ego,
        a if a % 2 == 1 => Actor::Pedestrian((a - 1) / 2),
        a => Actor::Car((a - 2) / 2),
    };
    (actor, OUTPUTS[(o as usize).min(OUTPUTS.len() - 1)])
}

/// What a `foreach` sink does with each event (paper §2: `foreach(walk)`). The event's value
/// is the action's argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Pedestrian `i` takes one walking step toward its target (the value is ignored).
    Walk(u32),
    /// Car `i` drives at the value, m/s (a number `>= 0`), from now on.
    SetSpeed(u32),
    /// Car `i` slows by the value times the step, m/s² (a number `> 0`), and keeps the
    /// lower speed.
    Brake(u32),
    /// Car `i` changes to the lane the value names (a lane number of its start segment, or a
    /// `(lane, duration_s)` tuple; 3 s by default).
    ChangeLane(u32),
}

const SINK_KIND_SHIFT: u32 = 24;

/// The sink number of `action`, for [`Node::Foreach`]; [`walk_sink`]`(i)` is `i`.
pub fn action_sink(action: Action) -> u32 {
    let (kind, i) = match action {
        Action::Walk(i) => (0, i),
        Action::SetSpeed(i) => (1, i),
        Action::Brake(i) => (2, i),
        Action::ChangeLane(i) => (3, i),
    };
    (kind << SINK_KIND_SHIFT) | (i & ((1 << SINK_KIND_SHIFT) - 1))
}

/// The inverse of [`action_sink`].
pub fn decode_sink(sink: u32) -> Action {
    let i = sink & ((1 << SINK_KIND_SHIFT) - 1);
    match sink >> SINK_KIND_SHIFT {
        1 => Action::SetSpeed(i),
        2 => Action::Brake(i),
        3 => Action::ChangeLane(i),
        _ => Action::Walk(i),
    }
}

/// The sink that makes pedestrian `i` take one walking step per event.
pub fn walk_sink(i: u32) -> u32 {
    action_sink(Action::Walk(i))
}

/// Collects nodes; each push returns the new stream's id.
#[derive(Debug, Clone, Default)]
pub struct GraphBuilder {
    nodes: Vec<Node>,
    sites: Vec<Option<String>>,
}

impl GraphBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        GraphBuilder::default()
    }

    /// Adds `node`.
    pub fn push(&mut self, node: Node) -> StreamId {
        self.nodes.push(node);
        self.sites.push(None);
        StreamId(self.nodes.len() - 1)
    }

    /// Adds `node` made at `site` (a program's `file:line:col`), which errors of the node
    /// name instead of `stream N` (see [`Graph::site`]).
    pub fn push_at(&mut self, node: Node, site: String) -> StreamId {
        let id = self.push(node);
        self.sites[id.0] = Some(site);
        id
    }

    /// Names `site` (a program's `file:line:col`) as where node `id` was made, as
    /// [`GraphBuilder::push_at`] does; an id past the graph is ignored.
    pub fn set_site(&mut self, id: StreamId, site: String) {
        if let Some(s) = self.sites.get_mut(id.0) {
            *s = Some(site);
        }
    }

    /// The nodes so far.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Where node `node` was made (`file:line:col`), when it was pushed with
    /// [`GraphBuilder::push_at`].
    pub fn site(&self, node: usize) -> Option<&str> {
        self.sites.get(node).and_then(Option::as_deref)
    }

    /// The checked graph.
    ///
    /// # Errors
    /// As [`Graph::new`].
    pub fn finish(self) -> Result<Graph, RxError> {
        Ok(Graph::new(self.nodes)?.with_sites(self.sites))
    }

    /// The paper's pedestrian behaviour (§2, "Reactive Behaviors") for pedestrian `index`:
    ///
    /// ```text
    /// trigger = car.zip(dist).filter(|car - start| < dist)   // planar distance, m
    /// done    = pos.filter(_ == target)
    /// tick.skipUntil(trigger).takeUntil(done).foreach(walk)
    /// ```
    ///
    /// `car` is a position stream (m), `dist` the trigger distance stream (m). The distance is
    /// measured in the ground plane (`x`, `z`), so the heights of a car's centre and a curb do
    /// not count. Returns the trigger stream.
    pub fn pedestrian(
        &mut self,
        index: u32,
        start: [f64; 3],
        target: [f64; 3],
        car: StreamId,
        dist: StreamId,
    ) -> StreamId {
        let pair = self.push(Node::Zip(car, dist));
        let trigger = self.push(Node::Filter {
            src: pair,
            pred: Func::native("|car - start| < dist", move |a| match &a[0] {
                Value::Tuple(p) => match (p[0].as_vec3(), p[1].as_num()) {
                    (Some(c), Some(d)) => {
                        Ok(Value::Bool((c[0] - start[0]).hypot(c[2] - start[2]) < d))
                    }
                    _ => Err("the car stream must carry positions and dist numbers".into()),
                },
                v => Err(format!(
                    "expected a (position, distance) pair, got a {}",
                    v.kind()
                )),
            }),
        });
        self.pedestrian_with_trigger(index, target, trigger);
        trigger
    }

    /// `tick.skipUntil(trigger).takeUntil(done).foreach(walk)` for pedestrian `index`, with
    /// any trigger stream (e.g. one a scenario computes with lambdas).
    pub fn pedestrian_with_trigger(&mut self, index: u32, target: [f64; 3], trigger: StreamId) {
        let pos = self.push(Node::Probe(probe(Actor::Pedestrian(index), Output::Pos)));
        let done = self.push(Node::Filter {
            src: pos,
            pred: Func::native("_ == target", move |a| {
                Ok(Value::Bool(a[0] == Value::Vec3(target)))
            }),
        });
        let tick = self.push(Node::Tick);
        let skip = self.push(Node::SkipUntil { src: tick, trigger });
        let take = self.push(Node::TakeUntil {
            src: skip,
            stop: done,
        });
        self.push(Node::Foreach {
            src: take,
            sink: walk_sink(index),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sinks_round_trip() {
        for a in [
            Action::Walk(0),
            Action::Walk(9),
            Action::SetSpeed(0),
            Action::Brake(3),
            Action::ChangeLane(12),
        ] {
            assert_eq!(decode_sink(action_sink(a)), a);
        }
        assert_eq!(walk_sink(4), 4);
    }

    #[test]
    fn probes_round_trip() {
        for actor in [
            Actor::Ego,
            Actor::Pedestrian(0),
            Actor::Pedestrian(7),
            Actor::Car(0),
            Actor::Car(3),
        ] {
            for output in OUTPUTS {
                assert_eq!(decode_probe(probe(actor, output)), (actor, output));
            }
        }
    }
}
