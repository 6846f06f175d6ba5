//! The one list of the language's builtins: each road piece, actor, monitor, parameter,
//! action, stream method, math function and setting is described once, by a [`Builtin`]
//! spec kept in the file that registers its function (`globals/*.rs`, `methods.rs`). Every
//! other description is derived from it: the keywords "did you mean" offers, the builtins
//! whose arguments the syntax walk follows ([`super::names::Syntax`]), the parameter
//! declarers, the unit and range of each numeric input ([`input_of`]) and the table of
//! LANGUAGE.md's "Builtins at a glance" ([`markdown_table`]). A test fails when a registered
//! function has no spec, a spec names no function, or LANGUAGE.md's table is stale.

use super::types::Input;
#[cfg(test)]
use super::types::Kind;

/// How a program calls a builtin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// A global function: `Car(...)`.
    Function,
    /// A method of a value of the named type: `r.onLane(...)` on a road piece.
    Method(&'static str),
    /// An action of an actor, given to `foreach` or called in a `def` (`car.brake(6)`).
    Action(&'static str),
}

/// What calling a builtin adds to the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Declares {
    /// Nothing: it computes a value or a stream.
    Nothing,
    /// An open parameter, a dimension of the test space.
    Parameter,
    /// A road piece.
    RoadPiece,
    /// An actor (the ego vehicle, a car, a pedestrian, an obstacle) or the world.
    Actor,
    /// A monitor, which judges each test.
    Monitor,
    /// A setting of the test (its horizon, the failure map's axes) or a published signal.
    Setting,
}

#[cfg(test)]
impl Declares {
    fn words(self) -> &'static str {
        match self {
            Declares::Nothing => "",
            Declares::Parameter => "an open parameter",
            Declares::RoadPiece => "a road piece",
            Declares::Actor => "an actor",
            Declares::Monitor => "a monitor",
            Declares::Setting => "a setting",
        }
    }
}

/// One input of a builtin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arg {
    /// Its keyword (or, for a positional input, the name LANGUAGE.md gives it).
    pub keyword: &'static str,
    /// Whether it is given by position (`VarInterval(lo, hi)`) rather than by keyword.
    pub positional: bool,
    /// What it accepts, in words (`"a location from onLane"`, `"number"`).
    pub accepts: &'static str,
    /// Its unit and range when it is a number checked at load ([`input_of`]).
    pub input: Option<Input>,
    /// Its default as a program would write it; `None` when it is required.
    pub default: Option<&'static str>,
    /// Whether [`Arg::input`] is the unit and range of each item of a tuple (`Obstacle(size =
    /// (l, w, h))`, looked up as `size[0]`...) rather than of the input itself.
    pub items: bool,
}

/// A required input given by keyword.
pub const fn named(keyword: &'static str, accepts: &'static str) -> Arg {
    Arg {
        keyword,
        positional: false,
        accepts,
        input: None,
        default: None,
        items: false,
    }
}

/// A required input given by position.
pub const fn positional(keyword: &'static str, accepts: &'static str) -> Arg {
    Arg {
        keyword,
        positional: true,
        accepts,
        input: None,
        default: None,
        items: false,
    }
}

impl Arg {
    /// The same input with a default (so optional).
    pub const fn or(self, default: &'static str) -> Arg {
        Arg {
            default: Some(default),
            ..self
        }
    }

    /// The same input with its unit and range checked at load.
    pub const fn checked(self, input: Input) -> Arg {
        Arg {
            input: Some(input),
            ..self
        }
    }

    /// The same input, a tuple each of whose items has `input`'s unit and range.
    pub const fn each(self, input: Input) -> Arg {
        Arg {
            input: Some(input),
            items: true,
            ..self
        }
    }
}

/// A builtin of the language: its name, how it is called, its inputs, what it declares and
/// its one-line doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Builtin {
    /// The name a program calls it by.
    pub name: &'static str,
    /// How it is called.
    pub form: Form,
    /// Its inputs, in order.
    pub inputs: &'static [Arg],
    /// What a call adds to the scene.
    pub declares: Declares,
    /// Whether its arguments are taken whole by the scene (a variable passed to it is an
    /// input of the world, not read by code): the syntax walk names parameters after such
    /// arguments (`Car(speed = v)`: `v` feeds `Car.speed`). Functions that compute
    /// (`abs`, `map`, `Monitor`) do not.
    pub takes_whole: bool,
    /// One line on what it does.
    pub doc: &'static str,
}

