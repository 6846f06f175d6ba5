//! Calling a program's lambdas from the stream graph during a test, with the evaluator of the
//! test's own evaluation of the program.

use paracosm_engine::rx::{Host, HostError, Runtime, StreamId, Value as Rx};

use std::cell::Cell;

use super::values::Stream;
use crate::memory::{self, Budget};
use starlark::eval::Evaluator;
use starlark::values::float::StarlarkFloat;
use starlark::values::tuple::{AllocTuple, TupleRef};
use starlark::values::{Heap, Value, ValueLike};

/// The lambdas of one evaluation of a program, called through its evaluator.
///
/// Lambdas see current values: before each call, every module-level variable that holds a
/// stream is set to that stream's latest value ([`paracosm_engine::rx::Runtime::current`]:
/// this step's event when the stream comes earlier in the graph's order, else the last one;
/// `None` before its first event), so `lambda c: c < limit` with `limit` a stream compares
/// numbers. The cost is one variable write per such variable and call.
pub struct StarHost<'a, 'v, 'b, 'e> {
    eval: &'a mut Evaluator<'v, 'b, 'e>,
    functions: &'a [Value<'v>],
    limits: &'b CallLimits,
    /// The program's file, for the hard heap limit's message.
    file: &'b str,
    /// Module-level variables holding streams, with the stream each holds.
    captured: Vec<(String, StreamId)>,
    /// The streams of `captured`, which lambdas read ([`Host::reads`]).
    reads: Vec<StreamId>,
    /// Who is calling, for the hard heap limit's message ("a lambda, during a test,").
    phase: &'static str,
}

impl<'a, 'v, 'b, 'e> StarHost<'a, 'v, 'b, 'e> {
    /// A host calling `functions` (host function `n` is `functions[n]`) with `eval`, whose
    /// periodic check is `limits` ([`CallLimits::install`]); `file` is the program's.
    pub fn new(
        eval: &'a mut Evaluator<'v, 'b, 'e>,
        functions: &'a [Value<'v>],
        limits: &'b CallLimits,
        file: &'b str,
    ) -> Self {
        let module = eval.module();
        let mut captured: Vec<(String, StreamId)> = module
            .names()
            .filter_map(|name| {
                let v = module.get(name.as_str())?;
                let s = v.downcast_ref::<Stream>()?;
                Some((name.as_str().to_owned(), StreamId(s.id)))
            })
            .collect();
        captured.sort();
        let reads = captured.iter().map(|(_, id)| *id).collect();
        StarHost {
            eval,
            functions,
            limits,
            file,
            captured,
            reads,
            phase: "a lambda, during a test,",
        }
    }

    /// The same host, calling at load (on sample values) rather than during a test: messages
    /// say so.
    #[must_use]
    pub fn at_load(mut self) -> Self {
        self.phase = "a lambda, called at load on sample values,";
        self
    }
}

fn to_star<'v>(v: &Rx, heap: Heap<'v>) -> Value<'v> {
    match v {
        Rx::Unit => Value::new_none(),
        Rx::Num(x) => heap.alloc(*x),
        Rx::Bool(b) => Value::new_bool(*b),
        Rx::Vec3(p) => heap.alloc(super::position::Vector(*p)),
        Rx::Tuple(items) => heap.alloc(AllocTuple(items.iter().map(|x| to_star(x, heap)))),
        Rx::Text(s) => heap.alloc(s.as_str()),
    }
}

/// What a lambda returned, as a stream carries it.
///
/// # Errors
/// [`HostError`] for a value no stream carries, or an int too large to be a number.
fn from_star(v: Value) -> Result<Rx, HostError> {
    if v.is_none() {
        return Ok(Rx::Unit);
    }
    if let Some(b) = v.unpack_bool() {
        return Ok(Rx::Bool(b));
    }
    if let Some(i) = v.unpack_i32() {
        return Ok(Rx::Num(f64::from(i)));
    }
    if v.get_type() == "int" {
        // Past i32: exact as an f64 up to 2^53; beyond, a rounding the program must ask for.
        const EXACT: i64 = 1 << 53;
        return match starlark::values::UnpackValue::unpack_value(v) {
            Ok(Some(i)) if (-EXACT..=EXACT).contains(&i) => Ok(Rx::Num(i as f64)),
            _ => Err(HostError(format!(
                "a lambda returned the int {v}, too large for a stream's number: a float holds \
                 whole numbers exactly only up to 2^53 = {EXACT}; write float(...) to accept \
                 the rounding"
            ))),
        };
    }
    if let Some(f) = v.downcast_ref::<StarlarkFloat>() {
        return Ok(Rx::Num(f.0));
    }
    if let Some(p) = v.downcast_ref::<super::position::Vector>() {
        return Ok(Rx::Vec3(p.0));
    }
    if let Some(l) = v.downcast_ref::<super::position::Loc>() {
        if let Some(at) = l.resolved() {
            return Ok(Rx::Vec3(at.pos_m));
        }
    }
    if let Some(s) = v.unpack_str() {
        return Ok(Rx::Text(s.to_owned()));
    }
    if let Some(t) = TupleRef::from_value(v) {
        let items = t
            .content()
            .iter()
            .map(|&x| from_star(x))
            .collect::<Result<Vec<_>, _>>()?;
        // A triple of numbers is a position or a velocity.
        if let [Rx::Num(a), Rx::Num(b), Rx::Num(c)] = items.as_slice() {
            return Ok(Rx::Vec3([*a, *b, *c]));
        }
        return Ok(Rx::Tuple(items));
    }
    Err(HostError(format!(
        "a lambda returned {}; streams carry numbers, bools, strings and tuples",
        crate::lang::a_type(v.get_type())
    )))
}

