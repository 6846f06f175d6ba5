//! Reading a test set: a CSV with a header, or the `results.jsonl` of `paracosm-fuzz`.

use std::path::Path;

use thiserror::Error;

use paracosm_generators::{Domain, Param, ParamSpace, Point, Value};

/// A bad input file: where and why. Lines count from 1 (the CSV header is line 1), columns
/// from 1.
#[derive(Debug, Error, PartialEq)]
#[error("{file}{}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default(), column.as_ref().map(|(i, n)| format!(": column {i} (`{n}`)")).unwrap_or_default())]
pub struct InputError {
    /// The file.
    pub file: String,
    /// The line, when the problem has one.
    pub line: Option<u64>,
    /// The column number and name, when the problem has one.
    pub column: Option<(usize, String)>,
    /// What is wrong.
    pub message: String,
}

/// Tests read from a file, as points of a space.
#[derive(Debug, Clone, PartialEq)]
pub struct TestSet {
    /// The space: the one given, or every column as a continuous parameter on `[0, 1]`.
    pub space: ParamSpace,
    /// One point per test, in file order.
    pub points: Vec<Point>,
}

/// Reads `path`. A `.jsonl` file is read as `paracosm-fuzz` results (its `params` by name when
/// `space` is given, else its `point.continuous`); anything else as CSV with a header. With a
/// space, each parameter is read from the column of its name (other columns are ignored),
/// interval values must lie in `[lo, hi]` and are scaled to `[0, 1]`, and level values must
/// be one of the parameter's levels as written. Without a space every column is a continuous
/// coordinate that must lie in `[0, 1]`, except a first column named `id`.
///
/// # Errors
/// [`InputError`] with the line and column for an empty file, a ragged or non-numeric row, NaN
/// or infinite values, or values outside their domain.
pub fn read_tests(path: &Path, space: Option<&ParamSpace>) -> Result<TestSet, InputError> {
    let file = path.display().to_string();
    let err = |line: Option<u64>, column: Option<(usize, String)>, message: String| InputError {
        file: file.clone(),
        line,
        column,
        message,
    };
    let text = paracosm_scenarios::text_file::read_text(
        path,
        paracosm_scenarios::text_file::MAX_DATA_BYTES,
    )
    .map_err(|e| err(None, None, format!("cannot read: {e}")))?;
    let is_jsonl = path.extension().is_some_and(|e| e == "jsonl");
    parse_tests(&file, &text, is_jsonl, space)
}

/// Reads a test set from `text`, the contents of the file named `file`: `paracosm-fuzz`
/// results when `is_jsonl`, else CSV with a header (see [`read_tests`]).
///
/// # Errors
/// As [`read_tests`].
pub fn parse_tests(
    file: &str,
    text: &str,
    is_jsonl: bool,
    space: Option<&ParamSpace>,
) -> Result<TestSet, InputError> {
    let err = |line: Option<u64>, column: Option<(usize, String)>, message: String| InputError {
        file: file.to_owned(),
        line,
        column,
        message,
    };
    if text.trim().is_empty() {
        return Err(err(None, None, "the file is empty".into()));
    }
    let (names, positions, rows) = if is_jsonl {
        jsonl_rows(text, space, &err)?
    } else {
        csv_rows(text, space, &err)?
    };
    let space = match space {
        Some(s) => s.clone(),
        None => ParamSpace::new(
            names
                .iter()
                .map(|n| Param::interval(n, 0.0, 1.0, "1"))
                .collect(),
        )
        .map_err(|e| err(Some(1), None, e.to_string()))?,
    };
    let mut points = Vec::with_capacity(rows.len());
    for (line, cells) in rows {
        let mut p = Point::default();
        for (j, (param, cell)) in space.params().iter().zip(&cells).enumerate() {
            let col = Some((positions[j], param.name.clone()));
            match &param.domain {
                Domain::Interval { lo, hi } => {
                    let v = match cell {
                        Cell::Number(v) => *v,
                        Cell::Text(t) => t.trim().parse::<f64>().map_err(|_| {
                            err(Some(line), col.clone(), format!("`{t}` is not a number"))
                        })?,
                    };
                    if !v.is_finite() || v < *lo || v > *hi {
                        return Err(err(
                            Some(line),
                            col,
                            format!("value {v} is outside the domain [{lo}, {hi}]"),
                        ));
                    }
                    // hi maps to the last representable coordinate below 1.
                    let u = ((v - lo) / (hi - lo)).min(1.0 - f64::EPSILON / 2.0);
                    p.continuous.push(u);
                }
                Domain::Levels(levels) => {
                    let text = match cell {
                        Cell::Number(v) => format!("{v}"),
                        Cell::Text(t) => t.trim().to_owned(),
                    };
                    let k = levels
                        .iter()
                        .position(|l| level_matches(l, &text))
                        .ok_or_else(|| {
                            let known: Vec<String> = levels.iter().map(|l| l.to_string()).collect();
                            err(
                                Some(line),
                                col,
                                format!("`{text}` is not one of the levels {}", known.join(", ")),
                            )
                        })?;
                    p.discrete.push(k as u32);
                }
            }
        }
        points.push(p);
    }
    if points.is_empty() {
        return Err(err(None, None, "the file has no tests".into()));
    }
    Ok(TestSet { space, points })
}

