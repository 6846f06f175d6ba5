//! What the program's syntax tells about its open parameters: the name each gets from where
//! it stands (LANGUAGE.md, "Names of parameters"), and where a variable holding one is read
//! other than as a whole argument of a builtin (then code of the program may depend on it in
//! ways the world does not show, so usage analysis counts it as used).

use std::collections::HashMap;

use starlark::syntax::AstModule;
use starlark_syntax::syntax::ast::{
    ArgumentP, AssignTargetP, AstArgument, AstExpr, AstLiteral, AstNoPayload, AstStmt, BinOp,
    CallArgsP, ExprP, StmtP,
};
use starlark_syntax::syntax::uniplate::Visit;

/// The first expression of the program that nests deeper than `limit` (operators, calls,
/// subscripts...: each level an expression inside another), with its depth (as far as it was
/// followed: the walk stops past the limit) and its `line:col`; `None` when none does.
pub fn deepest_expression(ast: &AstModule, limit: usize) -> Option<(usize, String)> {
    fn expr(e: &AstExpr, limit: usize) -> usize {
        let mut deepest = 0;
        e.visit_expr(|c| {
            if deepest <= limit {
                deepest = deepest.max(expr(c, limit));
            }
        });
        deepest + 1
    }
    fn stmt(s: &AstStmt, limit: usize, found: &mut Option<(usize, AstExpr)>) {
        s.visit_children(|v| {
            if found.is_some() {
                return;
            }
            match v {
                Visit::Stmt(s) => stmt(s, limit, found),
                Visit::Expr(e) => {
                    let d = expr(e, limit);
                    if d > limit {
                        *found = Some((d, e.clone()));
                    }
                }
            }
        });
    }
    let mut found = None;
    stmt(ast.statement(), limit, &mut found);
    found.map(|(d, e)| (d, format!("{}", ast.file_span(e.span).resolve_span().begin)))
}

/// What the syntax says about one `VarInterval`/`VarEnum` call site.
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    /// The name it gets from where it stands: the variable it is assigned to (`speed`), else
    /// `<variable>.<keyword>` of the call whose argument it is (`w.fog`), else
    /// `<Callee>.<keyword>` (`World.fog`), with `[i]` for item `i` of a tuple or list
    /// argument (`o.size[0]`); `None` elsewhere.
    pub name: Option<String>,
    /// The variable it is assigned to, if it is.
    pub variable: Option<String>,
    /// The builtin and keyword it is written inline as an argument of, if it is
    /// (`Car(speed = VarInterval(...))`: `("Car", "speed")`).
    pub argument_of: Option<(String, String)>,
    /// The variable holding the list, tuple or dict literal it is an item of, if it is
    /// (`xs = [VarInterval(...), ...]`: `xs`): code that reads `xs` reads it.
    pub container: Option<String>,
}

/// What the syntax of a program says, by call site (`"line:col"`, from 1).
#[derive(Debug, Default)]
pub struct Syntax {
    sites: HashMap<String, Site>,
    /// Identifiers read other than as a whole argument of a paracosm builtin: inside a lambda
    /// or a `def`, in an expression, as an argument of a user function.
    used_in_code: HashMap<String, usize>,
    /// `(builtin, keyword, variable)` for every `Builtin(keyword = variable)`.
    passed: Vec<(String, String, String)>,
    /// `(builtin, keyword, variable)` for every variable added or subtracted in a sum given
    /// to a builtin (`r.onLane(1, 10.0 + gap)`): its unit is the sum's.
    summed: Vec<(String, String, String)>,
    /// The variable each call is assigned to, by call site (`"line:col"`), for calls that run
    /// once per evaluation: `x = Builtin(...)` at the top level of the module or under an
    /// `if` there, not in a loop or a `def`.
    assigned_once: HashMap<String, String>,
    /// `"line:col"` and text of each action called as a statement of the program's own code
    /// (`c.setSpeed(2.0)` outside any `def`): it builds an action and drops it.
    dropped_actions: Vec<(String, String)>,
}

/// The methods that make actions (LANGUAGE.md, "Actions").
const ACTIONS: [&str; 3] = ["setSpeed", "brake", "changeLane"];