impl Host for StarHost<'_, '_, '_, '_> {
    fn call(&mut self, f: u32, args: &[Rx], streams: &Runtime) -> Result<Rx, HostError> {
        let heap = self.eval.heap();
        for (name, id) in &self.captured {
            let now = match streams.current(*id) {
                Some(v) => to_star(v, heap),
                None => Value::new_none(),
            };
            self.eval.module().set(name, now);
        }
        let event = match args {
            [v] => Some(v.clone()),
            _ => None,
        };
        let args: Vec<Value> = args.iter().map(|a| to_star(a, heap)).collect();
        let function = *self
            .functions
            .get(f as usize)
            .ok_or_else(|| format!("no lambda {f}"))?;
        self.limits.checks.set(0);
        self.limits.exceeded.set(None);
        let budget = Budget::start(
            memory::MAX_LAMBDA_HEAP_BYTES,
            memory::HARD_LAMBDA_HEAP_BYTES,
            self.file,
            self.phase,
        );
        let out = self.eval.eval_function(function, &args, &[]);
        let over_heap = memory::over_soft_limit();
        drop(budget);
        let out = match (out, self.limits.exceeded.get()) {
            (Err(e), Some(limit)) => return Err(limit.message(&e).into()),
            (_, _) if over_heap => {
                return Err(format!(
                    "heap limit: a lambda allocated more than {} MiB in one call (limit per \
                     call, LANGUAGE.md \"Limits\")",
                    memory::MAX_LAMBDA_HEAP_BYTES >> 20
                )
                .into())
            }
            // starlark's header says nothing here (the call comes from the engine, "File
            // <builtin>"); the frames of the program's own functions and the located error
            // stay.
            (out, _) => out.map_err(|e| {
                format!("{e}")
                    .lines()
                    .filter(|l| {
                        !(l.starts_with("Traceback (most recent call last)")
                            || l.trim_start().starts_with("File <builtin>"))
                    })
                    .collect::<Vec<_>>()
                    .join("\n")
            })?,
        };
        // A function given to foreach may return the action to perform: bound
        // (`c.setSpeed(2.0)`), or unbound (`c.setSpeed`), which takes the event's value as
        // when it is given to foreach itself.
        if let Some(a) = out.downcast_ref::<super::values::Action>() {
            if let Some(test) = self.test() {
                let value = a.bound_value().or(event).unwrap_or(Rx::Unit);
                test.performed.borrow_mut().push((a.sink, value));
            }
            return Ok(Rx::Unit);
        }
        from_star(out)
    }

    fn performed(&mut self) -> Vec<(paracosm_engine::behaviour::Action, Rx)> {
        self.test()
            .map(|t| std::mem::take(&mut *t.performed.borrow_mut()))
            .unwrap_or_default()
    }

    fn log(&mut self) -> Vec<String> {
        self.test()
            .map(|t| std::mem::take(&mut *t.log.borrow_mut()))
            .unwrap_or_default()
    }

    fn reads(&self) -> &[StreamId] {
        &self.reads
    }
}

impl StarHost<'_, '_, '_, '_> {
    /// The test's state the evaluator carries, if it carries one.
    fn test(&self) -> Option<&super::values::TestState> {
        self.eval
            .extra
            .and_then(|e| e.downcast_ref::<super::values::TestState>())
    }
}

/// Most evaluation steps (function calls and loop iterations) one lambda call may take during a
/// test, counted in starlark's periods of 1,000 steps: about 1,000,000 (a behaviour's lambda
/// takes tens). Past it the call fails with "step limit exceeded" and its test ends with
/// status `error`.
pub const MAX_LAMBDA_STEPS: u64 = 1_000_000;

/// Which limit a lambda call passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Limit {
    Steps,
    Heap,
}

