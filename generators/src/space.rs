use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize, Serializer};

use crate::{GeneratorError, Point};

/// A value of a parameter, in the parameter's unit.
///
/// In JSON an integer (`3`), a real (`0.4`, `3.0`), a bool (`true`) or a text (`"red"`); a
/// number written with a fraction or an exponent reads back as [`Value::Real`], one without
/// as [`Value::Int`]. A text level `"true"` stays a text.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// An integer level, e.g. a lane count.
    Int(i64),
    /// A real number, e.g. a speed in m/s.
    Real(f64),
    /// A truth value, e.g. whether an oncoming car is there.
    Bool(bool),
    /// A named level, e.g. a colour.
    Text(String),
}

/// Read through `serde_json::Value`, not derived: the workspace's serde_json has
/// `arbitrary_precision` (starlark turns it on), under which a derived untagged enum sees a
/// number as a map and matches no variant (`tests/read_back.rs`).
impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::Number(n) => match (n.as_i64(), n.as_f64()) {
                (Some(i), _) => Ok(Value::Int(i)),
                (None, Some(x)) => Ok(Value::Real(x)),
                (None, None) => Err(D::Error::custom(format!("{n} is not a finite number"))),
            },
            serde_json::Value::String(s) => Ok(Value::Text(s)),
            serde_json::Value::Bool(b) => Ok(Value::Bool(b)),
            other => Err(D::Error::custom(format!(
                "a parameter's value is a number, a bool or a text, not `{other}`"
            ))),
        }
    }
}

impl Value {
    /// The value as `f64`: reals as they are, integers converted, bools and text `None`.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Real(x) => Some(*x),
            Value::Int(i) => Some(*i as f64),
            Value::Bool(_) | Value::Text(_) => None,
        }
    }
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Int(i) => write!(f, "{i}"),
            Value::Bool(b) => write!(f, "{b}"),
            Value::Real(x) => write!(f, "{x}"),
            Value::Text(s) => write!(f, "{s}"),
        }
    }
}

/// The range of an open input stream (paper §2, "A Family of Worlds").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Domain {
    /// `VarInterval(lo, hi)`: a real interval; points map onto `[lo, hi)`.
    Interval {
        /// Lower bound, inclusive, in the parameter's unit.
        lo: f64,
        /// Upper bound, exclusive for sampled points, in the parameter's unit.
        hi: f64,
    },
    /// `VarEnum([...])`: a finite set of levels, indexed `0..len` in the given order.
    Levels(Vec<Value>),
}

/// One open parameter: a name, a domain and an optional unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Param {
    /// Unique name, used in results files and plots, e.g. `ped_speed`.
    pub name: String,
    /// The values the parameter may take.
    pub domain: Domain,
    /// Unit of the values (`m`, `m/s`, ...), `None` for unitless levels.
    pub unit: Option<String>,
    /// Where its values are likely, for random sampling ([`crate::UniformRandom`]); `None`:
    /// uniform over the domain. Coverage generators ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<crate::Density>,
}

impl Param {
    /// A `VarInterval(lo, hi)` parameter with a unit.
    pub fn interval(name: &str, lo: f64, hi: f64, unit: &str) -> Self {
        Param {
            name: name.to_owned(),
            domain: Domain::Interval { lo, hi },
            unit: Some(unit.to_owned()),
            density: None,
        }
    }

    /// A `VarEnum([...])` parameter.
    pub fn levels(name: &str, levels: Vec<Value>) -> Self {
        Param {
            name: name.to_owned(),
            domain: Domain::Levels(levels),
            unit: None,
            density: None,
        }
    }

    /// `"name [unit]"`, or the bare name when unitless: an axis label.
    pub fn label(&self) -> String {
        match &self.unit {
            Some(u) if !u.is_empty() => format!("{} [{u}]", self.name),
            _ => self.name.clone(),
        }
    }
}

/// The space of open parameters of a scenario. Declaration order is the coordinate order:
/// the `j`-th continuous parameter is `Point::continuous[j]`, the `j`-th discrete one is
/// `Point::discrete[j]`.
///
/// A space may carry constraints ([`ParamSpace::with_constraints`]): its valid region is
/// where they all hold. They are not serialised (a space read back from JSON has none), and
/// two spaces are equal when their parameters and their constraints' names are.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ParamSpace {
    params: Vec<Param>,
    #[serde(skip)]
    pub(crate) rules: std::sync::Arc<crate::constraint::Rules>,
}

impl PartialEq for ParamSpace {
    fn eq(&self, other: &Self) -> bool {
        let names = |s: &ParamSpace| -> Vec<String> {
            s.constraints()
                .iter()
                .map(|c| c.name().to_owned())
                .collect()
        };
        self.params == other.params && names(self) == names(other)
    }
}

