//! Parameter declarations, their values in nested scopes, and attribute resolution (ASAM
//! OpenSCENARIO XML 1.3 User Guide, section 9.1 "Parameters" and 9.2 "Expressions"; XSD types
//! `ParameterDeclarations`, `ParameterDeclaration`, `ValueConstraintGroup`, `ValueConstraint`,
//! `ParameterType`, `Rule`).
//!
//! An attribute's text is one of three forms: `$name` (the whole attribute) refers to a
//! parameter; `${expr}` is an expression ([`crate::expr`]); anything else is a literal. A text
//! starting with `$` that is neither form (`$ x`, `${1 + 2`) is an error rather than a literal,
//! as it is almost always a typing mistake. Surrounding white space is ignored when telling the
//! forms apart.
//!
//! A declaration's value may refer to any parameter of its own `ParameterDeclarations` (in any
//! order) or of the enclosing scopes; circular references are errors. Values are checked
//! against the declared type and, once every value of the scope is known, against the
//! declaration's constraint groups (a value must meet every constraint of at least one group).

use std::collections::HashMap;
use std::sync::Arc;

use roxmltree::Node;

use crate::error::{Pos, XoscError};
use crate::expr::{self, is_param_name, parse_number};
use crate::quantity::Quantity;
use crate::text::Text;
use crate::Value;

/// A parameter's declared type (XSD `ParameterType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    /// `double`: a finite number.
    Double,
    /// `int` (and OpenSCENARIO 1.0's deprecated `integer`): a whole number from -2^31 to
    /// 2^31 - 1 (`xsd:int`).
    Int,
    /// `unsignedInt`: a whole number from 0 to 2^32 - 1.
    UnsignedInt,
    /// `unsignedShort`: a whole number from 0 to 65535.
    UnsignedShort,
    /// `boolean`: `true`, `false`, `1` or `0` (`xsd:boolean`).
    Bool,
    /// `string`: any text.
    Str,
    /// `dateTime`: `YYYY-MM-DDThh:mm:ss` with optional fractional seconds and zone
    /// (`xsd:dateTime`), kept as text.
    DateTime,
}

impl ParamType {
    /// The type named `name` as the XSD writes it (`double`, `int`, `integer`, `unsignedInt`,
    /// `unsignedShort`, `boolean`, `string`, `dateTime`), or `None`.
    pub fn from_xsd(name: &str) -> Option<ParamType> {
        Some(match name {
            "double" => ParamType::Double,
            "int" | "integer" => ParamType::Int,
            "unsignedInt" => ParamType::UnsignedInt,
            "unsignedShort" => ParamType::UnsignedShort,
            "boolean" => ParamType::Bool,
            "string" => ParamType::Str,
            "dateTime" => ParamType::DateTime,
            _ => return None,
        })
    }

    /// The type's XSD name.
    pub fn xsd_name(self) -> &'static str {
        match self {
            ParamType::Double => "double",
            ParamType::Int => "int",
            ParamType::UnsignedInt => "unsignedInt",
            ParamType::UnsignedShort => "unsignedShort",
            ParamType::Bool => "boolean",
            ParamType::Str => "string",
            ParamType::DateTime => "dateTime",
        }
    }

    /// Whether values of the type are numbers.
    pub fn is_numeric(self) -> bool {
        matches!(
            self,
            ParamType::Double | ParamType::Int | ParamType::UnsignedInt | ParamType::UnsignedShort
        )
    }

    /// `v` as a value of this type: numbers as [`Value::Num`] (a text that is a number is
    /// converted; whole-number types require a whole number in range), booleans as
    /// [`Value::Bool`], strings and date-times as [`Value::Str`].
    ///
    /// # Errors
    /// Why `v` is not a value of this type.
    pub fn coerce(self, v: Value) -> Result<Value, ValueError> {
        let whole = |lo: f64, hi: f64| -> Result<Value, ValueError> {
            let x = as_number(&v)?;
            if x.fract() != 0.0 || x < lo || x > hi {
                return Err(format!(
                    "{} is not an {} (a whole number from {lo} to {hi})",
                    Value::Num(x).to_text(),
                    self.xsd_name()
                )
                .into());
            }
            Ok(Value::Num(x))
        };
        match self {
            ParamType::Double => as_number(&v).map(Value::Num),
            ParamType::Int => whole(f64::from(i32::MIN), f64::from(i32::MAX)),
            ParamType::UnsignedInt => whole(0.0, f64::from(u32::MAX)),
            ParamType::UnsignedShort => whole(0.0, f64::from(u16::MAX)),
            ParamType::Bool => as_bool(&v).map(Value::Bool),
            ParamType::Str => Ok(Value::Str(v.to_text())),
            ParamType::DateTime => match &v {
                Value::Str(s) if is_datetime(s) => Ok(Value::Str(s.trim().to_string())),
                other => Err(format!(
                    "{} is not a dateTime (YYYY-MM-DDThh:mm:ss, optional fraction and zone)",
                    quoted(other)
                )
                .into()),
            },
        }
    }
}

fn quoted(v: &Value) -> String {
    match v {
        Value::Str(s) => format!("{s:?}"),
        other => other.to_text(),
    }
}

fn as_number(v: &Value) -> Result<f64, ValueError> {
    match v {
        Value::Num(x) if x.is_finite() => Ok(*x),
        Value::Str(s) => parse_number(s).ok_or_else(|| format!("{s:?} is not a number").into()),
        other => Err(format!("{} is not a number", quoted(other)).into()),
    }
}

fn as_bool(v: &Value) -> Result<bool, ValueError> {
    match v {
        Value::Bool(b) => Ok(*b),
        Value::Str(s) => match s.trim() {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            _ => Err(format!("{s:?} is not a boolean (true, false, 1, 0)").into()),
        },
        other => Err(format!("{} is not a boolean (true, false, 1, 0)", quoted(other)).into()),
    }
}

/// Whether `s` is an `xsd:dateTime`: `YYYY-MM-DDThh:mm:ss`, optional `.fff`, optional `Z` or
/// `+hh:mm`/`-hh:mm`.
fn is_datetime(s: &str) -> bool {
    let b = s.trim().as_bytes();
    let digits =
        |i: usize, n: usize| b.len() >= i + n && b[i..i + n].iter().all(u8::is_ascii_digit);
    let at = |i: usize, c: u8| b.get(i) == Some(&c);
    let shape = digits(0, 4)
        && at(4, b'-')
        && digits(5, 2)
        && at(7, b'-')
        && digits(8, 2)
        && at(10, b'T')
        && digits(11, 2)
        && at(13, b':')
        && digits(14, 2)
        && at(16, b':')
        && digits(17, 2);
    if !shape {
        return false;
    }
    let two = |i: usize| u32::from(b[i] - b'0') * 10 + u32::from(b[i + 1] - b'0');
    if !(1..=12).contains(&two(5)) || !(1..=31).contains(&two(8)) {
        return false;
    }
    if two(11) > 24 || two(14) > 59 || two(17) > 60 {
        return false;
    }
    let mut i = 19;
    if at(i, b'.') {
        let start = i + 1;
        i = start;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i == start {
            return false;
        }
    }
    match b.get(i) {
        None => true,
        Some(b'Z') => i + 1 == b.len(),
        Some(b'+' | b'-') => {
            b.len() == i + 6 && digits(i + 1, 2) && at(i + 3, b':') && digits(i + 4, 2)
        }
        _ => false,
    }
}

/// Why a value is refused (not of its type, breaking its constraint groups): a message for
/// the caller to place at the attribute or declaration it came from.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ValueError(pub String);

impl From<String> for ValueError {
    fn from(s: String) -> Self {
        ValueError(s)
    }
}

/// A constraint's comparison (XSD `Rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// `equalTo`.
    EqualTo,
    /// `greaterThan`.
    GreaterThan,
    /// `lessThan`.
    LessThan,
    /// `greaterOrEqual` (OpenSCENARIO 1.2+).
    GreaterOrEqual,
    /// `lessOrEqual` (OpenSCENARIO 1.2+).
    LessOrEqual,
    /// `notEqualTo` (OpenSCENARIO 1.2+).
    NotEqualTo,
}

