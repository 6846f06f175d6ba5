#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! The global builtins of the scenario language (LANGUAGE.md documents each).

use std::cell::RefCell;

use anyhow::{anyhow, bail};
use paracosm_engine::behaviour::{Actor, Output};
use paracosm_engine::network::PieceKind;
use paracosm_engine::rx::{Node, StreamId, Value as Rx};
use paracosm_engine::sut::{AebConfig, SutConfig};
use paracosm_engine::NOMINAL_LIGHT;
use paracosm_generators::{Domain, Value as Level};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::list::UnpackList;
use starlark::values::none::NoneType;
use starlark::values::{ProvidesStaticType, UnpackValue, Value, ValueLike};

use super::scene::{turns, ObjectDecl, OverTime, ParamDecl, PedTrigger, Pending, SceneBuilder};
use super::types;
use super::values::{
    ActorKind, ActorVal, ChangeStart, LaneChangeVal, LaneSide, Loc, MonitorVal, ObstacleVal,
    OverTimeVal, Road, Stream, WorldVal,
};
use crate::MonitorSpec;

/// The state a program's builtins write into, reached through `Evaluator::extra`.
#[derive(ProvidesStaticType)]
pub struct LoadState {
    /// The declarations so far.
    pub scene: RefCell<SceneBuilder>,
    /// The variable each once-run call is assigned to, by `"line:col"` (objects are named
    /// after it in messages and `Stl` signals).
    pub objects: std::sync::Arc<std::collections::HashMap<String, String>>,
    /// What the program printed while evaluating.
    pub log: RefCell<Vec<String>>,
}

impl starlark::PrintHandler for LoadState {
    fn println(&self, text: &str) -> starlark::Result<()> {
        self.log.borrow_mut().push(text.to_owned());
        Ok(())
    }
}

impl LoadState {
    /// The state of an evaluation that gives the open parameters `values` (by declaration
    /// index; `None`: their representative values).
    pub fn new(
        values: Option<Vec<super::scene::ParamValue>>,
        objects: std::sync::Arc<std::collections::HashMap<String, String>>,
    ) -> Self {
        LoadState {
            scene: RefCell::new(SceneBuilder::new(values)),
            objects,
            log: RefCell::new(Vec::new()),
        }
    }
}

/// The variable the builtin call being evaluated is assigned to, when it runs once per
/// evaluation (`lead = Car(...)` at the top level).
pub(crate) fn variable_here(eval: &Evaluator) -> Option<String> {
    let at = here(eval);
    let mut parts = at.rsplitn(3, ':');
    let (col, line) = (parts.next()?, parts.next()?);
    state(eval)
        .ok()?
        .objects
        .get(&format!("{line}:{col}"))
        .cloned()
}

/// Where the builtin call being evaluated stands, with the top-level call it runs under when
/// it is inside a function: `f.star:3:9 (called from f.star:12:1)`.
fn site_here(eval: &Evaluator) -> String {
    let at = here(eval);
    let outer = (0..eval.call_stack_count())
        .filter_map(|n| eval.call_stack_nth_location(n))
        .last()
        .map(|l| format!("{}:{}", l.filename(), l.resolve_span().begin));
    match outer {
        Some(o) if o != at => format!("{at} (called from {o})"),
        _ => at,
    }
}

/// How messages name the object a builtin call declares: by the variable it is assigned to
/// (`Car lead`), else `Car at file:line:col`, adding where a function was called from.
pub(crate) fn object_name(eval: &Evaluator, what: &str) -> String {
    match variable_here(eval) {
        Some(v) => format!("{what} {v}"),
        None => format!("{what} at {}", site_here(eval)),
    }
}

/// The words after `<What>` naming the object in messages about its inputs: `lead
/// (f.star:4:5)`, or `at f.star:4:5` for an object without a variable.
pub(crate) fn object_at(eval: &Evaluator) -> String {
    match variable_here(eval) {
        Some(v) => format!("{v} ({})", here(eval)),
        None => format!("at {}", site_here(eval)),
    }
}

/// The program's [`LoadState`].
pub fn state<'a>(eval: &Evaluator<'_, 'a, '_>) -> anyhow::Result<&'a LoadState> {
    eval.extra
        .and_then(|e| e.downcast_ref::<LoadState>())
        .ok_or_else(|| {
            anyhow!(
                "scenario builtins (objects, `onLane`, streams, monitors) build the world, so \
                 they cannot run inside a lambda during a test: compute the value outside the \
                 lambda (`target = r.onLane(-2, 120)`) and use that variable in it"
            )
        })
}

/// Where the builtin being evaluated was called, `file:line:col`.
pub(crate) fn here(eval: &Evaluator) -> String {
    match eval.call_stack_top_location() {
        Some(l) => format!("{}:{}", l.filename(), l.resolve_span().begin),
        None => "?".into(),
    }
}

/// A number: an int, a float, or a `Const` stream of a number.
pub fn number(v: Value, what: &str) -> anyhow::Result<f64> {
    if let Some(i) = v.unpack_i32() {
        return Ok(f64::from(i));
    }
    if let Some(f) = v.downcast_ref::<starlark::values::float::StarlarkFloat>() {
        return Ok(f.0);
    }
    if v.get_type() == "int" {
        // An integer beyond 32 bits: its value as a float, so that range checks name it.
        if let Ok(x) = v.to_str().parse::<f64>() {
            return Ok(x);
        }
    }
    if let Some(s) = v.downcast_ref::<Stream>() {
        if let Some(x) = s.number {
            return Ok(x);
        }
        bail!(
            "{what} takes one number for the whole test, but got a stream, which has no single \
             value (an open parameter that varies over time is one)"
        );
    }
    bail!("{what} must be a number, got a {}", v.get_type())
}

