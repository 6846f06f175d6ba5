//! Each combinator pinned on hand-made streams.

use super::*;
use crate::actor::{Handle, Roster};
use crate::behaviour::{Action, ActorRef, Output, Probe};
use crate::PedestrianSpec;

/// The handle of the `i`-th pedestrian: these tests number their probes and sinks by it.
fn handle(i: usize) -> Handle<PedestrianSpec> {
    let mut roster = Roster::default();
    (0..=i).map(|_| roster.add()).last().expect("at least one")
}

/// Probe number `i`: the position of pedestrian `i`, which the script answers.
fn probe(i: usize) -> Node {
    Node::Probe(Probe::new(ActorRef::Pedestrian(handle(i)), Output::Pos))
}

/// Sink number `i`: pedestrian `i` walks.
fn sink(i: usize) -> Action {
    Action::Walk(handle(i))
}

/// The number of a test probe.
fn number(probe: Probe) -> usize {
    match probe.actor {
        ActorRef::Pedestrian(h) => h.index(),
        other => panic!("no scripted probe {other:?}"),
    }
}

/// Probe `p` at step `k` is `script[p][k]`; steps are 1 s apart, starting at `t = 0`.
struct Script(Vec<Vec<Value>>);

impl Inputs for Script {
    fn probe(&self, probe: Probe) -> Value {
        self.0[number(probe)][STEP.with(|s| s.get())].clone()
    }
}

