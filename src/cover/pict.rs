//! PICT's plain-text parameter models (`paracosm-cover generate --model FILE`).
//!
//! Supported: `# comments`, blank lines, parameter lines `Name: v1, v2, v3`, and constraints of
//! the form `IF [A] = "x" THEN [B] <> "y";` (values quoted, or bare numbers). Anything else in
//! the constraint section is refused with the line number.

use std::sync::LazyLock;

use regex::Regex;
use thiserror::Error;

use paracosm_generators::covering::Constraints;

/// A parsed model: parameters with their values as written, and forbidden combinations.
#[derive(Debug, Clone, PartialEq)]
pub struct PictModel {
    /// `(name, values)` in file order.
    pub params: Vec<(String, Vec<String>)>,
    /// The constraints, as forbidden `(parameter index, value index)` pairs.
    pub constraints: Constraints,
}

impl PictModel {
    /// Level counts, one per parameter.
    pub fn levels(&self) -> Vec<u32> {
        self.params.iter().map(|(_, v)| v.len() as u32).collect()
    }
}

/// A model error with its line (from 1).
#[derive(Debug, Error, PartialEq)]
#[error("{file}:{line}: {message}")]
pub struct PictError {
    /// The model file.
    pub file: String,
    /// The line, from 1.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

static IF_THEN: LazyLock<Regex> = LazyLock::new(|| {
    let value = r#"(?:"([^"]*)"|([0-9][^\s;]*))"#;
    Regex::new(&format!(
        r#"(?i)^\s*IF\s+\[([^\]]+)\]\s*=\s*{value}\s+THEN\s+\[([^\]]+)\]\s*<>\s*{value}\s*;\s*$"#
    ))
    .expect("the pattern is valid")
});

/// Parses a PICT model.
///
/// # Errors
/// [`PictError`] with the line for a malformed parameter line, a duplicate parameter or value,
/// a parameter without values, an unknown parameter or value in a constraint, or constraint
/// syntax other than `IF [A] = "x" THEN [B] <> "y";`.
pub fn parse_pict(file: &str, text: &str) -> Result<PictModel, PictError> {
    let err = |line: usize, message: String| PictError {
        file: file.to_owned(),
        line,
        message,
    };
    let mut params: Vec<(String, Vec<String>)> = Vec::new();
    let mut forbidden = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        if let Some(c) = IF_THEN.captures(content) {
            let lookup = |name: &str, value: &str| -> Result<(usize, u32), PictError> {
                let p = params
                    .iter()
                    .position(|(n, _)| n == name)
                    .ok_or_else(|| err(line, format!("unknown parameter [{name}]")))?;
                let v = params[p]
                    .1
                    .iter()
                    .position(|x| x == value)
                    .ok_or_else(|| err(line, format!("[{name}] has no value \"{value}\"")))?;
                Ok((p, v as u32))
            };
            let value = |q: usize, b: usize| c.get(q).or(c.get(b)).map_or("", |m| m.as_str());
            let a = lookup(c[1].trim(), value(2, 3))?;
            let b = lookup(c[4].trim(), value(5, 6))?;
            forbidden.push(vec![a, b]);
            continue;
        }
        let upper = content.to_ascii_uppercase();
        if upper.starts_with("IF ") || upper.starts_with('[') || content.ends_with(';') {
            return Err(err(
                line,
                format!(
                    "unsupported constraint `{content}`: only `IF [A] = \"x\" THEN [B] <> \"y\";` is supported"
                ),
            ));
        }
        let Some((name, values)) = content.split_once(':') else {
            return Err(err(
                line,
                format!("expected `Name: v1, v2, ...`, found `{content}`"),
            ));
        };
        let name = name.trim().to_owned();
        let values: Vec<String> = values.split(',').map(|v| v.trim().to_owned()).collect();
        if name.is_empty() || values.iter().any(String::is_empty) {
            return Err(err(
                line,
                "a parameter needs a name and non-empty values".into(),
            ));
        }
        if params.iter().any(|(n, _)| *n == name) {
            return Err(err(line, format!("parameter `{name}` is declared twice")));
        }
        let mut seen = std::collections::HashSet::with_capacity(values.len());
        if let Some(d) = values.iter().find(|v| !seen.insert(v.as_str())) {
            return Err(err(line, format!("value `{d}` appears twice")));
        }
        params.push((name, values));
    }
    if params.is_empty() {
        return Err(err(1, "the model declares no parameter".into()));
    }
    Ok(PictModel {
        params,
        constraints: Constraints::new(forbidden),
    })
}