impl Rule {
    /// The rule named `name` as the XSD writes it, or `None`.
    pub fn from_xsd(name: &str) -> Option<Rule> {
        Some(match name {
            "equalTo" => Rule::EqualTo,
            "greaterThan" => Rule::GreaterThan,
            "lessThan" => Rule::LessThan,
            "greaterOrEqual" => Rule::GreaterOrEqual,
            "lessOrEqual" => Rule::LessOrEqual,
            "notEqualTo" => Rule::NotEqualTo,
            _ => return None,
        })
    }

    /// The rule's XSD name.
    pub fn xsd_name(self) -> &'static str {
        match self {
            Rule::EqualTo => "equalTo",
            Rule::GreaterThan => "greaterThan",
            Rule::LessThan => "lessThan",
            Rule::GreaterOrEqual => "greaterOrEqual",
            Rule::LessOrEqual => "lessOrEqual",
            Rule::NotEqualTo => "notEqualTo",
        }
    }
}

/// One `<ValueConstraint rule value>` (XSD `ValueConstraint`): the parameter's value compared
/// with `value` by `rule`.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueConstraint {
    /// The comparison.
    pub rule: Rule,
    /// The value compared with, as written: a literal, `$name` or `${expr}` (evaluated in the
    /// declaring scope once all its values are known).
    pub value: String,
}

/// One `<ParameterDeclaration>` (XSD `ParameterDeclaration`).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    /// The name, `[A-Za-z_][A-Za-z0-9_]*`.
    pub name: String,
    /// The declared type.
    pub ty: ParamType,
    /// The `value` attribute as written (a literal, `$name` or `${expr}`).
    pub raw: String,
    /// The `ConstraintGroup`s: the value must meet every constraint of at least one group.
    pub constraint_groups: Vec<Vec<ValueConstraint>>,
    /// Where the declaration starts.
    pub pos: Pos,
    /// Byte offset in the file's text of the `value` attribute's text, so that an error in an
    /// expression can name its column.
    pub value_at: usize,
}

/// Unsupported when `node` has an attribute (outside any namespace) not in `allowed`.
pub(crate) fn check_attrs(
    text: &Text,
    node: Node<'_, '_>,
    allowed: &[&str],
) -> Result<(), XoscError> {
    for a in node.attributes() {
        if a.namespace().is_none() && !allowed.contains(&a.name()) {
            return Err(XoscError::Unsupported {
                pos: text.attr_pos(node, a.name()),
                reason: format!(
                    "<{}> has no attribute {}; it has {}",
                    node.tag_name().name(),
                    a.name(),
                    allowed.join(", ")
                ),
            });
        }
    }
    Ok(())
}

/// `node`'s attribute `name`, required.
pub(crate) fn required<'a>(
    text: &Text,
    node: Node<'a, '_>,
    name: &str,
) -> Result<&'a str, XoscError> {
    node.attribute(name).ok_or_else(|| {
        text.invalid(
            node,
            format!("<{}> needs the attribute {name}", node.tag_name().name()),
        )
    })
}

/// Reads a `<ParameterDeclarations>` element's children (`None`: no such element, no
/// declarations).
///
/// # Errors
/// Unsupported for an element other than `ParameterDeclaration` / `ConstraintGroup` /
/// `ValueConstraint` where those belong, for an unknown attribute and for a `parameterType`
/// given as a parameter; Invalid for a missing attribute, a name that cannot be referenced, an
/// unknown type or rule, an empty constraint group and a name declared twice with a different
/// type, value or constraints (the same declaration twice, as esmini's own files write, is
/// read as one).
pub fn read_declarations(
    text: &Text,
    node: Option<Node<'_, '_>>,
) -> Result<Vec<ParamDecl>, XoscError> {
    let Some(node) = node else {
        return Ok(Vec::new());
    };
    let mut out: Vec<ParamDecl> = Vec::new();
    // Each name's index in `out`: a linear scan per declaration was quadratic in their count.
    let mut seen: HashMap<String, usize> = HashMap::new();
    for child in node.children().filter(Node::is_element) {
        if child.tag_name().name() != "ParameterDeclaration" {
            return Err(text.unsupported(
                child,
                format!(
                    "<{}> in <ParameterDeclarations>: only <ParameterDeclaration> belongs there",
                    child.tag_name().name()
                ),
            ));
        }
        let d = read_declaration(text, child)?;
        if let Some(first) = seen.get(&d.name).map(|&i| &out[i]) {
            // esmini lets the later of two declarations shadow the earlier; a file written
            // for it (esmini's `follow_reference`, its vehicle catalog) repeats one with the
            // same type and value, which means one parameter. Two that differ are refused:
            // which one the author meant is not written.
            if first.ty == d.ty
                && first.raw == d.raw
                && first.constraint_groups.is_empty()
                && d.constraint_groups.is_empty()
            {
                continue;
            }
            return Err(XoscError::Invalid {
                pos: text.attr_pos(child, "name"),
                reason: format!(
                    "parameter {} is declared twice in one <ParameterDeclarations> (first at \
                     line {}) with a different type, value or constraints: the schema allows \
                     one declaration per name (the same type and value twice is read as one)",
                    d.name, first.pos.line
                ),
            });
        }
        seen.insert(d.name.clone(), out.len());
        out.push(d);
    }
    Ok(out)
}

fn read_declaration(text: &Text, node: Node<'_, '_>) -> Result<ParamDecl, XoscError> {
    check_attrs(text, node, &["name", "parameterType", "value"])?;
    let name = required(text, node, "name")?;
    if !is_param_name(name) {
        return Err(XoscError::Invalid {
            pos: text.attr_pos(node, "name"),
            reason: format!(
                "parameter name {name:?} cannot be referenced: a name is [A-Za-z_][A-Za-z0-9_]*"
            ),
        });
    }
    let ty_text = required(text, node, "parameterType")?;
    let ty = match ParamType::from_xsd(ty_text) {
        Some(t) => t,
        None if ty_text.starts_with('$') => {
            return Err(XoscError::Unsupported {
                pos: text.attr_pos(node, "parameterType"),
                reason: format!(
                    "parameter {name}: a parameterType given by a parameter ({ty_text})"
                ),
            })
        }
        None => {
            return Err(XoscError::Invalid {
                pos: text.attr_pos(node, "parameterType"),
                reason: format!(
                    "parameter {name}: unknown parameterType {ty_text:?}; the types are double, \
                     int, unsignedInt, unsignedShort, boolean, string, dateTime"
                ),
            })
        }
    };
    let raw = required(text, node, "value")?;
    let value_at = node
        .attribute_node("value")
        .map_or(node.range().start, |a| a.range_value().start);
    let mut constraint_groups = Vec::new();
    for g in node.children().filter(Node::is_element) {
        if g.tag_name().name() != "ConstraintGroup" {
            return Err(text.unsupported(
                g,
                format!(
                    "<{}> in <ParameterDeclaration>: only <ConstraintGroup> belongs there",
                    g.tag_name().name()
                ),
            ));
        }
        constraint_groups.push(read_group(text, g)?);
    }
    Ok(ParamDecl {
        name: name.to_string(),
        ty,
        raw: raw.to_string(),
        constraint_groups,
        pos: text.pos(node),
        value_at,
    })
}

fn read_group(text: &Text, g: Node<'_, '_>) -> Result<Vec<ValueConstraint>, XoscError> {
    check_attrs(text, g, &[])?;
    let mut group = Vec::new();
    for c in g.children().filter(Node::is_element) {
        if c.tag_name().name() != "ValueConstraint" {
            return Err(text.unsupported(
                c,
                format!(
                    "<{}> in <ConstraintGroup>: only <ValueConstraint> belongs there",
                    c.tag_name().name()
                ),
            ));
        }
        check_attrs(text, c, &["rule", "value"])?;
        let rule_text = required(text, c, "rule")?;
        let Some(rule) = Rule::from_xsd(rule_text) else {
            let why = if rule_text.starts_with('$') {
                "a rule given by a parameter is not supported; write the rule"
            } else {
                "the rules are equalTo, greaterThan, lessThan, greaterOrEqual, lessOrEqual, notEqualTo"
            };
            return Err(XoscError::Unsupported {
                pos: text.attr_pos(c, "rule"),
                reason: format!("rule {rule_text:?}: {why}"),
            });
        };
        let value = required(text, c, "value")?.to_string();
        group.push(ValueConstraint { rule, value });
    }
    if group.is_empty() {
        return Err(text.invalid(
            g,
            "an empty <ConstraintGroup>: it needs at least one <ValueConstraint>",
        ));
    }
    Ok(group)
}

