//! Constraints on the open parameters: `Require(lambda p: ..., name=)`.

use anyhow::{anyhow, bail};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::none::NoneType;
use starlark::values::structs::AllocStruct;
use starlark::values::Value;

use super::*;

use crate::lang::builtins::{named, positional, Builtin, Declares, Form};
use crate::scene::{ParamValue, Site};

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[Builtin {
    name: "Require",
    form: Form::Function,
    inputs: &[
        positional(
            "f",
            "a function of p, the open parameters' values, to True or False",
        ),
        named("name", "string").or("the variable, or require_N"),
    ],
    declares: Declares::Setting,
    takes_whole: false,
    doc: "a constraint on the open parameters: no test is run where f(p) is False",
}];

/// The parameters declared so far, by name, with this evaluation's values: the `p` a
/// `Require`'s function takes (a parameter that varies over time is left out: a constraint
/// is on values, not streams).
fn parameters<'v>(eval: &Evaluator<'v, '_, '_>) -> anyhow::Result<Value<'v>> {
    let st = state(eval)?;
    let b = st.scene.borrow();
    let mut fields: Vec<(String, Value<'v>)> = Vec::new();
    for k in 0..b.scene.params().len() {
        let (Some(name), Some(ParamValue::Level(l))) =
            (b.scene.param_name(k), b.scene.param_value(k))
        else {
            continue;
        };
        let heap = eval.heap();
        let v = match l {
            paracosm_generators::Value::Int(i) => heap.alloc(i),
            paracosm_generators::Value::Real(x) => heap.alloc(x),
            paracosm_generators::Value::Bool(x) => Value::new_bool(x),
            paracosm_generators::Value::Text(t) => heap.alloc(t.as_str()),
        };
        fields.retain(|(n, _)| *n != name);
        fields.push((name, v));
    }
    Ok(eval.heap().alloc(AllocStruct(fields)))
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `Require(f, name=None)`: a constraint on the open parameters. `f` takes `p`, the
    /// parameters declared so far by name (`p.speed`), and returns `True` where their values
    /// are valid. No test is run where it is `False`: every generator draws valid points
    /// only, and coverage counts the valid space. `f` must be a function of `p` alone: one
    /// that returns anything but `True` or `False` (a stream, because it read one) is refused
    /// at load, when the load checks the combinations of the parameters' values (the first
    /// evaluation, which names the parameters, records it only).
    fn Require<'v>(
        #[starlark(require = pos)] f: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let at = here(eval);
        let name = match name {
            Some(n) => n.to_owned(),
            None => super::variable_here(eval).unwrap_or_else(|| {
                let n = state(eval)
                    .map(|st| st.scene.borrow().requires.len())
                    .unwrap_or(0);
                format!("require_{n}")
            }),
        };
        {
            let st = state(eval)?;
            let mut b = st.scene.borrow_mut();
            if b.scene.params().is_empty() {
                bail!("Require `{name}`: no open parameter is declared before it to constrain");
            }
            if !b.scene.has_values() {
                // The first evaluation, with representative values, names the parameters;
                // the load's checks of the combinations call `f` with each one's values.
                if b.requires.iter().any(|(n, _)| *n == name) {
                    bail!("Require: a constraint named `{name}` is declared twice");
                }
                b.requires.push((name, Site::of(&at)));
                return Ok(NoneType);
            }
        }
        let p = parameters(eval)?;
        let got = eval.eval_function(f, &[p], &[]).map_err(|e| {
            anyhow!(
                "Require `{name}`: its function failed on the parameters' values (p holds {}): \
                 {e}",
                p.dir_attr().join(", ")
            )
        })?;
        let Some(holds) = got.unpack_bool() else {
            bail!(
                "Require `{name}`: its function returned {} ({}), not True or False: a \
                 constraint is a function of the open parameters' values (`p.speed < 10`), \
                 not of streams or of the test as it runs",
                got,
                got.get_type()
            );
        };
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        b.requires.push((name.clone(), Site::of(&at)));
        if !holds {
            let message = format!("these values break the constraint `{name}` ({at})");
            b.broken = Some(message.clone());
            bail!("{message}: no test is run on them");
        }
        Ok(NoneType)
    }
}
