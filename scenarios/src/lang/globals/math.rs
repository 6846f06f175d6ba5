#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! Math on numbers and positions: `abs`, `dist`, `sqrt`, `hypot`, `clamp`.

use anyhow::{anyhow, bail};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::Value;

use crate::lang::values::stream_hint;

use crate::lang::builtins::{positional, Builtin, Declares, Form};

/// A number or a vector.
const NUMBER: &str = "number";

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    Builtin {
        name: "abs",
        form: Form::Function,
        inputs: &[positional("x", "a number or a Vector")],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "the absolute value of a number, or the length of a vector",
    },
    Builtin {
        name: "dist",
        form: Form::Function,
        inputs: &[positional("a", "a position"), positional("b", "a position")],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "the distance between two positions in the ground plane, m",
    },
    Builtin {
        name: "sqrt",
        form: Form::Function,
        inputs: &[positional("x", "number >= 0")],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "the square root",
    },
    Builtin {
        name: "hypot",
        form: Form::Function,
        inputs: &[positional("x", NUMBER), positional("y", NUMBER)],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "sqrt(x² + y²) without overflow",
    },
    Builtin {
        name: "clamp",
        form: Form::Function,
        inputs: &[
            positional("x", NUMBER),
            positional("lo", NUMBER),
            positional("hi", NUMBER),
        ],
        declares: Declares::Nothing,
        takes_whole: false,
        doc: "x limited to [lo, hi]",
    },
];

/// A number argument of a math builtin.
pub(super) fn math_number(v: Value, what: &str) -> anyhow::Result<f64> {
    crate::lang::position::num(v).ok_or_else(|| {
        anyhow!(
            "{what} takes numbers, got {}{}",
            crate::lang::a_type(v.get_type()),
            stream_hint(v)
        )
    })
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `abs(x)`: the absolute value of a number, or the length of a `Vector` (a difference of
    /// positions: m). Replaces Starlark's `abs`, which takes numbers only.
    ///
    /// # Errors
    /// A location (subtract another position first), a stream or any other value.
    fn abs<'v>(
        #[starlark(require = pos)] x: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Value<'v>> {
        crate::lang::position::abs_of(x, eval.heap())
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
        crate::lang::position::dist_of(a, b)
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
}