/// The three forms of an attribute's text.
enum Form<'a> {
    /// `$name`.
    Ref(&'a str),
    /// `${inner}`, with the byte offset of `inner` in the text.
    Expr(&'a str, usize),
    /// Anything else.
    Lit,
}

/// The form of `v`, or the byte offset and reason of a malformed `$` text.
fn form(v: &str) -> Result<Form<'_>, (usize, String)> {
    let lead = v.len() - v.trim_start().len();
    let t = v.trim();
    if let Some(rest) = t.strip_prefix("${") {
        match rest.strip_suffix('}') {
            Some(inner) => Ok(Form::Expr(inner, lead + 2)),
            None => Err((
                lead,
                format!("{t:?}: an expression `${{` must end with `}}`"),
            )),
        }
    } else if let Some(name) = t.strip_prefix('$') {
        if is_param_name(name) {
            Ok(Form::Ref(name))
        } else {
            Err((
                lead,
                format!(
                    "{t:?} is not a parameter reference: `$` must be followed by a name \
                     ([A-Za-z_][A-Za-z0-9_]*) or by `{{` starting an expression"
                ),
            ))
        }
    } else {
        Ok(Form::Lit)
    }
}

/// The names `v` refers to (for ordering a scope's declarations).
pub(crate) fn refs_of(v: &str) -> Vec<String> {
    match form(v) {
        Ok(Form::Ref(n)) => vec![n.to_string()],
        Ok(Form::Expr(inner, _)) => expr::params_in(inner),
        _ => Vec::new(),
    }
}

/// The value of an attribute text `v`, or the byte offset in `v` and reason of its fault.
fn eval_text(v: &str, lookup: &dyn Fn(&str) -> Option<Value>) -> Result<Value, (usize, String)> {
    match form(v)? {
        Form::Ref(n) => lookup(n).ok_or_else(|| {
            let lead = v.len() - v.trim_start().len();
            (lead, format!("parameter ${n} is not declared"))
        }),
        Form::Expr(inner, off) => expr::eval(inner, lookup).map_err(|e| (off + e.offset, e.reason)),
        Form::Lit => Ok(Value::Str(v.to_string())),
    }
}

/// The position of byte `offset` of an attribute text `value` whose text starts at byte `at` of
/// the file, when the file holds the text verbatim (no entity references); else of its start.
fn pos_in_value(text: &Text, at: usize, value: &str, offset: usize) -> Pos {
    let verbatim = at
        .checked_add(value.len())
        .and_then(|end| text.text.get(at..end))
        == Some(value);
    if verbatim && offset <= value.len() {
        text.pos_at(at + offset)
    } else {
        text.pos_at(at)
    }
}

