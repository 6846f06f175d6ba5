//! The scenario language: Starlark programs (the `starlark` crate) that build a reactive world
//! with the paper's vocabulary (§2). LANGUAGE.md is the reference.
//!
//! A program is evaluated hermetically (no `load`, no file, network or clock access) and within
//! limits (a step count, a heap size, a call depth): when it loads, to learn its open parameters
//! and check its worlds, and once per test with that test's values, in a heap and evaluator of
//! the test's own ([`program`]). An open parameter that is constant over a test is a plain
//! value in the program (a number, string or bool), so every Starlark operation works on it
//! and the program may branch on it.

mod builtins;
pub mod constraint;
mod globals;
mod host;
mod methods;
mod names;
mod position;
mod program;
mod scene;
mod types;
mod units;
mod values;

use std::path::Path;

use starlark::environment::GlobalsBuilder;
use starlark::syntax::{AstModule, Dialect};

use crate::{Scenario, ScenarioError};

pub use crate::scene::{LoadError, LoadErrorKind, Site};
pub use host::MAX_LAMBDA_STEPS;
/// Where the language's refusals come from: the scene model's typed load errors.
pub mod load_error {
    pub use crate::scene::{refused, LoadError, LoadErrorKind, Site};
}
pub use program::{MAX_CHECKED_WORLDS, MAX_CHECK_STEPS, MAX_LOAD_CHECK_STEPS, MAX_PARAMS};
pub use values::OverTime;

/// The length of a test when the program does not set one with `test(horizon=)`, seconds.
pub use crate::scene::DEFAULT_HORIZON_S;
/// Most evaluation steps (function calls and loop iterations) a program may take to load.
pub const MAX_LOAD_STEPS: u64 = 10_000_000;
/// Most heap a program may use to load, in bytes.
pub const MAX_LOAD_HEAP_BYTES: usize = 256 << 20;
/// Deepest call stack a program may use.
pub const MAX_CALL_DEPTH: usize = 200;
/// Deepest nesting of brackets (`(`, `[`, `{`) a program may have. starlark's parser recurses
/// once per level and would overflow the stack (an abort, not an error) near 10,000 levels.
pub const MAX_NESTING: usize = 100;

/// Deepest an expression may nest, operators and calls included (`y = x + x + … + x` with
/// 1,000 terms nests 999 deep): a test evaluates the program on a worker thread, whose 2 MiB
/// stack held 600 and overflowed at 1,000, aborting the process. Refused at load instead.
pub const MAX_EXPR_DEPTH: usize = 300;

fn lambda_name(n: u32) -> String {
    // Not an identifier, so no program can read or overwrite it.
    format!("lambda#{n}")
}

/// Loads the scenario program at `path`. The scenario's name is the file stem with `_`
/// replaced by `-`; its description is the first paragraph of the file's header comment.
///
/// # Errors
/// [`ScenarioError::Io`] when the file cannot be read, is larger than
/// [`crate::text_file::MAX_SOURCE_BYTES`] or is not UTF-8 (naming the line and column of the
/// first bad byte); [`ScenarioError::Load`] with a diagnostic naming the file, line and
/// column (and a caret under the source) for any error in the program, typed by the phase of
/// the load that refused it ([`LoadErrorKind`]).
pub fn load_file(path: &Path) -> Result<Scenario, ScenarioError> {
    let source =
        crate::text_file::read_text(path, crate::text_file::MAX_SOURCE_BYTES).map_err(|e| {
            ScenarioError::Io {
                path: path.display().to_string(),
                message: e.to_string(),
            }
        })?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().replace('_', "-"))
        .unwrap_or_else(|| "scenario".into());
    load_source(&path.display().to_string(), &source, &stem)
}

/// A Starlark type name with its article, for messages: `an int`, `a list`, `an Arc`, and
/// `None` for `NoneType`.
pub(crate) fn a_type(type_name: &str) -> String {
    match type_name {
        "NoneType" => "None".to_owned(),
        t if t.starts_with(['a', 'e', 'i', 'o', 'u', 'A', 'E', 'I', 'O', 'U']) => format!("an {t}"),
        t => format!("a {t}"),
    }
}

/// Adds "did you mean `x`?" to starlark's "Found `y` extra named parameter(s) for call to F".
pub(crate) fn suggest_keyword(message: &str) -> String {
    let Some(rest) = message.split("Found `").nth(1) else {
        return message.to_owned();
    };
    let Some((wrong, tail)) = rest.split_once('`') else {
        return message.to_owned();
    };
    let Some(function) = tail.split("for call to ").nth(1).and_then(|f| {
        f.split(|c: char| !c.is_alphanumeric() && c != '_')
            .find(|w| !w.is_empty())
    }) else {
        return message.to_owned();
    };
    let best = builtins::keywords(function)
        .map(|k| (strsim::levenshtein(k, wrong), k))
        .filter(|(d, _)| *d <= 3)
        .min();
    match best {
        Some((_, key)) => message.replacen(
            &format!("call to {function}"),
            &format!("call to {function}, did you mean `{key}`?"),
            1,
        ),
        None => message.to_owned(),
    }
}

