#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! The test's settings: `test(horizon=, map=, offroad=)`.

use anyhow::bail;
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::list::UnpackList;
use starlark::values::none::NoneType;
use starlark::values::{UnpackValue, Value};

use super::*;

use crate::lang::builtins::{named, Builtin, Declares, Form};

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[Builtin {
    name: "test",
    form: Form::Function,
    inputs: &[
        named("horizon", "number, s, in (0, 3600]").or("15.0"),
        named("map", "one or two parameter names: the failure map's axes").or("None"),
        named("offroad", "bool: add the default OffRoadMonitor").or("True"),
    ],
    declares: Declares::Setting,
    takes_whole: true,
    doc: "the test's length, the failure map's axes and the default off-road monitor",
}];

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `test(horizon=15.0, map=None, offroad=True)`: the test length in seconds, the failure
    /// map's axes (one or two parameter names), and whether the default `OffRoadMonitor` is
    /// added to a program that declares none. Called at most once: a second call is an error
    /// naming the first.
    fn test<'v>(
        #[starlark(require = named)] horizon: Option<Value<'v>>,
        #[starlark(require = named)] map: Option<Value<'v>>,
        #[starlark(require = named)] offroad: Option<bool>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if let Some(first) = &b.scene.settings().site {
            // A second call would silently replace the first one's horizon and map.
            bail!("test(...) is called once per program; it was already called at {first}");
        }
        let mut settings = crate::scene::TestSettings {
            site: Some(crate::scene::Site::of(&here(eval))),
            ..Default::default()
        };
        if let Some(h) = horizon {
            let h = number(h, "horizon")?;
            if !(h.is_finite() && h > 0.0 && h <= 3600.0) {
                bail!("horizon {h} s must be in (0, 3600]");
            }
            settings.horizon_s = Some(h);
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
            settings.map_axes = Some(axes);
        }
        settings.offroad = offroad;
        b.scene.set_settings(settings).map_err(|e| anyhow!("{e}"))?;
        Ok(NoneType)
    }
}
