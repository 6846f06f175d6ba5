#![allow(non_snake_case)] // The builtins' names are the language's: `Import`.

//! `Import("scenario.xosc", params = {...})`: an OpenSCENARIO scenario's world in a program
//! (its map, its entities where `Init` puts them, its storyboard moving every entity but the
//! ego), so that a companion program adds monitors, signals and open parameters to a
//! scenario the industry wrote (issue "The industry's logical scenarios as campaigns").

use std::sync::Arc;

use anyhow::{anyhow, bail};
use paracosm_engine::behaviour::Output;
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::dict::{AllocDict, DictRef};
use starlark::values::structs::AllocStruct;
use starlark::values::{Heap, Value};

use super::*;

use crate::lang::builtins::{named, positional, Builtin, Declares, Form};
use crate::lang::values::ActorVal;

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[Builtin {
    name: "Import",
    form: Form::Function,
    inputs: &[
        positional(
            "path",
            "string: an OpenSCENARIO scenario (.xosc with a Storyboard), relative to the program",
        ),
        named(
            "params",
            "dict: a declared parameter's name -> its value (a number, string or bool, or an \
             open parameter constant over time)",
        )
        .or("{}"),
        named(
            "ego",
            "string: the vehicle the system under test drives, when the file does not say \
             plainly (none named Ego or hero, no controller activated, several vehicles)",
        )
        .or("None"),
    ],
    declares: Declares::Actor,
    takes_whole: true,
    doc: "an OpenSCENARIO scenario's map, entities and storyboard; returns its entities and \
          parameters",
}];

/// The `ActorVal::object` of an imported entity: its scenario places it, not `place(...)`.
pub(crate) const IMPORTED: usize = usize::MAX;

/// Names a returned struct holds besides the entities'.
const RESERVED: [&str; 3] = ["entities", "params", "ego"];

/// The builtins of this topic.
#[starlark_module]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `Import(path, params = {})`: builds the OpenSCENARIO scenario at `path` (relative to
    /// the program) into this world, with `params` overriding its declared parameters (each
    /// checked against the file's declarations and constraint groups). Returns a struct: each
    /// entity by its name (`s.TargetBlocking`), `s.ego` (the entity the system under test
    /// drives), `s.entities` (name -> actor, for any name) and `s.params` (name -> the value
    /// each declared parameter has in this test, as the file's text).
    fn Import<'v>(
        #[starlark(require = pos)] path: &str,
        #[starlark(require = named)] params: Option<Value<'v>>,
        #[starlark(require = named)] ego: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Value<'v>> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.story.is_some() {
            bail!("Import(...) is called once per program: a scenario brings its own ego");
        }
        let Some(file) = st.maps.resolve(path) else {
            bail!("a built-in scenario cannot Import a file");
        };
        let file = std::fs::canonicalize(&file).map_err(|e| {
            anyhow!(
                "cannot read the OpenSCENARIO scenario {}: {e}",
                file.display()
            )
        })?;
        let overrides = overrides(params, &b)?;
        let model = paracosm_openscenario::read_scenario_in(&st.maps.xosc, &file, &overrides)
            .map_err(|e| anyhow!("{e}"))?;
        let sets = crate::xosc::environment_sets(&model);
        if sets.light || sets.fog {
            bail!(
                "{}: an EnvironmentAction of this scenario sets the world's light or fog, \
                 which the program's World(...) gives: run the file itself (paracosm-fuzz \
                 FILE), or leave the light and fog to the program",
                model.file
            );
        }
        let ego = crate::xosc::ego_of(&model, ego, false).map_err(|e| anyhow!("{e}"))?;
        let warnings = crate::xosc::check(&model, Some(ego)).map_err(|e| anyhow!("{e}"))?;
        b.warnings.extend(warnings);
        let warnings = crate::xosc::check_presence(&model, ego).map_err(|e| anyhow!("{e}"))?;
        b.warnings.extend(warnings);
        let built = crate::xosc::build_into(
            &mut b.scene,
            &model,
            &st.maps,
            (ego, false),
            crate::xosc::IMPORT_HOST_BASE,
        )
        .map_err(|e| anyhow!("{e}"))?;
        // The values the storyboard reads are in no other input of the world: the scene
        // keeps the scenario as resolved with them, which the load compares between tests.
        let model = Arc::new(model);
        b.scene
            .set_host_inputs(Arc::new(crate::xosc::StoryInputs(model.clone())));
        let actors: Vec<(String, ActorVal)> = built
            .actors
            .iter()
            .map(|(name, actor)| {
                let outputs = Output::ALL.map(|o| b.probe(*actor, o).0);
                (
                    name.clone(),
                    ActorVal {
                        kind: *actor,
                        outputs,
                        object: IMPORTED,
                    },
                )
            })
            .collect();
        b.story = Some(crate::lang::scene::ImportedStory(built.host));
        drop(b);
        Ok(returned(eval.heap(), &actors, ego, &model))
    }
}