/// The first paragraph of the leading `#` comment, joined into one line.
pub(crate) fn header(source: &str) -> String {
    let mut out = Vec::new();
    for line in source.lines() {
        match line.strip_prefix('#') {
            Some(text) if !text.trim().is_empty() => out.push(text.trim().to_owned()),
            Some(_) if out.is_empty() => {}
            _ => break,
        }
    }
    out.join(" ")
}

/// The globals of a scenario program: Starlark's standard library, `print` (to the test's
/// log), plus the paracosm builtins.
fn globals() -> starlark::environment::Globals {
    GlobalsBuilder::extended_by(&[starlark::environment::LibraryExtension::Print])
        .with(globals::paracosm_globals)
        .build()
}

/// Where (line, column, from 1) brackets first nest deeper than [`MAX_NESTING`], skipping
/// strings and comments; `Ok` when they never do.
fn check_nesting(source: &str) -> Result<(), (usize, usize)> {
    let (mut depth, mut line, mut column) = (0usize, 1usize, 0usize);
    let mut quote: Option<(char, bool)> = None; // (quote char, triple)
    let mut chars = source.chars().peekable();
    let mut comment = false;
    while let Some(c) = chars.next() {
        column += 1;
        if c == '\n' {
            line += 1;
            column = 0;
            comment = false;
            continue;
        }
        if comment {
            continue;
        }
        match quote {
            Some((q, triple)) => {
                if c == '\\' {
                    chars.next();
                    column += 1;
                } else if c == q {
                    if !triple {
                        quote = None;
                    } else if chars.peek() == Some(&q) {
                        chars.next();
                        if chars.peek() == Some(&q) {
                            chars.next();
                            quote = None;
                        }
                    }
                }
            }
            None => match c {
                '#' => comment = true,
                '"' | '\'' => {
                    let triple = chars.peek() == Some(&c) && {
                        let mut ahead = chars.clone();
                        ahead.next();
                        ahead.peek() == Some(&c)
                    };
                    if triple {
                        chars.next();
                        chars.next();
                        column += 2;
                    }
                    quote = Some((c, triple));
                }
                '(' | '[' | '{' => {
                    depth += 1;
                    if depth > MAX_NESTING {
                        return Err((line, column));
                    }
                }
                ')' | ']' | '}' => depth = depth.saturating_sub(1),
                _ => {}
            },
        }
    }
    Ok(())
}

/// Loads a scenario program from `source`; `file` names it in diagnostics, `name` is the
/// scenario's name. The program is evaluated once to learn its open parameters, then once per
/// combination of its parameters' levels and interval ends (at most [`MAX_CHECKED_WORLDS`],
/// else a pairwise covering array of them), each of which must build a valid world; each test
/// evaluates it again with its own values.
///
/// # Errors
/// [`ScenarioError::Load`] as for [`load_file`]; an error that only some values cause
/// names them.
pub fn load_source(file: &str, source: &str, name: &str) -> Result<Scenario, ScenarioError> {
    load_with_base(file, source, name, crate::map_files::Base::of(file, false))
}

/// [`load_source`] for a built-in scenario, whose maps are built in too.
pub(crate) fn load_builtin(
    file: &str,
    source: &str,
    name: &str,
) -> Result<Scenario, ScenarioError> {
    load_with_base(file, source, name, crate::map_files::Base::Builtin)
}

fn load_with_base(
    file: &str,
    source: &str,
    name: &str,
    base: crate::map_files::Base,
) -> Result<Scenario, ScenarioError> {
    let lang = |m: String| ScenarioError::Load(LoadError::new(LoadErrorKind::Syntax, m));
    let dialect = Dialect {
        enable_load: false,
        enable_top_level_stmt: true,
        ..Dialect::Standard
    };
    check_nesting(source).map_err(|(line, column)| {
        lang(format!(
            "error: brackets nest deeper than {MAX_NESTING} levels\n --> {file}:{line}:{column}"
        ))
    })?;
    let ast = AstModule::parse(file, source.to_owned(), &dialect)
        .map_err(|e| lang(with_set_hint(format!("{e}"), file, source)))?;
    if let Some((depth, at)) = names::deepest_expression(&ast, MAX_EXPR_DEPTH) {
        return Err(lang(with_source_lines(
            &format!(
                "error: an expression nests {depth} operations deep, more than the limit of \
                 {MAX_EXPR_DEPTH} (each test evaluates it on a worker thread whose stack it \
                 would overflow): split it over several variables (`a = x + x`, then \
                 `b = a + a`)\n --> {file}:{at}"
            ),
            file,
            source,
        )));
    }
    program::load(file, source, name, ast, globals(), base).map_err(|e| match e {
        ScenarioError::Language(m) => {
            ScenarioError::Language(cut_stack(&with_source_lines(&m, file, source), KEPT_FRAMES))
        }
        ScenarioError::Load(e) => ScenarioError::Load(LoadError {
            message: cut_stack(&with_source_lines(&e.message, file, source), KEPT_FRAMES),
            ..e
        }),
        other => other,
    })
}

