#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! Open parameters and streams: `tick`, `Const`, `VarInterval`, `VarEnum`, `Piecewise`, `Polynomial` (paper §2, "A Family of Worlds"; §3.3).

use crate::lang::scene::Seen;
use anyhow::{anyhow, bail};
use paracosm_engine::rx::{Node, Value as Rx};
use paracosm_generators::{Domain, Value as Level};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::{Value, ValueLike};

use crate::lang::scene::ParamDecl;
use crate::lang::values::OverTime;
use crate::lang::values::{OverTimeVal, Stream};

use super::*;

use crate::lang::builtins::{named, positional, Builtin, Declares, Form};

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    Builtin {
        name: "Const",
        form: Form::Function,
        inputs: &[positional("v", "a number, a bool or a string")],
        declares: Declares::Nothing,
        takes_whole: true,
        doc: "the constant stream of a value",
    },
    Builtin {
        name: "VarInterval",
        form: Form::Function,
        inputs: &[
            positional("lo", "finite number"),
            positional("hi", "finite number"),
            named("unit", "string").or("None"),
            named("name", "string").or("where it stands"),
            named("over_time", "Piecewise(k) or Polynomial(deg)").or("None"),
        ],
        declares: Declares::Parameter,
        takes_whole: false,
        doc: "an open real parameter: the test's value in [lo, hi), or a stream of values",
    },
    Builtin {
        name: "VarEnum",
        form: Form::Function,
        inputs: &[
            positional("levels", "a list of numbers, strings or bools"),
            named("name", "string").or("where it stands"),
        ],
        declares: Declares::Parameter,
        takes_whole: false,
        doc: "an open discrete parameter: the test's level",
    },
    Builtin {
        name: "Piecewise",
        form: Form::Function,
        inputs: &[positional("k", "whole number >= 1")],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "for over_time=: a stream held constant on k equal parts of the test",
    },
    Builtin {
        name: "Polynomial",
        form: Form::Function,
        inputs: &[positional("deg", "whole number >= 1")],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "for over_time=: a Bernstein polynomial of degree deg in time",
    },
];

/// Whether `n` follows the rule for a name that keys results (a parameter's, a monitor's):
/// not empty, and only letters, digits and `_ . [ ]` (so it survives CSV columns, JUnit and
/// `report --map a,b`).
pub(crate) fn result_name_ok(n: &str) -> bool {
    !n.is_empty()
        && n.chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | '.' | '[' | ']'))
}

/// Declares an open parameter; returns what the program sees: the test's value as a plain
/// Starlark value (a float for an interval; an int, float, string or bool for a level), or,
/// for one that varies over time, its stream.
pub(super) fn declare_param<'v>(
    eval: &mut Evaluator<'v, '_, '_>,
    decl: ParamDecl,
) -> anyhow::Result<Value<'v>> {
    if let Some(n) = &decl.name {
        if !result_name_ok(n) {
            anyhow::bail!(
                "name = {n:?} is no parameter name: a name keys results.jsonl's params, the CSV \
                 columns, test(map=) and report --map a,b, so it is made of letters, digits and \
                 _ . [ ] only"
            );
        }
    }
    let heap = eval.heap();
    let st = state(eval)?;
    let seen = st.scene.borrow_mut().param(decl);
    Ok(match seen {
        Seen::Level(Level::Int(i)) => heap.alloc(i),
        Seen::Level(Level::Real(x)) => heap.alloc(x),
        Seen::Level(Level::Bool(b)) => Value::new_bool(b),
        Seen::Level(Level::Text(t)) => heap.alloc(t.as_str()),
        Seen::Stream(id) => heap.alloc(Stream::of(id.0)),
    })
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    const tick: Stream = Stream {
        id: crate::lang::scene::TICK.0,
        number: None,
    };
    /// `Const(v)`: the constant stream of `v`.
    fn Const<'v>(v: Value<'v>, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Stream> {
        let c = constant(v).ok_or_else(|| {
            anyhow!(
                "Const takes a number, a bool or a string, got {}",
                crate::lang::a_type(v.get_type())
            )
        })?;
        let number = match c {
            Rx::Num(x) => Some(x),
            _ => None,
        };
        let st = state(eval)?;
        let id = st.scene.borrow_mut().scene.push(Node::Const(c));
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
        if !(lo.is_finite() && hi.is_finite()) {
            bail!(
                "VarInterval({lo}, {hi}): both bounds must be finite numbers (a test's value is \
                 drawn from [lo, hi), which needs a finite width)"
            );
        }
        if !(hi - lo).is_finite() {
            bail!(
                "VarInterval({lo}, {hi}) is wider than a float can hold (hi - lo overflows), so \
                 no value could be drawn from it; rescale it"
            );
        }
        if lo >= hi {
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
                        "over_time must be Piecewise(k) or Polynomial(deg), got {}",
                        crate::lang::a_type(v.get_type())
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
                site: crate::scene::Site::of(&at).with_variable(super::variable_here(eval)),
            },
        )
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_levels(builder: &mut GlobalsBuilder) {
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
                    "VarEnum takes a list of levels, got {}",
                    crate::lang::a_type(levels.get_type())
                )
            })?
            .collect();
        if items.is_empty() {
            bail!("VarEnum([]) has no levels");
        }
        let mut out = Vec::new();
        // Levels seen, as hashable keys (linear in the levels, not quadratic: a VarEnum may
        // have tens of thousands). `0.0` and `-0.0` are one level, as `==` says, and so are
        // `1` and `1.0` (an int here fits in 32 bits, so its f64 is exact).
        let mut seen = std::collections::HashSet::with_capacity(items.len());
        for v in items {
            let level = if let Some(b) = v.unpack_bool() {
                Level::Bool(b)
            } else if let Some(i) = v.unpack_i32() {
                Level::Int(i64::from(i))
            } else if let Some(s) = v.unpack_str() {
                Level::Text(s.to_owned())
            } else {
                Level::Real(number(v, "a VarEnum level")?)
            };
            let key = match &level {
                Level::Bool(b) => (0u8, u64::from(*b), String::new()),
                Level::Int(i) => (
                    2,
                    if *i == 0 { 0 } else { (*i as f64).to_bits() },
                    String::new(),
                ),
                Level::Real(x) => (2, if *x == 0.0 { 0 } else { x.to_bits() }, String::new()),
                Level::Text(t) => (3, 0, t.clone()),
            };
            if !seen.insert(key) {
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
                site: crate::scene::Site::of(&at).with_variable(super::variable_here(eval)),
            },
        )
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
}