impl ParamSpace {
    /// Builds a space, checking it.
    ///
    /// # Errors
    /// [`GeneratorError::InvalidDomain`] for an interval with `lo >= hi`, a non-finite bound
    /// or a width `hi - lo` that overflows, an empty level list, or a density that does not
    /// fit its parameter ([`crate::Density::check`]); [`GeneratorError::DuplicateParam`] for a
    /// repeated name.
    pub fn new(params: Vec<Param>) -> Result<Self, GeneratorError> {
        // Linear, not quadratic: a CSV may have a million columns.
        let mut names = std::collections::HashSet::with_capacity(params.len());
        for p in params.iter() {
            if !names.insert(p.name.as_str()) {
                return Err(GeneratorError::DuplicateParam(p.name.clone()));
            }
            let bad = |reason: String| GeneratorError::InvalidDomain {
                name: p.name.clone(),
                reason,
            };
            match &p.domain {
                Domain::Interval { lo, hi } => {
                    if !lo.is_finite() || !hi.is_finite() || lo >= hi {
                        return Err(bad(format!("interval [{lo}, {hi}] is empty or not finite")));
                    }
                    if !(hi - lo).is_finite() {
                        // Unit coordinates map through `hi - lo`: every point would decode to
                        // an infinity and every estimate would be meaningless.
                        return Err(bad(format!(
                            "interval [{lo}, {hi}] is wider than a float can hold (hi - lo \
                             overflows); rescale it (for example to a unit of 1e300)"
                        )));
                    }
                }
                Domain::Levels(levels) if levels.is_empty() => {
                    return Err(bad("VarEnum has no levels".into()))
                }
                Domain::Levels(_) => {}
            }
            if let Some(d) = &p.density {
                let (interval, levels) = match &p.domain {
                    Domain::Interval { lo, hi } => (Some((*lo, *hi)), None),
                    Domain::Levels(l) => (None, Some(l.len())),
                };
                if let Some(reason) = d.check(interval, levels) {
                    return Err(bad(reason));
                }
            }
        }
        Ok(ParamSpace {
            params,
            rules: Default::default(),
        })
    }

    /// The unit cube `[0, 1)^d` as a space: continuous parameters `x0 .. x{d-1}`, unit `1`.
    /// Handy for using the generators and estimators on bare point sets.
    pub fn unit_cube(d: usize) -> Self {
        ParamSpace {
            params: (0..d)
                .map(|i| Param::interval(&format!("x{i}"), 0.0, 1.0, "1"))
                .collect(),
            rules: Default::default(),
        }
    }

    /// All parameters in declaration order.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// The parameter called `name`, if any.
    pub fn param(&self, name: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.name == name)
    }

    /// The continuous parameters in coordinate order.
    pub fn continuous(&self) -> impl Iterator<Item = &Param> {
        self.params
            .iter()
            .filter(|p| matches!(p.domain, Domain::Interval { .. }))
    }

    /// The discrete parameters in coordinate order.
    pub fn discrete(&self) -> impl Iterator<Item = &Param> {
        self.params
            .iter()
            .filter(|p| matches!(p.domain, Domain::Levels(_)))
    }

    /// Number of continuous coordinates `N_C`.
    pub fn continuous_dims(&self) -> usize {
        self.continuous().count()
    }

    /// Level counts of the discrete parameters, in coordinate order (length `N_D`).
    pub fn level_counts(&self) -> Vec<u32> {
        self.params
            .iter()
            .filter_map(|p| match &p.domain {
                Domain::Levels(l) => Some(l.len() as u32),
                Domain::Interval { .. } => None,
            })
            .collect()
    }

    /// Per parameter in declaration order: `None` for a continuous parameter, `Some(L)` for a
    /// discrete one with `L` levels. Generators walk this to fill a [`Point`].
    pub fn layout(&self) -> Vec<Option<u32>> {
        self.params
            .iter()
            .map(|p| match &p.domain {
                Domain::Levels(l) => Some(l.len() as u32),
                Domain::Interval { .. } => None,
            })
            .collect()
    }

    /// Maps a point to named values in the parameters' units, in declaration order.
    /// A continuous coordinate `u` becomes `lo + u (hi - lo)`; a level index selects its level.
    ///
    /// # Errors
    /// [`GeneratorError::PointMismatch`] when the point has the wrong number of coordinates,
    /// a continuous coordinate outside `[0, 1)`, or a level index out of range.
    pub fn decode(&self, point: &Point) -> Result<Assignment, GeneratorError> {
        let nc = self.continuous_dims();
        let nd = self.params.len() - nc;
        if point.continuous.len() != nc || point.discrete.len() != nd {
            return Err(GeneratorError::PointMismatch(format!(
                "expected {nc} continuous and {nd} discrete coordinates, got {} and {}",
                point.continuous.len(),
                point.discrete.len()
            )));
        }
        let (mut ci, mut di) = (0, 0);
        let mut values = Vec::with_capacity(self.params.len());
        for p in &self.params {
            let v = match &p.domain {
                Domain::Interval { lo, hi } => {
                    let u = point.continuous[ci];
                    ci += 1;
                    if !(0.0..1.0).contains(&u) {
                        return Err(GeneratorError::PointMismatch(format!(
                            "coordinate {u} of `{}` is outside [0, 1)",
                            p.name
                        )));
                    }
                    Value::Real(lo + u * (hi - lo))
                }
                Domain::Levels(levels) => {
                    let k = point.discrete[di] as usize;
                    di += 1;
                    levels.get(k).cloned().ok_or_else(|| {
                        GeneratorError::PointMismatch(format!(
                            "level index {k} of `{}` is out of range 0..{}",
                            p.name,
                            levels.len()
                        ))
                    })?
                }
            };
            values.push((p.name.clone(), v));
        }
        Ok(Assignment { values })
    }
}

