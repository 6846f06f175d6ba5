//! A heap budget that holds even for one huge allocation: for Starlark evaluation (the
//! scenario language) and for loading an ONNX model (`sut::onnx`), whose declared tensor
//! sizes tract allocates while it analyses the graph.
//!
//! starlark's own heap limit is checked every 1,000 evaluation steps, so one statement such
//! as `[0] * 1000000000` (8 GB in one `Vec`), or a loop of forty string doublings, runs to an
//! allocation failure (an abort) before it is looked at. [`CountingAlloc`] counts the bytes a
//! thread allocates while a [`Budget`] is active on it:
//!
//! - past the budget's soft limit, [`over_soft_limit`] says so, and the evaluator's periodic
//!   check (`Evaluator::set_check_cancelled`) and the caller's check after each call turn
//!   that into an error of the evaluation (the load fails with exit 2, a test ends with
//!   status `error`);
//! - past the hard limit, within one statement, the allocator itself prints the reason
//!   (`error: ... heap limit ...` and the program's file) and exits the process with code 2:
//!   no allocation of that size is attempted, and what the campaign already wrote stays. On a
//!   campaign's worker thread it parks instead, and the campaign writes the records of the
//!   tests finished before it, then exits with code 2 ([`park_on_hard_limit`]).
//!
//! The binaries install it (`#[global_allocator]`); a program that does not counts nothing,
//! and only starlark's own (later) checks apply.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Soft heap limit of one lambda call during a test, bytes (64 MiB): past it the call fails
/// with "heap limit" and its test ends with status `error`.
pub const MAX_LAMBDA_HEAP_BYTES: usize = 64 << 20;
/// Hard heap limit of an evaluation of the program (at load and at the start of each test),
/// bytes (1 GiB): an allocation that would pass it exits the process with code 2 and a
/// message instead of being attempted.
pub const HARD_HEAP_BYTES: usize = 1 << 30;
/// Hard heap limit of loading an ONNX model and running it once, bytes (2 GiB): a model whose
/// declared tensors (an intermediate of 10^10 elements) would pass it is refused, named, with
/// exit 2, instead of aborting on an allocation failure.
pub const HARD_MODEL_BYTES: usize = 2 << 30;
/// Hard heap limit of one lambda call during a test, bytes (256 MiB; as [`HARD_HEAP_BYTES`]).
/// Lower than the program's, so that a lambda squaring a big integer in a loop (whose
/// multiplications take minutes near 1 GiB, with no step between) stops within seconds.
pub const HARD_LAMBDA_HEAP_BYTES: usize = 256 << 20;

/// The tool's name for the first line of the hard limit's message ([`set_tool_name`]).
static TOOL: std::sync::OnceLock<&'static str> = std::sync::OnceLock::new();

/// Names the tool in the hard heap limit's message (`TOOL: error: ...`); "paracosm" when unset.
pub fn set_tool_name(name: &'static str) {
    let _ = TOOL.set(name);
}

