//! A loaded scenario program: evaluated once per test with that test's values of its open
//! parameters (paper §2, "A Family of Worlds": a test case closes every open stream, so every
//! input, road geometry included, may be open), and a few times when it loads, to learn its
//! parameters, to check its worlds over the levels and corners of its parameters, and to find
//! which inputs each parameter changes.

mod load;

use super::load_error::{LoadError, LoadErrorKind};
pub use load::load;
use std::io::Write;
use std::sync::Arc;

use paracosm_engine::rx::{Host, Node, OpenStream, RxError, StreamId};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{EngineError, WorldSpec};
use paracosm_generators::{Assignment, Domain, Param, ParamSpace, Value as Level};
use starlark::environment::{Globals, Module};
use starlark::eval::Evaluator;
use starlark::syntax::AstModule;
use starlark::values::Value;

use super::globals::LoadState;
use super::host::{CallLimits, StarHost};
use super::names::{final_names, Syntax};
use super::scene::{self, coordinate_names, ParamDecl, ParamValue, SceneBuilder};
use super::values::OverTime;
use crate::analysis as usage;
use crate::scenario::Warning;
use crate::scene::GivenValues;
use crate::{MonitorSpec, Scenario, ScenarioError};

/// Most combinations of parameter values checked when a program loads; beyond it, the rows
/// of a pairwise covering array over them.
pub const MAX_CHECKED_WORLDS: usize = 4096;

/// Where inside an interval loading probes one more value of each `VarInterval`, as a
/// fraction of its width: the golden ratio's, so that the value is no round number.
const INTERIOR_FRACTION: f64 = 0.618_033_988_749_894_8;

/// Most values of one parameter evaluated at load to learn which inputs it changes (spread
/// evenly over its levels, the first and last among them).
const MAX_PROBED_VALUES: usize = 64;

/// Most combinations of the other parameters' values from which a parameter that seems not
/// to matter is varied again ([`Program::changes_elsewhere`]).
const MAX_REPROBE_BASES: usize = 16;

/// Most evaluations that varying all such parameters again takes together, spread evenly
/// over them (each is varied from at least one combination).
const REPROBE_EVALUATIONS: usize = 4096;

/// Most values of such a parameter tried from each of those combinations.
const MAX_REPROBED_VALUES: usize = 4;

/// Most evaluation steps that varying one such parameter again may take.
const MAX_REPROBE_STEPS: u64 = 5_000_000;

/// Most evaluation steps that all the checks at load take together (the combinations, what
/// each parameter changes, the second looks at parameters that seem unused, the monitors of
/// constants), beyond the first evaluation: one budget, spent in that order. The combinations
/// take at most [`MAX_CHECK_STEPS`] of it. A check the budget does not reach is named in a
/// warning; a parameter whose effect was not probed counts as used.
pub const MAX_LOAD_CHECK_STEPS: u64 = 2 * MAX_CHECK_STEPS;

/// Most open parameters a program may declare: each one is a dimension of the test space
/// and costs its own probes at load (10,000 parameters would take minutes to load).
pub const MAX_PARAMS: usize = 500;

/// Most evaluation steps (function calls and loop iterations, as starlark counts them) that
/// checking the combinations at load may take in all. A program whose every evaluation is
/// long would otherwise take up to [`MAX_CHECKED_WORLDS`] × [`super::MAX_LOAD_STEPS`] steps;
/// past this budget, the combinations left are checked by the tests that reach them, and a
/// warning says how many were checked.
pub const MAX_CHECK_STEPS: u64 = 50_000_000;

/// A program and what its first evaluation told about it.
pub struct Program {
    file: String,
    ast: AstModule,
    globals: Globals,
    /// Final name and declaration of each open parameter, in declaration order.
    params: Vec<(String, ParamDecl)>,
    /// The monitors the program declares (without the default `OffRoadMonitor`).
    monitors: Vec<MonitorSpec>,
    horizon_s: f64,
    sut: SutConfig,
    syntax: Syntax,
    /// [`Syntax::objects`], shared with every evaluation.
    objects: Arc<std::collections::HashMap<String, String>>,
    /// The maps it reads, read once and shared with every evaluation.
    maps: Arc<crate::map_files::MapFiles>,
    /// The `Require`s of the first evaluation: name and where each stands.
    requires: Vec<(String, crate::scene::Site)>,
    /// Whether what the program prints at load has been shown (the load evaluates it more
    /// than once with the representative values; its output is shown once).
    load_output_shown: std::sync::atomic::AtomicBool,
    /// [`Program::combinations`], computed once.
    combinations: std::sync::OnceLock<Vec<(Vec<ParamValue>, String)>>,
    /// Evaluation steps the checks at load have taken ([`MAX_LOAD_CHECK_STEPS`]).
    load_steps: std::sync::atomic::AtomicU64,
    /// The worlds of the combinations that [`Program::changes_elsewhere`] varies parameters
    /// from, by index in [`Program::combinations`], with their step counts.
    #[allow(clippy::type_complexity)]
    base_worlds: std::sync::Mutex<std::collections::BTreeMap<usize, Option<(Arc<Evaluated>, u64)>>>,
}

fn lambda_values<'v>(b: &SceneBuilder, module: &Module<'v>) -> Result<Vec<Value<'v>>, LoadError> {
    (0..b.lambdas)
        .map(|n| {
            module.get(&super::lambda_name(n)).ok_or_else(|| {
                LoadError::new(
                    LoadErrorKind::Evaluation,
                    format!("lambda {n} is missing from the program's module"),
                )
            })
        })
        .collect()
}