/// Records every statement outside a `def` that is only a call of an action method.
fn dropped_actions(ast: &AstModule, s: &AstStmt, out: &mut Vec<(String, String)>) {
    match &s.node {
        StmtP::Statements(list) => list.iter().for_each(|s| dropped_actions(ast, s, out)),
        StmtP::If(_, body) => dropped_actions(ast, body, out),
        StmtP::IfElse(_, bodies) => {
            dropped_actions(ast, &bodies.0, out);
            dropped_actions(ast, &bodies.1, out);
        }
        StmtP::For(f) => dropped_actions(ast, &f.body, out),
        StmtP::Expression(e) => {
            if let ExprP::Call(f, _) = &e.node {
                if let ExprP::Dot(_, method) = &f.node {
                    if ACTIONS.contains(&method.node.as_str()) {
                        let span = ast.file_span(e.span);
                        let at = format!("{}", span.resolve_span().begin);
                        out.push((at, span.source_span().to_owned()));
                    }
                }
            }
        }
        _ => {}
    }
}

/// Records `x = f(...)` statements that run at most once per evaluation.
fn assigned_once(ast: &AstModule, s: &AstStmt, out: &mut HashMap<String, String>) {
    match &s.node {
        StmtP::Statements(list) => list.iter().for_each(|s| assigned_once(ast, s, out)),
        StmtP::If(_, body) => assigned_once(ast, body, out),
        StmtP::IfElse(_, bodies) => {
            assigned_once(ast, &bodies.0, out);
            assigned_once(ast, &bodies.1, out);
        }
        StmtP::Assign(a) => {
            if let (AssignTargetP::Identifier(id), ExprP::Call(..)) = (&a.lhs.node, &a.rhs.node) {
                let at = format!("{}", ast.file_span(a.rhs.span).resolve_span().begin);
                out.insert(at, id.node.ident.clone());
            }
        }
        _ => {}
    }
}

fn callee(e: &AstExpr) -> Option<String> {
    match &e.node {
        ExprP::Identifier(id) => Some(id.node.ident.clone()),
        ExprP::Dot(_, attr) => Some(attr.node.clone()),
        _ => None,
    }
}

/// The keyword of a method's positional argument `position`, for its unit:
/// `r.onLane(lane, at)`'s `at`, `car.brake(decel)`, `car.setSpeed(speed)`.
fn positional_keyword(method: &str, position: usize) -> Option<&'static str> {
    match (method, position) {
        ("onLane", 1) => Some("at"),
        ("brake", 0) => Some("decel"),
        ("setSpeed", 0) => Some("v"),
        ("changeLane", 1) => Some("duration"),
        _ => None,
    }
}

/// The position in `method`'s signature of its argument named `keyword`, given the keywords
/// of the call (a junction's `onLane` has a port and a turn first): `r.onLane(at = x)` is
/// argument 1, as in `r.onLane(1, x)`.
fn method_position(method: &str, keyword: &str, keywords: &[&str]) -> Option<usize> {
    let junction = keywords.iter().any(|k| matches!(*k, "port" | "turn"));
    let order: &[&str] = match (method, junction) {
        ("onLane", false) => &["lane", "at"],
        ("onLane", true) => &["port", "turn", "at", "lane"],
        ("changeLane", _) => &["lane", "duration"],
        ("brake", _) => &["decel"],
        ("setSpeed", _) => &["v"],
        _ => return None,
    };
    order.iter().position(|k| *k == keyword)
}

fn is_declarer(e: &AstExpr) -> bool {
    matches!(&e.node, ExprP::Call(f, _) if callee(f).is_some_and(|c| super::builtins::declares_parameter(&c)))
}

/// What the walk knows of a call while it walks its arguments.
struct Call<'a> {
    /// The callee.
    f: &'a AstExpr,
    /// Its name (a function's, or a method's without the object).
    name: Option<String>,
    /// Whether it is a builtin that takes its arguments whole (not a declarer).
    builtin: bool,
    /// How many positional arguments are open parameters.
    open_positional: usize,
    /// How many keyword arguments are open parameters.
    open_named: usize,
    /// `(object, method)` for a method of an object named by a variable.
    method_of: Option<(String, String)>,
    /// The call's keywords.
    keywords: Vec<&'a str>,
    /// The variable the call is assigned to, if any.
    target: Option<&'a str>,
    /// Whether the call is read by code.
    in_code: bool,
}