/// Seed rows for a model (PICT's `/e`): a CSV whose header names model parameters (any
/// subset, any order) and whose cells are values as written in the model; an empty cell or a
/// parameter without a column is left to the generator.
///
/// # Errors
/// [`PictError`] with the line for an unknown parameter in the header, an unknown value, or a
/// malformed row.
pub fn read_seeds(
    model: &PictModel,
    file: &str,
    text: &str,
) -> Result<Vec<Vec<Option<u32>>>, PictError> {
    let err = |line: usize, message: String| PictError {
        file: file.to_owned(),
        line,
        message,
    };
    let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    let header = reader.headers().map_err(|e| err(1, e.to_string()))?.clone();
    let columns: Vec<usize> = header
        .iter()
        .map(|h| {
            model
                .params
                .iter()
                .position(|(n, _)| n == h.trim())
                .ok_or_else(|| err(1, format!("`{h}` is not a parameter of the model")))
        })
        .collect::<Result<_, _>>()?;
    let mut seeds = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            err(
                e.position().map_or(0, |p| p.line() as usize),
                format!("malformed row: {e}"),
            )
        })?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        let mut seed = vec![None; model.params.len()];
        for (cell, &p) in record.iter().zip(&columns) {
            let cell = cell.trim();
            if cell.is_empty() {
                continue;
            }
            let (name, values) = &model.params[p];
            let v = values
                .iter()
                .position(|x| x == cell)
                .ok_or_else(|| err(line, format!("`{cell}` is not a value of `{name}`")))?;
            seed[p] = Some(v as u32);
        }
        seeds.push(seed);
    }
    Ok(seeds)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODEL: &str = "# a PICT model\nType: Primary, Logical, Single\nSize: 10, 100, 500\nFormat: FAT, NTFS\n\nIF [Type] = \"Single\" THEN [Format] <> \"FAT\";\nif [Size] = 500 then [Format] <> \"NTFS\";\n";

    #[test]
    fn parses_parameters_and_if_then_constraints() {
        let m = parse_pict("m.txt", MODEL).unwrap();
        assert_eq!(m.levels(), [3, 3, 2]);
        assert_eq!(m.params[1].1, ["10", "100", "500"]);
        assert_eq!(
            m.constraints.forbidden(),
            [vec![(0, 2), (2, 0)], vec![(1, 2), (2, 1)]]
        );
    }

    #[test]
    fn seeds_map_names_to_levels_and_leave_blanks_open() {
        let m = parse_pict("m.txt", MODEL).unwrap();
        let seeds = read_seeds(&m, "s.csv", "Format,Type\nNTFS,Single\n,Logical\n").unwrap();
        assert_eq!(
            seeds,
            [vec![Some(2), None, Some(1)], vec![Some(1), None, None]]
        );
        let e = read_seeds(&m, "s.csv", "Format\nexFAT\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "s.csv:2: `exFAT` is not a value of `Format`");
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            (
                "A: x, y\nIF [A] = \"x\" THEN [B] <> \"y\";\n",
                "m:2: unknown parameter [B]",
            ),
            (
                "A: x, y\nIF [A] = \"x\" OR [A] = \"y\" THEN [A] <> \"x\";\n",
                "m:2: unsupported constraint",
            ),
            ("A: x, y\nB x, y\n", "m:2: expected `Name: v1, v2, ...`"),
            ("A: x, x\n", "m:1: value `x` appears twice"),
            ("A: x\nA: y\n", "m:2: parameter `A` is declared twice"),
            ("# nothing\n", "m:1: the model declares no parameter"),
        ];
        for (text, want) in cases {
            let e = parse_pict("m", text).unwrap_err().to_string();
            assert!(e.starts_with(want), "{e}");
        }
    }
}