/// Checks what every evaluation must have declared once the program has run; the error is
/// the whole message, pointing at the declaration at fault, else at `file`.
fn finished(b: &SceneBuilder, file: &str) -> Result<(), LoadError> {
    finished_message(b).map_err(|(m, at)| {
        let message = format!("error: {m}\n --> {}", at.unwrap_or(file));
        LoadError::new(LoadErrorKind::Declarations, message)
    })
}

/// What [`finished`] finds wrong, and where, when one declaration is at fault.
fn finished_message(b: &SceneBuilder) -> Result<(), (String, Option<&str>)> {
    if !b.placed && (b.story.is_none() || !b.objects.is_empty()) {
        return Err((
            "the program never calls place(...): nothing to test".into(),
            None,
        ));
    }
    if let Some(o) = b.objects.iter().find(|o| !o.placed) {
        return Err((
            format!(
                "{} is declared after place(...), so it is never placed: declare every actor \
                 and obstacle before place(...), and list it there",
                o.name
            ),
            Some(&o.at),
        ));
    }
    if b.scene.ego().is_none() {
        return Err((
            "the program places no AutonomousVehicle: nothing to test".into(),
            b.placed_at.as_deref(),
        ));
    }
    if b.scene.environment().is_none() {
        return Err(("the program has no World(...)".into(), None));
    }
    Ok(())
}