struct Walker<'a> {
    ast: &'a AstModule,
    builtins: &'a [&'a str],
    out: Syntax,
    /// The variable assigned the list, tuple or dict literal being walked, if any.
    container: Option<String>,
}

impl Walker<'_> {
    fn pos(&self, e: &AstExpr) -> String {
        format!("{}", self.ast.file_span(e.span).resolve_span().begin)
    }

    fn site(
        &mut self,
        e: &AstExpr,
        name: Option<String>,
        variable: Option<String>,
        argument_of: Option<(String, String)>,
    ) {
        let key = self.pos(e);
        let container = self.container.clone();
        self.out.sites.entry(key).or_insert(Site {
            name,
            variable,
            argument_of,
            container,
        });
    }

    fn stmt(&mut self, s: &AstStmt, in_code: bool) {
        match &s.node {
            StmtP::Assign(a) => {
                let target = match &a.lhs.node {
                    AssignTargetP::Identifier(id) => Some(id.node.ident.clone()),
                    _ => None,
                };
                // `dist = trigger_distance`: an alias may be read anywhere, so the value is
                // read by code.
                let alias = matches!(a.rhs.node, ExprP::Identifier(_));
                // `a, b = VarInterval(...), VarInterval(...)`: each item is assigned to its
                // own variable, and named by it.
                if let (AssignTargetP::Tuple(targets), ExprP::Tuple(items)) =
                    (&a.lhs.node, &a.rhs.node)
                {
                    if targets.len() == items.len() {
                        for (t, x) in targets.iter().zip(items) {
                            let name = match &t.node {
                                AssignTargetP::Identifier(id) => Some(id.node.ident.clone()),
                                _ => None,
                            };
                            let alias = matches!(x.node, ExprP::Identifier(_));
                            self.expr(x, name.as_deref(), in_code || alias);
                        }
                        a.lhs.visit_expr(|e| self.expr(e, None, true));
                        return;
                    }
                }
                // `xs = [VarInterval(...), ...]`, `cfg = {"k": VarEnum(...)}`: the items are
                // read through the variable.
                let literal = matches!(
                    a.rhs.node,
                    ExprP::List(_)
                        | ExprP::Tuple(_)
                        | ExprP::Dict(_)
                        | ExprP::ListComprehension(..)
                        | ExprP::DictComprehension(..)
                );
                let outer = self.container.take();
                self.container = if literal {
                    target.clone()
                } else {
                    outer.clone()
                };
                self.expr(&a.rhs, target.as_deref(), in_code || alias);
                self.container = outer;
                a.lhs.visit_expr(|e| self.expr(e, None, true));
            }
            // Everything a function does is code.
            StmtP::Def(_) => s.visit_children(|v| match v {
                Visit::Stmt(s) => self.stmt(s, true),
                Visit::Expr(e) => self.expr(e, None, true),
            }),
            StmtP::For(f) => {
                self.expr(&f.over, None, true);
                self.stmt(&f.body, in_code);
            }
            StmtP::If(c, body) => {
                self.expr(c, None, true);
                self.stmt(body, in_code);
            }
            StmtP::IfElse(c, bodies) => {
                self.expr(c, None, true);
                self.stmt(&bodies.0, in_code);
                self.stmt(&bodies.1, in_code);
            }
            _ => s.visit_children(|v| match v {
                Visit::Stmt(s) => self.stmt(s, in_code),
                Visit::Expr(e) => self.expr(e, None, in_code),
            }),
        }
    }

    /// Walks `e`, the direct right-hand side of an assignment to `target` if any; `in_code`:
    /// identifiers here are read by code rather than passed whole to a builtin.
    fn expr(&mut self, e: &AstExpr, target: Option<&str>, in_code: bool) {
        match &e.node {
            ExprP::Call(f, args) => self.call(e, f, args, target, in_code),
            ExprP::Identifier(id) => {
                if in_code {
                    *self
                        .out
                        .used_in_code
                        .entry(id.node.ident.clone())
                        .or_default() += 1;
                }
            }
            ExprP::Lambda(_) => e.visit_expr(|x| self.expr(x, None, true)),
            // Tuples and lists of arguments (`connect((a.ONE, b, b.TWO))`, `route = [x]`)
            // pass their items on as they are.
            ExprP::Tuple(items) | ExprP::List(items) => {
                for x in items {
                    match &x.node {
                        ExprP::Identifier(_) if !in_code => {}
                        _ => self.expr(x, None, in_code),
                    }
                }
            }
            _ => e.visit_expr(|x| self.expr(x, None, true)),
        }
    }

    /// A call: names the open parameters among its arguments and notes the variables it
    /// takes whole, then walks the callee.
    fn call(
        &mut self,
        e: &AstExpr,
        f: &AstExpr,
        args: &CallArgsP<AstNoPayload>,
        target: Option<&str>,
        in_code: bool,
    ) {
        let name = callee(f);
        if is_declarer(e) {
            let given = target.map(str::to_owned);
            self.site(e, given.clone(), given, None);
        }
        let builtin = name
            .as_deref()
            .is_some_and(|n| self.builtins.contains(&n) && !super::builtins::declares_parameter(n));
        // Open parameters among a method's positional arguments: one is named by the
        // method, several by their positions too.
        let open_positional = args
            .args
            .iter()
            .filter(|a| matches!(a.node, ArgumentP::Positional(_)) && is_declarer(a.node.expr()))
            .count();
        // A method of an object named by a variable (`r.onLane(...)`): its open
        // arguments are named after the object and the method, by keyword as by
        // position (`r.onLane(lane = 1, at = x)` is `r.onLane(1, x)`).
        let method_of = match &f.node {
            ExprP::Dot(obj, method) => match &obj.node {
                ExprP::Identifier(o) => Some((o.node.ident.clone(), method.node.clone())),
                _ => None,
            },
            _ => None,
        };
        let keywords: Vec<&str> = args
            .args
            .iter()
            .filter_map(|a| match &a.node {
                ArgumentP::Named(kw, _) => Some(kw.node.as_str()),
                _ => None,
            })
            .collect();
        let open_named = args
            .args
            .iter()
            .filter(|a| matches!(a.node, ArgumentP::Named(..)) && is_declarer(a.node.expr()))
            .count();
        let c = Call {
            f,
            name,
            builtin,
            open_positional,
            open_named,
            method_of,
            keywords,
            target,
            in_code,
        };
        for (position, a) in args.args.iter().enumerate() {
            self.argument(&c, position, a);
        }
        self.expr(f, None, in_code);
    }

    /// The items of a dict argument: an open value is named by its key (`Import("s.xosc",
    /// params = {"Ego_Speed": VarInterval(...)})` opens the file's parameter `Ego_Speed`).
    fn dict_items(&mut self, items: &[(AstExpr, AstExpr)]) {
        for (k, v) in items {
            if let (ExprP::Literal(AstLiteral::String(key)), true) = (&k.node, is_declarer(v)) {
                self.site(v, Some(key.node.clone()), None, None);
            }
        }
    }

    /// Argument number `position` of the call `c`.
    fn argument(&mut self, c: &Call<'_>, position: usize, a: &AstArgument) {
        let value = a.node.expr();
        self.named_argument(c, a);
        // An item of a tuple or list argument: `o = Obstacle(size = (VarInterval(
        // ...), 1, 1))` is `o.size[0]`, `route = [VarEnum(...)]` of `v` is
        // `v.route[0]`.
        if let (ArgumentP::Named(kw, _), ExprP::Tuple(items) | ExprP::List(items)) =
            (&a.node, &value.node)
        {
            self.item_arguments(c, &kw.node, items);
        }
        if let (ArgumentP::Named(..), ExprP::Dict(items)) = (&a.node, &value.node) {
            self.dict_items(items);
        }
        // A positional argument of a method: `lead.brake(VarEnum(...))` is
        // `lead.brake`; with several, `r.onLane(VarEnum(...), VarInterval(...))`
        // gives `r.onLane[0]` and `r.onLane[1]`.
        if let (ArgumentP::Positional(_), true, ExprP::Dot(obj, method)) =
            (&a.node, is_declarer(value), &c.f.node)
        {
            if let ExprP::Identifier(o) = &obj.node {
                let n = if c.open_positional + c.open_named > 1 {
                    format!("{}.{}[{position}]", o.node.ident, method.node)
                } else {
                    format!("{}.{}", o.node.ident, method.node)
                };
                // The input it feeds, for its unit: `onLane(lane, at)`'s `at`.
                let argument_of = positional_keyword(&method.node, position)
                    .map(|k| (method.node.to_string(), k.to_owned()));
                self.site(value, Some(n), None, argument_of);
            }
        }
        self.argument_value(c, position, a);
    }

    /// A keyword argument `a` of the call `c` that is an open parameter: named after the
    /// object and method (`r.onLane(at = VarInterval(...))` is `r.onLane`, or
    /// `r.onLane[i]` among several), else after the variable assigned the call or the
    /// callee, and the keyword (`w.fog`, `World.fog`).
    fn named_argument(&mut self, c: &Call<'_>, a: &AstArgument) {
        let value = a.node.expr();
        let signature_position = match (&a.node, &c.method_of) {
            (ArgumentP::Named(kw, _), Some((_, m))) => method_position(m, &kw.node, &c.keywords),
            _ => None,
        };
        if let (ArgumentP::Named(kw, _), true, Some(i), Some((o, m))) = (
            &a.node,
            is_declarer(value),
            signature_position,
            &c.method_of,
        ) {
            let n = if c.open_named + c.open_positional > 1 {
                format!("{o}.{m}[{i}]")
            } else {
                format!("{o}.{m}")
            };
            let argument_of = c
                .name
                .clone()
                .filter(|_| c.builtin)
                .map(|b| (b, kw.node.clone()));
            self.site(value, Some(n), None, argument_of);
        } else if let (ArgumentP::Named(kw, _), true) = (&a.node, is_declarer(value)) {
            let owner = c.target.map(str::to_owned).or_else(|| c.name.clone());
            let n = owner.map(|o| format!("{o}.{}", kw.node));
            let argument_of = c
                .name
                .clone()
                .filter(|_| c.builtin)
                .map(|b| (b, kw.node.clone()));
            self.site(value, n, None, argument_of);
        }
    }

    /// The items of a tuple or list given to keyword `kw` of the call `c`: a variable passed
    /// whole to a builtin's item, and an open parameter named `<owner>.<kw>[i]`.
    fn item_arguments(&mut self, c: &Call<'_>, kw: &str, items: &[AstExpr]) {
        let owner = c.target.map(str::to_owned).or_else(|| c.name.clone());
        for (i, x) in items.iter().enumerate() {
            // A variable as an item (`size = (sz, 1, 1)`): passed whole to
            // that item's input, for its unit.
            if let (ExprP::Identifier(id), true, Some(b)) = (&x.node, c.builtin, &c.name) {
                self.out
                    .passed
                    .push((b.clone(), format!("{kw}[{i}]"), id.node.ident.clone()));
            }
            if is_declarer(x) {
                let n = owner.as_ref().map(|o| format!("{o}.{kw}[{i}]"));
                let argument_of = c
                    .name
                    .clone()
                    .filter(|_| c.builtin)
                    .map(|b| (b, format!("{kw}[{i}]")));
                self.site(x, n, None, argument_of);
            }
        }
    }

    /// What argument number `position` of the call `c` passes: a variable passed whole to a
    /// builtin (under the keyword of the input it feeds), the variables a sum adds whole, and
    /// the walk of any other expression.
    fn argument_value(&mut self, c: &Call<'_>, position: usize, a: &AstArgument) {
        let value = a.node.expr();
        // The keyword of the input the argument feeds: its own, or a method's
        // by position (`r.onLane(1, x)`'s `at`).
        let keyword = match (&a.node, &c.method_of) {
            (ArgumentP::Named(kw, _), _) => Some(kw.node.clone()),
            (ArgumentP::Positional(_), Some((_, m))) => {
                positional_keyword(m, position).map(str::to_owned)
            }
            _ => None,
        };
        match (&value.node, c.builtin) {
            // A variable passed whole to a builtin: the world shows its effect.
            (ExprP::Identifier(id), true) => {
                if let (Some(kw), Some(n)) = (keyword, &c.name) {
                    self.out.passed.push((n.clone(), kw, id.node.ident.clone()));
                }
                if c.in_code {
                    *self
                        .out
                        .used_in_code
                        .entry(id.node.ident.clone())
                        .or_default() += 1;
                }
            }
            // A sum or difference (`10.0 + gap`): each variable added whole
            // carries its unit into the sum, so it is checked against the input's.
            (ExprP::Op(_, BinOp::Add | BinOp::Subtract, _) | ExprP::Minus(_), true) => {
                if let (Some(kw), Some(n)) = (keyword, &c.name) {
                    let mut terms = Vec::new();
                    summed_variables(value, &mut terms);
                    for v in terms {
                        self.out.summed.push((n.clone(), kw.clone(), v));
                    }
                }
                self.expr(value, None, true);
            }
            _ => self.expr(value, None, c.in_code || !c.builtin),
        }
    }
}

