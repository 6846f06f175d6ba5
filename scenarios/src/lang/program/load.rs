//! Loading a program, in named phases (LANGUAGE.md, "A family of worlds" and "Errors and
//! limits"):
//!
//! 1. [`refuse_dropped_actions`]: the syntax alone;
//! 2. [`first_look`]: the first evaluation, with representative values, and what it must
//!    have declared (limits, monitors' windows, one walker a pedestrian, signals, lambdas);
//! 3. [`name_parameters`]: every open parameter and coordinate gets one name;
//! 4. [`settle_declarations`] and [`parameter_space`]: the monitors, horizon, system under
//!    test and the test space;
//! 5. [`check_combinations`]: every combination of levels and interval ends builds a valid
//!    world with the same declarations;
//! 6. [`probe_effects`]: what each parameter changes, from its other values;
//! 7. [`monitors_and_map`]: the default off-road monitor and the failure map's axes;
//! 8. [`load_warnings`] and [`monitor_warnings`]: streams nothing reads, the budgets, no
//!    monitor, monitors of constants;
//! 9. [`second_looks`]: parameters that seem unused are varied again from other
//!    combinations before a warning calls them unused;
//! 10. [`load`] puts the [`Scenario`] together.
//!
//! Each phase refuses with a [`LoadError`] of its kind; the load budget is spent in this
//! order ([`MAX_LOAD_CHECK_STEPS`]).

use std::collections::BTreeSet;

use super::*;

/// What the first evaluation left: its builder, the streams its top-level variables hold
/// (a lambda reads those by name, with no edge in the graph), and its world.
struct FirstLook {
    world: SceneBuilder,
    stream_variables: Vec<(String, usize)>,
}

/// What checking the combinations found: how far the budget let it go (`(checked, total,
/// steps)` when it stopped early) and, per world checked, the streams nothing reads.
struct Combinations {
    stopped: Option<(usize, usize, u64)>,
    unread: Vec<BTreeSet<String>>,
}

/// What each parameter changes, against the first world.
struct Effects {
    /// Each parameter's representative value, by declaration index.
    base_values: Vec<ParamValue>,
    /// Streams nothing reads in any world checked (`file:line:col` of each).
    unread_everywhere: BTreeSet<String>,
    /// Per parameter, the changes its other values make.
    changes: Vec<Vec<usage::Change>>,
    /// Parameters whose effect the budget left unprobed (they count as used).
    unprobed: Vec<usize>,
}

/// Loads a program: the phases of this module, in order.
///
/// # Errors
/// [`ScenarioError::Load`]: a diagnostic naming the file, line and column, and for a world
/// that fails only for some values, those values.
pub fn load(
    file: &str,
    source: &str,
    name: &str,
    ast: AstModule,
    globals: Globals,
    base: crate::map_files::Base,
) -> Result<Scenario, ScenarioError> {
    let syntax = Syntax::of(&ast, &crate::lang::builtins::taking_whole());
    refuse_dropped_actions(&syntax, file)?;
    let mut program = Program {
        objects: Arc::new(syntax.objects()),
        syntax,
        file: file.to_owned(),
        ast,
        globals,
        params: Vec::new(),
        monitors: Vec::new(),
        horizon_s: crate::lang::DEFAULT_HORIZON_S,
        sut: SutConfig::builtin("aeb")
            .map_err(|e| LoadError::new(LoadErrorKind::Declarations, e.to_string()))?,
        maps: Arc::new(crate::map_files::MapFiles::new(base)),
        load_output_shown: false.into(),
        requires: Vec::new(),
        combinations: std::sync::OnceLock::new(),
        load_steps: 0.into(),
        base_worlds: Default::default(),
    };
    let first = first_look(&mut program)?;
    program.requires = first.world.requires.clone();
    name_parameters(&mut program, &first.world)?;
    settle_declarations(&mut program, &first.world)?;
    let space = parameter_space(&program)?;
    let combinations = check_combinations(&program)?;
    let mut effects = probe_effects(&program, &first, &combinations.unread)?;
    let (monitors, _map_axes) = monitors_and_map(&first.world, &space, file)?;
    let mut warnings = first.world.warnings.clone();
    load_warnings(
        &first.world,
        &effects,
        &combinations,
        &monitors,
        file,
        &mut warnings,
    );
    monitor_warnings(&program, &first.world, &mut warnings);
    let read_in_code = second_looks(&program, &monitors, &mut effects, file, &mut warnings);
    let sites: Vec<(String, String)> = (program.params.iter())
        .map(|(name, decl)| (name.clone(), decl.site.to_string()))
        .collect();
    let found = usage::analyse(usage::Inputs {
        params: &sites,
        changes: &effects.changes,
        read_in_code: &read_in_code,
        stl_reads_light: reads_light(&monitors),
        scene: &first.world.scene,
    });
    warnings.extend(found.warnings);
    warnings.extend(crate::lang::units::unit_warnings(
        &program.params,
        &program.syntax,
    ));
    for message in program.maps.warnings() {
        // "file:line: what": the map's own place.
        let (at, what) = match message.split_once(": ") {
            Some((at, what)) if at.contains(':') => (at.to_owned(), what.to_owned()),
            _ => (file.to_owned(), message.clone()),
        };
        warnings.push(Warning { at, message: what });
    }
    let unused_params: Vec<String> = found
        .unused
        .iter()
        .flat_map(|&k| coordinate_names(&program.params[k].0, program.params[k].1.over_time))
        .collect();
    let source = crate::front_end::Source {
        name: name.to_owned(),
        description: crate::lang::header(source),
        text: Arc::from(source),
        files: program.maps.inputs(),
        ego: None,
        map_axes_by_relevance: false,
    };
    let findings = crate::front_end::Findings {
        warnings,
        unused_params,
        camera_only: found.camera_only,
    };
    let program = Arc::new(program);
    let space = required_space(&program, space)?;
    let loaded = Loaded {
        program,
        space,
        source,
        findings,
    };
    Scenario::new(Arc::new(loaded))
}