fn constant(v: Value) -> Option<Rx> {
    if let Some(b) = v.unpack_bool() {
        return Some(Rx::Bool(b));
    }
    if let Some(s) = v.unpack_str() {
        return Some(Rx::Text(s.to_owned()));
    }
    number(v, "").ok().map(Rx::Num)
}

/// A stream argument: a stream, or a plain number, bool or string (a constant stream).
pub fn stream_arg(v: Value, b: &mut SceneBuilder, what: &str) -> anyhow::Result<StreamId> {
    if let Some(s) = v.downcast_ref::<Stream>() {
        return Ok(StreamId(s.id));
    }
    match constant(v) {
        Some(c) => Ok(b.graph.push(Node::Const(c))),
        None => bail!(
            "{what} must be a stream or a constant, got a {}",
            v.get_type()
        ),
    }
}

/// A stream argument for `input` of `owner` (declared `at`), with its type checked: now where
/// its values are known, as the test runs where a lambda computes them
/// ([`super::types::typed_stream`]).
fn typed_arg(
    v: Value,
    b: &mut SceneBuilder,
    input: &types::Input,
    owner: &str,
    at: &str,
) -> anyhow::Result<StreamId> {
    let id = stream_arg(v, b, input.keyword)?;
    types::typed_stream(b, id, input, owner, at)
}

/// A value fixed for a test for `input` of `owner`: a constant (a plain value, `Const(...)`,
/// or an open parameter constant over time, which the program sees as its value), checked.
///
/// # Errors
/// A message for a stream (it has no single value) or a value of the wrong kind or range.
fn fixed_typed(
    v: Value,
    b: &SceneBuilder,
    input: &types::Input,
    owner: &str,
) -> anyhow::Result<Rx> {
    let c = match v.downcast_ref::<Stream>() {
        Some(s) => match b.graph.nodes().get(s.id) {
            Some(Node::Const(c)) => c.clone(),
            _ => bail!(
                "{owner}({}=) is fixed for a test: give it a constant or an open parameter that \
                 does not vary over time, not a stream",
                input.keyword
            ),
        },
        None => constant(v).ok_or_else(|| {
            anyhow!(
                "{owner}({}=) takes {}, got a {}",
                input.keyword,
                input.kind,
                v.get_type()
            )
        })?,
    };
    types::check_const(&c, input, owner)?;
    Ok(c)
}

/// A number known when the world is built: a plain number, `Const(number)`, or an open
/// parameter constant over time (its value in this test).
fn load_time_number(v: Value, b: &SceneBuilder, what: &str) -> anyhow::Result<f64> {
    if let Some(s) = v.downcast_ref::<Stream>() {
        if let Some(Node::Const(c)) = b.graph.nodes().get(s.id) {
            return c
                .as_num()
                .filter(|_| matches!(c, Rx::Num(_)))
                .ok_or_else(|| anyhow!("{what} must be a number, got a {}", c.kind()));
        }
    }
    number(v, what)
}

/// A hint for a stream passed where a value is needed, empty for anything else.
pub(crate) fn stream_hint(v: Value) -> &'static str {
    if v.downcast_ref::<Stream>().is_some() {
        " (a stream has a value only while a test runs: apply the function inside a lambda, \
         e.g. s.map(lambda x: sqrt(x)))"
    } else {
        ""
    }
}

/// A number argument of a math builtin.
fn math_number(v: Value, what: &str) -> anyhow::Result<f64> {
    super::position::num(v).ok_or_else(|| {
        anyhow!(
            "{what} takes numbers, got a {}{}",
            v.get_type(),
            stream_hint(v)
        )
    })
}

fn lanes(v: Option<Value>, b: &SceneBuilder, default: u32) -> anyhow::Result<u32> {
    let Some(v) = v else { return Ok(default) };
    let x = load_time_number(v, b, "nlanes=")?;
    if x.fract() != 0.0 || !(2.0..=16.0).contains(&x) || (x as u32) % 2 == 1 {
        bail!("nlanes must be an even whole number from 2 to 16, got {x}");
    }
    Ok(x as u32)
}

fn add_piece(
    eval: &Evaluator,
    what: &str,
    kind: PieceKind,
    friction: StreamId,
) -> anyhow::Result<Road> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    let segment = matches!(kind, PieceKind::Segment { .. });
    let ports = kind.ports().len();
    let name = object_name(eval, what);
    let id = b
        .roads
        .add(&name, kind)
        .map_err(|e| anyhow!(super::scene::strip(e)))?;
    b.frictions.push((id, friction));
    Ok(Road {
        piece: id.0,
        ports,
        segment,
        network: false,
    })
}

/// A road piece from its keyword arguments: `make` gets the program's declarations, the lane
/// count (default 2) and the friction at the start (default 0.8; for a friction that varies
/// over the test, its value is set from its stream every step) and reads any further
/// arguments.
fn road_piece(
    eval: &Evaluator,
    what: &str,
    nlanes: Option<Value>,
    friction: Option<Value>,
    make: impl FnOnce(&SceneBuilder, u32, f64) -> anyhow::Result<PieceKind>,
) -> anyhow::Result<Road> {
    let at = object_at(eval);
    let (kind, stream) = {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let stream = match friction {
            Some(v) => typed_arg(v, &mut b, &types::FRICTION, what, &at)?,
            None => b.graph.push(Node::Const(Rx::Num(0.8))),
        };
        let mu = match b.graph.nodes().get(stream.0) {
            Some(Node::Const(Rx::Num(mu))) => *mu,
            _ => 0.8,
        };
        let lanes = lanes(nlanes, &b, 2)?;
        (make(&b, lanes, mu)?, stream)
    };
    add_piece(eval, what, kind, stream)
}

