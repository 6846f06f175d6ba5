#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! The global builtins of the scenario language (LANGUAGE.md documents each).

pub(crate) mod actors;
pub(crate) mod constraints;
pub(crate) mod import;
pub(crate) mod math;
pub(crate) mod monitors;
pub(crate) mod roads;
pub(crate) mod settings;
pub(crate) mod streams;

use std::cell::RefCell;

use anyhow::{anyhow, bail};
use paracosm_engine::rx::{Node, StreamId, Value as Rx};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::values::{ProvidesStaticType, Value, ValueLike};

use super::scene::SceneBuilder;
use super::types;
use super::values::Stream;

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
    /// The maps the program reads, shared by its evaluations.
    pub(crate) maps: std::sync::Arc<crate::map_files::MapFiles>,
}

impl starlark::PrintHandler for LoadState {
    fn println(&self, text: &str) -> starlark::Result<()> {
        self.log.borrow_mut().push(text.to_owned());
        Ok(())
    }
}

impl LoadState {
    /// The state of an evaluation that gives the open parameters `values` (by name; `None`:
    /// their representative values).
    pub fn new(
        values: Option<crate::scene::GivenValues>,
        objects: std::sync::Arc<std::collections::HashMap<String, String>>,
        maps: std::sync::Arc<crate::map_files::MapFiles>,
    ) -> Self {
        LoadState {
            scene: RefCell::new(SceneBuilder::new(values)),
            objects,
            log: RefCell::new(Vec::new()),
            maps,
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
pub(super) fn site_here(eval: &Evaluator) -> String {
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
    bail!(
        "{what} must be a number, got {}",
        crate::lang::a_type(v.get_type())
    )
}

pub(super) fn constant(v: Value) -> Option<Rx> {
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
        Some(c) => Ok(b.scene.push(Node::Const(c))),
        None => bail!(
            "{what} must be a stream or a constant, got {}",
            crate::lang::a_type(v.get_type())
        ),
    }
}

/// A stream argument for `input` of `owner` (declared `at`), with its type checked: now where
/// its values are known, as the test runs where a lambda computes them
/// ([`super::types::typed_stream`]).
pub(super) fn typed_arg(
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
pub(super) fn fixed_typed(
    v: Value,
    b: &SceneBuilder,
    input: &types::Input,
    owner: &str,
) -> anyhow::Result<Rx> {
    let c = match v.downcast_ref::<Stream>() {
        Some(s) => match b.scene.nodes().get(s.id) {
            Some(Node::Const(c)) => c.clone(),
            _ => bail!(
                "{owner}({}=) is fixed for a test: give it a constant or an open parameter that \
                 does not vary over time, not a stream",
                input.keyword
            ),
        },
        None => constant(v).ok_or_else(|| {
            anyhow!(
                "{owner}({}=) takes {}, got {}",
                input.keyword,
                input.kind,
                crate::lang::a_type(v.get_type())
            )
        })?,
    };
    types::check_const(&c, input, owner)?;
    Ok(c)
}

/// A number known when the world is built: a plain number, `Const(number)`, or an open
/// parameter constant over time (its value in this test).
pub(super) fn load_time_number(v: Value, b: &SceneBuilder, what: &str) -> anyhow::Result<f64> {
    if let Some(s) = v.downcast_ref::<Stream>() {
        if let Some(Node::Const(c)) = b.scene.nodes().get(s.id) {
            return c
                .as_num()
                .filter(|_| matches!(c, Rx::Num(_)))
                .ok_or_else(|| anyhow!("{what} must be a number, got a {}", c.kind()));
        }
    }
    number(v, what)
}

/// A string fixed for a test: a plain string, `Const("...")` or an open `VarEnum` level.
pub(crate) fn text_value(v: Value, b: &SceneBuilder) -> Option<String> {
    if let Some(t) = v.unpack_str() {
        return Some(t.to_owned());
    }
    match v
        .downcast_ref::<Stream>()
        .map(|s| b.scene.nodes().get(s.id))
    {
        Some(Some(Node::Const(Rx::Text(t)))) => Some(t.clone()),
        _ => None,
    }
}

/// The builtins, by topic (LANGUAGE.md documents each).
pub(crate) fn paracosm_globals(builder: &mut GlobalsBuilder) {
    streams::register(builder);
    streams::register_levels(builder);
    math::register(builder);
    roads::register(builder);
    roads::register_curves_and_maps(builder);
    roads::register_junctions(builder);
    actors::register(builder);
    actors::register_cars(builder);
    actors::register_lane_changes_and_obstacles(builder);
    actors::register_pedestrians(builder);
    monitors::register(builder);
    monitors::register_stream_monitors(builder);
    monitors::register_time_to_failure(builder);
    settings::register(builder);
    constraints::register(builder);
    import::register(builder);
}