/// The program's `Require`s as a constraint of its space: a point is valid when the
/// program, evaluated with its values, passes every `Require`.
struct Requires(Arc<Program>);

impl std::fmt::Debug for Requires {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Requires({})", self.0.file)
    }
}

impl paracosm_generators::Constraint for Requires {
    fn name(&self) -> &str {
        "the program's Require"
    }

    fn violation(
        &self,
        a: &Assignment,
    ) -> Result<Option<String>, paracosm_generators::ConstraintError> {
        let values =
            (self.0.values(a)).map_err(|e| paracosm_generators::ConstraintError(e.to_string()))?;
        match self.0.evaluate(Some(values), |_, _| Ok(())) {
            Err(e) if e.kind == LoadErrorKind::Constraint => Ok(Some(e.message)),
            // Values that fail otherwise are that test's error.
            _ => Ok(None),
        }
    }
}

/// `space` with the program's `Require`s, when it has any, checked to leave some valid point.
///
/// # Errors
/// [`LoadErrorKind::Constraint`] when no point of the space meets them.
fn required_space(program: &Arc<Program>, space: ParamSpace) -> Result<ParamSpace, LoadError> {
    if program.requires.is_empty() {
        return Ok(space);
    }
    let space = space.with_constraints(vec![Arc::new(Requires(program.clone()))]);
    if let Err(e) = space.valid_fraction() {
        let sites: Vec<String> = (program.requires.iter())
            .map(|(n, at)| format!("`{n}` ({at})"))
            .collect();
        return Err(LoadError::new(
            LoadErrorKind::Constraint,
            format!(
                "error: {e}: the constraints {} refuse every test\n --> {}",
                sites.join(", "),
                program.requires[0].1
            ),
        ));
    }
    Ok(space)
}

/// A loaded program as a front end: its space, what it read and what its load found.
struct Loaded {
    program: Arc<Program>,
    space: ParamSpace,
    source: crate::front_end::Source,
    findings: crate::front_end::Findings,
}

impl crate::FrontEnd for Loaded {
    fn space(&self) -> &ParamSpace {
        &self.space
    }

    fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&crate::scene::Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        self.program.with_scene(assignment, run)
    }

    fn source(&self) -> crate::front_end::Source {
        self.source.clone()
    }

    fn findings(&self) -> crate::front_end::Findings {
        self.findings.clone()
    }
}

/// Phase 1: an action on a line of its own (`car.brake(6)`) does nothing.
fn refuse_dropped_actions(syntax: &Syntax, file: &str) -> Result<(), LoadError> {
    match syntax.dropped_actions().first() {
        Some((at, call)) => Err(LoadError::new(
            LoadErrorKind::Syntax,
            format!(
                "error: `{call}` on a line of its own does nothing: an action is performed by \
                 foreach, at the events of a stream (`tick.take(1).foreach({call})` performs it \
                 at t = 0; `tick.filter(lambda t: t > 5).take(1).foreach({call})` after 5 s)\n \
                 --> {file}:{at}"
            ),
        )),
        None => Ok(()),
    }
}