fn location(v: Value, what: &str) -> anyhow::Result<usize> {
    v.downcast_ref::<Loc>().map(|l| l.index).ok_or_else(|| {
        anyhow!(
            "{what} must be a location from r.onLane(lane, at), got a {}",
            v.get_type()
        )
    })
}

fn declare(
    eval: &Evaluator,
    b: &mut SceneBuilder,
    what: &str,
    kind: ActorKind,
    pending: Pending,
) -> ActorVal {
    let actor = match kind {
        ActorKind::Ego => Actor::Ego,
        ActorKind::Pedestrian(i) => Actor::Pedestrian(i),
        ActorKind::Car(i) => Actor::Car(i),
    };
    let outputs = [
        Output::Pos,
        Output::Vel,
        Output::Heading,
        Output::Speed,
        Output::Collision,
    ]
    .map(|o| b.probe(actor, o).0);
    b.objects.push(ObjectDecl {
        name: object_name(eval, what),
        at: here(eval),
        variable: variable_here(eval),
        actor: Some(actor),
        pending,
        placed: false,
    });
    ActorVal {
        kind,
        outputs,
        object: b.objects.len() - 1,
    }
}

/// A string fixed for a test: a plain string, `Const("...")` or an open `VarEnum` level.
pub(crate) fn text_value(v: Value, b: &SceneBuilder) -> Option<String> {
    if let Some(t) = v.unpack_str() {
        return Some(t.to_owned());
    }
    match v
        .downcast_ref::<Stream>()
        .map(|s| b.graph.nodes().get(s.id))
    {
        Some(Some(Node::Const(Rx::Text(t)))) => Some(t.clone()),
        _ => None,
    }
}

/// A route: `None`, one turn (a string, `Const("left")`, or an open `VarEnum` of turns) or a
/// list of turns.
fn route_arg(
    v: Option<Value>,
    b: &SceneBuilder,
) -> anyhow::Result<Option<Vec<paracosm_engine::network::Turn>>> {
    let one = |v: Value| text_value(v, b);
    match v {
        None => Ok(None),
        Some(v) if v.is_none() => Ok(None),
        // One turn, e.g. an open parameter `VarEnum(["left", "straight", "right"])`.
        Some(v) if one(v).is_some() => turns(&[one(v).unwrap_or_default()])
            .map(Some)
            .map_err(|e| anyhow!(e)),
        Some(v) if v.downcast_ref::<Stream>().is_some() => bail!(
            "route is fixed for a test, since the path is planned when the world is built: give \
             a turn, a list of turns or an open VarEnum of turns, not a stream"
        ),
        Some(v) => {
            let wrong = || {
                anyhow!(
                    "route must be a turn or a list of turns such as [\"left\", \"straight\"], \
                     got a {}",
                    v.get_type()
                )
            };
            let items = UnpackList::<Value>::unpack_value(v)
                .ok()
                .flatten()
                .ok_or_else(wrong)?;
            let list = items
                .items
                .into_iter()
                .map(|t| one(t).ok_or_else(wrong))
                .collect::<anyhow::Result<Vec<String>>>()?;
            turns(&list).map(Some).map_err(|e| anyhow!(e))
        }
    }
}

fn unique_monitor_name(b: &SceneBuilder, name: &str) -> anyhow::Result<()> {
    if b.monitors.iter().any(|m| m.name() == name) {
        bail!(
            "two monitors are named `{name}`: results are keyed by monitor name, so give one \
             another name="
        );
    }
    Ok(())
}

/// Publishes the stream a `Monitor` or `Assert` named `name` judges, checking that it carries
/// `want` (numbers or bools) when that is known; returns the signal's name.
fn publish_monitored(
    eval: &Evaluator,
    stream: Value,
    name: &str,
    what: &str,
    want: types::SType,
) -> anyhow::Result<String> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    if stream.downcast_ref::<Stream>().is_none() {
        bail!(
            "{what} judges a stream (such as `v.speed.map(lambda s: 20 - s)`), got a {}",
            stream.get_type()
        );
    }
    let id = stream_arg(stream, &mut b, what)?;
    let kind = types::stream_types(&b)[id.0];
    if kind != want && kind != types::SType::Any {
        bail!(
            "{what} needs a stream of {}, and this one carries {}{}",
            want.name(),
            kind.name(),
            if want == types::SType::Num {
                " (for a stream of bools, use Assert)"
            } else {
                ""
            }
        );
    }
    let signal = format!("monitor:{name}");
    b.published.push((signal.clone(), id));
    Ok(signal)
}

fn monitor(eval: &Evaluator, spec: MonitorSpec) -> anyhow::Result<MonitorVal> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    unique_monitor_name(&b, spec.name())?;
    b.monitors.push(spec);
    b.monitors_at.push(here(eval));
    Ok(MonitorVal {
        index: b.monitors.len() - 1,
    })
}

fn ego_arg(v: Value, what: &str) -> anyhow::Result<()> {
    match v.downcast_ref::<ActorVal>() {
        Some(a) if a.kind == ActorKind::Ego => Ok(()),
        _ => bail!(
            "{what} watches the AutonomousVehicle; got a {}",
            v.get_type()
        ),
    }
}