/// Frames a Starlark traceback keeps at each end when a message is cut ([`cut_stack`]).
pub const KEPT_FRAMES: usize = 3;

/// `message` with its Starlark traceback ("Traceback (most recent call last):" and frames of
/// `  * file:line, in f` with their source line) cut to its first and last `keep` frames and
/// a line counting the rest: a recursion 400 frames deep reads as its reason and 7 frames.
pub fn cut_stack(message: &str, keep: usize) -> String {
    let Some(start) = message.find("Traceback (most recent call last):") else {
        return message.to_owned();
    };
    let (head, tail) = message.split_at(start);
    let mut lines = tail.lines();
    let title = lines.next().unwrap_or_default();
    // Frames: a `  * ` line and the indented lines after it; the first other line ends them.
    let mut frames: Vec<Vec<&str>> = Vec::new();
    let mut rest: Vec<&str> = Vec::new();
    for line in lines {
        if !rest.is_empty() {
            rest.push(line);
        } else if line.starts_with("  * ") {
            frames.push(vec![line]);
        } else if line.starts_with("    ") && !frames.is_empty() {
            if let Some(f) = frames.last_mut() {
                f.push(line);
            }
        } else {
            rest.push(line);
        }
    }
    if frames.len() <= 2 * keep + 1 {
        return message.to_owned();
    }
    let mut out = format!("{head}{title}\n");
    for f in &frames[..keep] {
        for l in f {
            out.push_str(l);
            out.push('\n');
        }
    }
    out.push_str(&format!(
        "  ... {} more frames ...\n",
        frames.len() - 2 * keep
    ));
    for f in &frames[frames.len() - keep..] {
        for l in f {
            out.push_str(l);
            out.push('\n');
        }
    }
    for l in rest {
        out.push_str(l);
        out.push('\n');
    }
    if !message.ends_with('\n') {
        out.pop();
    }
    out
}

/// Adds a note to a syntax error on a line that writes `VarEnum({...})`, the paper's set
/// notation (§2: `VarEnum({2,4,6})`): in Starlark `{...}` is a dict, so the parser stops at
/// its first `,` expecting `:`, and the note says to write a list.
fn with_set_hint(message: String, file: &str, source: &str) -> String {
    let at = format!("{file}:");
    let line = message
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("--> "))
        .filter_map(|l| l.strip_prefix(at.as_str()))
        .filter_map(|l| l.split(':').next()?.parse::<usize>().ok())
        .next();
    let writes_set = line
        .and_then(|n| source.lines().nth(n.checked_sub(1)?))
        .is_some_and(|l| {
            l.split("VarEnum").skip(1).any(|rest| {
                rest.trim_start()
                    .strip_prefix('(')
                    .is_some_and(|r| r.trim_start().starts_with('{'))
            })
        });
    if writes_set {
        format!(
            "{message}\nnote: `{{...}}` is a dict in Starlark, not a set: write the paper's \
             `VarEnum({{2, 4, 6}})` as `VarEnum([2, 4, 6])`"
        )
    } else {
        message
    }
}

/// Adds the source line and a caret under each ` --> FILE:LINE:COL` of `message` that names
/// `file` and is not followed by them already, as starlark's own diagnostics show them
/// (LANGUAGE.md, "Errors and limits": every error names the file, line and column, with the
/// source line and a caret).
fn with_source_lines(message: &str, file: &str, source: &str) -> String {
    let lines: Vec<&str> = message.lines().collect();
    let mut out = String::with_capacity(message.len() + 256);
    for (k, line) in lines.iter().enumerate() {
        out.push_str(line);
        out.push('\n');
        let shown = lines
            .get(k + 1)
            .is_some_and(|next| next.trim_start().starts_with('|'));
        let Some(place) = line.trim_start().strip_prefix("--> ") else {
            continue;
        };
        let Some(rest) = place.strip_prefix(file).and_then(|r| r.strip_prefix(':')) else {
            continue;
        };
        let mut parts = rest.splitn(2, ':');
        let (Some(Ok(row)), Some(Ok(col))) = (
            parts.next().map(str::parse::<usize>),
            parts.next().map(|c| c.trim_end().parse::<usize>()),
        ) else {
            continue;
        };
        let Some(text) = source.lines().nth(row.wrapping_sub(1)) else {
            continue;
        };
        if shown {
            continue;
        }
        let gutter = " ".repeat(row.to_string().len());
        let indent = " ".repeat(col.saturating_sub(1).min(text.chars().count()));
        out.push_str(&format!(
            "{gutter} |\n{row} | {text}\n{gutter} | {indent}^\n"
        ));
    }
    if !message.ends_with('\n') {
        out.pop();
    }
    out
}

#[cfg(test)]
mod tests;