impl Syntax {
    /// Analyses `ast`; `builtins` are the names of paracosm's builtins and methods (a variable
    /// passed whole to one of them is not "read by code").
    pub fn of(ast: &AstModule, builtins: &[&str]) -> Syntax {
        let mut w = Walker {
            ast,
            builtins,
            out: Syntax::default(),
            container: None,
        };
        w.stmt(ast.statement(), false);
        assigned_once(ast, ast.statement(), &mut w.out.assigned_once);
        dropped_actions(ast, ast.statement(), &mut w.out.dropped_actions);
        w.out
    }

    /// Actions called as statements outside any `def` (`c.setSpeed(2.0)` on a line of its
    /// own): `("line:col", the call's text)`.
    pub fn dropped_actions(&self) -> &[(String, String)] {
        &self.dropped_actions
    }

    /// Every call assigned once to a variable: `"line:col"` of the call → the variable.
    pub fn objects(&self) -> HashMap<String, String> {
        self.assigned_once.clone()
    }

    /// The site at `at` (`file:line:col`, the position of the call).
    pub fn site(&self, at: &str) -> Option<&Site> {
        let mut parts = at.rsplitn(3, ':');
        let col = parts.next()?;
        let line = parts.next()?;
        self.sites.get(&format!("{line}:{col}"))
    }

