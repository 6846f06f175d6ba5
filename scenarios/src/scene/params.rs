//! The open parameters of a scene (paper §2, `VarInterval` and `VarEnum`; §3.3, parameters
//! that vary over time): how each is declared and what value one test gives it.

use paracosm_engine::rx::{OpenStream, Value};
use paracosm_generators::{Domain, Value as Level};

use super::Site;

/// How an open stream varies over a test (paper §3.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OverTime {
    /// One value for the whole test.
    Constant,
    /// `Piecewise(k)`: `k` values, each held for `T / k`.
    Piecewise(usize),
    /// `Polynomial(deg)`: a Bernstein polynomial with `deg + 1` coefficients.
    Polynomial(usize),
}

/// An open parameter as declared (`VarInterval`, `VarEnum`, or a scenario file's
/// distribution).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    /// Its name in the space, if the declaration gives one.
    pub name: Option<String>,
    /// Range `[lo, hi)` or levels.
    pub domain: Domain,
    /// Its unit (`m/s`), if declared.
    pub unit: Option<String>,
    /// How it varies over a test.
    pub over_time: OverTime,
    /// Where it was declared.
    pub site: Site,
}

/// What an open parameter is in one test.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A parameter constant over the test: its value, which the scene reads as a plain
    /// number, string or bool.
    Level(Level),
    /// A parameter that varies over the test: the stream of its values.
    Over(OpenStream),
}

/// A level as a stream carries it: numbers as numbers, bools as bools, texts as strings.
pub fn level_value(l: &Level) -> Value {
    match l {
        Level::Int(i) => Value::Num(*i as f64),
        Level::Real(x) => Value::Num(*x),
        Level::Bool(b) => Value::Bool(*b),
        Level::Text(t) => Value::Text(t.clone()),
    }
}

/// The value a parameter takes when a test gives it none: an interval's lower bound, the
/// first level (constant over time, or the same for every coefficient over time);
/// `horizon_s` is the test's length, s.
pub fn representative(decl: &ParamDecl, horizon_s: f64) -> ParamValue {
    let lowest = match &decl.domain {
        Domain::Interval { lo, .. } => Level::Real(*lo),
        Domain::Levels(levels) => levels[0].clone(),
    };
    match decl.over_time {
        OverTime::Constant => ParamValue::Level(lowest),
        over => {
            let lo = lowest.as_f64().unwrap_or(0.0);
            let n = coordinate_names("p", over).len();
            ParamValue::Over(match over {
                OverTime::Piecewise(_) => OpenStream::Piecewise {
                    values: vec![lo; n],
                    horizon_s,
                },
                _ => OpenStream::Polynomial {
                    coefficients: vec![lo; n],
                    horizon_s,
                },
            })
        }
    }
}

/// The names of the coordinates a parameter called `name` adds to the space: itself when
/// constant, `name[i]` for `k` pieces, `name.ci` for a polynomial's coefficients.
pub fn coordinate_names(name: &str, over_time: OverTime) -> Vec<String> {
    match over_time {
        OverTime::Constant => vec![name.to_owned()],
        OverTime::Piecewise(k) => (0..k).map(|i| format!("{name}[{i}]")).collect(),
        OverTime::Polynomial(d) => (0..=d).map(|i| format!("{name}.c{i}")).collect(),
    }
}

/// The values one test gives a scenario's open parameters, bound by name as each parameter is
/// declared ([`super::Scene::declare_param`]): one way for every front end.
///
/// A parameter is named by its declaration (`name=`, a scenario file's parameter) or, for one
/// that takes its name from where it stands (a program's `x = VarInterval(...)`, or the
/// `param3` of one assigned to nothing), by the names the front end learnt from its first
/// evaluation ([`GivenValues::standing`]). A parameter without a name, or one whose name
/// the values lack, takes its [`representative`] value, so that the front end goes on and
/// reports the mismatch, naming the parameter.
#[derive(Debug, Clone, Default)]
pub struct GivenValues {
    values: std::collections::BTreeMap<String, ParamValue>,
    standing: Option<std::sync::Arc<[(Site, String)]>>,
}

impl GivenValues {
    /// Values by name; a name given twice keeps its last value.
    pub fn new(values: impl IntoIterator<Item = (String, ParamValue)>) -> Self {
        GivenValues {
            values: values.into_iter().collect(),
            standing: None,
        }
    }

    /// The values of a generator's assignment, each a constant level
    /// ([`ParamValue::Level`]); a parameter that varies over time finds none here and takes
    /// its representative value.
    pub fn of_assignment(assignment: &paracosm_generators::Assignment) -> Self {
        Self::new(
            assignment
                .iter()
                .map(|(n, v)| (n.to_owned(), ParamValue::Level(v.clone()))),
        )
    }

    /// These values, for parameters whose declarations give no name: the parameter declared
    /// `k`-th is named `standing[k].1` when it is declared at `standing[k].0`.
    pub fn standing(mut self, standing: std::sync::Arc<[(Site, String)]>) -> Self {
        self.standing = Some(standing);
        self
    }

    /// The name of `decl`, declared `k`-th: its own, else the one it stands under.
    pub fn name_of<'a>(&'a self, decl: &'a ParamDecl, k: usize) -> Option<&'a str> {
        decl.name.as_deref().or_else(|| {
            let (site, name) = self.standing.as_deref()?.get(k)?;
            (*site == decl.site).then_some(name.as_str())
        })
    }

    /// The value `decl`, declared `k`-th, takes: the one given under its name when it is of
    /// the declaration's kind (a level for a constant, a stream for one over time).
    pub fn value_of(&self, decl: &ParamDecl, k: usize) -> Option<&ParamValue> {
        let v = self.values.get(self.name_of(decl, k)?)?;
        let constant = decl.over_time == OverTime::Constant;
        (matches!(v, ParamValue::Level(_)) == constant).then_some(v)
    }
}