/// Declares an open parameter; returns what the program sees: the test's value as a plain
/// Starlark value (a float for an interval; an int, float, string or bool for a level), or,
/// for one that varies over time, its stream.
fn declare_param<'v>(
    eval: &mut Evaluator<'v, '_, '_>,
    decl: ParamDecl,
) -> anyhow::Result<Value<'v>> {
    let heap = eval.heap();
    let st = state(eval)?;
    let got = st
        .scene
        .borrow_mut()
        .param(decl)
        .map_err(anyhow::Error::msg)?;
    Ok(match got {
        Ok(Level::Int(i)) => heap.alloc(i),
        Ok(Level::Real(x)) => heap.alloc(x),
        Ok(Level::Text(t)) if t == "true" => Value::new_bool(true),
        Ok(Level::Text(t)) if t == "false" => Value::new_bool(false),
        Ok(Level::Text(t)) => heap.alloc(t.as_str()),
        Err(id) => heap.alloc(Stream::of(id.0)),
    })
}

/// The builtins.
#[starlark_module]
#[allow(non_snake_case)]
pub(crate) fn paracosm_globals(builder: &mut GlobalsBuilder) {
    const tick: Stream = Stream {
        id: super::scene::TICK.0,
        number: None,
    };
    const SideWalk: LaneSide = LaneSide { opposite: false };

    /// `Const(v)`: the constant stream of `v`.
    fn Const<'v>(v: Value<'v>, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Stream> {
        let c = constant(v).ok_or_else(|| {
            anyhow!(
                "Const takes a number, a bool or a string, got a {}",
                v.get_type()
            )
        })?;
        let number = match c {
            Rx::Num(x) => Some(x),
            _ => None,
        };
        let st = state(eval)?;
        let id = st.scene.borrow_mut().graph.push(Node::Const(c));
        Ok(Stream { id: id.0, number })
    }

    /// `VarInterval(lo, hi, unit=None, name=None, over_time=None)`: an open real parameter:
    /// the test's value in `[lo, hi)`, or with `over_time=` a stream of values in `[lo, hi]`.
    fn VarInterval<'v>(
        lo: Value<'v>,
        hi: Value<'v>,
        #[starlark(require = named)] unit: Option<&str>,
        #[starlark(require = named)] name: Option<&str>,
        #[starlark(require = named)] over_time: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Value<'v>> {
        let (lo, hi) = (number(lo, "VarInterval lo")?, number(hi, "VarInterval hi")?);
        if !(lo.is_finite() && hi.is_finite()) || lo >= hi {
            bail!("VarInterval({lo}, {hi}) is empty: lo must be below hi");
        }
        let over_time = match over_time {
            None => OverTime::Constant,
            Some(v) if v.is_none() => OverTime::Constant,
            Some(v) => v
                .downcast_ref::<OverTimeVal>()
                .map(|o| o.over_time)
                .ok_or_else(|| {
                    anyhow!(
                        "over_time must be Piecewise(k) or Polynomial(deg), got a {}",
                        v.get_type()
                    )
                })?,
        };
        let at = here(eval);
        declare_param(
            eval,
            ParamDecl {
                name: name.map(str::to_owned),
                domain: Domain::Interval { lo, hi },
                unit: unit.map(str::to_owned),
                over_time,
                at,
            },
        )
    }

    /// `VarEnum([levels...], name=None)`: an open discrete parameter: the test's level.
    fn VarEnum<'v>(
        levels: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Value<'v>> {
        let items: Vec<Value> = levels
            .iterate(eval.heap())
            .map_err(|_| {
                anyhow!(
                    "VarEnum takes a list of levels, got a {}",
                    levels.get_type()
                )
            })?
            .collect();
        if items.is_empty() {
            bail!("VarEnum([]) has no levels");
        }
        let mut out = Vec::new();
        for v in items {
            let level = if let Some(b) = v.unpack_bool() {
                Level::Text(b.to_string())
            } else if let Some(i) = v.unpack_i32() {
                Level::Int(i64::from(i))
            } else if let Some(s) = v.unpack_str() {
                Level::Text(s.to_owned())
            } else {
                Level::Real(number(v, "a VarEnum level")?)
            };
            if out.contains(&level) {
                bail!("VarEnum lists the level {level} twice");
            }
            out.push(level);
        }
        let at = here(eval);
        declare_param(
            eval,
            ParamDecl {
                name: name.map(str::to_owned),
                domain: Domain::Levels(out),
                unit: None,
                over_time: OverTime::Constant,
                at,
            },
        )
    }

    /// `abs(x)`: the absolute value of a number, or the length of a `Vector` (a difference of
    /// positions: m). Replaces Starlark's `abs`, which takes numbers only.
    ///
    /// # Errors
    /// A location (subtract another position first), a stream or any other value.
    fn abs<'v>(
        #[starlark(require = pos)] x: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Value<'v>> {
        super::position::abs_of(x, eval.heap())
    }

    /// `dist(a, b)`: the distance between two positions (locations or vectors), m; in the
    /// ground plane (`x`, `z`) when either is a location.
    ///
    /// # Errors
    /// An argument that is not a position.
    fn dist<'v>(
        #[starlark(require = pos)] a: Value<'v>,
        #[starlark(require = pos)] b: Value<'v>,
    ) -> anyhow::Result<f64> {
        super::position::dist_of(a, b)
    }

    /// `sqrt(x)`: the square root of a number `>= 0`.
    ///
    /// # Errors
    /// A negative number or a value that is not a number.
    fn sqrt<'v>(#[starlark(require = pos)] x: Value<'v>) -> anyhow::Result<f64> {
        let v = math_number(x, "sqrt")?;
        if v < 0.0 {
            bail!("sqrt of a negative number, {v}");
        }
        Ok(v.sqrt())
    }

    /// `hypot(x, y)`: `sqrt(x² + y²)` without overflow.
    ///
    /// # Errors
    /// An argument that is not a number.
    fn hypot<'v>(
        #[starlark(require = pos)] x: Value<'v>,
        #[starlark(require = pos)] y: Value<'v>,
    ) -> anyhow::Result<f64> {
        Ok(math_number(x, "hypot")?.hypot(math_number(y, "hypot")?))
    }

    /// `clamp(x, lo, hi)`: `x` limited to `[lo, hi]`.
    ///
    /// # Errors
    /// An argument that is not a number, or `lo > hi`.
    fn clamp<'v>(
        #[starlark(require = pos)] x: Value<'v>,
        #[starlark(require = pos)] lo: Value<'v>,
        #[starlark(require = pos)] hi: Value<'v>,
    ) -> anyhow::Result<f64> {
        let (x, lo, hi) = (
            math_number(x, "clamp")?,
            math_number(lo, "clamp")?,
            math_number(hi, "clamp")?,
        );
        if lo > hi || lo.is_nan() || hi.is_nan() {
            bail!("clamp(x, lo, hi) needs lo <= hi, got lo = {lo}, hi = {hi}");
        }
        Ok(x.clamp(lo, hi))
    }

    /// `Piecewise(k)`: an open stream held constant on `k` equal parts of the test.
    fn Piecewise(k: i32) -> anyhow::Result<OverTimeVal> {
        if !(1..=64).contains(&k) {
            bail!("Piecewise(k) needs 1 <= k <= 64, got {k}");
        }
        Ok(OverTimeVal {
            over_time: OverTime::Piecewise(k as usize),
        })
    }

    /// `Polynomial(deg)`: an open stream that is a Bernstein polynomial of degree `deg` in time.
    fn Polynomial(deg: i32) -> anyhow::Result<OverTimeVal> {
        if !(0..=16).contains(&deg) {
            bail!("Polynomial(deg) needs 0 <= deg <= 16, got {deg}");
        }
        Ok(OverTimeVal {
            over_time: OverTime::Polynomial(deg as usize),
        })
    }

    /// `World(light=0.5, fog=0.0)`: global conditions as streams (light 0.5 is the nominal
    /// daylight a camera's exposure is calibrated for).
    fn World<'v>(
        #[starlark(require = named)] light: Option<Value<'v>>,
        #[starlark(require = named)] fog: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<WorldVal> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.world.is_some() {
            bail!("a program has one World");
        }
        let heap = eval.heap();
        let at = object_at(eval);
        let light = typed_arg(
            light.unwrap_or_else(|| heap.alloc(NOMINAL_LIGHT)),
            &mut b,
            &types::LIGHT,
            "World",
            &at,
        )?;
        let fog = typed_arg(
            fog.unwrap_or_else(|| heap.alloc(0.0)),
            &mut b,
            &types::FOG,
            "World",
            &at,
        )?;
        b.world = Some((light, fog));
        Ok(WorldVal {
            light: light.0,
            fog: fog.0,
        })
    }

    /// `RoadSegment(len=200.0, nlanes=2, friction=0.8)`.
    fn RoadSegment<'v>(
        #[starlark(require = named)] len: Option<Value<'v>>,
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "RoadSegment",
            nlanes,
            friction,
            |b, lanes, friction| {
                let length_m = match len {
                    Some(v) => load_time_number(v, b, "RoadSegment(len=)")?,
                    None => 200.0,
                };
                Ok(PieceKind::Segment {
                    length_m,
                    lanes,
                    friction,
                })
            },
        )
    }

    /// `TIntersection(nlanes=2, friction=0.8)`; `numLane=` is the paper's spelling.
    fn TIntersection<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "TIntersection",
            nlanes.or(numLane),
            friction,
            |_, lanes, friction| Ok(PieceKind::TIntersection { lanes, friction }),
        )
    }

    /// `CrossIntersection(nlanes=2, friction=0.8)`; `numLane=` too.
    fn CrossIntersection<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "CrossIntersection",
            nlanes.or(numLane),
            friction,
            |_, lanes, friction| Ok(PieceKind::CrossIntersection { lanes, friction }),
        )
    }

    /// `Roundabout(nlanes=2, radius=20.0, friction=0.8)`.
    fn Roundabout<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] radius: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "Roundabout",
            nlanes,
            friction,
            |b, lanes, friction| {
                let radius_m = match radius {
                    Some(v) => load_time_number(v, b, "Roundabout(radius=)")?,
                    None => 20.0,
                };
                Ok(PieceKind::Roundabout {
                    lanes,
                    radius_m,
                    friction,
                })
            },
        )
    }

    /// `AutonomousVehicle(loc=, sut="aeb", route=None, speed=None)`: the ego vehicle and its
    /// default system under test (`aeb` or `vision`; `--sut`/`--sut-cmd` override it).
    fn AutonomousVehicle<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] sut: Option<&str>,
        #[starlark(require = named)] route: Option<Value<'v>>,
        #[starlark(require = named)] speed: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let loc = location(loc, "loc")?;
        let sut = SutConfig::builtin(sut.unwrap_or("aeb")).map_err(anyhow::Error::msg)?;
        let initial_speed_mps = match speed {
            Some(v) => number(v, "AutonomousVehicle(speed=), the initial speed,")?,
            None => AebConfig::default().cruise.target_speed_mps,
        };
        if !(initial_speed_mps.is_finite() && initial_speed_mps >= 0.0) {
            bail!("speed {initial_speed_mps} m/s must be >= 0");
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let route = route_arg(route, &b)?;
        Ok(declare(
            eval,
            &mut b,
            "AutonomousVehicle",
            ActorKind::Ego,
            Pending::Ego {
                loc,
                route,
                initial_speed_mps,
                sut,
            },
        ))
    }

    /// `Car(loc=, speed=10.0, route=[], color="red", enabled=True, lane_change=None)`: an
    /// NPC car that follows the lane graph, and may change lanes once (`ChangeLane`).
    fn Car<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] speed: Option<Value<'v>>,
        #[starlark(require = named)] route: Option<Value<'v>>,
        #[starlark(require = named)] color: Option<Value<'v>>,
        #[starlark(require = named)] enabled: Option<Value<'v>>,
        #[starlark(require = named)] lane_change: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let loc = location(loc, "loc")?;
        let lane_change = match lane_change {
            None => None,
            Some(v) if v.is_none() => None,
            Some(v) => Some(*v.downcast_ref::<LaneChangeVal>().ok_or_else(|| {
                anyhow!(
                    "Car(lane_change=) takes ChangeLane(to = lane, at = seconds or when = stream, duration = seconds), got a {}",
                    v.get_type()
                )
            })?),
        };
        let heap = eval.heap();
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let route = route_arg(route, &b)?.unwrap_or_default();
        let at = object_at(eval);
        let speed = typed_arg(
            speed.unwrap_or_else(|| heap.alloc(10.0)),
            &mut b,
            &types::CAR_SPEED,
            "Car",
            &at,
        )?;
        let color = match fixed_typed(
            color.unwrap_or_else(|| heap.alloc("red")),
            &b,
            &types::COLOR,
            "Car",
        )? {
            Rx::Text(t) => t.to_ascii_lowercase(),
            c => bail!("Car(color=) takes a colour name, got a {}", c.kind()),
        };
        let enabled = fixed_typed(
            enabled.unwrap_or_else(|| Value::new_bool(true)),
            &b,
            &types::ENABLED,
            "Car",
        )?
        .as_bool()
        .unwrap_or(true);
        let i = b.n_cars;
        b.n_cars += 1;
        Ok(declare(
            eval,
            &mut b,
            "Car",
            ActorKind::Car(i),
            Pending::Car {
                loc,
                route,
                speed,
                color,
                enabled,
                lane_change,
            },
        ))
    }

    /// `ChangeLane(to=, at=None, when=None, duration=3.0)`: a lane change for
    /// `Car(lane_change=)`: to lane `to` of the car's segment, starting `at` seconds into the
    /// test or at the first event of the stream `when`, over `duration` seconds.
    fn ChangeLane<'v>(
        #[starlark(require = named)] to: Value<'v>,
        #[starlark(require = named)] at: Option<Value<'v>>,
        #[starlark(require = named)] when: Option<Value<'v>>,
        #[starlark(require = named)] duration: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<LaneChangeVal> {
        let to = number(to, "ChangeLane(to=)")?;
        if to.fract() != 0.0 || to == 0.0 {
            bail!("ChangeLane(to=) is a lane number (1, 2, ... or -1, -2, ...), got {to}");
        }
        let duration_s = match duration {
            Some(v) => number(v, "ChangeLane(duration=)")?,
            None => 3.0,
        };
        if !(duration_s.is_finite() && duration_s > 0.0) {
            bail!("ChangeLane(duration=) takes a number in s, > 0, got {duration_s}");
        }
        let start = match (at, when) {
            (Some(t), None) => {
                let t = number(t, "ChangeLane(at=)")?;
                if !(t.is_finite() && t >= 0.0) {
                    bail!("ChangeLane(at=) takes a number in s, >= 0, got {t}");
                }
                ChangeStart::At(t)
            }
            (None, Some(w)) => {
                let st = state(eval)?;
                let mut b = st.scene.borrow_mut();
                ChangeStart::When(stream_arg(w, &mut b, "ChangeLane(when=)")?.0)
            }
            _ => bail!("ChangeLane needs either at = seconds or when = a stream"),
        };
        Ok(LaneChangeVal {
            to: to as i32,
            start,
            duration_s,
        })
    }

    /// `Obstacle(loc=, size=(4.5, 1.8, 1.5), color="grey")`: a static box (a parked car, a
    /// cone, a barrier) standing at `loc`, turned along its lane; `size` is its length, width
    /// and height in metres. It collides with the ego vehicle, stops lidar beams and is drawn
    /// by the camera.
    fn Obstacle<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] size: Option<Value<'v>>,
        #[starlark(require = named)] color: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ObstacleVal> {
        let loc = location(loc, "loc")?;
        let size = match size {
            None => paracosm_engine::Size::CAR,
            Some(v) => {
                let items: Vec<Value> = v
                    .iterate(eval.heap())
                    .map_err(|_| {
                        anyhow!(
                            "Obstacle(size=) takes (length, width, height) in m, got a {}",
                            v.get_type()
                        )
                    })?
                    .collect();
                let [l, w, h] = items.as_slice() else {
                    bail!(
                        "Obstacle(size=) takes three numbers (length, width, height) in m, got {}",
                        items.len()
                    );
                };
                let size = paracosm_engine::Size {
                    length_m: number(*l, "Obstacle(size=) length")?,
                    width_m: number(*w, "Obstacle(size=) width")?,
                    height_m: number(*h, "Obstacle(size=) height")?,
                };
                if !size.is_valid() {
                    bail!("Obstacle(size=) needs three positive lengths in m, got {size:?}");
                }
                size
            }
        };
        let heap = eval.heap();
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let color = match fixed_typed(
            color.unwrap_or_else(|| heap.alloc("grey")),
            &b,
            &types::COLOR,
            "Obstacle",
        )? {
            Rx::Text(t) => t.to_ascii_lowercase(),
            c => bail!("Obstacle(color=) takes a colour name, got a {}", c.kind()),
        };
        b.objects.push(ObjectDecl {
            name: object_name(eval, "Obstacle"),
            at: here(eval),
            variable: variable_here(eval),
            actor: None,
            pending: Pending::Obstacle { loc, size, color },
            placed: false,
        });
        Ok(ObstacleVal {
            object: b.objects.len() - 1,
        })
    }

    /// `Pedestrian(start=, target=, speed=, dist=None, car=None, trigger=None)`: walks from
    /// `start` to `target` once `car` comes within `dist` metres of `start` (or once
    /// `trigger` fires).
    fn Pedestrian<'v>(
        #[starlark(require = named)] start: Value<'v>,
        #[starlark(require = named)] target: Value<'v>,
        #[starlark(require = named)] speed: Value<'v>,
        #[starlark(require = named)] dist: Option<Value<'v>>,
        #[starlark(require = named)] car: Option<Value<'v>>,
        #[starlark(require = named)] trigger: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let (start, target) = (location(start, "start")?, location(target, "target")?);
        let at = object_at(eval);
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let owner = "Pedestrian";
        let speed = typed_arg(speed, &mut b, &types::PEDESTRIAN_SPEED, owner, &at)?;
        let trigger = match (dist, car, trigger) {
            (Some(d), Some(c), None) => {
                let car = match c.downcast_ref::<ActorVal>() {
                    Some(a) => StreamId(a.outputs[0]),
                    None => typed_arg(c, &mut b, &types::WATCHED_POSITION, owner, &at)?,
                };
                PedTrigger::Near {
                    car,
                    dist: typed_arg(d, &mut b, &types::TRIGGER_DISTANCE, owner, &at)?,
                }
            }
            (None, None, Some(t)) => {
                PedTrigger::Stream(typed_arg(t, &mut b, &types::TRIGGER, owner, &at)?)
            }
            (None, None, None) => PedTrigger::Never,
            _ => bail!(
                "Pedestrian takes dist= and car= together, or trigger=, or neither (then it \
                 walks only when an action moves it: stream.foreach(p.walk))"
            ),
        };
        let i = b.n_pedestrians;
        b.n_pedestrians += 1;
        Ok(declare(
            eval,
            &mut b,
            "Pedestrian",
            ActorKind::Pedestrian(i),
            Pending::Pedestrian {
                start,
                target,
                speed,
                trigger,
            },
        ))
    }

    /// `CollisionMonitor(v, name="collision")`: fails when the ego vehicle touches a
    /// pedestrian or a car; robustness is the smallest separation in metres.
    fn CollisionMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        ego_arg(v, "CollisionMonitor")?;
        monitor(
            eval,
            MonitorSpec::Collision {
                name: name.unwrap_or("collision").to_owned(),
            },
        )
    }

    /// `OffRoadMonitor(v, name="offroad")`: fails when the centre of the ego vehicle's
    /// footprint leaves the driving surface (a sidewalk, an island, the ground beside the road
    /// or past a dead end); robustness is the smallest signed distance to the surface's edge
    /// in metres.
    fn OffRoadMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        ego_arg(v, "OffRoadMonitor")?;
        monitor(
            eval,
            MonitorSpec::OffRoad {
                name: name.unwrap_or("offroad").to_owned(),
                implicit: false,
            },
        )
    }

    /// `DistanceMonitor(v, minD=, name="distance")`: fails unless the ego vehicle travels at
    /// least `minD` metres; robustness `D - minD` in metres.
    fn DistanceMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] minD: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        ego_arg(v, "DistanceMonitor")?;
        let min_distance_m = number(minD, "minD")?;
        monitor(
            eval,
            MonitorSpec::Distance {
                name: name.unwrap_or("distance").to_owned(),
                min_distance_m,
            },
        )
    }

    /// `Stl(formula, name="stl")`: a signal temporal logic property over the runner's
    /// signals ([`crate::signal::ALL`]), judged at the start of the test; robustness in the
    /// formula's units. The formula is parsed when the program loads: a syntax error shows a
    /// caret, an unknown signal is named.
    fn Stl<'v>(
        #[starlark(require = pos)] formula: &str,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        // Signal names are checked once the program has run (a Signal(...) or an actor may
        // come later in the program).
        paracosm_oracles::stl::parse(formula).map_err(anyhow::Error::msg)?;
        monitor(
            eval,
            MonitorSpec::Stl {
                name: name.unwrap_or("stl").to_owned(),
                formula: formula.to_owned(),
            },
        )
    }

    /// `Monitor(stream, name=<variable> or "monitor", unit=None, over="always")`: a monitor
    /// written by the program; its robustness is the stream's value taken `over` the test
    /// (`"always"`: the minimum, failing at the first value `<= 0`; `"end"`: the last value;
    /// `"eventually"`: the maximum), in `unit`.
    fn Monitor<'v>(
        #[starlark(require = pos)] stream: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        #[starlark(require = named)] unit: Option<&str>,
        #[starlark(require = named)] over: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let word = over.unwrap_or("always");
        let over = paracosm_oracles::Over::parse(word).ok_or_else(|| {
            anyhow!("Monitor(over=) is \"always\", \"end\" or \"eventually\", got {word:?}")
        })?;
        let name = name
            .map(str::to_owned)
            .or_else(|| variable_here(eval))
            .unwrap_or_else(|| "monitor".to_owned());
        let signal = publish_monitored(eval, stream, &name, "Monitor", types::SType::Num)?;
        monitor(
            eval,
            MonitorSpec::Stream {
                name,
                signal,
                unit: unit.map(str::to_owned),
                over,
            },
        )
    }

    /// `Assert(stream, name=<variable> or "assert")`: fails at the first event of the stream
    /// (of bools) that is false; robustness `+1` or `-1`.
    fn Assert<'v>(
        #[starlark(require = pos)] stream: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let name = name
            .map(str::to_owned)
            .or_else(|| variable_here(eval))
            .unwrap_or_else(|| "assert".to_owned());
        let signal = publish_monitored(eval, stream, &name, "Assert", types::SType::Bool)?;
        monitor(eval, MonitorSpec::Assert { name, signal })
    }

    /// `Signal(name, stream)`: publishes a stream of numbers, bools or vectors under `name`
    /// for `Stl` formulas (a vector as `name.x`, `name.y`, `name.z`).
    fn Signal<'v>(
        #[starlark(require = pos)] name: &str,
        #[starlark(require = pos)] stream: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let valid = name.split('.').all(|part| {
            part.chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && part.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        });
        if !valid {
            bail!(
                "Signal: `{name}` is not a signal name (letters, digits and _, parts joined by .)"
            );
        }
        if crate::runner::signal::ALL.contains(&name) {
            bail!("Signal: `{name}` is one of the runner's own signals; choose another name");
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.published.iter().any(|(n, _)| n == name) {
            bail!("Signal: `{name}` is published twice");
        }
        let id = stream_arg(stream, &mut b, "Signal")?;
        let kind = types::stream_types(&b)[id.0];
        if matches!(
            kind,
            types::SType::Text | types::SType::Tuple | types::SType::Unit
        ) {
            bail!(
                "Signal `{name}` carries {}; a signal is a number, a bool or a vector",
                kind.name()
            );
        }
        b.published.push((name.to_owned(), id));
        Ok(NoneType)
    }

    /// `TimeToFailure(m, minT=0.0)`: wraps monitor `m`; reports the time of its first
    /// violation and fails when it comes before `minT` seconds.
    fn TimeToFailure<'v>(
        m: Value<'v>,
        #[starlark(require = named)] minT: Option<Value<'v>>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let inner = m
            .downcast_ref::<MonitorVal>()
            .ok_or_else(|| anyhow!("TimeToFailure wraps a monitor, got a {}", m.get_type()))?
            .index;
        let min_s = match minT {
            Some(v) => number(v, "minT")?,
            None => 0.0,
        };
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let wrapped = b
            .monitors
            .get(inner)
            .cloned()
            .ok_or_else(|| anyhow!("that monitor is already wrapped"))?;
        let name = name.unwrap_or("time_to_failure");
        if wrapped.name() != name {
            unique_monitor_name(&b, name)?;
        }
        b.monitors_at[inner] = here(eval);
        b.monitors[inner] = MonitorSpec::TimeToFailure {
            name: name.to_owned(),
            inner: Box::new(wrapped),
            min_s,
        };
        Ok(MonitorVal { index: inner })
    }

    /// `test(horizon=15.0, map=None, offroad=True)`: the test length in seconds, the failure
    /// map's axes (one or two parameter names), and whether the default `OffRoadMonitor` is
    /// added to a program that declares none.
    fn test<'v>(
        #[starlark(require = named)] horizon: Option<Value<'v>>,
        #[starlark(require = named)] map: Option<Value<'v>>,
        #[starlark(require = named)] offroad: Option<bool>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        b.test_at = Some(here(eval));
        if let Some(h) = horizon {
            let h = number(h, "horizon")?;
            if !(h.is_finite() && h > 0.0 && h <= 3600.0) {
                bail!("horizon {h} s must be in (0, 3600]");
            }
            b.horizon_s = Some(h);
        }
        if let Some(m) = map {
            let axes: Vec<String> = if let Some(one) = m.unpack_str() {
                vec![one.to_owned()]
            } else {
                let items = UnpackList::<String>::unpack_value(m)
                    .ok()
                    .flatten()
                    .map(|l| l.items)
                    .or_else(|| {
                        starlark::values::tuple::TupleRef::from_value(m).and_then(|t| {
                            t.content()
                                .iter()
                                .map(|v| v.unpack_str().map(str::to_owned))
                                .collect::<Option<Vec<String>>>()
                        })
                    });
                match items {
                    Some(items) if (1..=2).contains(&items.len()) => items,
                    _ => bail!(
                        "test(map=) takes one or two parameter names, such as \"speed\" or \
                         (\"speed\", \"dist\"), got {m}"
                    ),
                }
            };
            b.map_axes = Some(axes);
        }
        if let Some(o) = offroad {
            b.offroad = Some(o);
        }
        Ok(NoneType)
    }
}