    /// Whether the program reads `variable` in code (a lambda, a `def`, an expression, a user
    /// function's argument) rather than only passing it whole to builtins.
    pub fn read_in_code(&self, variable: &str) -> bool {
        self.used_in_code.get(variable).copied().unwrap_or(0) > 0
    }

    /// The `(builtin, keyword)` pairs that `variable` is passed to whole.
    pub fn passed_to(&self, variable: &str) -> Vec<(&str, &str)> {
        self.passed
            .iter()
            .filter(|(_, _, v)| v == variable)
            .map(|(b, k, _)| (b.as_str(), k.as_str()))
            .collect()
    }

    /// The `(builtin, keyword)` pairs that `variable` is added to or subtracted from others
    /// in (`r.onLane(1, 10.0 + gap)` gives `("onLane", "at")` for `gap`): the sum is in the
    /// variable's unit.
    pub fn summed_in(&self, variable: &str) -> Vec<(&str, &str)> {
        self.summed
            .iter()
            .filter(|(_, _, v)| v == variable)
            .map(|(b, k, _)| (b.as_str(), k.as_str()))
            .collect()
    }
}

/// The variables that the sum or difference `e` adds or subtracts whole (`10.0 + gap - a`
/// gives `gap` and `a`; `-gap` gives `gap`); a product's or a call's are not taken (`kmh /
/// 3.6` converts a unit).
fn summed_variables(e: &AstExpr, out: &mut Vec<String>) {
    match &e.node {
        ExprP::Identifier(id) => out.push(id.node.ident.clone()),
        ExprP::Op(l, BinOp::Add | BinOp::Subtract, r) => {
            summed_variables(l, out);
            summed_variables(r, out);
        }
        ExprP::Minus(x) | ExprP::Plus(x) => summed_variables(x, out),
        _ => {}
    }
}