/// Phase 2: the first evaluation, with representative values, and what it must declare. Its
/// lambdas are checked on this same evaluation; their result is reported after the checks
/// that come before it. Sets the program's horizon.
fn first_look(program: &mut Program) -> Result<FirstLook, LoadError> {
    let (first, stream_variables, lambdas) = program.evaluate(None, |b, module| {
        let held: Vec<(String, usize)> = module
            .names()
            .filter_map(|name| {
                let v = module.get(name.as_str())?;
                let s =
                    starlark::values::ValueLike::downcast_ref::<crate::lang::values::Stream>(v)?;
                Some((name.as_str().to_owned(), s.id))
            })
            .collect();
        // After `held`: calling the lambdas sets the variables that hold streams to their
        // sample values.
        let lambdas = program.check_lambdas_in(&b, module);
        Ok((b, held, lambdas))
    })?;
    if let Some(past) = first.scene.params().get(MAX_PARAMS) {
        return Err(LoadError::new(
            LoadErrorKind::Parameters,
            format!(
                "error: the program declares {} open parameters; the limit is {MAX_PARAMS} \
                 (each is a dimension of the test space and is probed at load); this is \
                 parameter {}\n --> {}",
                first.scene.params().len(),
                MAX_PARAMS + 1,
                past.site
            ),
        ));
    }
    program.horizon_s = first
        .scene
        .settings()
        .horizon_s
        .unwrap_or(crate::lang::DEFAULT_HORIZON_S);
    windows_within_horizon(&first, program.horizon_s)?;
    one_walker_each(&first)?;
    // Signals the monitors read exist (checked when the world is built).
    first.scene.check_signals()?;
    lambdas?;
    Ok(FirstLook {
        world: first,
        stream_variables,
    })
}

/// Phase 3: names, explicit, else from where the parameter stands, else by position; two
/// parameters may not share one, nor two coordinates. Sets the program's parameters.
fn name_parameters(program: &mut Program, first: &SceneBuilder) -> Result<(), LoadError> {
    let syntax = &program.syntax;
    let explicit: Vec<Option<String>> = first
        .scene
        .params()
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let derived: Vec<Option<String>> = first
        .scene
        .params()
        .iter()
        .map(|p| {
            syntax
                .site(&p.site.to_string())
                .and_then(|s| s.name.clone())
        })
        .collect();
    let named = |message: String| LoadError::new(LoadErrorKind::Parameters, message);
    for (i, a) in explicit.iter().enumerate() {
        if let Some(a) = a {
            if let Some(j) = (0..i).find(|&j| explicit[j].as_deref() == Some(a)) {
                return Err(named(format!(
                    "error: two open parameters are named `{a}` (declared at {} and {}); give \
                     one another name=\n --> {}",
                    first.scene.params()[j].site,
                    first.scene.params()[i].site,
                    first.scene.params()[i].site
                )));
            }
        }
    }
    // An explicit name that another parameter takes from where it stands (`b = VarInterval(
    // ..., name = "a")` beside `a = VarInterval(...)`) would file one under the other's name.
    for (i, a) in explicit.iter().enumerate() {
        let Some(a) = a else { continue };
        // What parameter `j` is named from where it stands: its derived name, else its
        // position (`param3`, as `names::final_names` gives it).
        let standing = |j: usize| derived[j].clone().unwrap_or_else(|| format!("param{j}"));
        if let Some(j) =
            (0..explicit.len()).find(|&j| j != i && explicit[j].is_none() && standing(j) == *a)
        {
            return Err(named(format!(
                "error: name = \"{a}\" (declared at {}) is the name the open parameter declared \
                 at {} takes from where it stands; give one another name=\n --> {}",
                first.scene.params()[i].site,
                first.scene.params()[j].site,
                first.scene.params()[i].site
            )));
        }
    }
    let names = final_names(&explicit, &derived);
    program.params = names
        .iter()
        .cloned()
        .zip(first.scene.params().iter().cloned())
        .collect();
    // Every coordinate of the space has its own name: an explicit `name = "f[0]"` or
    // `"a_1"` must not meet a coordinate of a parameter that varies over time or a suffix.
    let mut coordinates: std::collections::HashMap<String, usize> = Default::default();
    for (k, (name, p)) in program.params.iter().enumerate() {
        for c in coordinate_names(name, p.over_time) {
            if let Some(&j) = coordinates.get(&c) {
                let (a, b) = (&program.params[j], &program.params[k]);
                // Point at the parameter whose name was written out, if one was.
                let at = if explicit[j].is_some() && explicit[k].is_none() {
                    &a.1.site
                } else {
                    &b.1.site
                };
                return Err(named(format!(
                    "error: two open parameters give a coordinate the name `{c}`: `{}` \
                     (declared at {}) and `{}` (declared at {}); give one another name=\n --> \
                     {at}",
                    a.0, a.1.site, b.0, b.1.site
                )));
            }
            coordinates.insert(c, k);
        }
    }
    Ok(())
}