/// Named parameter values in the parameters' units, in declaration order. Serialises as a
/// JSON object whose keys keep that order.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    values: Vec<(String, Value)>,
}

impl Assignment {
    /// The value of `name`, if the assignment has it.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.values.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// The real value of `name` (integers converted), if present and numeric.
    pub fn real(&self, name: &str) -> Option<f64> {
        self.get(name).and_then(Value::as_f64)
    }

    /// `(name, value)` pairs in declaration order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.values.iter().map(|(n, v)| (n.as_str(), v))
    }
}

impl Serialize for Assignment {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.values.len()))?;
        for (n, v) in &self.values {
            map.serialize_entry(n, v)?;
        }
        map.end()
    }
}

/// Reads the object [`Assignment`]'s `Serialize` writes, keeping the keys' order.
impl<'de> Deserialize<'de> for Assignment {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Ordered;
        impl<'de> serde::de::Visitor<'de> for Ordered {
            type Value = Assignment;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of parameter values")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Assignment, A::Error> {
                let mut values = Vec::new();
                while let Some(entry) = map.next_entry::<String, Value>()? {
                    values.push(entry);
                }
                Ok(Assignment { values })
            }
        }
        d.deserialize_map(Ordered)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::interval("speed", 0.5, 10.0, "m/s"),
            Param::levels("lanes", vec![Value::Int(2), Value::Int(4)]),
            Param::interval("dist", 5.0, 60.0, "m"),
        ])
        .unwrap()
    }

    #[test]
    fn decode_maps_unit_coordinates_onto_intervals_and_levels() {
        let a = space()
            .decode(&Point {
                discrete: vec![1],
                continuous: vec![0.0, 0.5],
            })
            .unwrap();
        assert_eq!(a.real("speed"), Some(0.5));
        assert_eq!(a.get("lanes"), Some(&Value::Int(4)));
        assert_eq!(a.real("dist"), Some(32.5));
        let names: Vec<_> = a.iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["speed", "lanes", "dist"]);
    }

    #[test]
    fn decode_rejects_points_that_do_not_fit() {
        let s = space();
        let outside = Point {
            discrete: vec![0],
            continuous: vec![1.0, 0.1],
        };
        assert!(matches!(
            s.decode(&outside),
            Err(GeneratorError::PointMismatch(_))
        ));
        let bad_level = Point {
            discrete: vec![2],
            continuous: vec![0.1, 0.1],
        };
        assert!(s.decode(&bad_level).is_err());
        let short = Point {
            discrete: vec![],
            continuous: vec![0.1, 0.1],
        };
        assert!(s.decode(&short).is_err());
    }

    #[test]
    fn unit_cube_is_a_valid_continuous_space() {
        let c = ParamSpace::unit_cube(3);
        assert_eq!(c.continuous_dims(), 3);
        assert_eq!(ParamSpace::new(c.params().to_vec()), Ok(c));
    }

    #[test]
    fn new_rejects_empty_intervals_and_duplicate_names() {
        assert!(ParamSpace::new(vec![Param::interval("a", 1.0, 1.0, "m")]).is_err());
        assert!(ParamSpace::new(vec![Param::interval("a", 0.0, f64::NAN, "m")]).is_err());
        assert!(ParamSpace::new(vec![Param::levels("a", vec![])]).is_err());
        assert_eq!(
            ParamSpace::new(vec![
                Param::interval("a", 0.0, 1.0, "m"),
                Param::interval("a", 0.0, 1.0, "m")
            ]),
            Err(GeneratorError::DuplicateParam("a".into()))
        );
    }

    #[test]
    fn assignment_serialises_in_declaration_order() {
        let a = space()
            .decode(&Point {
                discrete: vec![0],
                continuous: vec![0.5, 0.0],
            })
            .unwrap();
        let json = serde_json::to_string(&a).unwrap();
        assert_eq!(json, r#"{"speed":5.25,"lanes":2,"dist":5.0}"#);
    }
}