/// Every builtin, by topic: the streams and parameters, math, roads, actors, monitors,
/// settings and the methods and actions of values.
pub fn all() -> impl Iterator<Item = &'static Builtin> {
    [
        super::globals::streams::SPECS,
        super::globals::math::SPECS,
        super::globals::roads::SPECS,
        super::globals::actors::SPECS,
        super::globals::monitors::SPECS,
        super::globals::settings::SPECS,
        super::globals::constraints::SPECS,
        super::globals::import::SPECS,
        super::methods::SPECS,
    ]
    .into_iter()
    .flatten()
}

/// The builtin called `name` (a function, a method or an action).
pub fn find(name: &str) -> Option<&'static Builtin> {
    all().find(|b| b.name == name)
}

/// The keywords `name` takes by keyword, for "did you mean" (none for an unknown name).
pub fn keywords(name: &str) -> impl Iterator<Item = &'static str> + '_ {
    all()
        .filter(move |b| b.name == name)
        .flat_map(|b| b.inputs.iter().filter(|a| !a.positional).map(|a| a.keyword))
}

/// The builtins whose arguments the syntax walk follows ([`Builtin::takes_whole`]).
pub fn taking_whole() -> Vec<&'static str> {
    let mut names: Vec<&str> = all().filter(|b| b.takes_whole).map(|b| b.name).collect();
    names.dedup();
    names
}

/// Whether `name` declares an open parameter (`VarInterval`, `VarEnum`).
pub fn declares_parameter(name: &str) -> bool {
    all().any(|b| b.name == name && b.declares == Declares::Parameter)
}

/// `builtin(keyword=)`'s input, for the inputs that take numbers with a unit or a range (to
/// check the unit a parameter declares). `keyword` may name an item of a tuple input
/// (`size[0]`).
pub fn input_of(builtin: &str, keyword: &str) -> Option<Input> {
    let (key, item) = match keyword.split_once('[') {
        Some((key, _)) => (key, true),
        None => (keyword, false),
    };
    all()
        .filter(|b| b.name == builtin)
        .flat_map(|b| b.inputs)
        .find(|a| a.keyword == key && a.items == item)
        .and_then(|a| a.input)
}

#[cfg(test)]
/// A number's unit and range, as LANGUAGE.md writes them (`m/s, >= 0`; `[0, 1]`).
fn range_words(input: &Input) -> String {
    let Kind::Number {
        unit,
        min,
        max,
        min_open,
    } = input.kind
    else {
        return String::new();
    };
    let open = if min_open { "(" } else { "[" };
    let range = if max.is_infinite() {
        format!("{} {min}", if min_open { ">" } else { ">=" })
    } else {
        format!("{open}{min}, {max}]")
    };
    if unit.is_empty() {
        range
    } else {
        format!("{unit}, {range}")
    }
}

#[cfg(test)]
/// The table of every builtin, as LANGUAGE.md's "Builtins at a glance" shows it (Markdown,
/// one row a builtin, generated from [`all`]).
pub fn markdown_table() -> String {
    let mut out = String::from(
        "| builtin | inputs (unit, range; default) | declares | what it does |\n|---|---|---|---|\n",
    );
    for b in all() {
        let call = match b.form {
            Form::Function => format!("`{}`", b.name),
            Form::Method(on) => format!("`{on}.{}`", b.name),
            Form::Action(on) => format!("`{on}.{}` (action)", b.name),
        };
        let inputs: Vec<String> = b
            .inputs
            .iter()
            .map(|a| {
                let key = if a.positional {
                    format!("`{}`", a.keyword)
                } else {
                    format!("`{}=`", a.keyword)
                };
                let mut range = a.input.as_ref().map(range_words).unwrap_or_default();
                if a.items && !range.is_empty() {
                    range = format!("each {range}");
                }
                let what = [a.accepts, range.as_str()]
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect::<Vec<_>>()
                    .join(", ");
                match a.default {
                    Some(d) => format!("{key} {what}; `{d}`"),
                    None => format!("{key} {what}"),
                }
            })
            .collect();
        let inputs = if inputs.is_empty() {
            "—".to_owned()
        } else {
            inputs.join("<br>")
        };
        out.push_str(&format!(
            "| {call} | {} | {} | {} |\n",
            inputs.replace('|', "\\|"),
            b.declares.words(),
            b.doc.replace('|', "\\|")
        ));
    }
    out
}