/// Phase 4a: the monitors, horizon and system under test every test shares.
fn settle_declarations(program: &mut Program, first: &SceneBuilder) -> Result<(), LoadError> {
    program.monitors = first.scene.monitor_specs();
    program.horizon_s = first
        .scene
        .settings()
        .horizon_s
        .unwrap_or(crate::lang::DEFAULT_HORIZON_S);
    program.sut = first
        .scene
        .ego()
        .map(|(_, sut)| sut.clone())
        .ok_or_else(|| {
            LoadError::new(
                LoadErrorKind::Declarations,
                "the program places no AutonomousVehicle",
            )
        })?;
    Ok(())
}

/// Phase 4b: the test space, one coordinate per parameter (several for one that varies over
/// time).
fn parameter_space(program: &Program) -> Result<ParamSpace, LoadError> {
    let mut space = Vec::new();
    for (name, p) in &program.params {
        for coordinate in coordinate_names(name, p.over_time) {
            space.push(Param {
                name: coordinate,
                domain: p.domain.clone(),
                unit: p.unit.clone(),
                density: None,
            });
        }
    }
    ParamSpace::new(space).map_err(|e| LoadError::new(LoadErrorKind::Parameters, e.to_string()))
}

/// A world's refusal for the test values `label`, which the message then names.
fn for_values(label: &str, e: LoadError) -> LoadError {
    if label.is_empty() {
        e
    } else {
        e.with_context(&format!("\n(the world fails for the test values {label})"))
    }
}

/// Phase 5: every combination of levels and interval ends builds a valid world, within the
/// budget ([`MAX_CHECK_STEPS`], [`MAX_CHECKED_WORLDS`]).
fn check_combinations(program: &Program) -> Result<Combinations, LoadError> {
    let mut stopped = None;
    // Streams nothing reads in any world checked: each world's, intersected.
    let mut unread: Vec<BTreeSet<String>> = Vec::new();
    if !program.params.is_empty() {
        let combinations = program.combinations();
        let total = combinations.len();
        let mut steps = 0u64;
        for (done, (values, label)) in combinations.iter().enumerate() {
            if steps > MAX_CHECK_STEPS || done >= MAX_CHECKED_WORLDS {
                stopped = Some((done, total, steps));
                break;
            }
            let (w, s) = match program.world_counted(values.clone()) {
                // A combination the program's constraints forbid runs no test.
                Err(e) if e.kind == LoadErrorKind::Constraint => continue,
                r => r.map_err(|e| for_values(label, e))?,
            };
            unread.push(usage::unread_streams(&w.world, &[]));
            steps += s;
        }
    }
    Ok(Combinations { stopped, unread })
}