/// Refuses an `Stl` monitor with a temporal operator whose window lies entirely after the
/// test's horizon ([`paracosm_oracles::stl::Formula::windows_after`]): no frame of a test is
/// in it, so its verdict is the same in every test (an `F` always fails, a `G` always
/// passes on it).
fn windows_within_horizon(b: &SceneBuilder, horizon_s: f64) -> Result<(), LoadError> {
    for (m, at) in b.scene.monitors() {
        let mut spec = m;
        while let MonitorSpec::TimeToFailure { inner, .. } = spec {
            spec = inner;
        }
        let MonitorSpec::Stl { name, formula } = spec else {
            continue;
        };
        let Ok(f) = paracosm_oracles::stl::parse(formula) else {
            continue;
        };
        if let Some(&(op, lo, hi, start)) = f.windows_after(horizon_s).first() {
            let verdict = match op {
                'G' => "it can never fail (nothing to check)",
                _ => "it can never be satisfied, and fails every test",
            };
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "error: Stl monitor `{name}`: the window {op}[{lo},{hi}] starts at {start} s, \
                 after the test's horizon of {horizon_s} s: no frame of a test falls in it, so \
                 {verdict}; make the horizon longer (test(horizon = ...)) or the window \
                 earlier\n --> {at}"
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a pedestrian walked by two behaviours (its `dist=`/`car=` or `trigger=` and a
/// `foreach(p.walk)`, or two `foreach(p.walk)`): each walks it when it fires, and a
/// pedestrian takes one walking step per step, so one of the two would only change when it
/// walks, without a word.
fn one_walker_each(b: &SceneBuilder) -> Result<(), LoadError> {
    use paracosm_engine::behaviour::{Action, ActorRef};
    let mut walkers: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    let mut handles = std::collections::BTreeMap::new();
    for (i, node) in b.scene.nodes().iter().enumerate() {
        if let Node::Foreach {
            sink: Action::Walk(p),
            ..
        } = node
        {
            handles.insert(p.index(), *p);
            walkers.entry(p.index()).or_default().push(i);
        }
    }
    for (p, nodes) in walkers {
        let [first, second, ..] = nodes[..] else {
            continue;
        };
        let name = b
            .objects
            .iter()
            .find(|o| o.actor == handles.get(&p).map(|&h| ActorRef::Pedestrian(h)))
            .map_or_else(|| format!("pedestrian {p}"), |o| o.name.clone());
        let site = |n: usize| b.scene.graph().site(n).unwrap_or("?").to_owned();
        return Err(LoadError::new(
            LoadErrorKind::Declarations,
            format!(
            "error: {name} is walked by two behaviours, at {} and at {}: a pedestrian takes one \
             walking step per step, so the second would change only when it walks; keep one \
             (a Pedestrian given dist= and car=, or trigger=, walks by itself: drop the \
             foreach(...walk), or give the Pedestrian neither)\n --> {}",
            site(first),
            site(second),
            site(second)
        ),
        ));
    }
    Ok(())
}

/// Lets an imported entity held by a top-level variable of `module` (`lead = s.Lead`)
/// publish its outputs in `b` under that variable's name, as a declaration's variable does.
fn alias_imported(module: &Module<'_>, b: &mut SceneBuilder) {
    for name in module.names() {
        let imported = module.get(name.as_str()).and_then(|v| {
            starlark::values::ValueLike::downcast_ref::<crate::lang::values::ActorVal>(v)
                .filter(|a| a.object == crate::lang::globals::import::IMPORTED)
                .map(|a| a.kind)
        });
        if let Some(actor) = imported {
            b.scene.alias_actor(name.as_str().to_owned(), actor);
        }
    }
}

impl Program {
    /// Evaluates the program with `values` (bound by name, [`Program::given`]; `None`:
    /// representative values) within the loading limits, checks that it finished, and calls `then` with what
    /// it declared and its module (whose lambdas the test calls).
    fn evaluate<R>(
        &self,
        values: Option<GivenValues>,
        then: impl FnOnce(SceneBuilder, &Module) -> Result<R, LoadError>,
    ) -> Result<R, LoadError> {
        self.evaluate_counted(values, then).map(|(r, _)| r)
    }

    /// [`Program::evaluate`], also returning the evaluation's step count.
    fn evaluate_counted<R>(
        &self,
        values: Option<GivenValues>,
        then: impl FnOnce(SceneBuilder, &Module) -> Result<R, LoadError>,
    ) -> Result<(R, u64), LoadError> {
        let again = values.clone();
        Module::with_temp_heap(|module| {
            let state = LoadState::new(values, self.objects.clone(), self.maps.clone());
            state.scene.borrow_mut().route_m = scene::route_length_m(self.horizon_s);
            let steps;
            {
                let mut eval = Evaluator::new(&module);
                eval.extra = Some(&state);
                eval.set_print_handler(&state);
                let budget = self.limit_load(&module, &mut eval)?;
                let result = eval.eval_module(self.ast.clone(), &self.globals);
                let result = match result {
                    Err(_) if crate::memory::over_soft_limit() => {
                        Err(starlark::Error::new_other(anyhow::anyhow!(
                            "error: the program used more than the heap limit of {} MiB",
                            super::MAX_LOAD_HEAP_BYTES >> 20
                        )))
                    }
                    r => r,
                };
                drop(budget);
                if result.is_err() && state.scene.borrow().scene.has_values() {
                    // A parameter that only these values declare explains the failure first.
                    self.same_params_so_far(&state.scene.borrow())?;
                }
                if result.is_err() {
                    if let Some(broken) = state.scene.borrow().broken.clone() {
                        return Err(LoadError::new(
                            LoadErrorKind::Constraint,
                            format!("error: {broken}: no test is run on them"),
                        ));
                    }
                }
                result.map_err(|e| self.evaluation_error(e, again, &state.scene))?;
                steps = eval.get_total_tick_count();
            }
            let printed = std::mem::take(&mut *state.log.borrow_mut());
            let mut b = state.scene.into_inner();
            alias_imported(&module, &mut b);
            self.show_load_output(&b, &printed);
            b.log = printed;
            finished(&b, &self.file)?;
            Ok((then(b, &module)?, steps))
        })
    }

    /// The load error of an evaluation with `values` (`None`: representative values) that failed with `e`, having declared `scene` so far:
    /// starlark's message with a keyword suggested, where it stopped when the message names
    /// no place in the program, and, for the first evaluation, the values it ran with.
    fn evaluation_error(
        &self,
        e: starlark::Error,
        values: Option<GivenValues>,
        scene: &std::cell::RefCell<SceneBuilder>,
    ) -> LoadError {
        let message = super::suggest_keyword(&format!("{e}"));
        // Limit errors (steps, heap) carry no span: say which program hit them,
        // and the statement it was running then.
        let message = if message.contains(&self.file) {
            message
        } else {
            match self.where_stopped(values) {
                Some(at) => format!("{message}\n{at}"),
                None => format!("{message}\n --> {}", self.file),
            }
        };
        // The first evaluation: say which values it ran with.
        let b = scene.borrow();
        let message = if !b.scene.has_values() && !b.scene.params().is_empty() {
            let values: Vec<String> = b
                .scene
                .params()
                .iter()
                .enumerate()
                .map(|(k, d)| {
                    let name = self.param_name(d).unwrap_or_else(|| format!("param{k}"));
                    match &d.domain {
                        Domain::Interval { lo, .. } => format!("{name} = {lo}"),
                        Domain::Levels(l) => format!("{name} = {}", l[0]),
                    }
                })
                .collect();
            format!(
                "{message}\n(evaluated with the first values: {})",
                values.join(", ")
            )
        } else {
            message
        };
        LoadError::new(LoadErrorKind::Evaluation, message)
    }

    /// Shows what an evaluation printed (`printed`), once per program, when it is the
    /// evaluation at load (`b` was given no values).
    fn show_load_output(&self, b: &SceneBuilder, printed: &[String]) {
        if !b.scene.has_values()
            && !self
                .load_output_shown
                .swap(true, std::sync::atomic::Ordering::Relaxed)
        {
            // The evaluation at load: what the program prints is shown once, on stderr.
            // A stderr that cannot be written (`2>&1 | head -1`) drops the lines.
            let mut err = std::io::stderr().lock();
            for line in printed {
                let _ = writeln!(err, "{}: print: {line}", self.file);
            }
        }
    }

    /// Sets the limits of an evaluation at load on `eval` (steps, heap, call depth, and the
    /// allocation budget, returned: it holds until dropped) and puts `tick` in `module`.
    ///
    /// # Errors
    /// starlark's message when a limit cannot be set.
    fn limit_load<'v>(
        &self,
        module: &Module<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> Result<crate::memory::Budget<'_>, LoadError> {
        for limit in [
            eval.set_max_tick_count(super::MAX_LOAD_STEPS),
            eval.set_max_heap_size(super::MAX_LOAD_HEAP_BYTES),
            eval.set_max_callstack_size(super::MAX_CALL_DEPTH),
        ] {
            limit.map_err(|e| LoadError::new(LoadErrorKind::Evaluation, e.to_string()))?;
        }
        // starlark checks its own heap every 1,000 steps; the budget also counts what one
        // statement allocates ([`crate::memory`]).
        let budget = crate::memory::Budget::start(
            super::MAX_LOAD_HEAP_BYTES,
            crate::memory::HARD_HEAP_BYTES,
            &self.file,
            "the program",
        );
        eval.set_check_cancelled(Box::new(crate::memory::over_soft_limit));
        // The statement running is noted for the hard limit's message (`file:line:col`).
        eval.before_stmt_for_dap(starlark::eval::BeforeStmtFunc::Fn(&note_statement));
        // `tick` as a variable of the module, on its heap, rather than the frozen global
        // alone: starlark inlines a module variable that holds a frozen value into the lambdas
        // it compiles, so `ticks = tick` read in a lambda stayed a stream instead of reading as
        // its current value, as every other top-level stream variable does.
        module.set(
            "tick",
            module
                .heap()
                .alloc(super::values::Stream::of(super::scene::TICK.0)),
        );
        Ok(budget)
    }

    /// Where an evaluation with `values` that stopped at a limit (steps or heap) stopped:
    /// ` --> file:line:col`, the line and a caret under the statement it was running. Found
    /// by evaluating again, with the same values and limits, with a hook before every
    /// statement that notes it: only on this error path, since the hook slows every
    /// statement. `None` when the second evaluation ran no statement.
    fn where_stopped(&self, values: Option<GivenValues>) -> Option<String> {
        let last: std::cell::Cell<Option<starlark::codemap::Span>> = std::cell::Cell::new(None);
        let note = |at: starlark::codemap::FileSpanRef, _: bool, _: &mut Evaluator<'_, '_, '_>| {
            last.set(Some(at.span));
        };
        Module::with_temp_heap(|module| {
            let state = LoadState::new(values, self.objects.clone(), self.maps.clone());
            state.scene.borrow_mut().route_m = scene::route_length_m(self.horizon_s);
            let mut eval = Evaluator::new(&module);
            eval.extra = Some(&state);
            eval.set_print_handler(&state);
            let budget = self.limit_load(&module, &mut eval).ok()?;
            eval.before_stmt_for_dap(starlark::eval::BeforeStmtFunc::Fn(&note));
            let _ = eval.eval_module(self.ast.clone(), &self.globals);
            drop(budget);
            Some(())
        })?;
        let span = self.ast.file_span(last.get()?);
        let begin = span.resolve_span().begin;
        let line = span.file.source_line(begin.line);
        let number = (begin.line + 1).to_string();
        let gutter = " ".repeat(number.len());
        Some(format!(
            "{gutter}--> {}:{number}:{}\n{gutter} |\n{number} | {line}\n{gutter} | {}^ running \
             here when it stopped",
            self.file,
            begin.column + 1,
            " ".repeat(begin.column),
        ))
    }

    /// A parameter's name: `name=`, else the one it takes from where it stands (the variable
    /// it is assigned to); `None` for neither.
    fn param_name(&self, d: &ParamDecl) -> Option<String> {
        d.name.clone().or_else(|| {
            self.syntax
                .site(&d.site.to_string())
                .and_then(|s| s.name.clone())
        })
    }

    /// Checks that the parameters an evaluation declared so far are the first ones the first
    /// evaluation declared, and no more.
    fn same_params_so_far(&self, b: &SceneBuilder) -> Result<(), LoadError> {
        for (k, d) in b.scene.params().iter().enumerate() {
            match self.params.get(k) {
                Some((_, decl)) if d == decl => {}
                Some((name, decl)) if decl.site == d.site => {
                    // The same declaration, evaluated to another range, levels, unit or
                    // over_time.
                    let what = |p: &ParamDecl| match &p.domain {
                        Domain::Interval { lo, hi } => format!("[{lo}, {hi})"),
                        Domain::Levels(levels) => format!(
                            "the levels [{}]",
                            levels
                                .iter()
                                .map(ToString::to_string)
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    };
                    let differs = if decl.domain != d.domain {
                        format!("{} for some values and {} for others", what(decl), what(d))
                    } else if decl.unit != d.unit {
                        format!(
                            "the unit {:?} for some values and {:?} for others",
                            decl.unit, d.unit
                        )
                    } else {
                        "another over_time or name for some values".to_owned()
                    };
                    return Err(LoadError::new(
                        LoadErrorKind::Worlds,
                        format!(
                            "error: the open parameters depend on their values: `{name}` has \
                         {differs}; its range, levels, unit and over_time must be the same in \
                         every test (compute with the value instead: `base + m`)\n --> {}",
                            d.site
                        ),
                    ));
                }
                Some((name, decl)) => {
                    return Err(LoadError::new(
                        LoadErrorKind::Worlds,
                        format!(
                    "error: the open parameters depend on their values: parameter {k} is `{name}` \
                         (declared at {}) for some values and the one declared at {} for \
                         others\n --> {}",
                    decl.site, d.site, d.site
                ),
                    ))
                }
                None => break,
            }
        }
        if let Some(extra) = b.scene.params().get(self.params.len()) {
            let name = self
                .param_name(extra)
                .map(|n| format!("`{n}` "))
                .unwrap_or_default();
            return Err(LoadError::new(LoadErrorKind::Worlds, format!(
                "error: the open parameters depend on their values: {name}(declared at {}) exists only \
                 for some values\n --> {}",
                extra.site, extra.site
            )));
        }
        Ok(())
    }

    /// Checks that an evaluation declared what the first one did: the same open parameters,
    /// monitors, horizon and system under test.
    fn consistent(&self, b: &SceneBuilder) -> Result<(), LoadError> {
        self.same_params_so_far(b)?;
        if let Some((name, decl)) = self.params.get(b.scene.params().len()) {
            return Err(LoadError::new(LoadErrorKind::Worlds, format!(
                "error: the open parameters depend on their values: `{name}` (declared at {}) is not \
                 declared for these values\n --> {}",
                decl.site, decl.site
            )));
        }
        let monitors = b.scene.monitor_specs();
        if monitors != self.monitors {
            // The first monitor that differs, or the first one missing or extra.
            let k = (0..monitors.len().max(self.monitors.len()))
                .find(|&k| monitors.get(k) != self.monitors.get(k))
                .unwrap_or(0);
            let at = b
                .scene
                .monitors()
                .nth(k)
                .map(|(_, a)| format!("\n --> {a}"))
                .unwrap_or_else(|| format!("\n --> {}", self.file));
            return Err(LoadError::new(LoadErrorKind::Worlds, format!(
                "error: the monitors depend on the open parameters' values: declare the same monitors, \
                 with the same settings, for every test (a verdict must mean the same in every \
                 test of a campaign){at}"
            )));
        }
        if b.scene
            .settings()
            .horizon_s
            .unwrap_or(super::DEFAULT_HORIZON_S)
            != self.horizon_s
        {
            return Err(LoadError::new(
                LoadErrorKind::Worlds,
                format!(
                "error: test(horizon=) depends on the open parameters' values: every test of a \
                 campaign has one length\n --> {}",
                b.scene.settings().site.as_ref().map_or(self.file.clone(), |s| s.to_string())
            ),
            ));
        }
        if b.scene.ego().map(|(_, sut)| sut) != Some(&self.sut) {
            let at = b
                .objects
                .iter()
                .find(|o| matches!(o.pending, super::scene::Pending::Ego { .. }))
                .map(|o| o.at.clone())
                .unwrap_or_else(|| self.file.clone());
            return Err(LoadError::new(LoadErrorKind::Worlds, format!(
                "error: AutonomousVehicle(sut=) depends on the open parameters' values: one system is \
                 under test in a campaign\n --> {at}"
            )));
        }
        Ok(())
    }

    /// The values of an assignment, by name ([`Program::given`]).
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for a parameter (or coordinate) it lacks.
    fn values(&self, a: &Assignment) -> Result<GivenValues, ScenarioError> {
        self.values_by_index(a).map(|v| self.given(v))
    }

    /// The values of `values`, one per parameter in declaration order, by the parameters'
    /// names (and the names they stand under, for a declaration that gives none).
    fn given(&self, values: Vec<ParamValue>) -> GivenValues {
        let standing: Arc<[(crate::scene::Site, String)]> = (self.params.iter())
            .map(|(name, d)| (d.site.clone(), name.clone()))
            .collect();
        GivenValues::new(self.params.iter().map(|(n, _)| n.clone()).zip(values)).standing(standing)
    }

    /// The values of an assignment, one per parameter in declaration order.
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for a parameter (or coordinate) it lacks.
    fn values_by_index(&self, a: &Assignment) -> Result<Vec<ParamValue>, ScenarioError> {
        self.params
            .iter()
            .map(|(name, p)| {
                let get = |n: &str| {
                    a.get(n)
                        .ok_or_else(|| ScenarioError::MissingParam(n.to_owned()))
                };
                let reals = || -> Result<Vec<f64>, ScenarioError> {
                    coordinate_names(name, p.over_time)
                        .iter()
                        .map(|n| {
                            get(n)?
                                .as_f64()
                                .ok_or(ScenarioError::MissingParam(n.clone()))
                        })
                        .collect()
                };
                Ok(match p.over_time {
                    OverTime::Constant => ParamValue::Level(get(name)?.clone()),
                    OverTime::Piecewise(_) => ParamValue::Over(OpenStream::Piecewise {
                        values: reals()?,
                        horizon_s: self.horizon_s,
                    }),
                    OverTime::Polynomial(_) => ParamValue::Over(OpenStream::Polynomial {
                        coefficients: reals()?,
                        horizon_s: self.horizon_s,
                    }),
                })
            })
            .collect()
    }

    /// The value `x` of interval parameter `k` (constant, or the same at every coordinate of
    /// one varying over time).
    fn checked_values_at(&self, k: usize, x: f64) -> ParamValue {
        let (name, p) = &self.params[k];
        let n = coordinate_names(name, p.over_time).len();
        match p.over_time {
            OverTime::Constant => ParamValue::Level(Level::Real(x)),
            OverTime::Piecewise(_) => ParamValue::Over(OpenStream::Piecewise {
                values: vec![x; n],
                horizon_s: self.horizon_s,
            }),
            OverTime::Polynomial(_) => ParamValue::Over(OpenStream::Polynomial {
                coefficients: vec![x; n],
                horizon_s: self.horizon_s,
            }),
        }
    }

    /// The test values a parameter is checked at when the program loads: every level; an
    /// interval's two ends (over time: all coefficients at one end, then at the other).
    fn checked_values(&self, k: usize) -> Vec<(ParamValue, String)> {
        let (name, p) = &self.params[k];
        match &p.domain {
            Domain::Interval { lo, hi } => vec![
                (self.checked_values_at(k, *lo), format!("{name} = {lo}")),
                (self.checked_values_at(k, *hi), format!("{name} = {hi}")),
            ],
            Domain::Levels(levels) => levels
                .iter()
                .map(|l| (ParamValue::Level(l.clone()), format!("{name} = {l}")))
                .collect(),
        }
    }

    /// Every combination of [`Program::checked_values`] when there are at most
    /// [`MAX_CHECKED_WORLDS`], else the rows of a pairwise covering array over them, or of
    /// one with each value once when a pairwise one would have more than 4 ×
    /// [`MAX_CHECKED_WORLDS`] rows.
    fn combinations(&self) -> &[(Vec<ParamValue>, String)] {
        self.combinations.get_or_init(|| self.make_combinations())
    }

    /// Whether the checks at load have steps left of [`MAX_LOAD_CHECK_STEPS`].
    fn load_budget_left(&self) -> bool {
        self.load_steps.load(std::sync::atomic::Ordering::Relaxed) < MAX_LOAD_CHECK_STEPS
    }

    /// [`Program::combinations`], computed.
    fn make_combinations(&self) -> Vec<(Vec<ParamValue>, String)> {
        let options: Vec<Vec<(ParamValue, String)>> = (0..self.params.len())
            .map(|k| self.checked_values(k))
            .collect();
        let count = options
            .iter()
            .try_fold(1usize, |n, o| n.checked_mul(o.len()))
            .unwrap_or(usize::MAX);
        let rows: Vec<Vec<usize>> = if count <= MAX_CHECKED_WORLDS {
            let mut rows = vec![Vec::new()];
            for o in &options {
                rows = rows
                    .into_iter()
                    .flat_map(|r| {
                        (0..o.len()).map(move |i| {
                            let mut r = r.clone();
                            r.push(i);
                            r
                        })
                    })
                    .collect();
            }
            rows
        } else {
            let levels: Vec<u32> = options.iter().map(|o| o.len() as u32).collect();
            // Pairwise when its array stays near the check's budget, else each value once
            // (two 10,000-level parameters would need 10^8 pairwise rows).
            let mut largest = levels.clone();
            largest.sort_unstable_by(|a, b| b.cmp(a));
            let pairs = u64::from(largest[0]) * u64::from(largest.get(1).copied().unwrap_or(1));
            let t = if pairs <= 4 * MAX_CHECKED_WORLDS as u64 {
                2
            } else {
                1
            };
            match paracosm_generators::covering::ipog(&levels, t) {
                Ok(array) => (0..array.len())
                    .map(|r| array.row(r).iter().map(|&i| i as usize).collect())
                    .collect(),
                Err(_) => vec![vec![0; options.len()]],
            }
        };
        rows.into_iter()
            .map(|r| {
                let values = r
                    .iter()
                    .zip(&options)
                    .map(|(&i, o)| o[i].0.clone())
                    .collect();
                let label = r
                    .iter()
                    .zip(&options)
                    .map(|(&i, o)| o[i].1.clone())
                    .collect::<Vec<_>>()
                    .join(", ");
                (values, label)
            })
            .collect()
    }

    /// What parameter `k` changes when the other parameters take other values than `base`'s:
    /// its checked values (at most [`MAX_REPROBED_VALUES`], its first and last among them)
    /// against each of at most [`MAX_REPROBE_BASES`] combinations of the others' values
    /// (spread over [`Program::combinations`], those equal to `base` but for `k` left out),
    /// stopping at the first change that can affect the ego. Worlds that fail are skipped
    /// (their tests report the error), and the probing stops after [`MAX_REPROBE_STEPS`]
    /// evaluation steps.
    fn changes_elsewhere(&self, k: usize, base: &[ParamValue], bases: usize) -> Vec<usage::Change> {
        let mut out = Vec::new();
        let mut steps = 0u64;
        let spread = |n: usize, most: usize| -> Vec<usize> {
            if n <= most {
                (0..n).collect()
            } else if most <= 1 {
                // One of them: the first (`j * (n - 1) / (most - 1)` needs two).
                vec![0]
            } else {
                let mut v: Vec<usize> = (0..most).map(|j| j * (n - 1) / (most - 1)).collect();
                v.dedup();
                v
            }
        };
        let values = self.checked_values(k);
        let chosen: Vec<&ParamValue> = spread(values.len(), MAX_REPROBED_VALUES)
            .into_iter()
            .map(|i| &values[i].0)
            .collect();
        let others = |v: &[ParamValue]| -> bool {
            v.iter()
                .zip(base)
                .enumerate()
                .any(|(j, (a, b))| j != k && a != b)
        };
        let rows: Vec<(usize, &Vec<ParamValue>)> = self
            .combinations()
            .iter()
            .map(|(v, _)| v)
            .enumerate()
            .filter(|(_, v)| others(v))
            .collect();
        for r in spread(rows.len(), bases.clamp(1, MAX_REPROBE_BASES)) {
            let (index, row) = rows[r];
            if !self.load_budget_left() {
                break;
            }
            // The world of a combination is built once for all the parameters varied from it.
            let from = {
                let mut cache = self
                    .base_worlds
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                cache
                    .entry(index)
                    .or_insert_with(|| {
                        self.world_counted(row.clone())
                            .ok()
                            .map(|(w, s)| (Arc::new(w), s))
                    })
                    .clone()
            };
            let Some((from, s)) = from else {
                continue;
            };
            steps += s;
            for v in &chosen {
                if **v == row[k] || steps > MAX_REPROBE_STEPS {
                    continue;
                }
                let mut values = row.clone();
                values[k] = (*v).clone();
                let Ok((to, s)) = self.world_counted(values) else {
                    continue;
                };
                steps += s;
                let found = from.changes(&to, self.horizon_s);
                let decisive = found.iter().any(|c| !usage::inert(c, false));
                out.extend(found);
                if decisive {
                    return out;
                }
            }
            if steps > MAX_REPROBE_STEPS {
                break;
            }
        }
        out
    }

    /// The world of one evaluation with `values`, checked for consistency.
    fn world_for(&self, values: Vec<ParamValue>) -> Result<Evaluated, LoadError> {
        self.world_counted(values).map(|(w, _)| w)
    }

    /// [`Program::world_for`], also returning the evaluation's step count.
    fn world_counted(&self, values: Vec<ParamValue>) -> Result<(Evaluated, u64), LoadError> {
        let out = self.evaluate_counted(Some(self.given(values)), |b, _| {
            self.consistent(&b)?;
            Evaluated::of(&b.scene)
        });
        if let Ok((_, steps)) = &out {
            self.load_steps
                .fetch_add(*steps, std::sync::atomic::Ordering::Relaxed);
        }
        out
    }
}

/// The world one evaluation built, with what the storyboard it imported reads
/// ([`crate::scene::Scene::host_inputs`]): two evaluations differ in either.
struct Evaluated {
    /// The world.
    world: WorldSpec,
    /// What an `Import`ed storyboard reads in this world; `None` without one.
    host: Option<Arc<dyn crate::scene::HostInputs>>,
}

impl Evaluated {
    /// The world of `scene` and its host's inputs.
    ///
    /// # Errors
    /// What [`crate::scene::Scene::world`] returns.
    fn of(scene: &crate::scene::Scene) -> Result<Evaluated, LoadError> {
        Ok(Evaluated {
            world: scene.world()?,
            host: scene.shared_host_inputs(),
        })
    }

    /// What differs from `self` in `to`, whose tests last `horizon_s` (s): the worlds'
    /// [`usage::world_changes`], and [`usage::Change::Other`] when the storyboards read
    /// different inputs (an `Import(params=)` speed, trigger or route).
    fn changes(&self, to: &Evaluated, horizon_s: f64) -> Vec<usage::Change> {
        let mut out = usage::world_changes(&self.world, &to.world, horizon_s);
        if !usage::same_host_inputs(self.host.as_deref(), to.host.as_deref()) {
            out.push(usage::Change::Other);
        }
        out
    }
}

/// Notes the statement about to run for the hard heap limit's message
/// ([`crate::memory::note_statement`]); the program's source outlives every evaluation.
fn note_statement(at: starlark::codemap::FileSpanRef, _: bool, _: &mut Evaluator<'_, '_, '_>) {
    crate::memory::note_statement(at.file.source(), at.span.begin().get());
}

/// Errors of a lambda that depend on the values it is given rather than on their types: a
/// sample value may cause them where no test would (a division by a distance that is 0 only
/// at t = 0), so the check at load lets them through to the tests.
const VALUE_ERRORS: [&str; 4] = [
    "division by zero",
    "sqrt of a negative",
    "out of bound",
    "fail:",
];

impl Program {
    /// Calls every lambda of the world the first evaluation built once, on sample values of
    /// its streams at t = 0 ([`paracosm_engine::Simulation::check_streams`]), so that a type
    /// error in a lambda is one error at load rather than one per test: `b` and `module` are
    /// that evaluation's builder and module.
    ///
    /// # Errors
    /// The lambda's error with its `file:line:col`, unless it is one of [`VALUE_ERRORS`].
    fn check_lambdas_in(&self, b: &SceneBuilder, module: &Module<'_>) -> Result<(), LoadError> {
        {
            let spec = b.scene.world()?;
            // A world that does not build is reported elsewhere, by the test that builds it.
            let Ok(sim) = paracosm_engine::Simulation::new(&spec) else {
                return Ok(());
            };
            let functions = lambda_values(b, module)?;
            let test = super::values::TestState::default();
            let limits = CallLimits::default();
            let mut eval = Evaluator::new(module);
            eval.extra = Some(&test);
            eval.set_print_handler(&test);
            limits
                .install(&mut eval)
                .map_err(|e| LoadError::new(LoadErrorKind::Evaluation, e.to_string()))?;
            let host = StarHost::new(&mut eval, &functions, &limits, &self.file).at_load();
            let mut host = super::host::WithStory::new(host, None);
            match sim.check_streams(&mut host) {
                Ok(samples) => judged_kinds(b, &samples),
                Err(e) => {
                    // A lambda's message has its own traceback and location, but for a call
                    // stopped by a limit: that one is located at the combinator.
                    let message = match e {
                        EngineError::Stream(RxError::Host { message, at, .. }) => {
                            if message.contains(&format!("{}:", self.file)) {
                                message
                            } else {
                                format!("{message}\n --> {at}")
                            }
                        }
                        e => e.to_string(),
                    };
                    let lower = message.to_ascii_lowercase();
                    if VALUE_ERRORS.iter().any(|v| lower.contains(v)) {
                        return Ok(());
                    }
                    Err(LoadError::new(
                        LoadErrorKind::Evaluation,
                        format!(
                        "{message}{}\n(found when loading: every lambda and combinator is called \
                         once on sample values of its stream's type, those of the first test's \
                         world at t = 0)",
                        if message.contains("Stream") {
                            STREAM_IN_LAMBDA
                        } else {
                            ""
                        }
                    ),
                    ))
                }
            }
        }
    }
}

/// The hint added to an error at load that involves a stream inside a lambda (`lambda s: s -
/// lead.speed`): LANGUAGE.md, "What a lambda sees".
const STREAM_IN_LAMBDA: &str = "\nhint: inside a lambda, a stream reads as its current value only \
     when a variable at the top level of the program holds it: write `lead_speed = lead.speed` \
     at the top level and use `lead_speed` in the lambda; or zip the stream in \
     (`v.speed.zip(lead.speed).map(lambda p: p[1] - p[0])`)";

/// Checks that each `Monitor` judges numbers, each `Assert` bools and each `Signal` numbers,
/// bools or vectors, by their streams' sample values from the check at load: a stream made by
/// a lambda has no kind until it is called.
///
/// # Errors
/// The first monitor or signal whose sample is of another kind, with its `file:line:col`.
fn judged_kinds(
    b: &SceneBuilder,
    samples: &[Option<paracosm_engine::rx::Value>],
) -> Result<(), LoadError> {
    let sample_of = |signal: &str| sample_of(b, samples, signal);
    for (m, at) in b.scene.monitors() {
        let Some((name, signal, bools)) = m.judged_stream() else {
            continue;
        };
        if let Some(why) =
            sample_of(signal).and_then(|v| crate::scenario::judged_kind_error(v, bools))
        {
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                "error: monitor `{name}`: {why} (found when loading, from the sample value its \
                 stream gives in the first test's world at t = 0)\n --> {at}"
            ),
            ));
        }
    }
    action_kinds(b, samples)?;
    formula_kinds(b, samples)?;
    for (name, at) in b
        .scene
        .signals()
        .iter()
        .filter_map(|s| Some((&s.name, s.site.as_ref()?)))
    {
        use paracosm_engine::rx::Value;
        if let Some(v @ (Value::Unit | Value::Tuple(_) | Value::Text(_))) = sample_of(name) {
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "error: Signal `{name}` carried {}; a signal is a number, a bool or a vector \
                 (found when loading, from the sample value its stream gives in the first \
                 test's world at t = 0)\n --> {at}",
                    paracosm_engine::rx::describe(v)
                ),
            ));
        }
    }
    Ok(())
}