#[cfg(test)]
/// Where LANGUAGE.md's generated table begins and ends.
pub const TABLE_MARKERS: (&str, &str) = (
    "<!-- builtins table: generated from scenarios/src/lang/builtins.rs; do not edit -->",
    "<!-- end of the builtins table -->",
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every function a program can call has a spec, and every spec names one.
    #[test]
    fn every_registered_function_has_one_spec_and_every_spec_a_function() {
        let globals = starlark::environment::GlobalsBuilder::new()
            .with(super::super::globals::paracosm_globals)
            .build();
        // Constants (`tick`, `SideWalk`) are values, not functions.
        let registered: Vec<String> = globals
            .iter()
            .filter(|(_, v)| v.to_value().get_type() == "function")
            .map(|(n, _)| n.to_owned())
            .collect();
        assert!(registered.len() >= 30, "functions found: {registered:?}");
        let functions: Vec<&str> = all()
            .filter(|b| b.form == Form::Function)
            .map(|b| b.name)
            .collect();
        for name in &registered {
            assert!(
                functions.contains(&name.as_str()),
                "`{name}` is registered but has no spec in the file that registers it"
            );
        }
        for name in &functions {
            assert!(
                registered.iter().any(|r| r == name),
                "`{name}` has a spec but no registered function"
            );
            assert_eq!(
                all().filter(|b| b.name == *name).count(),
                1,
                "`{name}` has two specs"
            );
        }
    }

    /// The methods and actions a program can call on a value have a spec each.
    #[test]
    fn every_method_and_action_has_a_spec() {
        let methods = super::super::methods::registered_names();
        assert!(methods.len() >= 14, "methods found: {methods:?}");
        for name in &methods {
            assert!(
                all().any(|b| b.name == *name && b.form != Form::Function),
                "method `{name}` has no spec"
            );
        }
        for b in all().filter(|b| matches!(b.form, Form::Method(_))) {
            assert!(
                methods.contains(&b.name),
                "`{}` has a method spec but is not a method",
                b.name
            );
        }
    }

    /// LANGUAGE.md's table is the one the specs generate (`PARACOSM_BLESS=1` rewrites it).
    #[test]
    fn languages_table_of_builtins_is_generated_from_the_specs() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../LANGUAGE.md");
        let text = std::fs::read_to_string(&path).expect("LANGUAGE.md");
        let (begin, end) = TABLE_MARKERS;
        let (Some(a), Some(b)) = (text.find(begin), text.find(end)) else {
            panic!("LANGUAGE.md has no generated builtins table (markers `{begin}`)");
        };
        let current = &text[a + begin.len()..b];
        let wanted = format!("\n{}", markdown_table());
        if current != wanted {
            if std::env::var_os("PARACOSM_BLESS").is_some() {
                let new = format!("{}{wanted}{}", &text[..a + begin.len()], &text[b..]);
                std::fs::write(&path, new).expect("write LANGUAGE.md");
            } else {
                panic!(
                    "LANGUAGE.md's builtins table is stale: rerun this test with \
                     PARACOSM_BLESS=1 to regenerate it from the specs"
                );
            }
        }
    }

    /// The derived lists agree with what the language does.
    #[test]
    fn derived_lists_match_the_specs() {
        assert!(declares_parameter("VarInterval") && declares_parameter("VarEnum"));
        assert!(!declares_parameter("Car"));
        assert!(keywords("Monitor").any(|k| k == "name"));
        assert!(keywords("Assert").any(|k| k == "name"));
        assert!(input_of("Obstacle", "size[2]").is_some());
        assert!(input_of("Obstacle", "size").is_none());
        assert!(input_of("Car", "loc").is_none());
        assert!(taking_whole().contains(&"Car") && !taking_whole().contains(&"abs"));
    }
}
