//! Helpers shared by the command-line tools.

/// Parses a count that must be at least 1 (`--budget`, `-n`).
///
/// # Errors
/// A message naming the rule, for clap to report.
pub fn positive(s: &str) -> Result<u64, String> {
    match s.parse::<u64>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("not a whole number ({e})")),
    }
}

/// A clap error as one line: its first paragraph with the lines joined and the `error: `
/// prefix dropped, e.g. `the following required arguments were not provided: <SCENARIO>`.
pub fn one_line(e: &clap::Error) -> String {
    let rendered = e.to_string();
    let paragraph: Vec<&str> = rendered
        .lines()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let line = paragraph.join(" ");
    let line = line.trim_start_matches("error: ");
    if line.is_empty() {
        "invalid arguments".to_owned()
    } else {
        line.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positive_rejects_zero_and_garbage() {
        assert_eq!(positive("3"), Ok(3));
        assert_eq!(positive("0"), Err("must be at least 1".into()));
        assert!(positive("-1").is_err());
        assert!(positive("ten").is_err());
    }
}