/// The sample value of the stream published as `signal`, if it had one.
fn sample_of<'a>(
    b: &SceneBuilder,
    samples: &'a [Option<paracosm_engine::rx::Value>],
    signal: &str,
) -> Option<&'a paracosm_engine::rx::Value> {
    b.scene
        .signals()
        .iter()
        .find(|s| s.name == signal)
        .and_then(|s| samples.get(s.stream.0))
        .and_then(Option::as_ref)
}

/// [`judged_kinds`] for the actions' arguments: an argument from a lambda has its kind from
/// the sample (a string given to setSpeed would otherwise end each test where it first fires,
/// or never be noticed).
fn action_kinds(
    b: &SceneBuilder,
    samples: &[Option<paracosm_engine::rx::Value>],
) -> Result<(), LoadError> {
    for (i, node) in b.scene.nodes().iter().enumerate() {
        use paracosm_engine::behaviour::Action;
        use paracosm_engine::rx::Value;
        let paracosm_engine::rx::Node::Foreach { src, sink } = node else {
            continue;
        };
        let Some(v) = samples.get(src.0).and_then(Option::as_ref) else {
            continue;
        };
        let car = |c: paracosm_engine::Handle<paracosm_engine::CarSpec>| {
            b.scene.car_name(c.index()).unwrap_or("a Car")
        };
        let (what, ok, wanted) = match *sink {
            Action::Walk(_)
            | Action::PlaceCar(_)
            | Action::PlacePedestrian(_)
            | Action::PlaceEgo
            | Action::SetEgoSpeed
            | Action::ReleaseEgo
            | Action::SetEgoRoute
            | Action::SetPresent(_) => continue,
            Action::SetSpeed(c) => (
                format!("setSpeed of {}", car(c)),
                matches!(v, Value::Num(_)),
                "a number (m/s)",
            ),
            Action::Brake(c) => (
                format!("brake of {}", car(c)),
                matches!(v, Value::Num(_)),
                "a number (m/s²)",
            ),
            Action::ChangeLane(c) => (
                format!("changeLane of {}", car(c)),
                match v {
                    Value::Num(_) => true,
                    Value::Tuple(t) => t.len() == 2 && t.iter().all(|x| matches!(x, Value::Num(_))),
                    _ => false,
                },
                "a lane number or a (lane, duration in s) pair",
            ),
        };
        if !ok {
            let at = b.scene.graph().site(i).unwrap_or("");
            return Err(LoadError::new(
                LoadErrorKind::Declarations,
                format!(
                    "error: {what} is given {} by its stream; it takes {wanted} (found when \
                 loading, from the sample value the stream gives in the first test's world at \
                 t = 0)\n --> {at}",
                    paracosm_engine::rx::describe(v)
                ),
            ));
        }
    }
    Ok(())
}