fn level_matches(level: &Value, text: &str) -> bool {
    match level {
        Value::Text(s) => s == text,
        Value::Bool(b) => text == b.to_string(),
        Value::Int(i) => text.parse::<f64>().is_ok_and(|v| v == *i as f64),
        Value::Real(x) => text.parse::<f64>().is_ok_and(|v| v == *x),
    }
}

/// A raw cell: JSON numbers stay numbers, everything else is text.
enum Cell {
    Number(f64),
    Text(String),
}

/// The parameters' names, the file column (from 1) each is read from, and the rows of cells
/// in that order with their line numbers.
type Rows = (Vec<String>, Vec<usize>, Vec<(u64, Vec<Cell>)>);

fn csv_rows(
    text: &str,
    space: Option<&ParamSpace>,
    err: &dyn Fn(Option<u64>, Option<(usize, String)>, String) -> InputError,
) -> Result<Rows, InputError> {
    // A quote left open swallows the rest of the file into one field, which the csv crate
    // reads without a word: refuse it where it opens.
    let mut open_at = None;
    for (n, line) in text.lines().enumerate() {
        for (c, ch) in line.chars().enumerate() {
            if ch == '"' {
                open_at = match open_at {
                    Some(_) => None,
                    None => Some((n as u64 + 1, c + 1)),
                };
            }
        }
    }
    if let Some((line, column)) = open_at {
        return Err(err(
            Some(line),
            Some((column, "\"".to_owned())),
            "a quote opens here and is never closed".into(),
        ));
    }
    let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| err(Some(1), None, e.to_string()))?
        .iter()
        .map(str::to_owned)
        .collect();
    // A name twice would be read from one of its columns and the other ignored (a map of
    // first columns: 10^6 columns are checked in linear time).
    let mut first: std::collections::HashMap<&str, usize> =
        std::collections::HashMap::with_capacity(header.len());
    for (j, h) in header.iter().enumerate() {
        if let std::collections::hash_map::Entry::Occupied(e) = first.entry(h.as_str()) {
            let i = *e.get();
            return Err(err(
                Some(1),
                Some((j + 1, h.clone())),
                format!(
                    "the column `{h}` appears twice (columns {} and {})",
                    i + 1,
                    j + 1
                ),
            ));
        }
        first.insert(h, j);
    }
    // Which CSV column feeds each parameter.
    let (names, columns): (Vec<String>, Vec<usize>) = match space {
        Some(s) => {
            let mut cols = Vec::new();
            for p in s.params() {
                let c = first.get(p.name.as_str()).copied().ok_or_else(|| {
                    err(
                        Some(1),
                        None,
                        format!(
                            "no column named `{}` (header: {})",
                            p.name,
                            header.join(", ")
                        ),
                    )
                })?;
                cols.push(c);
            }
            (s.params().iter().map(|p| p.name.clone()).collect(), cols)
        }
        None => {
            let skip = usize::from(header.first().is_some_and(|h| h == "id"));
            (header[skip..].to_vec(), (skip..header.len()).collect())
        }
    };
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line());
            err(line, None, format!("malformed row: {e}"))
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let mut cells = Vec::with_capacity(columns.len());
        for (&c, name) in columns.iter().zip(&names) {
            let v = record.get(c).ok_or_else(|| {
                err(
                    Some(line),
                    Some((c + 1, name.clone())),
                    "missing value".into(),
                )
            })?;
            cells.push(Cell::Text(v.to_owned()));
        }
        rows.push((line, cells));
    }
    let positions = columns.iter().map(|c| c + 1).collect();
    Ok((names, positions, rows))
}

/// The keys of a `results.jsonl` line.
const RESULT_KEYS: [&str; 12] = [
    "campaign", "id", "seed", "strategy", "point", "params", "status", "monitors", "metrics",
    "error", "log", "wall_ms",
];