/// Two numbers equal within 1e-12 relative (of the larger magnitude, at least 1), so that
/// `${0.1 + 0.2}` equals `0.3`.
fn approx_eq(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

/// The declarations' order for evaluation (dependencies first), or a cycle as the indices
/// along it (first repeated at the end). Iterative: no recursion however long the chain.
fn eval_order(deps: &[Vec<usize>]) -> Result<Vec<usize>, Vec<usize>> {
    let n = deps.len();
    let mut state = vec![0u8; n]; // 0 unseen, 1 on the path, 2 done
    let mut out = Vec::with_capacity(n);
    for root in 0..n {
        if state[root] != 0 {
            continue;
        }
        state[root] = 1;
        let mut path: Vec<(usize, usize)> = vec![(root, 0)];
        while let Some(top) = path.last_mut() {
            let node = top.0;
            let next = deps[node].get(top.1).copied();
            top.1 += 1;
            match next {
                Some(d) if state[d] == 0 => {
                    state[d] = 1;
                    path.push((d, 0));
                }
                Some(d) if state[d] == 1 => {
                    let start = path.iter().position(|&(p, _)| p == d).unwrap_or(0);
                    let mut cycle: Vec<usize> = path[start..].iter().map(|&(p, _)| p).collect();
                    cycle.push(d);
                    return Err(cycle);
                }
                Some(_) => {}
                None => {
                    state[node] = 2;
                    out.push(node);
                    path.pop();
                }
            }
        }
    }
    Ok(out)
}

/// A scope of parameter values: one `ParameterDeclarations` evaluated, over the scopes
/// enclosing it (a catalog entry's or a storyboard element's declarations over the scenario's).
///
/// A scope is shared, not copied: a nested scope holds its own declarations and a handle on
/// the one enclosing it, so nesting costs the nested declarations only (a storyboard of
/// 10,000 maneuvers under 10,000 parameters does not copy them 10,000 times), and a lookup
/// walks at most the nesting depth.
#[derive(Debug, Clone, Default)]
pub struct Scope(Arc<Frame>);

/// One scope's own parameters and the scope enclosing it.
#[derive(Debug, Default)]
struct Frame {
    /// This scope's own declarations, in declaration order.
    own: Vec<(String, Value)>,
    /// This scope's own parameters by name (they shadow the enclosing scopes').
    vars: HashMap<String, (Value, ParamType)>,
    /// The scope enclosing this one.
    parent: Option<Scope>,
}

impl Scope {
    /// The scope of `decls` (read from `text`), with `overrides` (name, text: from a variation
    /// file or the command line) replacing declared values; a later override of the same name
    /// replaces an earlier one. An override's text may itself be `$name` or `${expr}`.
    ///
    /// # Errors
    /// Invalid, at the declaration (or at the expression's column in its `value`): an override
    /// of an undeclared name (listing the declared ones), a name declared twice, a circular
    /// reference ("circular parameter reference a -> b -> a"), an undeclared parameter, an
    /// expression that fails, a value that is not of the declared type, a value that meets
    /// none of its constraint groups.
    pub fn new(
        text: &Text,
        decls: &[ParamDecl],
        overrides: &[(String, String)],
    ) -> Result<Scope, XoscError> {
        let scope = Scope::build(None, text, decls, &texts(overrides))?;
        scope.check_all_constraints(decls)?;
        Ok(scope)
    }

    /// The scope of `decls` (read from `text`) with `values` (name, typed value: a run's,
    /// from a campaign's test or a program's `Import(params=)`) replacing declared values; a
    /// later value of the same name replaces an earlier one. A value is coerced to the
    /// declared type as the declaration's own text would be (`Str("5")` is the number 5 for a
    /// `double`) but never evaluated: a text holding `$name` is that text.
    ///
    /// # Errors
    /// As [`Scope::new`].
    pub fn with_values(
        text: &Text,
        decls: &[ParamDecl],
        values: &[(String, Value)],
    ) -> Result<Scope, XoscError> {
        let scope = Scope::with_values_unconstrained(text, decls, values)?;
        scope.check_all_constraints(decls)?;
        Ok(scope)
    }

    /// As [`Scope::with_values`] without the constraint check ([`Constrained::violation`]
    /// checks them after).
    ///
    /// # Errors
    /// As [`Scope::with_values`], except for broken constraints.
    pub fn with_values_unconstrained(
        text: &Text,
        decls: &[ParamDecl],
        values: &[(String, Value)],
    ) -> Result<Scope, XoscError> {
        let given: Vec<(&str, Given<'_>)> = (values.iter())
            .map(|(n, v)| (n.as_str(), Given::Value(v)))
            .collect();
        Scope::build(None, text, decls, &given)
    }

    /// As [`Scope::new`] without the constraint check, so that a campaign can tell the
    /// combinations of a variation that a template's constraints refuse (see
    /// [`Scope::check_all_constraints`]) from other errors.
    ///
    /// # Errors
    /// As [`Scope::new`], except for broken constraints.
    pub fn new_unconstrained(
        text: &Text,
        decls: &[ParamDecl],
        overrides: &[(String, String)],
    ) -> Result<Scope, XoscError> {
        Scope::build(None, text, decls, &texts(overrides))
    }

    /// Checks every declaration of `decls` (this scope's own) against its constraint groups
    /// with this scope's values: what [`Scope::new`] does last.
    ///
    /// # Errors
    /// Invalid at the first declaration whose value meets none of its constraint groups, with
    /// [`Scope::check_constraints`]'s message.
    pub fn check_all_constraints(&self, decls: &[ParamDecl]) -> Result<(), XoscError> {
        for d in decls {
            let Some(v) = self.get(&d.name) else {
                return Err(XoscError::Invalid {
                    pos: d.pos.clone(),
                    reason: format!("parameter {} has no value in this scope", d.name),
                });
            };
            self.check_constraints(d, v)
                .map_err(|reason| XoscError::Invalid {
                    pos: d.pos.clone(),
                    reason: reason.to_string(),
                })?;
        }
        Ok(())
    }

    /// A scope nested in this one: `decls` (read from `text`) evaluated with this scope's
    /// parameters visible; its names shadow this scope's.
    ///
    /// # Errors
    /// As [`Scope::new`].
    pub fn child(&self, text: &Text, decls: &[ParamDecl]) -> Result<Scope, XoscError> {
        self.child_with(text, decls, &[])
    }

    /// As [`Scope::child`], with `overrides` replacing declared values (a `CatalogReference`'s
    /// `ParameterAssignments`; resolve their texts in the referencing scope first, as a `$name`
    /// here refers to the nested scope).
    ///
    /// # Errors
    /// As [`Scope::new`].
    pub fn child_with(
        &self,
        text: &Text,
        decls: &[ParamDecl],
        overrides: &[(String, String)],
    ) -> Result<Scope, XoscError> {
        let scope = Scope::build(Some(self), text, decls, &texts(overrides))?;
        scope.check_all_constraints(decls)?;
        Ok(scope)
    }

    fn build(
        parent: Option<&Scope>,
        text: &Text,
        decls: &[ParamDecl],
        overrides: &[(&str, Given<'_>)],
    ) -> Result<Scope, XoscError> {
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (i, d) in decls.iter().enumerate() {
            if index.insert(d.name.as_str(), i).is_some() {
                return Err(XoscError::Invalid {
                    pos: d.pos.clone(),
                    reason: format!("parameter {} is declared twice in one scope", d.name),
                });
            }
        }
        let mut given: Vec<Option<Given<'_>>> = vec![None; decls.len()];
        for &(name, value) in overrides {
            match index.get(name) {
                Some(&i) => given[i] = Some(value),
                None => return Err(undeclared_override(text, decls, name)),
            }
        }
        // What each declaration's value reads: a typed value reads nothing.
        let deps: Vec<Vec<usize>> = decls
            .iter()
            .zip(&given)
            .map(|(d, g)| match g {
                Some(Given::Value(_)) => Vec::new(),
                Some(Given::Text(t)) => refs_of(t),
                None => refs_of(&d.raw),
            })
            .map(|refs| {
                refs.iter()
                    .filter_map(|n| index.get(n.as_str()).copied())
                    .collect()
            })
            .collect();
        let order = eval_order(&deps).map_err(|cycle| {
            let names: Vec<&str> = cycle.iter().map(|&i| decls[i].name.as_str()).collect();
            // A long cycle is shown by its first and last eight names.
            let shown = if names.len() > 17 {
                format!(
                    "{} -> ... ({} more) -> {}",
                    names[..8].join(" -> "),
                    names.len() - 16,
                    names[names.len() - 8..].join(" -> ")
                )
            } else {
                names.join(" -> ")
            };
            XoscError::Invalid {
                pos: decls[cycle[0]].pos.clone(),
                reason: format!("circular parameter reference {shown}"),
            }
        })?;
        let mut values: Vec<Option<Value>> = vec![None; decls.len()];
        for i in order {
            let v = {
                let lookup = |n: &str| match index.get(n) {
                    Some(&j) => values[j].clone(),
                    None => parent.and_then(|p| p.get(n).cloned()),
                };
                evaluate_decl(text, &decls[i], given[i], &lookup)?
            };
            values[i] = Some(v);
        }
        let mut frame = Frame {
            parent: parent.cloned(),
            ..Frame::default()
        };
        for (d, v) in decls.iter().zip(values) {
            let v = v.unwrap_or(Value::Str(String::new()));
            frame.vars.insert(d.name.clone(), (v.clone(), d.ty));
            frame.own.push((d.name.clone(), v));
        }
        Ok(Scope(Arc::new(frame)))
    }

    /// The visible parameter `name`: its value and declared type, from the innermost scope
    /// that declares it.
    fn lookup(&self, name: &str) -> Option<&(Value, ParamType)> {
        let mut scope = self;
        loop {
            if let Some(found) = scope.0.vars.get(name) {
                return Some(found);
            }
            scope = scope.0.parent.as_ref()?;
        }
    }

    /// The value of the visible parameter `name` (without `$`).
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.lookup(name).map(|(v, _)| v)
    }

    /// The declared type of the visible parameter `name`.
    pub fn ty(&self, name: &str) -> Option<ParamType> {
        self.lookup(name).map(|&(_, t)| t)
    }

    /// This scope's own parameters and values, in declaration order (not the enclosing
    /// scopes').
    pub fn declared(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.0.own.iter().map(|(n, v)| (n.as_str(), v))
    }

    /// Whether `value` meets `decl`'s constraint groups: every constraint of at least one group
    /// (none: always). Constraint values are evaluated in this scope. Numeric types compare
    /// numerically (`equalTo`/`notEqualTo` within 1e-12 relative); `boolean`, `string` and
    /// `dateTime` compare their text and allow only `equalTo` and `notEqualTo`.
    ///
    /// # Errors
    /// A message naming the parameter, the value and every group with the constraints it
    /// breaks; or why a constraint cannot be evaluated.
    pub fn check_constraints(&self, decl: &ParamDecl, value: &Value) -> Result<(), ValueError> {
        if decl.constraint_groups.is_empty() {
            return Ok(());
        }
        let mut failures = Vec::new();
        for group in &decl.constraint_groups {
            let mut broken = Vec::new();
            let mut all = Vec::new();
            for c in group {
                let (holds, shown) = self.holds(decl, value, c)?;
                if !holds {
                    broken.push(shown.clone());
                }
                all.push(shown);
            }
            if broken.is_empty() {
                return Ok(());
            }
            failures.push(format!(
                "[{}] breaks {}",
                all.join(" and "),
                broken.join(", ")
            ));
        }
        Err(format!(
            "parameter {} = {} meets none of its constraint groups: {}",
            decl.name,
            quoted(value),
            failures.join("; or ")
        )
        .into())
    }

    /// Whether `value` meets constraint `c`, and `c` as shown in messages.
    fn holds(
        &self,
        decl: &ParamDecl,
        value: &Value,
        c: &ValueConstraint,
    ) -> Result<(bool, String), ValueError> {
        let lookup = |n: &str| self.get(n).cloned();
        let bound = eval_text(&c.value, &lookup).map_err(|(_, reason)| {
            format!(
                "parameter {}: constraint {} {:?}: {reason}",
                decl.name,
                c.rule.xsd_name(),
                c.value
            )
        })?;
        let mut shown = format!("{} {}", c.rule.xsd_name(), c.value);
        if !matches!(form(&c.value), Ok(Form::Lit)) {
            shown.push_str(&format!(" (= {})", bound.to_text()));
        }
        if decl.ty.is_numeric() {
            let a = as_number(value).map_err(|e| format!("parameter {}: {e}", decl.name))?;
            let b = as_number(&bound)
                .map_err(|e| format!("parameter {}: constraint {shown}: {e}", decl.name))?;
            let holds = match c.rule {
                Rule::EqualTo => approx_eq(a, b),
                Rule::NotEqualTo => !approx_eq(a, b),
                Rule::GreaterThan => a > b && !approx_eq(a, b),
                Rule::LessThan => a < b && !approx_eq(a, b),
                Rule::GreaterOrEqual => a >= b || approx_eq(a, b),
                Rule::LessOrEqual => a <= b || approx_eq(a, b),
            };
            return Ok((holds, shown));
        }
        let (a, b) = if decl.ty == ParamType::Bool {
            let conv = |v: &Value| as_bool(v).map(|x| x.to_string());
            let a = conv(value).map_err(|e| format!("parameter {}: {e}", decl.name))?;
            let b = conv(&bound)
                .map_err(|e| format!("parameter {}: constraint {shown}: {e}", decl.name))?;
            (a, b)
        } else {
            (value.to_text(), bound.to_text())
        };
        match c.rule {
            Rule::EqualTo => Ok((a == b, shown)),
            Rule::NotEqualTo => Ok((a != b, shown)),
            r => Err(format!(
                "parameter {} ({}): rule {} compares numbers only; use equalTo or notEqualTo",
                decl.name,
                decl.ty.xsd_name(),
                r.xsd_name()
            )
            .into()),
        }
    }

    /// Resolves `node`'s attribute `attr`: `$name` (the whole attribute) is that parameter's
    /// value; `${expr}` the expression's value; anything else the text itself as
    /// [`Value::Str`]. `None` when there is no such attribute.
    ///
    /// # Errors
    /// Invalid at the attribute (for an expression, at the column of the fault inside it): an
    /// undeclared parameter, a malformed `$` text, an expression that fails.
    pub fn resolve(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
    ) -> Result<Option<Value>, XoscError> {
        let Some(a) = node.attribute_node(attr) else {
            return Ok(None);
        };
        let v = a.value();
        let lookup = |n: &str| self.get(n).cloned();
        eval_text(v, &lookup)
            .map(Some)
            .map_err(|(off, reason)| XoscError::Invalid {
                pos: pos_in_value(text, a.range_value().start, v, off),
                reason: format!("attribute {attr} = {v:?}: {reason}"),
            })
    }

    fn converted<T>(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
        conv: impl Fn(&Value) -> Result<T, ValueError>,
    ) -> Result<Option<T>, XoscError> {
        let Some(v) = self.resolve(text, node, attr)? else {
            return Ok(None);
        };
        conv(&v).map(Some).map_err(|e| {
            let written = node.attribute(attr).unwrap_or_default();
            XoscError::Invalid {
                pos: text.attr_pos(node, attr),
                reason: format!("attribute {attr} = {written:?}: {e}"),
            }
        })
    }

    fn need<T>(text: &Text, node: Node<'_, '_>, attr: &str, v: Option<T>) -> Result<T, XoscError> {
        v.ok_or_else(|| {
            text.invalid(
                node,
                format!("<{}> needs the attribute {attr}", node.tag_name().name()),
            )
        })
    }

    /// `node`'s attribute `attr` resolved as a number (a text that is a number is fine).
    ///
    /// # Errors
    /// Invalid when the attribute is missing, does not resolve, or is not a finite number.
    pub fn num(&self, text: &Text, node: Node<'_, '_>, attr: &str) -> Result<f64, XoscError> {
        let v = self.opt_num(text, node, attr)?;
        Scope::need(text, node, attr, v)
    }

    /// As [`Scope::num`], `None` when the attribute is absent.
    ///
    /// # Errors
    /// As [`Scope::num`], except for a missing attribute.
    pub fn opt_num(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
    ) -> Result<Option<f64>, XoscError> {
        self.converted(text, node, attr, as_number)
    }

    /// `node`'s attribute `attr` resolved as a number ([`Scope::num`]) of quantity `q`,
    /// refused outside `q`'s range ([`Quantity::range`]).
    ///
    /// # Errors
    /// As [`Scope::num`]; Invalid at the attribute, naming the element, when the value is
    /// out of range.
    pub fn num_in(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
        q: Quantity,
    ) -> Result<f64, XoscError> {
        let v = self.opt_num_in(text, node, attr, q)?;
        Scope::need(text, node, attr, v)
    }

    /// As [`Scope::num_in`], `None` when the attribute is absent.
    ///
    /// # Errors
    /// As [`Scope::num_in`], except for a missing attribute.
    pub fn opt_num_in(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
        q: Quantity,
    ) -> Result<Option<f64>, XoscError> {
        let v = self.opt_num(text, node, attr)?;
        match v.and_then(|v| q.refusal(v)) {
            None => Ok(v),
            Some(why) => Err(XoscError::Invalid {
                pos: text.attr_pos(node, attr),
                reason: format!(
                    "<{}> attribute {attr} = {:?}: {why}",
                    node.tag_name().name(),
                    node.attribute(attr).unwrap_or_default()
                ),
            }),
        }
    }

    /// `node`'s attribute `attr` resolved as a text (numbers and booleans as written by
    /// [`Value::to_text`]).
    ///
    /// # Errors
    /// Invalid when the attribute is missing or does not resolve.
    pub fn string(&self, text: &Text, node: Node<'_, '_>, attr: &str) -> Result<String, XoscError> {
        let v = self.opt_string(text, node, attr)?;
        Scope::need(text, node, attr, v)
    }

    /// As [`Scope::string`], `None` when the attribute is absent.
    ///
    /// # Errors
    /// As [`Scope::string`], except for a missing attribute.
    pub fn opt_string(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
    ) -> Result<Option<String>, XoscError> {
        self.converted(text, node, attr, |v| Ok(v.to_text()))
    }

    /// `node`'s attribute `attr` resolved as a boolean (`true`, `false`, `1`, `0`).
    ///
    /// # Errors
    /// Invalid when the attribute is missing, does not resolve, or is not a boolean.
    pub fn bool(&self, text: &Text, node: Node<'_, '_>, attr: &str) -> Result<bool, XoscError> {
        let v = self.opt_bool(text, node, attr)?;
        Scope::need(text, node, attr, v)
    }

    /// As [`Scope::bool`], `None` when the attribute is absent.
    ///
    /// # Errors
    /// As [`Scope::bool`], except for a missing attribute.
    pub fn opt_bool(
        &self,
        text: &Text,
        node: Node<'_, '_>,
        attr: &str,
    ) -> Result<Option<bool>, XoscError> {
        self.converted(text, node, attr, as_bool)
    }
}

/// A value replacing a declared one.
#[derive(Debug, Clone, Copy)]
enum Given<'a> {
    /// A text the file writes (a `CatalogReference`'s `ParameterAssignment`), evaluated as
    /// the declaration's own text would be.
    Text(&'a str),
    /// A run's typed value, coerced to the declared type and never evaluated.
    Value(&'a Value),
}

/// `overrides` as texts to evaluate.
fn texts(overrides: &[(String, String)]) -> Vec<(&str, Given<'_>)> {
    (overrides.iter())
        .map(|(n, t)| (n.as_str(), Given::Text(t.as_str())))
        .collect()
}

fn undeclared_override(text: &Text, decls: &[ParamDecl], name: &str) -> XoscError {
    let declared: Vec<&str> = decls.iter().map(|d| d.name.as_str()).collect();
    let listing = if declared.is_empty() {
        "it declares no parameters".to_string()
    } else {
        format!("it declares {}", declared.join(", "))
    };
    XoscError::Invalid {
        pos: decls
            .first()
            .map_or_else(|| text.pos_at(0), |d| d.pos.clone()),
        reason: format!(
            "a value is given for parameter {name}, which is not declared here; {listing}"
        ),
    }
}

/// The value of declaration `d` (its own text, or `given` by an override), typed.
fn evaluate_decl(
    text: &Text,
    d: &ParamDecl,
    given: Option<Given<'_>>,
    lookup: &dyn Fn(&str) -> Option<Value>,
) -> Result<Value, XoscError> {
    let given = match given {
        Some(Given::Value(v)) => {
            return d.ty.coerce(v.clone()).map_err(|reason| XoscError::Invalid {
                pos: d.pos.clone(),
                reason: format!(
                    "parameter {} = {} (given for the run) ({}): {reason}",
                    d.name,
                    quoted(v),
                    d.ty.xsd_name()
                ),
            });
        }
        Some(Given::Text(t)) => Some(t),
        None => None,
    };
    let written = given.unwrap_or(&d.raw);
    let (pos_of, label) = match given {
        Some(g) => (
            None,
            format!("parameter {} = {g:?} (given for the run)", d.name),
        ),
        None => (Some(d.value_at), format!("parameter {}", d.name)),
    };
    let at = |off: usize| match pos_of {
        Some(start) => pos_in_value(text, start, &d.raw, off),
        None => d.pos.clone(),
    };
    let v = eval_text(written, lookup).map_err(|(off, reason)| XoscError::Invalid {
        pos: at(off),
        reason: format!("{label}: {reason}"),
    })?;
    d.ty.coerce(v).map_err(|reason| XoscError::Invalid {
        pos: at(0),
        reason: format!("{label} ({}): {reason}", d.ty.xsd_name()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(decls: &str) -> Text {
        Text::new(
            "t.xosc",
            format!("<OpenSCENARIO>\n<ParameterDeclarations>\n{decls}\n</ParameterDeclarations>\n</OpenSCENARIO>"),
        )
    }

    fn decls_of(text: &Text) -> Result<Vec<ParamDecl>, XoscError> {
        let d = text.parse()?;
        let node = d
            .descendants()
            .find(|n| n.has_tag_name("ParameterDeclarations"));
        read_declarations(text, node)
    }

    fn scope(decls: &str, overrides: &[(&str, &str)]) -> Result<Scope, XoscError> {
        let text = doc(decls);
        let ds = decls_of(&text)?;
        let ov: Vec<(String, String)> = overrides
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect();
        Scope::new(&text, &ds, &ov)
    }

    fn p(name: &str, ty: &str, value: &str) -> String {
        format!(r#"<ParameterDeclaration name="{name}" parameterType="{ty}" value="{value}"/>"#)
    }

    /// esmini's own files repeat a declaration word for word: read as one. Two that differ
    /// are refused, naming the line of the first.
    #[test]
    fn a_declaration_repeated_word_for_word_is_one_and_a_different_one_is_refused() {
        let same = format!(
            "{}\n{}\n{}",
            p("a", "double", "2"),
            p("b", "int", "1"),
            p("a", "double", "2")
        );
        let ds = decls_of(&doc(&same)).unwrap();
        assert_eq!(
            ds.iter().map(|d| d.name.as_str()).collect::<Vec<_>>(),
            ["a", "b"]
        );
        let other = format!("{}\n{}", p("a", "double", "2"), p("a", "double", "3"));
        let e = reason(decls_of(&doc(&other)).unwrap_err());
        assert!(e.contains("parameter a is declared twice"), "{e}");
        assert!(e.contains("first at line 3"), "{e}");
    }

    fn reason(e: XoscError) -> String {
        e.to_string()
    }

    #[test]
    fn alks_declarations_resolve() {
        // Excerpt of alks_scenario_4_4_1_cut_in_no_collision_template.xosc.
        let decls = r#"
    <ParameterDeclaration name="Ego_InitSpeed_Ve0_kph" parameterType="double" value="60.0">
      <ConstraintGroup>
        <ValueConstraint rule="greaterThan" value="0.0" />
        <ValueConstraint rule="lessOrEqual" value="60.0" />
      </ConstraintGroup>
    </ParameterDeclaration>
    <ParameterDeclaration name="CutInVehicle_Model" parameterType="string" value="car">
      <!--Not constrained so it's possible to use different models.-->
    </ParameterDeclaration>
    <ParameterDeclaration name="CutInVehicle_InitPosition_RelativeLaneId" parameterType="int" value="-1">
      <ConstraintGroup><ValueConstraint rule="equalTo" value="-1" /></ConstraintGroup>
      <ConstraintGroup><ValueConstraint rule="equalTo" value="1" /></ConstraintGroup>
    </ParameterDeclaration>
    <ParameterDeclaration name="CutInVehicle_RelativeInitSpeed_Ve0_Vo0_kph" parameterType="double" value="-20.0">
      <ConstraintGroup><ValueConstraint rule="lessThan" value="0.0" /></ConstraintGroup>
      <ConstraintGroup><ValueConstraint rule="greaterThan" value="${-$Ego_InitSpeed_Ve0_kph}" /></ConstraintGroup>
    </ParameterDeclaration>
    <ParameterDeclaration name="CutInVehicle_LaneChange_MaxLateralVelocity_Vy_mps" parameterType="double" value="2.0">
      <ConstraintGroup>
        <ValueConstraint rule="greaterThan" value="0.0" />
        <ValueConstraint rule="lessThan" value="${($Ego_InitSpeed_Ve0_kph + $CutInVehicle_RelativeInitSpeed_Ve0_Vo0_kph) / 3.6}" />
      </ConstraintGroup>
    </ParameterDeclaration>
    <ParameterDeclaration name="Ego_InitPosition_LaneId" parameterType="string" value="-4">
      <ConstraintGroup><ValueConstraint rule="equalTo" value="-4" /></ConstraintGroup>
      <ConstraintGroup><ValueConstraint rule="equalTo" value="4" /></ConstraintGroup>
    </ParameterDeclaration>"#;
        let s = scope(decls, &[]).unwrap();
        let names: Vec<&str> = s.declared().map(|(n, _)| n).collect();
        assert_eq!(names[0], "Ego_InitSpeed_Ve0_kph");
        assert_eq!(names.len(), 6);
        assert_eq!(s.get("Ego_InitSpeed_Ve0_kph"), Some(&Value::Num(60.0)));
        assert_eq!(s.get("CutInVehicle_Model"), Some(&Value::Str("car".into())));
        assert_eq!(
            s.get("Ego_InitPosition_LaneId"),
            Some(&Value::Str("-4".into()))
        );
        assert_eq!(
            s.ty("CutInVehicle_InitPosition_RelativeLaneId"),
            Some(ParamType::Int)
        );
        // Overridden as a variation file would.
        let s = scope(
            decls,
            &[
                ("Ego_InitSpeed_Ve0_kph", "30.0"),
                ("Ego_InitPosition_LaneId", "4"),
            ],
        )
        .unwrap();
        assert_eq!(s.get("Ego_InitSpeed_Ve0_kph"), Some(&Value::Num(30.0)));
        // Without the constraint check the same combination builds; the check then refuses it.
        let text = doc(decls);
        let ds = decls_of(&text).unwrap();
        let ov = [("Ego_InitSpeed_Ve0_kph".to_string(), "70".to_string())];
        let s = Scope::new_unconstrained(&text, &ds, &ov).unwrap();
        assert_eq!(s.get("Ego_InitSpeed_Ve0_kph"), Some(&Value::Num(70.0)));
        assert!(s.check_all_constraints(&ds).is_err());
        // 70 kph breaks the ALKS speed limit constraint.
        let e = reason(scope(decls, &[("Ego_InitSpeed_Ve0_kph", "70")]).unwrap_err());
        assert!(
            e.contains("parameter Ego_InitSpeed_Ve0_kph = 70 meets none"),
            "{e}"
        );
        assert!(e.contains("breaks lessOrEqual 60.0"), "{e}");
        // Lane 3 is neither -4 nor 4 (OR across groups).
        let e = reason(scope(decls, &[("Ego_InitPosition_LaneId", "3")]).unwrap_err());
        assert!(
            e.contains("breaks equalTo -4; or [equalTo 4] breaks equalTo 4"),
            "{e}"
        );
        // At 5 kph the lateral velocity bound is (5 - 20) / 3.6 < 0: 2.0 fails (AND in a group).
        let e = reason(scope(decls, &[("Ego_InitSpeed_Ve0_kph", "5")]).unwrap_err());
        assert!(
            e.contains("MaxLateralVelocity_Vy_mps = 2 meets none"),
            "{e}"
        );
        assert!(e.contains("(= -4.1666"), "{e}");
    }

    #[test]
    fn chained_references_in_any_order() {
        let decls = [
            p("speed_ms", "double", "${$speed_kph / 3.6}"),
            p("speed_kph", "double", "$base"),
            p("base", "double", "36"),
            p("label", "string", "$speed_kph"),
        ]
        .join("\n");
        let s = scope(&decls, &[]).unwrap();
        assert_eq!(s.get("speed_ms"), Some(&Value::Num(10.0)));
        assert_eq!(s.get("label"), Some(&Value::Str("36".into())));
        let order: Vec<&str> = s.declared().map(|(n, _)| n).collect();
        assert_eq!(order, ["speed_ms", "speed_kph", "base", "label"]);
        let s = scope(&decls, &[("base", "72")]).unwrap();
        assert_eq!(s.get("speed_ms"), Some(&Value::Num(20.0)));
        // A long chain resolves without recursion.
        let chain: Vec<String> = (0..5000)
            .map(|i| {
                if i == 4999 {
                    p(&format!("a{i}"), "int", "7")
                } else {
                    p(&format!("a{i}"), "int", &format!("$a{}", i + 1))
                }
            })
            .collect();
        let s = scope(&chain.join("\n"), &[]).unwrap();
        assert_eq!(s.get("a0"), Some(&Value::Num(7.0)));
    }

    #[test]
    fn circular_references_are_errors() {
        let decls = [p("a", "double", "$b"), p("b", "double", "${$a + 1}")].join("\n");
        let e = reason(scope(&decls, &[]).unwrap_err());
        assert!(
            e.contains("circular parameter reference a -> b -> a"),
            "{e}"
        );
        assert!(e.starts_with("t.xosc:3:1"), "{e}");
        let decls = [p("a", "double", "1"), p("b", "double", "$a")].join("\n");
        let e = reason(scope(&decls, &[("a", "$b")]).unwrap_err());
        assert!(
            e.contains("circular parameter reference a -> b -> a"),
            "{e}"
        );
        let e = reason(scope(&p("a", "double", "$a"), &[]).unwrap_err());
        assert!(e.contains("a -> a"), "{e}");
        let n = 3000;
        let ring: Vec<String> = (0..n)
            .map(|i| p(&format!("r{i}"), "int", &format!("$r{}", (i + 1) % n)))
            .collect();
        assert!(reason(scope(&ring.join("\n"), &[]).unwrap_err()).contains("circular"));
    }

    #[test]
    fn types_are_checked() {
        assert!(scope(&p("n", "int", "2"), &[]).is_ok());
        assert!(scope(&p("n", "integer", "-2"), &[]).is_ok());
        let e = reason(scope(&p("n", "int", "2.5"), &[]).unwrap_err());
        assert!(e.contains("2.5 is not an int"), "{e}");
        let e = reason(scope(&p("n", "unsignedInt", "-1"), &[]).unwrap_err());
        assert!(e.contains("-1 is not an unsignedInt"), "{e}");
        assert!(scope(&p("n", "unsignedShort", "70000"), &[]).is_err());
        assert!(scope(&p("n", "unsignedShort", "${60000 + 5535}"), &[]).is_ok());
        assert!(scope(&p("x", "double", "fast"), &[]).is_err());
        assert!(scope(&p("x", "double", "INF"), &[]).is_err());
        let s = scope(
            &[p("b", "boolean", "1"), p("c", "boolean", "${not $b}")].join("\n"),
            &[],
        )
        .unwrap();
        assert_eq!(
            (s.get("b"), s.get("c")),
            (Some(&Value::Bool(true)), Some(&Value::Bool(false)))
        );
        assert!(scope(&p("b", "boolean", "yes"), &[]).is_err());
        assert!(scope(&p("t", "dateTime", "2021-07-06T10:00:00"), &[]).is_ok());
        assert!(scope(&p("t", "dateTime", "2022-03-08T12:00:00.5+01:00"), &[]).is_ok());
        assert!(scope(&p("t", "dateTime", "2021-13-06T10:00:00"), &[]).is_err());
        assert!(scope(&p("t", "dateTime", "yesterday"), &[]).is_err());
        let e = reason(scope(&p("n", "int", "1"), &[("n", "1.5")]).unwrap_err());
        assert!(e.contains("(given for the run)"), "{e}");
        assert!(e.contains("1.5 is not an int"), "{e}");
    }

    /// A run's value is bound by name as the value it is: coerced to the declared type, never
    /// evaluated (a text holding `$b` is that text), and what reads it sees it.
    #[test]
    fn a_runs_value_is_typed_and_never_evaluated() {
        let text = doc(&[
            p("s", "string", "x"),
            p("d", "double", "1"),
            p("n", "int", "1"),
            p("twice", "double", "${$d * 2}"),
        ]
        .join("\n"));
        let ds = decls_of(&text).unwrap();
        let values = [
            ("s".to_owned(), Value::Str("$d".to_owned())),
            ("d".to_owned(), Value::Str("5".to_owned())),
            ("n".to_owned(), Value::Num(3.0)),
        ];
        let s = Scope::with_values(&text, &ds, &values).unwrap();
        assert_eq!(s.get("s"), Some(&Value::Str("$d".to_owned())));
        assert_eq!(s.get("d"), Some(&Value::Num(5.0)));
        assert_eq!(s.get("n"), Some(&Value::Num(3.0)));
        assert_eq!(s.get("twice"), Some(&Value::Num(10.0)));
        let e = Scope::with_values(&text, &ds, &[("n".to_owned(), Value::Num(1.5))]).unwrap_err();
        let e = reason(e);
        assert!(e.contains("n = 1.5 (given for the run) (int)"), "{e}");
        assert!(e.contains("1.5 is not an int"), "{e}");
    }

    #[test]
    fn overrides_must_be_declared() {
        let decls = [p("a", "double", "1"), p("b", "double", "2")].join("\n");
        let e = reason(scope(&decls, &[("c", "3")]).unwrap_err());
        assert!(
            e.contains("parameter c, which is not declared here; it declares a, b"),
            "{e}"
        );
        let e = reason(scope("", &[("c", "3")]).unwrap_err());
        assert!(e.contains("it declares no parameters"), "{e}");
        let s = scope(&decls, &[("a", "5"), ("a", "6")]).unwrap();
        assert_eq!(s.get("a"), Some(&Value::Num(6.0)));
    }

    #[test]
    fn constraint_groups_and_or() {
        let decl = r#"<ParameterDeclaration name="x" parameterType="double" value="5">
            <ConstraintGroup>
              <ValueConstraint rule="greaterOrEqual" value="0"/>
              <ValueConstraint rule="lessThan" value="$hi"/>
            </ConstraintGroup>
            <ConstraintGroup><ValueConstraint rule="equalTo" value="${0.1 + 0.2}"/></ConstraintGroup>
          </ParameterDeclaration>"#;
        let decls = format!("{decl}\n{}", p("hi", "double", "10"));
        assert!(scope(&decls, &[]).is_ok());
        assert!(scope(&decls, &[("x", "0.3")]).is_ok());
        assert!(scope(&decls, &[("x", "0")]).is_ok());
        let e = reason(scope(&decls, &[("x", "10")]).unwrap_err());
        assert!(
            e.contains("[greaterOrEqual 0 and lessThan $hi (= 10)] breaks lessThan $hi (= 10)"),
            "{e}"
        );
        assert!(scope(&decls, &[("x", "-1")]).is_err());
        let s = r#"<ParameterDeclaration name="m" parameterType="string" value="car">
            <ConstraintGroup><ValueConstraint rule="notEqualTo" value="bus"/></ConstraintGroup>
          </ParameterDeclaration>"#;
        assert!(scope(s, &[]).is_ok());
        assert!(scope(s, &[("m", "bus")]).is_err());
        let bad = r#"<ParameterDeclaration name="m" parameterType="string" value="car">
            <ConstraintGroup><ValueConstraint rule="lessThan" value="bus"/></ConstraintGroup>
          </ParameterDeclaration>"#;
        assert!(reason(scope(bad, &[]).unwrap_err()).contains("compares numbers only"));
        let undeclared = r#"<ParameterDeclaration name="x" parameterType="double" value="1">
            <ConstraintGroup><ValueConstraint rule="lessThan" value="$nope"/></ConstraintGroup>
          </ParameterDeclaration>"#;
        assert!(
            reason(scope(undeclared, &[]).unwrap_err()).contains("parameter $nope is not declared")
        );
    }

    #[test]
    fn declaration_errors() {
        let e = reason(
            scope(
                &[p("a", "double", "1"), p("a", "double", "2")].join("\n"),
                &[],
            )
            .unwrap_err(),
        );
        assert!(e.contains("declared twice"), "{e}");
        assert!(e.starts_with("t.xosc:4:"), "{e}");
        assert!(reason(scope(&p("a", "float", "1"), &[]).unwrap_err())
            .contains("unknown parameterType"));
        assert!(matches!(
            scope(&p("a", "$t", "1"), &[]),
            Err(XoscError::Unsupported { .. })
        ));
        assert!(reason(scope(&p("a b", "double", "1"), &[]).unwrap_err())
            .contains("cannot be referenced"));
        let e = scope(
            r#"<ParameterDeclaration name="a" parameterType="double"/>"#,
            &[],
        )
        .unwrap_err();
        assert!(reason(e).contains("needs the attribute value"));
        let e = scope(
            r#"<ParameterDeclaration name="a" parameterType="double" value="1" unit="m"/>"#,
            &[],
        );
        assert!(matches!(e, Err(XoscError::Unsupported { .. })));
        let e = scope(r#"<Parameter name="a"/>"#, &[]);
        assert!(matches!(e, Err(XoscError::Unsupported { .. })));
        let e = scope(
            r#"<ParameterDeclaration name="a" parameterType="double" value="1"><ConstraintGroup/></ParameterDeclaration>"#,
            &[],
        );
        assert!(reason(e.unwrap_err()).contains("empty <ConstraintGroup>"));
        let e = scope(
            r#"<ParameterDeclaration name="a" parameterType="double" value="1"><ConstraintGroup><ValueConstraint rule="near" value="1"/></ConstraintGroup></ParameterDeclaration>"#,
            &[],
        );
        assert!(matches!(e, Err(XoscError::Unsupported { .. })));
        let text = doc("");
        assert!(read_declarations(&text, None).unwrap().is_empty());
    }

    #[test]
    fn expression_errors_name_the_column() {
        // Line 3 is the declaration.
        let e = scope(&p("a", "double", "${1 + $nope}"), &[]).unwrap_err();
        let Some(pos) = e.pos() else { panic!("{e:?}") };
        let col =
            r#"<ParameterDeclaration name="a" parameterType="double" value=""#.len() as u32 + 1;
        assert_eq!((pos.line, pos.col), (3, col + 6), "{e}");
        assert!(reason(e).contains("parameter $nope is not declared"));
        let e = scope(&p("a", "double", "${4 / 0}"), &[]).unwrap_err();
        assert_eq!(e.pos().map(|p| p.col), Some(col + 4));
        assert!(reason(e).contains("divides by zero"));
        let e = scope(&p("a", "double", "$ x"), &[]).unwrap_err();
        assert!(reason(e).contains("is not a parameter reference"));
        let e = scope(&p("a", "double", "${1 + 2"), &[]).unwrap_err();
        assert!(reason(e).contains("must end with"));
    }

    #[test]
    fn child_scopes_shadow_and_see_outer() {
        let text = doc(&[p("speed", "double", "10"), p("name", "string", "ego")].join("\n"));
        let outer = Scope::new(&text, &decls_of(&text).unwrap(), &[]).unwrap();
        let inner_text = doc(&[p("speed", "double", "${$name == 1}")].join("\n"));
        assert!(outer
            .child(&inner_text, &decls_of(&inner_text).unwrap())
            .is_err());
        let inner_text = doc(&[
            p("speed", "double", "20"),
            p("twice", "double", "${2 * $speed}"),
            p("who", "string", "$name"),
        ]
        .join("\n"));
        let inner = outer
            .child(&inner_text, &decls_of(&inner_text).unwrap())
            .unwrap();
        assert_eq!(inner.get("twice"), Some(&Value::Num(40.0)));
        assert_eq!(inner.get("who"), Some(&Value::Str("ego".into())));
        assert_eq!(outer.get("speed"), Some(&Value::Num(10.0)));
        assert_eq!(inner.declared().count(), 3);
        let ov = [("speed".to_string(), "30".to_string())];
        let inner = outer
            .child_with(&inner_text, &decls_of(&inner_text).unwrap(), &ov)
            .unwrap();
        assert_eq!(inner.get("twice"), Some(&Value::Num(60.0)));
        // Referring to the outer value of a shadowed name is circular.
        let self_ref = doc(&p("speed", "double", "${$speed + 1}"));
        let e = outer
            .child(&self_ref, &decls_of(&self_ref).unwrap())
            .unwrap_err();
        assert!(reason(e).contains("speed -> speed"));
    }

    #[test]
    fn resolving_attributes() {
        let text = Text::new(
            "r.xosc",
            "<R>\n<ParameterDeclarations>\n<ParameterDeclaration name=\"v\" parameterType=\"double\" value=\"36\"/>\n\
             <ParameterDeclaration name=\"lane\" parameterType=\"string\" value=\"-4\"/>\n\
             <ParameterDeclaration name=\"on\" parameterType=\"boolean\" value=\"true\"/>\n</ParameterDeclarations>\n\
             <A speed=\"${$v / 3.6}\" lane=\"$lane\" name=\"car\" flag=\"$on\" bad=\"${$v / 0}\" word=\"fast\" zero=\"0\" miss=\"$w\" n=\"${1 + true}\"/>\n</R>",
        );
        let d = text.parse().unwrap();
        let decls = read_declarations(
            &text,
            d.descendants()
                .find(|n| n.has_tag_name("ParameterDeclarations")),
        )
        .unwrap();
        let s = Scope::new(&text, &decls, &[]).unwrap();
        let a = d.descendants().find(|n| n.has_tag_name("A")).unwrap();
        assert_eq!(s.num(&text, a, "speed").unwrap(), 10.0);
        assert_eq!(s.num(&text, a, "lane").unwrap(), -4.0);
        assert_eq!(s.string(&text, a, "lane").unwrap(), "-4");
        assert_eq!(s.string(&text, a, "speed").unwrap(), "10");
        assert_eq!(
            s.resolve(&text, a, "name").unwrap(),
            Some(Value::Str("car".into()))
        );
        assert_eq!(s.resolve(&text, a, "absent").unwrap(), None);
        assert_eq!(s.opt_num(&text, a, "absent").unwrap(), None);
        assert_eq!(s.opt_string(&text, a, "absent").unwrap(), None);
        assert_eq!(s.opt_bool(&text, a, "absent").unwrap(), None);
        assert!(s.bool(&text, a, "flag").unwrap());
        assert!(!s.bool(&text, a, "zero").unwrap());
        assert!(s.bool(&text, a, "name").is_err());
        let e = s.num(&text, a, "word").unwrap_err();
        assert!(reason(e).contains("attribute word = \"fast\": \"fast\" is not a number"));
        let e = s.num(&text, a, "absent").unwrap_err();
        assert!(reason(e).contains("<A> needs the attribute absent"));
        let e = s.num(&text, a, "bad").unwrap_err();
        let line = "<A speed=\"${$v / 3.6}\" lane=\"$lane\" name=\"car\" flag=\"$on\" bad=\"";
        let pos = e.pos().cloned().unwrap();
        assert_eq!((pos.line, pos.col as usize), (7, line.len() + 1 + 5), "{e}");
        assert!(reason(e).contains("divides by zero"));
        let e = s.num(&text, a, "miss").unwrap_err();
        assert!(reason(e).contains("parameter $w is not declared"));
        assert!(reason(s.num(&text, a, "n").unwrap_err()).contains("takes numbers"));
    }

    #[test]
    fn ordering_is_iterative_and_finds_cycles() {
        assert_eq!(eval_order(&[vec![1], vec![2], vec![]]), Ok(vec![2, 1, 0]));
        assert_eq!(eval_order(&[vec![1], vec![0]]), Err(vec![0, 1, 0]));
        assert_eq!(eval_order(&[vec![], vec![2], vec![1]]), Err(vec![1, 2, 1]));
        assert!(approx_eq(0.1 + 0.2, 0.3));
        assert!(!approx_eq(1.0, 1.0001));
    }
}

/// A scenario's global parameter declarations with their `ConstraintGroup`s, read once: what
/// a campaign checks each combination of values against before it runs a test on it (the
/// valid region of a logical scenario).
#[derive(Debug, Clone)]
pub struct Constrained {
    text: std::sync::Arc<Text>,
    decls: Vec<ParamDecl>,
}

impl Constrained {
    /// The global `ParameterDeclarations` of the scenario `path`, read through `files`.
    ///
    /// # Errors
    /// The file does not read or parse, or its declarations are malformed.
    pub fn read(files: &crate::FileSet, path: &std::path::Path) -> Result<Self, XoscError> {
        let text = files.text(path)?;
        let decls = {
            let doc = text.parse()?;
            let root = text.open_root(doc)?;
            read_declarations(&text, crate::xml::child(root, "ParameterDeclarations"))?
        };
        Ok(Constrained { text, decls })
    }

    /// Whether any declaration has a constraint group.
    pub fn has_constraints(&self) -> bool {
        self.decls.iter().any(|d| !d.constraint_groups.is_empty())
    }

    /// The first constraint group the scenario's values break with `values` (typed values by
    /// name, as [`Scope::with_values`] takes them), as a message naming the declaration's
    /// file, line and column; `None` when every declaration meets one of its groups, or when
    /// the values fail otherwise (a test with them reports that error).
    pub fn violation(&self, values: &[(String, Value)]) -> Option<String> {
        let scope = Scope::with_values_unconstrained(&self.text, &self.decls, values).ok()?;
        scope
            .check_all_constraints(&self.decls)
            .err()
            .map(|e| e.to_string())
    }
}