/// Phase 6: what each parameter changes, its other checked values against the first world
/// (at most [`MAX_PROBED_VALUES`] of them, and a value inside an interval).
fn probe_effects(
    program: &Program,
    first: &FirstLook,
    unread: &[BTreeSet<String>],
) -> Result<Effects, LoadError> {
    let syntax = &program.syntax;
    let base = Evaluated::of(&first.world.scene)?;
    let read_by_name: Vec<usize> = first
        .stream_variables
        .iter()
        .filter(|(name, _)| syntax.read_in_code(name))
        .map(|&(_, id)| id)
        .collect();
    let mut unread_everywhere = usage::unread_streams(&base.world, &read_by_name);
    for other in unread {
        unread_everywhere.retain(|site| other.contains(site));
    }
    let base_values: Vec<ParamValue> = program
        .params
        .iter()
        .map(|(_, d)| scene::representative(d, program.horizon_s))
        .collect();
    let mut changes = Vec::with_capacity(program.params.len());
    let mut unprobed: Vec<usize> = Vec::new();
    for k in 0..program.params.len() {
        if !program.load_budget_left() {
            unprobed.push(k);
            changes.push(Vec::new());
            continue;
        }
        let (seen, forbidden) = probe_parameter(program, k, &base, &base_values)?;
        if seen.is_empty() && forbidden {
            // A `Require` forbade some of its values beside the others' first ones: what it
            // changes is unknown there, so it counts as used rather than called unused.
            unprobed.push(k);
        }
        changes.push(seen);
    }
    Ok(Effects {
        base_values,
        unread_everywhere,
        changes,
        unprobed,
    })
}

/// What parameter `k`'s other values change against the world `base` of `base_values`, and
/// whether a `Require` forbade some of those values.
fn probe_parameter(
    program: &Program,
    k: usize,
    base: &Evaluated,
    base_values: &[ParamValue],
) -> Result<(Vec<usage::Change>, bool), LoadError> {
    let mut seen = Vec::new();
    let mut forbidden = false;
    // At most MAX_PROBED_VALUES of its values, spread over them (a VarEnum may have
    // thousands of levels, each one evaluation of the program).
    let mut all = program.checked_values(k);
    // And a value inside an interval, not a round one: a world that takes only whole
    // numbers (`nlanes`, a lane) fails there, though both ends may be whole.
    if let (name, Domain::Interval { lo, hi }) = (&program.params[k].0, &program.params[k].1.domain)
    {
        let x = lo + (hi - lo) * INTERIOR_FRACTION;
        let values = program.checked_values_at(k, x);
        all.push((
            values,
            format!(
                "{name} = {x}, inside its interval [{lo}, {hi}): every value of a VarInterval \
                 must build a valid world; an input of whole numbers takes a VarEnum of them"
            ),
        ));
    }
    let n = all.len();
    let probed = all.into_iter().enumerate().filter(|(i, _)| {
        n <= MAX_PROBED_VALUES
            || (0..MAX_PROBED_VALUES).any(|j| j * (n - 1) / (MAX_PROBED_VALUES - 1) == *i)
    });
    for (_, (v, label)) in probed {
        if v == base_values[k] {
            continue;
        }
        let mut values = base_values.to_vec();
        values[k] = v;
        let other = match program.world_for(values) {
            Err(e) if e.kind == LoadErrorKind::Constraint => {
                forbidden = true;
                continue;
            }
            r => r.map_err(|e| for_values(&label, e))?,
        };
        seen.extend(base.changes(&other, program.horizon_s));
        if !program.load_budget_left() {
            break;
        }
    }
    Ok((seen, forbidden))
}

/// Phase 7: the monitors, with the default `OffRoadMonitor` unless the program opts out or
/// declares one, and the failure map's axes (`test(map=)`, else the first two parameters),
/// as [`crate::Scenario::new`] reads them from any front end's scene.
fn monitors_and_map(
    first: &SceneBuilder,
    space: &ParamSpace,
    file: &str,
) -> Result<(Vec<MonitorSpec>, Vec<String>), LoadError> {
    let monitors = crate::scenario::monitors_of(&first.scene, file)?;
    let map_axes = crate::scenario::map_axes_of(&first.scene, space, file)?;
    Ok((monitors, map_axes))
}