thread_local! {
    /// Bytes allocated (net of frees) on this thread since the active budget started.
    static USED: Cell<isize> = const { Cell::new(0) };
    /// The active budget's hard limit, bytes; 0 when no budget is active.
    static HARD: Cell<usize> = const { Cell::new(0) };
    /// The active budget's soft limit, bytes.
    static SOFT: Cell<usize> = const { Cell::new(usize::MAX) };
    /// The program's file (pointer and length of a `str` that the active [`Budget`] borrows)
    /// and what is being evaluated, for the hard limit's message.
    static WHAT: Cell<(*const u8, usize, &'static str)> =
        const { Cell::new((std::ptr::null(), 0, "")) };
    /// Whether a hard limit parks this thread ([`park_on_hard_limit`]) instead of exiting.
    static PARK: Cell<bool> = const { Cell::new(false) };
    /// The statement being evaluated under the active budget, as the evaluator's hook notes
    /// it ([`note_statement`]): its file's source (pointer and length) and the statement's
    /// byte offset in it; a null pointer when none was noted since the budget started.
    static STATEMENT: Cell<(*const u8, usize, u32)> =
        const { Cell::new((std::ptr::null(), 0, 0)) };
}

/// Notes the statement an evaluation is about to run, for the hard limit's message
/// (`file:line:col`): `source` is the text of its file, which must outlive the active
/// [`Budget`], and `offset` the statement's byte offset in it. Allocates nothing.
pub fn note_statement(source: &str, offset: u32) {
    STATEMENT.with(|s| s.set((source.as_ptr(), source.len(), offset)));
}

/// The 1-based line and column (in bytes) of the statement last noted, if any.
fn noted_place() -> Option<(usize, usize)> {
    let (ptr, len, offset) = STATEMENT.with(Cell::get);
    let offset = offset as usize;
    if ptr.is_null() || offset > len {
        return None;
    }
    // SAFETY: noted by `note_statement` from a `&str` that outlives the active budget (the
    // note is cleared when a budget starts and restored when it ends).
    let text = unsafe { std::slice::from_raw_parts(ptr, len) };
    let before = &text[..offset];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    Some((line, offset - start + 1))
}

/// The global allocator of the paracosm binaries: [`System`], counting the bytes of threads
/// with an active [`Budget`] (see the module's documentation). Declare it with
/// `#[global_allocator] static A: CountingAlloc = CountingAlloc;`.
pub struct CountingAlloc;

#[inline]
fn count(delta: isize, request: usize) {
    let hard = HARD.with(Cell::get);
    if hard == 0 {
        return;
    }
    let used = USED.with(|u| {
        let v = u.get().saturating_add(delta);
        u.set(v);
        v
    });
    if delta > 0 && (used.max(0) as usize > hard || request > hard) {
        hard_limit_exceeded(hard, request);
    }
}

#[cold]
fn hard_limit_exceeded(hard: usize, request: usize) -> ! {
    use std::io::Write;
    // No allocation from here: the message is formatted into a buffer on the stack.
    HARD.with(|h| h.set(0));
    let (ptr, len, what) = WHAT.with(Cell::get);
    let file = if ptr.is_null() {
        ""
    } else {
        // SAFETY: set by `Budget::start` from a `&str` that the live `Budget` borrows (the
        // budget is active, so it has not been dropped): valid UTF-8 of `len` bytes.
        unsafe { std::str::from_utf8_unchecked(std::slice::from_raw_parts(ptr, len)) }
    };
    let mut buf = [0u8; 1024];
    let mut cursor = std::io::Cursor::new(&mut buf[..]);
    let tool = TOOL.get().copied().unwrap_or("paracosm");
    let _ = write!(
        cursor,
        "{tool}: error: {what} exceeded the heap limit of {} MiB (its last allocation asked \
         for {} MiB: a value or tensor too large)\n --> {file}",
        hard >> 20,
        request >> 20
    );
    if let Some((line, column)) = noted_place() {
        let _ = write!(cursor, ":{line}:{column} (the statement it was running)");
    }
    let _ = write!(
        cursor,
        "\n(results already written are kept; nothing after this allocation ran)\n"
    );
    let n = cursor.position() as usize;
    let _ = std::io::stderr().write_all(&buf[..n]);
    if PARK.with(Cell::get) {
        // A campaign's worker: its collector writes the records of the tests finished before
        // this one, then exits the process with code 2 ([`hard_limit_hit`]). Sleeping does
        // not allocate.
        HIT.store(true, std::sync::atomic::Ordering::SeqCst);
        loop {
            std::thread::sleep(std::time::Duration::from_secs(3600));
        }
    }
    std::process::exit(2)
}

/// Whether a thread of a campaign has passed a hard heap limit and waits, parked, for the
/// process to end (see [`park_on_hard_limit`]).
static HIT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes the current thread, past a hard heap limit, print the message and park instead of
/// ending the process, so that the campaign's collector can write the records already
/// finished and then exit (`false` restores the default, an immediate exit). For the worker
/// threads of a campaign, whose collector polls [`hard_limit_hit`].
pub fn park_on_hard_limit(park: bool) {
    PARK.with(|p| p.set(park));
}

/// Whether a thread set to [`park_on_hard_limit`] has passed a hard heap limit: the process
/// must now end with exit code 2, the message being printed.
pub fn hard_limit_hit() -> bool {
    HIT.load(std::sync::atomic::Ordering::SeqCst)
}

// SAFETY: every method forwards to `System` with the same arguments; the counting touches only
// const-initialised thread-locals without destructors, and never allocates.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as isize, layout.size());
        System.alloc(layout)
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size() as isize, layout.size());
        System.alloc_zeroed(layout)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count(-(layout.size() as isize), 0);
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size as isize - layout.size() as isize, new_size);
        System.realloc(ptr, layout, new_size)
    }
}

/// A heap budget active on the current thread until dropped (budgets do not nest: a new one
/// replaces the outer one, whose count resumes from zero when it is restored). It borrows the
/// program's file name, which the hard limit's message shows.
pub struct Budget<'a> {
    saved: (isize, usize, usize, (*const u8, usize, &'static str)),
    /// The outer budget's noted statement ([`note_statement`]).
    statement: (*const u8, usize, u32),
    _file: std::marker::PhantomData<&'a str>,
}

impl<'a> Budget<'a> {
    /// Starts counting this thread's allocations from zero, with `soft` and `hard` limits in
    /// bytes. `file` (the program) and `what` (for example "the program, while loading") name
    /// the evaluation in the hard limit's message.
    pub fn start(soft: usize, hard: usize, file: &'a str, what: &'static str) -> Budget<'a> {
        let saved = (
            USED.with(|u| u.replace(0)),
            HARD.with(|h| h.replace(hard.max(1))),
            SOFT.with(|s| s.replace(soft)),
            WHAT.with(|w| w.replace((file.as_ptr(), file.len(), what))),
        );
        Budget {
            saved,
            statement: STATEMENT.with(|s| s.replace((std::ptr::null(), 0, 0))),
            _file: std::marker::PhantomData,
        }
    }

    /// Starts counting again from zero (for example before each lambda call), keeping the
    /// limits.
    pub fn reset(&self) {
        USED.with(|u| u.set(0));
    }
}

impl Drop for Budget<'_> {
    fn drop(&mut self) {
        let (used, hard, soft, what) = self.saved;
        USED.with(|u| u.set(used));
        HARD.with(|h| h.set(hard));
        SOFT.with(|s| s.set(soft));
        WHAT.with(|w| w.set(what));
        STATEMENT.with(|s| s.set(self.statement));
    }
}

/// Whether this thread's active budget has allocated more than its soft limit (always false
/// without a budget, or without [`CountingAlloc`] as the global allocator).
pub fn over_soft_limit() -> bool {
    HARD.with(Cell::get) != 0 && USED.with(Cell::get).max(0) as usize > SOFT.with(Cell::get)
}

/// Bytes allocated (net) on this thread under the active budget, 0 without one.
pub fn used_bytes() -> usize {
    USED.with(Cell::get).max(0) as usize
}
