//! What a scene's load (and the worlds it builds) can refuse, typed by the phase that
//! refuses it ([`LoadErrorKind`]) and located where the declaration at fault stands
//! ([`Site`]). The message is the whole diagnostic, as the tools print it. Front ends (the
//! Starlark language, a scenario file) report their refusals with the same type.

use std::fmt;

/// Where something was declared in a program: its file, line and column (from 1), and the
/// variable the declaration was assigned to, when it was.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Site {
    /// The program's file, as the user named it.
    pub file: String,
    /// The line, from 1.
    pub line: u32,
    /// The column, from 1.
    pub col: u32,
    /// The variable the declaration was assigned to (`speed = VarInterval(...)`), if any.
    pub variable: Option<String>,
}

impl Site {
    /// The site written `file:line:col` (as declarations note where they stand); `None` for
    /// text of another form.
    pub fn parse(at: &str) -> Option<Site> {
        let mut parts = at.rsplitn(3, ':');
        let col = parts.next()?.trim().parse().ok()?;
        let line = parts.next()?.trim().parse().ok()?;
        let file = parts.next()?.trim().to_owned();
        (!file.is_empty()).then_some(Site {
            file,
            line,
            col,
            variable: None,
        })
    }

    /// The site `at` names (`file:line:col`), or, for text of another form (`?` where a
    /// front end knows no position), a site of that text at line 0, column 0, which
    /// displays as the text alone.
    pub fn of(at: &str) -> Site {
        Site::parse(at).unwrap_or_else(|| Site {
            file: at.to_owned(),
            line: 0,
            col: 0,
            variable: None,
        })
    }

    /// The same site, naming the variable its declaration was assigned to.
    pub fn with_variable(mut self, variable: Option<String>) -> Site {
        self.variable = variable;
        self
    }

    /// The site a diagnostic points at: the `file:line:col` after its last ` --> `.
    pub fn of_message(message: &str) -> Option<Site> {
        let (_, rest) = message.rsplit_once("--> ")?;
        Site::parse(rest.lines().next()?)
    }
}

impl fmt::Display for Site {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.file)
        } else {
            write!(f, "{}:{}:{}", self.file, self.line, self.col)
        }
    }
}

/// The phase of a load that refuses a program (LANGUAGE.md, "Errors and limits").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadErrorKind {
    /// The text itself: an action on a line of its own, nesting too deep, a file that cannot
    /// be read.
    Syntax,
    /// An evaluation failed: a builtin refused its arguments, a limit (steps, heap, call
    /// depth) was reached, a lambda failed on its sample value.
    Evaluation,
    /// The declarations of one evaluation do not make a test: no `place`, no ego vehicle, two
    /// behaviours walking one pedestrian, a monitor's window after the horizon.
    Declarations,
    /// The open parameters: too many, two with one name, a coordinate named twice.
    Parameters,
    /// Some values of the parameters build no valid world, or build a world with other
    /// declarations than the first.
    Worlds,
    /// The monitors and the test's settings: a monitor named as the default one, a failure
    /// map naming no parameter.
    Settings,
    /// A file the program reads (an OpenDRIVE map, an ONNX model) cannot be read.
    Files,
    /// These values break a `Require` of the program: no test is run on them, and the
    /// load's checks pass over them.
    Constraint,
}

/// Why a program does not load, or a world of it cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct LoadError {
    /// Where the declaration at fault stands, when the diagnostic points at one.
    pub at: Option<Site>,
    /// The phase that refused it.
    pub kind: LoadErrorKind,
    /// The whole diagnostic (`error: ...`, ` --> file:line:col`, and what to do).
    pub message: String,
}

impl LoadError {
    /// A refusal of `kind` with the diagnostic `message`; [`LoadError::at`] is read from the
    /// message's ` --> file:line:col`.
    pub fn new(kind: LoadErrorKind, message: impl Into<String>) -> Self {
        let message = message.into();
        LoadError {
            at: Site::of_message(&message),
            kind,
            message,
        }
    }

    /// The same error with `more` appended to its message (a line of context).
    pub fn with_context(mut self, more: &str) -> Self {
        self.message = format!("{}{more}", self.message);
        self
    }
}

/// A closure for `map_err` that makes a message a [`LoadError`] of `kind`.
pub fn refused(kind: LoadErrorKind) -> impl Fn(String) -> LoadError {
    move |message| LoadError::new(kind, message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sites_are_read_from_diagnostics() {
        let e = LoadError::new(
            LoadErrorKind::Parameters,
            "error: two open parameters are named `a`\n --> dir/p.star:12:7",
        );
        assert_eq!(
            e.at,
            Some(Site {
                file: "dir/p.star".into(),
                line: 12,
                col: 7,
                variable: None
            })
        );
        assert_eq!(e.at.unwrap().to_string(), "dir/p.star:12:7");
        assert_eq!(Site::parse("p.star"), None);
        assert_eq!(LoadError::new(LoadErrorKind::Syntax, "no site").at, None);
    }
}