fn jsonl_rows(
    text: &str,
    space: Option<&ParamSpace>,
    err: &dyn Fn(Option<u64>, Option<(usize, String)>, String) -> InputError,
) -> Result<Rows, InputError> {
    let mut rows = Vec::new();
    let mut names: Vec<String> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let ln = i as u64 + 1;
        if line.trim().is_empty() {
            continue;
        }
        let v: serde_json::Value = serde_json::from_str(line).map_err(|e| {
            err(
                Some(ln),
                None,
                format!("not JSON (column {}): {e}", e.column()),
            )
        })?;
        // A line with other keys was not written by paracosm-fuzz.
        if let Some(obj) = v.as_object() {
            if let Some(k) = obj.keys().find(|k| !RESULT_KEYS.contains(&k.as_str())) {
                return Err(err(
                    Some(ln),
                    None,
                    format!(
                        "unknown key `{k}`: not a paracosm-fuzz results line (keys: {})",
                        RESULT_KEYS.join(", ")
                    ),
                ));
            }
        }
        let cells: Vec<Cell> = match space {
            Some(s) => s
                .params()
                .iter()
                .enumerate()
                .map(|(j, p)| match &v["params"][&p.name] {
                    serde_json::Value::Number(x) => {
                        Ok(Cell::Number(x.as_f64().unwrap_or(f64::NAN)))
                    }
                    serde_json::Value::String(t) => Ok(Cell::Text(t.clone())),
                    serde_json::Value::Bool(b) => Ok(Cell::Text(b.to_string())),
                    _ => Err(err(
                        Some(ln),
                        Some((j + 1, p.name.clone())),
                        "no value in `params`".into(),
                    )),
                })
                .collect::<Result<_, _>>()?,
            None => unit_cells(&v, ln, &mut names, err)?,
        };
        rows.push((ln, cells));
    }
    if let Some(s) = space {
        names = s.params().iter().map(|p| p.name.clone()).collect();
    }
    let positions = (1..=names.len()).collect();
    Ok((names, positions, rows))
}

