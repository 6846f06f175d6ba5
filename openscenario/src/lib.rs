//! OpenSCENARIO 1.0–1.3 reading for paracosm (issue "The industry's logical scenarios as
//! campaigns"): a scenario file's parameters, expressions, catalogs and storyboard, and a
//! parameter value distribution file's varied parameters, read into a typed model. Every
//! error names the file, line and column and what is supported; nothing the model does not
//! hold is passed over in silence. Building a paracosm `Scene` from the model is the
//! `paracosm-scenarios` crate's (`scenarios/src/xosc/`).
//!
//! The standard: ASAM OpenSCENARIO XML 1.3 (the User Guide's sections on parameters,
//! expressions, catalogs, the storyboard and parameter value distributions).
#![warn(missing_docs)]

pub mod distribution;
pub mod error;
pub mod expr;
pub mod files;
pub mod model;
pub mod params;
pub mod quantity;
pub mod read;
pub mod support;
pub mod text;
mod xml;

pub use error::{Pos, XoscError};
pub use files::FileSet;
pub use quantity::Quantity;
pub use read::{read_scenario, read_scenario_in, read_scenario_text};
pub use text::Text;

/// A parameter's or expression's value (OpenSCENARIO 1.3, "Parameters": `double`, `int`,
/// `unsignedInt`, `unsignedShort` are numbers here; `boolean` a bool; `string` and `dateTime`
/// texts).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A number.
    Num(f64),
    /// A boolean.
    Bool(bool),
    /// A text.
    Str(String),
}

impl Value {
    /// The value as an attribute's text: numbers in Rust's shortest round-trip form, bools
    /// as `true`/`false`.
    pub fn to_text(&self) -> String {
        match self {
            Value::Num(v) => format!("{v}"),
            Value::Bool(b) => b.to_string(),
            Value::Str(s) => s.clone(),
        }
    }
}