/// `Import`'s struct: the entities by name, `ego`, `entities` and `params`.
fn returned<'v>(
    heap: Heap<'v>,
    actors: &[(String, ActorVal)],
    ego: usize,
    model: &paracosm_openscenario::model::Scenario,
) -> Value<'v> {
    let entities = heap.alloc(AllocDict(
        actors
            .iter()
            .map(|(n, a)| (n.clone(), heap.alloc(*a)))
            .collect::<Vec<_>>(),
    ));
    let params = heap.alloc(AllocDict(
        model
            .params
            .iter()
            .map(|(d, v)| (d.name.clone(), v.to_text()))
            .collect::<Vec<_>>(),
    ));
    let mut fields: Vec<(String, Value<'v>)> = vec![
        ("entities".into(), entities),
        ("params".into(), params),
        ("ego".into(), heap.alloc(actors[ego].1)),
    ];
    fields.extend(
        actors
            .iter()
            .filter(|(n, _)| !RESERVED.contains(&n.as_str()))
            .map(|(n, a)| (n.clone(), heap.alloc(*a))),
    );
    heap.alloc(AllocStruct(fields))
}

/// `params` as OpenSCENARIO overrides `(name, typed value)`: numbers, strings (taken as they
/// are, never evaluated: `"$x"` is that text) and bools; an open parameter constant over time
/// is its value in this evaluation. The file coerces each to its declared type.
///
/// # Errors
/// A value that is not a dict of strings to numbers, strings or bools (a stream, which has no
/// one value for the file, included).
fn overrides(
    params: Option<Value>,
    b: &SceneBuilder,
) -> anyhow::Result<Vec<(String, paracosm_openscenario::Value)>> {
    let Some(params) = params.filter(|p| !p.is_none()) else {
        return Ok(Vec::new());
    };
    let dict = DictRef::from_value(params).ok_or_else(|| {
        anyhow!(
            "Import(params=) takes a dict of parameter names to values, got {}",
            crate::lang::a_type(params.get_type())
        )
    })?;
    let mut out = Vec::new();
    for (k, v) in dict.iter() {
        let Some(name) = k.unpack_str() else {
            bail!("Import(params=): a parameter's name is a string, got {k}");
        };
        let value = if let Some(t) = text_value(v, b) {
            paracosm_openscenario::Value::Str(t)
        } else if let Some(x) = v.unpack_bool() {
            paracosm_openscenario::Value::Bool(x)
        } else {
            let x = load_time_number(v, b, &format!("Import(params=) {name:?}")).map_err(|_| {
                anyhow!(
                    "Import(params=) {name:?} takes a number, a string, a bool or an open \
                         parameter constant over time (the file reads one value per test), \
                         got {}",
                    crate::lang::a_type(v.get_type())
                )
            })?;
            paracosm_openscenario::Value::Num(x)
        };
        out.push((name.to_owned(), value));
    }
    Ok(out)
}