/// [`judged_kinds`] for the signals formulas read: a vector Signal named whole, or a
/// component of a number, is known from the sample where a lambda computes the stream.
fn formula_kinds(
    b: &SceneBuilder,
    samples: &[Option<paracosm_engine::rx::Value>],
) -> Result<(), LoadError> {
    let sample_of = |signal: &str| sample_of(b, samples, signal);
    for (m, at) in b.scene.monitors() {
        use paracosm_engine::rx::Value;
        for s in m.signals() {
            for n in b
                .scene
                .signals()
                .iter()
                .map(|s| &s.name)
                .filter(|n| !n.starts_with("monitor:"))
            {
                let component = s
                    .strip_prefix(n.as_str())
                    .is_some_and(|c| [".x", ".y", ".z"].contains(&c));
                let why = match (n == &s, component, sample_of(n)) {
                    (true, _, Some(Value::Vec3(_))) => format!(
                        "`{s}` carries vectors: a formula compares numbers, so write `{s}.x`, \
                         `{s}.y` or `{s}.z`"
                    ),
                    (false, true, Some(Value::Num(_) | Value::Bool(_))) => format!(
                        "`{n}` carries numbers, with no component `{}`: write `{n}`",
                        &s[n.len() + 1..]
                    ),
                    _ => continue,
                };
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "error: {} reads the signal: {why} (found when loading, from the sample \
                     value its stream gives in the first test's world at t = 0)\n --> {at}",
                        m.name()
                    ),
                ));
            }
        }
    }
    Ok(())
}