/// Phase 8a: streams nothing reads, a budget that stopped the combinations' check, a
/// program without monitors.
fn load_warnings(
    first: &SceneBuilder,
    effects: &Effects,
    combinations: &Combinations,
    monitors: &[MonitorSpec],
    file: &str,
    warnings: &mut Vec<Warning>,
) {
    for site in &effects.unread_everywhere {
        warnings.push(Warning {
            at: site.clone(),
            message: "nothing uses this stream's values (no object's input, monitor, Signal \
                      or foreach, directly, through other streams or by its name in a lambda): \
                      the parameters only its functions read change no verdict (its functions \
                      still run every step; for an effect such as print, use foreach)"
                .to_owned(),
        });
    }
    if let Some((done, total, steps)) = combinations.stopped {
        warnings.push(Warning {
            at: format!("{file}:1:1"),
            message: format!(
                "loading checked {done} of the {total} combinations of levels and interval ends \
                 ({steps} evaluation steps; the budget is {MAX_CHECK_STEPS} steps and \
                 {MAX_CHECKED_WORLDS} worlds); a test whose values break the world among the \
                 others ends with status `error`"
            ),
        });
    }
    if first.scene.monitors().len() == 0 {
        warnings.push(Warning {
            at: first.placed_at.clone().unwrap_or_default(),
            message: if monitors.is_empty() {
                "the program declares no monitor and opts out of the default OffRoadMonitor: \
                 every test passes whatever happens"
                    .to_owned()
            } else {
                "the program declares no monitor: only the default OffRoadMonitor judges its \
                 tests, so a test passes whatever else happens (add CollisionMonitor(v), \
                 DistanceMonitor(v, minD = ...) or Stl(...))"
                    .to_owned()
            },
        });
    } else if !monitors.iter().any(MonitorSpec::can_fail_a_stopped_car) {
        warnings.push(Warning {
            at: first.placed_at.clone().unwrap_or_default(),
            message: "no monitor checks that the ego vehicle gets anywhere: a car that stops, \
                      and so never meets the danger, passes every test (add \
                      DistanceMonitor(v, minD = ...) with minD past the point where the danger \
                      is, or a Monitor or Stl of progress)"
                .to_owned(),
        });
    }
}

/// The constant a published signal holds in a world, if it is one.
fn constant_of(published: &[(String, StreamId)], nodes: &[Node], signal: &str) -> Option<String> {
    published
        .iter()
        .find(|(n, _)| n == signal)
        .and_then(|(_, id)| nodes.get(id.0))
        .and_then(|n| match n {
            Node::Const(v) => Some(format!("{v:?}")),
            _ => None,
        })
}

/// Phase 8b: monitors that judge a constant stream in every world checked, `Stl` monitors
/// that read no signal, and `Stl` windows lowered to the horizon.
fn monitor_warnings(program: &Program, first: &SceneBuilder, warnings: &mut Vec<Warning>) {
    // Monitors of a constant in the first world, and whether that constant is an open
    // parameter's (`Monitor(k)`): then it differs between the worlds of some combinations.
    let published: Vec<(String, StreamId)> = first
        .scene
        .signals()
        .iter()
        .map(|s| (s.name.clone(), s.stream))
        .collect();
    let mut constants: Vec<(String, Option<String>, bool)> = first
        .scene
        .monitors()
        .filter_map(|(m, _)| m.judged_stream())
        .map(|(_, signal, _)| {
            let c = constant_of(&published, first.scene.nodes(), signal);
            (signal.to_owned(), c, false)
        })
        .collect();
    if constants.iter().any(|(_, c, _)| c.is_some()) {
        let rows = program.combinations();
        let n = rows.len();
        for (i, (values, _)) in rows.iter().enumerate() {
            if n > 16 && !(0..16).any(|j| j * (n - 1) / 15 == i) {
                continue;
            }
            if !program.load_budget_left() {
                // Unchecked: the monitor's constant counts as varying (no warning).
                for c in constants.iter_mut() {
                    c.2 = true;
                }
                break;
            }
            let Ok(w) = program.world_for(values.clone()) else {
                continue;
            };
            for (signal, c, varies) in constants.iter_mut() {
                if c.is_some()
                    && constant_of(&w.world.published, w.world.streams.nodes(), signal) != *c
                {
                    *varies = true;
                }
            }
        }
    }
    for (m, at) in first.scene.monitors() {
        // A Monitor or Assert of a constant (`Monitor(5.0)`) judges nothing of the world.
        if let Some((name, signal, _)) = m.judged_stream() {
            let constant = constants
                .iter()
                .any(|(s, c, varies)| s == signal && c.is_some() && !varies);
            if constant {
                warnings.push(Warning {
                    at: at.to_string(),
                    message: format!(
                        "monitor `{name}` judges a constant stream: its verdict is the same in \
                         every test, whatever the world does"
                    ),
                });
            }
        }
        stl_warnings(m, &at.to_string(), program.horizon_s, warnings);
    }
}