/// Gives each parameter its final name: `explicit[k]` when given, else the site's name, else
/// `param<k>`; names that two parameters derive alike (one call site in a loop, or the same
/// keyword of two calls) get `_1`, `_2`, ... in declaration order.
///
/// # Errors
/// A message when two explicit names clash.
pub fn final_names(explicit: &[Option<String>], derived: &[Option<String>]) -> Vec<String> {
    let base: Vec<String> = explicit
        .iter()
        .zip(derived)
        .enumerate()
        .map(|(k, (e, d))| {
            e.clone()
                .or_else(|| d.clone())
                .unwrap_or_else(|| format!("param{k}"))
        })
        .collect();
    let mut out = base.clone();
    for (k, name) in base.iter().enumerate() {
        if explicit[k].is_some() {
            continue;
        }
        let same: Vec<usize> = (0..base.len())
            .filter(|&j| base[j] == *name && explicit[j].is_none())
            .collect();
        let taken_explicitly = (0..base.len()).any(|j| explicit[j].as_deref() == Some(name));
        if same.len() > 1 || taken_explicitly {
            let i = same.iter().position(|&j| j == k).unwrap_or(0) + 1;
            out[k] = format!("{name}_{i}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use starlark::syntax::Dialect;

    fn syntax(src: &str) -> Syntax {
        let dialect = Dialect {
            enable_top_level_stmt: true,
            ..Dialect::Standard
        };
        let ast = AstModule::parse("t.star", src.to_owned(), &dialect).unwrap();
        Syntax::of(&ast, &["World", "Car", "RoadSegment", "onLane", "map"])
    }

    #[test]
    fn names_come_from_where_the_parameter_stands() {
        let s = syntax(
            "speed = VarInterval(0, 1)\nw = World(fog = VarInterval(0, 1))\nWorld(light = VarEnum([0.1, 0.2]))\nx = [VarInterval(0, 1)]\n",
        );
        assert_eq!(s.site("t.star:1:9").unwrap().name.as_deref(), Some("speed"));
        assert_eq!(
            s.site("t.star:1:9").unwrap().variable.as_deref(),
            Some("speed")
        );
        assert_eq!(
            s.site("t.star:2:17").unwrap().name.as_deref(),
            Some("w.fog")
        );
        assert_eq!(
            s.site("t.star:3:15").unwrap().name.as_deref(),
            Some("World.light")
        );
        assert_eq!(s.site("t.star:4:6").unwrap().name, None);
    }

    #[test]
    fn reading_a_variable_in_code_is_told_apart_from_passing_it_to_a_builtin() {
        let s = syntax(
            "c = VarEnum(['red', 'white'])\nk = VarEnum([1, 2])\nd = VarInterval(0, 1)\ncar = Car(color = c, speed = tick.map(lambda t: k * t))\nif d > 0.5:\n    pass\n",
        );
        assert!(!s.read_in_code("c"));
        assert_eq!(s.passed_to("c"), [("Car", "color")]);
        assert!(s.read_in_code("k"), "inside a lambda");
        assert!(s.read_in_code("d"), "in a condition");
    }

    /// An open parameter written inline in `Import`'s `params` is named by the file's
    /// parameter it opens (it was `param0`).
    #[test]
    fn an_inline_import_parameter_is_named_by_its_key() {
        let src = "s = Import(\"x.xosc\", params = {\"Ego_Speed\": VarInterval(1, 2)})\n";
        let col = src.find("VarInterval").unwrap() + 1;
        let s = syntax(src);
        assert_eq!(
            s.site(&format!("t.star:1:{col}")).unwrap().name.as_deref(),
            Some("Ego_Speed")
        );
    }

    #[test]
    fn alike_names_are_numbered_and_explicit_ones_win() {
        let names = final_names(
            &[None, None, Some("x".into()), None],
            &[
                Some("Car.speed".into()),
                Some("Car.speed".into()),
                None,
                Some("x".into()),
            ],
        );
        assert_eq!(names, ["Car.speed_1", "Car.speed_2", "x", "x_1"]);
    }
}