/// The cells of results line `ln` (`v`) read without a space: its unit-cube coordinates
/// (`point.continuous`), named `u0, u1, ...` in `names` from the first line on.
fn unit_cells(
    v: &serde_json::Value,
    ln: u64,
    names: &mut Vec<String>,
    err: &dyn Fn(Option<u64>, Option<(usize, String)>, String) -> InputError,
) -> Result<Vec<Cell>, InputError> {
    // Discrete coordinates are level indices: without the space they cannot be named or
    // counted, and dropping them would report the coverage of a smaller space than the one
    // tested.
    if v["point"]["discrete"]
        .as_array()
        .is_some_and(|d| !d.is_empty())
    {
        return Err(err(
            Some(ln),
            None,
            "the tests have discrete parameters (`point.discrete`); give --space \
             with the scenario they were run on to read them by name"
                .into(),
        ));
    }
    let coords = v["point"]["continuous"]
        .as_array()
        .ok_or_else(|| err(Some(ln), None, "no `point.continuous` array".into()))?;
    if names.is_empty() {
        *names = (0..coords.len()).map(|j| format!("u{j}")).collect();
    }
    if coords.len() != names.len() {
        return Err(err(
            Some(ln),
            None,
            format!(
                "{} coordinates where earlier lines have {}",
                coords.len(),
                names.len()
            ),
        ));
    }
    coords
        .iter()
        .enumerate()
        .map(|(j, c)| {
            c.as_f64().map(Cell::Number).ok_or_else(|| {
                err(
                    Some(ln),
                    Some((j + 1, names[j].clone())),
                    format!("`{c}` in `point.continuous` is not a number"),
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn reads_csv_with_and_without_a_space() {
        let dir = tempfile::tempdir().unwrap();
        let space = paracosm_scenarios::builtin("pedestrian-crossing")
            .unwrap()
            .space()
            .clone();
        let f = write(
            &dir,
            "a.csv",
            "id,walking_speed,trigger_distance\n0,0.5,5\n1,10,60\n",
        );
        let t = read_tests(&f, Some(&space)).unwrap();
        assert_eq!(t.points[0].continuous, [0.0, 0.0]);
        assert!(t.points[1].continuous.iter().all(|&u| u < 1.0 && u > 0.999));
        let g = write(&dir, "b.csv", "id,x,y\n0,0.25,0.5\n");
        let t = read_tests(&g, None).unwrap();
        assert_eq!(t.space.continuous_dims(), 2);
        assert_eq!(t.points[0].continuous, [0.25, 0.5]);
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            ("empty.csv", "", "the file is empty"),
            ("ragged.csv", "x,y\n0.1,0.2\n0.3\n", ":3"),
            (
                "text.csv",
                "x,y\n0.1,abc\n",
                ":2: column 2 (`y`): `abc` is not a number",
            ),
            ("nan.csv", "x,y\n0.1,NaN\n", ":2: column 2 (`y`): value NaN"),
            ("out.csv", "x,y\n0.1,1.5\n", "outside the domain [0, 1]"),
            (
                "twice.csv",
                "x,y,x\n0.1,0.2,0.9\n",
                ":1: column 3 (`x`): the column `x` appears twice (columns 1 and 3)",
            ),
            (
                "quote.csv",
                "x,y\n0.1,0.2\n0.3,\"0.4\n",
                ":3: column 5 (`\"`): a quote opens here and is never closed",
            ),
        ];
        for (name, text, needle) in cases {
            let f = write(&dir, name, text);
            let e = read_tests(&f, None).unwrap_err().to_string();
            assert!(e.contains(needle), "{name}: {e}");
        }
        let space = paracosm_scenarios::builtin("pedestrian-crossing")
            .unwrap()
            .space()
            .clone();
        let f = write(&dir, "far.csv", "walking_speed,trigger_distance\n11,30\n");
        let e = read_tests(&f, Some(&space)).unwrap_err().to_string();
        assert!(
            e.ends_with(":2: column 1 (`walking_speed`): value 11 is outside the domain [0.5, 10]"),
            "{e}"
        );
        let j = write(&dir, "r.jsonl", "{\"params\":{\"walking_speed\":1}}\n");
        let e = read_tests(&j, Some(&space)).unwrap_err().to_string();
        assert!(e.contains(":1: column 2 (`trigger_distance`)"), "{e}");
    }

    /// paracosm-cover reads every key paracosm-fuzz writes: a record with all its optional
    /// keys (the campaign tag, a log) is read, its point kept.
    #[test]
    fn reads_a_results_line_with_every_key_the_writer_writes() {
        use paracosm_generators::{Param, ParamSpace, Point};
        let space = ParamSpace::new(vec![Param::interval("v", 0.0, 2.0, "m/s")]).unwrap();
        let point = Point {
            discrete: vec![],
            continuous: vec![0.25],
        };
        let record = crate::record::RunRecord {
            passive: Vec::new(),
            campaign: Some("0123456789abcdef".into()),
            id: 0,
            seed: 1,
            strategy: "halton".into(),
            params: space.decode(&point).ok(),
            point,
            status: crate::record::Status::Error,
            monitors: vec![],
            metrics: vec![("simulated_s".into(), 1.0)],
            error: Some("why".into()),
            log: vec!["printed".into()],
            wall_ms: 1.0,
        };
        let line = serde_json::to_string(&record).unwrap();
        let value: serde_json::Value = serde_json::from_str(&line).unwrap();
        for key in value.as_object().unwrap().keys() {
            assert!(RESULT_KEYS.contains(&key.as_str()), "{key}");
        }
        let t = parse_tests("r.jsonl", &line, true, Some(&space)).unwrap();
        assert_eq!(t.points[0].continuous, [0.25]);
    }

    /// A VarEnum of bools is written to `params` as JSON `true`/`false` by paracosm-fuzz and
    /// read back as its level; text levels and numbers alike.
    #[test]
    fn reads_bool_text_and_number_levels_from_results() {
        use paracosm_generators::{Param, ParamSpace, Value};
        let space = ParamSpace::new(vec![
            Param::levels("wet", vec![Value::Bool(false), Value::Bool(true)]),
            Param::levels(
                "kind",
                vec![Value::Text("car".into()), Value::Text("van".into())],
            ),
            Param::levels("lanes", vec![Value::Int(2), Value::Int(4)]),
        ])
        .unwrap();
        let lines = "{\"params\":{\"wet\":true,\"kind\":\"van\",\"lanes\":2}}\n\
                     {\"params\":{\"wet\":false,\"kind\":\"car\",\"lanes\":4}}\n";
        let t = parse_tests("r.jsonl", lines, true, Some(&space)).unwrap();
        assert_eq!(t.points[0].discrete, [1, 1, 0]);
        assert_eq!(t.points[1].discrete, [0, 0, 1]);
        let e = parse_tests(
            "r.jsonl",
            "{\"params\":{\"wet\":1,\"kind\":\"car\",\"lanes\":4}}\n",
            true,
            Some(&space),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`1` is not one of the levels false, true"),
            "{e}"
        );
    }
}