/// An `Stl` monitor that reads no signal, or whose windows reach past the horizon `horizon_s`
/// (s) and are lowered.
fn stl_warnings(m: &MonitorSpec, at: &str, horizon_s: f64, warnings: &mut Vec<Warning>) {
    let MonitorSpec::Stl { name, formula } = m else {
        return;
    };
    if paracosm_oracles::stl::parse(formula).is_ok_and(|f| f.signals().is_empty()) {
        warnings.push(Warning {
            at: at.to_owned(),
            message: format!(
                "Stl monitor `{name}` reads no signal: its verdict is the same in every test, \
                 whatever the world does"
            ),
        });
    }
    let clamped = paracosm_oracles::stl::parse(formula)
        .map(|f| f.clamped(horizon_s).1)
        .unwrap_or(false);
    if clamped {
        warnings.push(Warning {
            at: at.to_owned(),
            message: format!(
                "Stl monitor `{name}`: time bounds past the test's horizon of {h} s are lowered \
                 to {c} s, which changes no verdict (a window is cut at the end of the test) \
                 and keeps its memory to the horizon's samples",
                h = horizon_s,
                c = horizon_s + 1.0
            ),
        });
    }
}

/// Whether a monitor reads the light, which makes a light parameter matter.
fn reads_light(monitors: &[MonitorSpec]) -> bool {
    monitors
        .iter()
        .any(|m| m.reads_signal(crate::signal::LIGHT))
}

/// Phase 9: a parameter that, from the first world, changes nothing or nothing the ego can
/// meet may still matter where the others take other values (a radius read only on one
/// branch of an `if`, a friction reached only from another start): before a warning calls it
/// unused, it is varied again from other combinations of the others' values. The second looks
/// share a budget of evaluations ([`REPROBE_EVALUATIONS`]). Returns, per parameter, whether
/// code reads it (an unprobed one counts as read).
fn second_looks(
    program: &Program,
    monitors: &[MonitorSpec],
    effects: &mut Effects,
    file: &str,
    warnings: &mut Vec<Warning>,
) -> Vec<bool> {
    let syntax = &program.syntax;
    let stl_reads_light = reads_light(monitors);
    let unprobed = &mut effects.unprobed;
    let read_in_code: Vec<bool> = program
        .params
        .iter()
        .enumerate()
        .map(|(k, (_, d))| {
            // Unprobed, a parameter counts as read: it is neither warned of nor left out.
            unprobed.contains(&k)
                || syntax.site(&d.site.to_string()).is_some_and(|s| {
                    [&s.variable, &s.container]
                        .into_iter()
                        .flatten()
                        .any(|v| syntax.read_in_code(v))
                })
        })
        .collect();
    let suspects = (0..effects.changes.len())
        .filter(|&k| {
            !read_in_code[k]
                && effects.changes[k]
                    .iter()
                    .all(|c| usage::inert(c, stl_reads_light))
        })
        .count();
    let bases = REPROBE_EVALUATIONS / (suspects.max(1) * (1 + MAX_REPROBED_VALUES));
    for (k, seen) in effects.changes.iter_mut().enumerate() {
        if !read_in_code[k] && seen.iter().all(|c| usage::inert(c, stl_reads_light)) {
            if program.load_budget_left() {
                seen.extend(program.changes_elsewhere(k, &effects.base_values, bases));
            } else {
                unprobed.push(k);
            }
        }
    }
    let read_in_code: Vec<bool> = read_in_code
        .iter()
        .enumerate()
        .map(|(k, r)| *r || unprobed.contains(&k))
        .collect();
    if !unprobed.is_empty() {
        unprobed.sort_unstable();
        unprobed.dedup();
        warnings.push(unprobed_warning(program, unprobed, file));
    }
    read_in_code
}

/// The warning that the budget, or a `Require` that forbids their other values beside the
/// others' representative ones, left parameters `unprobed` (by declaration index).
fn unprobed_warning(program: &Program, unprobed: &[usize], file: &str) -> Warning {
    let names: Vec<&str> = unprobed
        .iter()
        .take(8)
        .map(|&k| program.params[k].0.as_str())
        .collect();
    Warning {
        at: format!("{file}:1:1"),
        message: format!(
            "loading could not probe what {} parameter{} ({}{}) change (its budget of \
             {MAX_LOAD_CHECK_STEPS} evaluation steps ran out, or a Require forbids their \
             other values beside the others' representative ones): they count as used, \
             unprobed (no warning says whether an object uses them, and coverage includes \
             them)",
            unprobed.len(),
            if unprobed.len() == 1 { "" } else { "s" },
            names.join(", "),
            if unprobed.len() > names.len() {
                ", ..."
            } else {
                ""
            }
        ),
    }
}
