//! A constraint written as a Starlark expression over the open parameters' names (a
//! `paracosm-cover` space file's `[[constraint]]`: `require = "lane != 2 or speed < 10"`).

use starlark::environment::{Globals, Module};
use starlark::eval::Evaluator;
use starlark::syntax::{AstModule, Dialect};
use starlark::values::Value as StarValue;

use paracosm_generators::{Assignment, Constraint, ConstraintError, ParamSpace, Point, Value};

/// The most Starlark steps one evaluation of a constraint's expression may take.
pub const MAX_CONSTRAINT_STEPS: u64 = 100_000;

/// A named Starlark expression that is true where the parameters' values are valid: every
/// parameter of the space is a variable holding the test's value in its unit (a level as
/// written: a number, a bool or a string). It reads nothing else, so it is a function of the
/// parameters alone.
pub struct ExprConstraint {
    name: String,
    expr: String,
    ast: AstModule,
    globals: Globals,
}

impl std::fmt::Debug for ExprConstraint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ExprConstraint({:?}: {:?})", self.name, self.expr)
    }
}

impl ExprConstraint {
    /// The constraint `name`, true where `expr` is, over `space`'s parameters; `label` names
    /// the expression in messages (e.g. `space.toml:7:11`).
    ///
    /// # Errors
    /// A message naming `label` when the expression does not parse, names a variable that is
    /// no parameter, or is not `True` or `False` at the space's first point (every level
    /// first, every interval at its lower end).
    pub fn new(
        name: &str,
        expr: &str,
        label: &str,
        space: &ParamSpace,
    ) -> Result<Self, ConstraintError> {
        let dialect = Dialect {
            enable_load: false,
            enable_def: false,
            enable_lambda: true,
            enable_top_level_stmt: false,
            ..Dialect::Standard
        };
        let ast = AstModule::parse(label, expr.to_owned(), &dialect)
            .map_err(|e| ConstraintError(format!("constraint `{name}`: {e}")))?;
        let c = ExprConstraint {
            name: name.to_owned(),
            expr: expr.to_owned(),
            ast,
            globals: Globals::standard(),
        };
        let first = Point {
            discrete: vec![0; space.level_counts().len()],
            continuous: vec![0.0; space.continuous_dims()],
        };
        let values = space
            .decode(&first)
            .map_err(|e| ConstraintError(e.to_string()))?;
        c.holds(&values)?;
        Ok(c)
    }

    /// Whether the expression is true at `values`.
    fn holds(&self, values: &Assignment) -> Result<bool, ConstraintError> {
        Module::with_temp_heap(|module| {
            let heap = module.heap();
            for (n, v) in values.iter() {
                let value: StarValue = match v {
                    Value::Int(i) => heap.alloc(*i),
                    Value::Real(x) => heap.alloc(*x),
                    Value::Bool(b) => StarValue::new_bool(*b),
                    Value::Text(t) => heap.alloc(t.as_str()),
                };
                module.set(n, value);
            }
            let mut eval = Evaluator::new(&module);
            eval.set_max_callstack_size(50)
                .map_err(|e| ConstraintError(format!("constraint `{}`: {e}", self.name)))?;
            let got = eval
                .eval_module(self.ast.clone(), &self.globals)
                .map_err(|e| ConstraintError(format!("constraint `{}`: {e}", self.name)))?;
            if eval.get_total_tick_count() > MAX_CONSTRAINT_STEPS {
                return Err(ConstraintError(format!(
                    "constraint `{}` took more than {MAX_CONSTRAINT_STEPS} steps",
                    self.name
                )));
            }
            got.unpack_bool().ok_or_else(|| {
                ConstraintError(format!(
                    "constraint `{}`: `{}` is {} ({}), not True or False",
                    self.name,
                    self.expr,
                    got,
                    got.get_type()
                ))
            })
        })
    }
}

impl Constraint for ExprConstraint {
    fn name(&self) -> &str {
        &self.name
    }

    fn violation(&self, values: &Assignment) -> Result<Option<String>, ConstraintError> {
        Ok((!self.holds(values)?).then(|| format!("`{}` is False", self.expr)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use paracosm_generators::Param;

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::levels("lane", vec![Value::Int(1), Value::Int(2)]),
            Param::interval("speed", 0.0, 40.0, "m/s"),
            Param::levels(
                "kind",
                vec![Value::Text("car".into()), Value::Text("van".into())],
            ),
        ])
        .unwrap()
    }

    #[test]
    fn an_expression_over_the_parameters_decides_validity() {
        let c = ExprConstraint::new(
            "slow_vans_in_2",
            "lane != 2 or (speed < 10 and kind == \"van\")",
            "t",
            &space(),
        )
        .unwrap();
        let s = space();
        let at = |lane: u32, kind: u32, u: f64| {
            s.decode(&Point {
                discrete: vec![lane, kind],
                continuous: vec![u],
            })
            .unwrap()
        };
        assert_eq!(c.violation(&at(0, 0, 0.9)).unwrap(), None);
        assert_eq!(c.violation(&at(1, 1, 0.1)).unwrap(), None);
        assert!(c.violation(&at(1, 1, 0.5)).unwrap().is_some());
        assert!(c.violation(&at(1, 0, 0.1)).unwrap().is_some());
    }

    #[test]
    fn what_is_no_function_of_the_parameters_is_refused() {
        for (expr, needle) in [
            ("lane + 1", "not True or False"),
            ("lanes == 2", "Variable `lanes` not found"),
            ("speed <", "Parse error"),
        ] {
            let e = ExprConstraint::new("c", expr, "space.toml:3:11", &space()).unwrap_err();
            assert!(e.0.contains(needle), "{expr}: {e}");
        }
    }
}