impl Program {
    /// The scene of one test ([`crate::FrontEnd::with_scene`]): the program evaluated with
    /// `assignment`'s values (`None`: each parameter's representative value), its lambdas
    /// run by a fresh evaluator.
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for an assignment that lacks a parameter;
    /// [`ScenarioError::Load`] when the program fails for these values.
    pub(crate) fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&crate::scene::Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let values = assignment.map(|a| self.values(a)).transpose()?;
        self.evaluate(values, |mut b, module| {
            self.consistent(&b)?;
            let functions = lambda_values(&b, module)?;
            let test = super::values::TestState::default();
            test.log.borrow_mut().extend(b.log.iter().cloned());
            let limits = CallLimits::default();
            let mut eval = Evaluator::new(module);
            eval.extra = Some(&test);
            eval.set_print_handler(&test);
            limits
                .install(&mut eval)
                .map_err(|e| LoadError::new(LoadErrorKind::Evaluation, e.to_string()))?;
            let host = StarHost::new(&mut eval, &functions, &limits, &self.file);
            let mut story = b.story.take();
            let story = story.as_mut().map(|s| &mut s.0 as &mut dyn Host);
            let mut host = super::host::WithStory::new(host, story);
            run(&b.scene, &mut host);
            Ok(())
        })
        .map_err(|e| {
            ScenarioError::Load(LoadError {
                message: format!("the program failed for this test's values: {}", e.message),
                ..e
            })
        })
    }
}