thread_local! {
    static STEP: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Runs `nodes` for `steps` steps and returns what the last node emitted at each step (`None`
/// when it did not fire), plus the sink events.
fn run(
    nodes: Vec<Node>,
    script: Vec<Vec<Value>>,
    steps: usize,
) -> (Vec<Option<Value>>, Vec<(Action, Value)>) {
    let last = StreamId(nodes.len() - 1);
    let mut rt = Runtime::new(Graph::new(nodes).unwrap());
    let inputs = Script(script);
    let mut sinks = Vec::new();
    let mut out = Vec::new();
    for k in 0..steps {
        STEP.with(|s| s.set(k));
        rt.step(k as f64, &inputs, &mut NoHost, &mut sinks).unwrap();
        out.push(rt.fired(last).then(|| rt.current(last).unwrap().clone()));
    }
    (out, sinks)
}

fn nums(xs: &[f64]) -> Vec<Value> {
    xs.iter().map(|&x| Value::Num(x)).collect()
}

fn n(x: f64) -> Option<Value> {
    Some(Value::Num(x))
}

/// `probe(0) > 0`: a stream that fires only where the script is positive.
fn positive(src: usize) -> Node {
    Node::Filter {
        src: StreamId(src),
        pred: Func::native("> 0", |a| Ok(Value::Bool(a[0].as_num().unwrap() > 0.0))),
    }
}

#[test]
fn const_and_tick_fire_every_step() {
    let (out, _) = run(vec![Node::Const(Value::Num(4.0))], vec![], 3);
    assert_eq!(out, vec![n(4.0), n(4.0), n(4.0)]);
    let (out, _) = run(vec![Node::Tick], vec![], 3);
    assert_eq!(out, vec![n(0.0), n(1.0), n(2.0)]);
}

#[test]
fn map_applies_the_function_to_each_event() {
    let nodes = vec![
        Node::Tick,
        Node::Map {
            src: StreamId(0),
            f: Func::native("double", |a| Ok(Value::Num(2.0 * a[0].as_num().unwrap()))),
        },
    ];
    assert_eq!(run(nodes, vec![], 3).0, vec![n(0.0), n(2.0), n(4.0)]);
}

#[test]
fn filter_passes_only_events_that_satisfy_the_predicate() {
    let nodes = vec![probe(0), positive(0)];
    let script = vec![nums(&[1.0, -1.0, 0.0, 3.0])];
    assert_eq!(run(nodes, script, 4).0, vec![n(1.0), None, None, n(3.0)]);
}

#[test]
fn take_passes_the_first_n_events_then_completes() {
    let nodes = vec![
        probe(0),
        positive(0),
        Node::Take {
            src: StreamId(1),
            n: 2,
        },
    ];
    let script = vec![nums(&[-1.0, 5.0, -2.0, 6.0, 7.0])];
    assert_eq!(
        run(nodes, script, 5).0,
        vec![None, n(5.0), None, n(6.0), None]
    );
}

#[test]
fn skip_until_opens_at_the_first_trigger_inclusive_and_stays_open() {
    let nodes = vec![
        Node::Tick,
        probe(0),
        positive(1),
        Node::SkipUntil {
            src: StreamId(0),
            trigger: StreamId(2),
        },
    ];
    let script = vec![nums(&[0.0, 0.0, 1.0, 0.0, 0.0])];
    assert_eq!(
        run(nodes, script, 5).0,
        vec![None, None, n(2.0), n(3.0), n(4.0)]
    );
}

#[test]
fn take_until_closes_at_the_first_stop_exclusive_and_completes() {
    let nodes = vec![
        Node::Tick,
        probe(0),
        positive(1),
        Node::TakeUntil {
            src: StreamId(0),
            stop: StreamId(2),
        },
    ];
    let script = vec![nums(&[0.0, 0.0, 1.0, 0.0, 0.0])];
    assert_eq!(
        run(nodes, script, 5).0,
        vec![n(0.0), n(1.0), None, None, None]
    );
}

#[test]
fn zip_pairs_the_ith_events_of_both_sides() {
    let nodes = vec![
        Node::Tick,
        probe(0),
        positive(1),
        Node::Zip(StreamId(0), StreamId(2)),
    ];
    // The right side fires at steps 1 and 3 only: pairs (t0, 5), (t1, 7).
    let script = vec![nums(&[0.0, 5.0, 0.0, 7.0])];
    let pair = |a: f64, b: f64| Some(Value::Tuple(vec![Value::Num(a), Value::Num(b)]));
    assert_eq!(
        run(nodes, script, 4).0,
        vec![None, pair(0.0, 5.0), None, pair(1.0, 7.0)]
    );
}

#[test]
fn concat_emits_the_first_stream_then_the_second() {
    // tick.take(2).concat(probe): 0, 1, then the probe from the step `take` completed in.
    let nodes = vec![
        Node::Tick,
        Node::Take {
            src: StreamId(0),
            n: 2,
        },
        probe(0),
        Node::Concat(StreamId(1), StreamId(2)),
    ];
    let script = vec![nums(&[10.0, 11.0, 12.0, 13.0])];
    assert_eq!(
        run(nodes, script, 4).0,
        vec![n(0.0), n(1.0), n(11.0), n(12.0)]
    );
}

#[test]
fn sum_is_a_running_total_and_a_fold_with_a_function() {
    let nodes = vec![
        probe(0),
        positive(0),
        Node::Sum {
            src: StreamId(1),
            init: Value::Num(0.0),
            f: None,
        },
    ];
    let script = vec![nums(&[1.0, -5.0, 2.0, 3.0])];
    assert_eq!(
        run(nodes, script.clone(), 4).0,
        vec![n(1.0), None, n(3.0), n(6.0)]
    );
    let nodes = vec![
        probe(0),
        Node::Sum {
            src: StreamId(0),
            init: Value::Num(1.0),
            f: Some(Func::native("max", |a| {
                Ok(Value::Num(
                    a[0].as_num().unwrap().max(a[1].as_num().unwrap()),
                ))
            })),
        },
    ];
    assert_eq!(
        run(nodes, script, 4).0,
        vec![n(1.0), n(1.0), n(2.0), n(3.0)]
    );
}

#[test]
fn foreach_hands_each_event_to_its_sink() {
    let nodes = vec![
        probe(0),
        positive(0),
        Node::Foreach {
            src: StreamId(1),
            sink: sink(7),
        },
    ];
    let script = vec![nums(&[1.0, -1.0, 2.0])];
    let (out, sinks) = run(nodes, script, 3);
    assert_eq!(out, vec![None, None, None], "a sink emits nothing");
    assert_eq!(
        sinks,
        vec![(sink(7), Value::Num(1.0)), (sink(7), Value::Num(2.0))]
    );
}

/// The paper's pedestrian (§2, "Reactive Behaviors"):
/// `tick.skipUntil(trigger).takeUntil(done).foreach(walk)` walks from the step the car comes
/// close until the step the target is reached, exclusive.
#[test]
fn the_papers_pedestrian_walks_between_trigger_and_done() {
    // probe 0: car distance; probe 1: pedestrian at target (1) or not (0).
    let nodes = vec![
        Node::Tick,
        probe(0),
        Node::Filter {
            src: StreamId(1),
            pred: Func::native("< 30", |a| Ok(Value::Bool(a[0].as_num().unwrap() < 30.0))),
        },
        probe(1),
        positive(3),
        Node::SkipUntil {
            src: StreamId(0),
            trigger: StreamId(2),
        },
        Node::TakeUntil {
            src: StreamId(5),
            stop: StreamId(4),
        },
        Node::Foreach {
            src: StreamId(6),
            sink: sink(0),
        },
    ];
    let script = vec![
        nums(&[50.0, 40.0, 29.0, 35.0, 20.0, 10.0]),
        nums(&[0.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
    ];
    let (_, sinks) = run(nodes, script, 6);
    let walked: Vec<f64> = sinks.iter().map(|(_, v)| v.as_num().unwrap()).collect();
    // Triggered at t = 2 (stays triggered when the car is 35 m away at t = 3), done at t = 4.
    assert_eq!(walked, vec![2.0, 3.0]);
}

/// The paper's `DistanceMonitor`: `pOld = pos.take(1).concat(pos)`,
/// `D = pos.zip(pOld).map(|_ - _|).sum()` is the distance travelled.
#[test]
fn the_papers_distance_monitor_sums_step_lengths() {
    let norm = Func::native("|a - b|", |a| match &a[0] {
        Value::Tuple(p) => {
            let (x, y) = (p[0].as_vec3().unwrap(), p[1].as_vec3().unwrap());
            Ok(Value::Num(
                (0..3).map(|i| (x[i] - y[i]).powi(2)).sum::<f64>().sqrt(),
            ))
        }
        v => Err(NativeError(format!("got {v:?}"))),
    });
    let nodes = vec![
        probe(0),
        Node::Take {
            src: StreamId(0),
            n: 1,
        },
        Node::Concat(StreamId(1), StreamId(0)),
        Node::Zip(StreamId(0), StreamId(2)),
        Node::Map {
            src: StreamId(3),
            f: norm,
        },
        Node::Sum {
            src: StreamId(4),
            init: Value::Num(0.0),
            f: None,
        },
    ];
    let path = [
        [0.0, 0.0, 0.0],
        [3.0, 0.0, 4.0],
        [3.0, 0.0, 5.0],
        [3.0, 0.0, 5.0],
    ];
    let script = vec![path.iter().map(|&p| Value::Vec3(p)).collect()];
    let (out, _) = run(nodes, script, 4);
    assert_eq!(out, vec![n(0.0), n(5.0), n(6.0), n(6.0)]);
}

#[test]
fn cycles_and_dangling_references_are_errors() {
    let cyc = vec![
        Node::Map {
            src: StreamId(1),
            f: Func::Host(0),
        },
        Node::Map {
            src: StreamId(0),
            f: Func::Host(0),
        },
    ];
    assert_eq!(Graph::new(cyc).unwrap_err(), RxError::Cycle(0));
    let dangling = vec![Node::Zip(StreamId(0), StreamId(9))];
    assert!(matches!(
        Graph::new(dangling).unwrap_err(),
        RxError::Dangling {
            node: 0,
            missing: 9
        }
    ));
}

#[test]
fn topological_order_lets_a_node_read_a_later_index() {
    let nodes = vec![
        Node::Map {
            src: StreamId(1),
            f: Func::native("neg", |a| Ok(Value::Num(-a[0].as_num().unwrap()))),
        },
        Node::Tick,
    ];
    let g = Graph::new(nodes).unwrap();
    assert_eq!(g.order(), &[1, 0]);
    let mut rt = Runtime::new(g);
    rt.step(3.0, &Script(vec![]), &mut NoHost, &mut Vec::new())
        .unwrap();
    assert_eq!(rt.current(StreamId(0)), Some(&Value::Num(-3.0)));
}

#[test]
fn open_streams_bind_and_vary_over_time() {
    let g = Graph::new(vec![Node::Param(0)]).unwrap();
    let piecewise = OpenStream::Piecewise {
        values: vec![0.1, 0.5, 0.9],
        horizon_s: 3.0,
    };
    let (mut rt, mut sinks) = (Runtime::new(g.bind(&[piecewise]).unwrap()), Vec::new());
    let mut seen = vec![];
    for t in [0.0, 0.99, 1.0, 2.5, 7.0] {
        rt.step(t, &Script(vec![]), &mut NoHost, &mut sinks)
            .unwrap();
        seen.push(rt.current(StreamId(0)).unwrap().as_num().unwrap());
    }
    assert_eq!(seen, vec![0.1, 0.1, 0.5, 0.9, 0.9]);
    // A rising linear fog: Bernstein coefficients (0, 1) give s = t / T.
    let fog = OpenStream::Polynomial {
        coefficients: vec![0.0, 1.0],
        horizon_s: 10.0,
    };
    assert_eq!(fog.at(2.5), Value::Num(0.25));
    // Degree 2 with coefficients in [0, 1] stays in [0, 1].
    let bump = OpenStream::Polynomial {
        coefficients: vec![0.0, 1.0, 0.0],
        horizon_s: 1.0,
    };
    assert_eq!(bump.at(0.5), Value::Num(0.5));
    assert!(Runtime::new(g)
        .step(0.0, &Script(vec![]), &mut NoHost, &mut sinks)
        .is_err());
}

/// Counts the probes it answers (every probe reads 1.0).
struct Counting(std::cell::Cell<usize>);

impl Inputs for Counting {
    fn probe(&self, _: Probe) -> Value {
        self.0.set(self.0.get() + 1);
        Value::Num(1.0)
    }
}

/// A host whose function 0 fails once `t >= 2` and which reads stream `reads` (as a lambda
/// reads a module-level stream).
struct Reading {
    reads: Vec<StreamId>,
    seen: Vec<Option<Value>>,
}

impl Host for Reading {
    fn call(&mut self, _: u32, args: &[Value], streams: &Runtime) -> Result<Value, HostError> {
        for id in &self.reads {
            self.seen.push(streams.current(*id).cloned());
        }
        match args[0].as_num() {
            Some(t) if t >= 2.0 => Err(HostError(format!("failed at {t}"))),
            _ => Ok(Value::Num(0.0)),
        }
    }
    fn reads(&self) -> &[StreamId] {
        &self.reads
    }
}

#[test]
fn streams_nothing_reads_are_not_evaluated_and_change_nothing_else() {
    // 0, 1: probes nobody reads; 2: a probe the caller reads; 3: a zip of the unread ones;
    // 4: a probe feeding a sink; 5: the sink.
    let nodes = vec![
        probe(0),
        probe(1),
        probe(2),
        Node::Zip(StreamId(0), StreamId(1)),
        probe(3),
        Node::Foreach {
            src: StreamId(4),
            sink: sink(9),
        },
    ];
    let graph = Graph::new(nodes).unwrap();
    let inputs = Counting(std::cell::Cell::new(0));
    let (mut all, mut some) = (Runtime::new(graph.clone()), Runtime::new(graph));
    some.evaluate_only([StreamId(2)]);
    let (mut sinks_all, mut sinks_some) = (Vec::new(), Vec::new());
    for k in 0..3 {
        all.step(k as f64, &inputs, &mut NoHost, &mut sinks_all)
            .unwrap();
    }
    assert_eq!(inputs.0.replace(0), 12, "four probes a step");
    for k in 0..3 {
        some.step(k as f64, &inputs, &mut NoHost, &mut sinks_some)
            .unwrap();
    }
    assert_eq!(
        inputs.0.get(),
        6,
        "the read probe and the sink's, each step"
    );
    assert_eq!(sinks_all, sinks_some);
    assert_eq!(all.current(StreamId(2)), some.current(StreamId(2)));
    assert!(all.current(StreamId(3)).is_some());
    assert_eq!(some.current(StreamId(3)), None, "never evaluated");
}

#[test]
fn a_function_whose_stream_nobody_reads_still_runs_and_fails() {
    // 0: tick; 1: a host function of it, read by nobody: its error must end the run. 2: a
    // probe that only the host's function reads; it must hold its value when called.
    let nodes = vec![
        Node::Tick,
        Node::Map {
            src: StreamId(0),
            f: Func::Host(0),
        },
        probe(0),
    ];
    let mut rt = Runtime::new(Graph::new(nodes).unwrap());
    rt.evaluate_only([]);
    let inputs = Counting(std::cell::Cell::new(0));
    let mut host = Reading {
        reads: vec![StreamId(2)],
        seen: Vec::new(),
    };
    let mut sinks = Vec::new();
    rt.step(0.0, &inputs, &mut host, &mut sinks).unwrap();
    rt.step(1.0, &inputs, &mut host, &mut sinks).unwrap();
    // The probe comes after the function in the graph: the first call sees no value yet,
    // the second sees the first step's.
    assert_eq!(host.seen, vec![None, Some(Value::Num(1.0))]);
    let e = rt.step(2.0, &inputs, &mut host, &mut sinks).unwrap_err();
    assert!(e.to_string().contains("failed at 2"), "{e}");
}