impl Limit {
    /// The test's error for a call stopped by this limit; `e` is starlark's error, whose
    /// traceback names the lambda's file and line.
    fn message(self, e: &starlark::Error) -> String {
        let traceback = format!("{e}").replace("Evaluation cancelled", "stopped here");
        match self {
            Limit::Steps => format!(
                "step limit exceeded: a lambda took more than {MAX_LAMBDA_STEPS} steps (loop \
                 iterations and calls) in one call (LANGUAGE.md \"Limits\")\n{traceback}"
            ),
            Limit::Heap => format!(
                "heap limit: a lambda allocated more than {} MiB in one call (LANGUAGE.md \
                 \"Limits\")\n{traceback}",
                memory::MAX_LAMBDA_HEAP_BYTES >> 20
            ),
        }
    }
}

/// The per-call limits of the lambdas of one test: starlark calls [`CallLimits::check`] every
/// 1,000 evaluation steps, and [`StarHost`] restarts the count before each call.
#[derive(Default)]
pub struct CallLimits {
    /// Periodic checks (of 1,000 steps each) in the current call.
    checks: Cell<u64>,
    /// The limit the current call passed, if any.
    exceeded: Cell<Option<Limit>>,
}

impl CallLimits {
    /// Whether the current call must stop: past [`MAX_LAMBDA_STEPS`], or past the heap budget
    /// of [`memory::MAX_LAMBDA_HEAP_BYTES`].
    fn check(&self) -> bool {
        let n = self.checks.get() + 1;
        self.checks.set(n);
        let limit = if n.saturating_mul(1000) > MAX_LAMBDA_STEPS {
            Some(Limit::Steps)
        } else if memory::over_soft_limit() {
            Some(Limit::Heap)
        } else {
            None
        };
        self.exceeded.set(limit);
        limit.is_some()
    }

    /// Makes `eval` check these limits, and limits its call depth to
    /// [`super::MAX_CALL_DEPTH`].
    ///
    /// # Errors
    /// starlark's, when the evaluator already has a call depth limit.
    pub fn install<'a>(&'a self, eval: &mut Evaluator<'_, 'a, '_>) -> anyhow::Result<()> {
        eval.set_check_cancelled(Box::new(move || self.check()));
        eval.set_max_callstack_size(super::MAX_CALL_DEPTH)
    }
}

/// A program's host with the storyboard of the scenario it imported (`Import(...)`): host
/// functions from [`crate::xosc::IMPORT_HOST_BASE`] are the storyboard's, the others the
/// program's lambdas. Without a storyboard (the check at load, on sample values), the
/// storyboard's functions answer as they would before it moves anything: nothing performed,
/// measures 0.
pub(crate) struct WithStory<'s, H: Host> {
    /// The program's host.
    pub(crate) program: H,
    /// The storyboard's host, `None` at load.
    pub(crate) story: Option<&'s mut dyn Host>,
    /// Both hosts' [`Host::reads`].
    reads: Vec<StreamId>,
}

impl<'s, H: Host> WithStory<'s, H> {
    /// `program` beside `story`.
    pub(crate) fn new(program: H, story: Option<&'s mut dyn Host>) -> Self {
        let mut reads = program.reads().to_vec();
        if let Some(s) = &story {
            reads.extend_from_slice(s.reads());
        }
        WithStory {
            program,
            story,
            reads,
        }
    }
}

impl<H: Host> Host for WithStory<'_, H> {
    fn call(&mut self, f: u32, args: &[Rx], streams: &Runtime) -> Result<Rx, HostError> {
        if f < crate::xosc::IMPORT_HOST_BASE {
            return self.program.call(f, args, streams);
        }
        match &mut self.story {
            Some(s) => s.call(f, args, streams),
            None if f == crate::xosc::IMPORT_HOST_BASE => Ok(Rx::Unit),
            None => Ok(Rx::Num(0.0)),
        }
    }

    fn performed(&mut self) -> Vec<(paracosm_engine::behaviour::Action, Rx)> {
        let mut out = self.program.performed();
        if let Some(s) = &mut self.story {
            out.extend(s.performed());
        }
        out
    }

    fn log(&mut self) -> Vec<String> {
        let mut out = self.program.log();
        if let Some(s) = &mut self.story {
            out.extend(s.log());
        }
        out
    }

    fn reads(&self) -> &[StreamId] {
        &self.reads
    }

    fn ended(&self) -> bool {
        self.program.ended() || self.story.as_ref().is_some_and(|s| s.ended())
    }

    fn finish(&mut self, t_s: f64) -> Result<(), HostError> {
        match self.story.as_mut() {
            Some(s) if !self.program.ended() => s.finish(t_s),
            _ => Ok(()),
        }
    }
}
