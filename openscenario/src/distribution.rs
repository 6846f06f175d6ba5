//! Parameter value distribution files: which parameters of a scenario vary and how (ASAM
//! OpenSCENARIO XML 1.3 User Guide, section 9.3 "Parameter value distribution file"; XSD types
//! `ParameterValueDistribution`, `Deterministic`, `Stochastic` and the distributions below).
//!
//! Read: `Deterministic` with `DeterministicSingleParameterDistribution` (`DistributionSet`,
//! `DistributionRange`) and `DeterministicMultiParameterDistribution` (`ValueSetDistribution`);
//! `Stochastic` (`numberOfTestRuns`, `randomSeed`) with `StochasticDistribution`
//! (`ProbabilityDistributionSet`, `NormalDistribution`, `LogNormalDistribution`,
//! `UniformDistribution`, `PoissonDistribution`, `Histogram`). Refused as Unsupported:
//! `UserDefinedDistribution` (its meaning is tool-specific) and any element the XSD does not
//! place there. Numbers are literals or constant expressions (`${50 / 3.6}`); a distribution
//! file declares no parameters, so `$name` is Invalid in a numeric attribute. Texts (set
//! elements, assigned values, the scenario's path) are kept as written.

use roxmltree::{Document, Node};

use crate::error::{Pos, XoscError};
use crate::expr::{self, parse_number};
use crate::params::{check_attrs, required};
use crate::text::Text;
use crate::Value;

/// The most levels a `DistributionRange` may have.
pub const MAX_LEVELS: u64 = 1_000_000;

/// A parameter value distribution file (XSD `ParameterValueDistribution`).
#[derive(Debug, Clone, PartialEq)]
pub struct VariationFile {
    /// The `ScenarioFile` `filepath` as written (relative paths are relative to the
    /// distribution file's directory).
    pub scenario_file: String,
    /// Where `filepath` is.
    pub scenario_pos: Pos,
    /// Deterministic or stochastic, with the stochastic run count and seed.
    pub kind: Kind,
    /// The single-parameter distributions, in file order.
    pub params: Vec<Varied>,
    /// The multi-parameter distributions (`ValueSetDistribution`, deterministic only), in file
    /// order. Each is one dimension of the variation whose levels are its value sets; the
    /// dimensions (these and `params`) combine as a cartesian product.
    pub multi: Vec<ValueSets>,
}

/// How the parameters vary (XSD group `DistributionDefinition`).
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// Every combination of the levels of the distributions (`Deterministic`).
    Deterministic,
    /// `runs` random draws (`Stochastic`).
    Stochastic {
        /// `numberOfTestRuns`, at least 1.
        runs: u32,
        /// `randomSeed`, when given.
        random_seed: Option<f64>,
    },
}

/// One parameter's distribution (`DeterministicSingleParameterDistribution` or
/// `StochasticDistribution`).
#[derive(Debug, Clone, PartialEq)]
pub struct Varied {
    /// `parameterName`.
    pub name: String,
    /// Where the distribution element is.
    pub pos: Pos,
    /// The distribution.
    pub dist: Dist,
}

/// One `ValueSetDistribution`: alternative assignments of several parameters at once.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueSets {
    /// Where the `DeterministicMultiParameterDistribution` is.
    pub pos: Pos,
    /// The `ParameterValueSet`s; each assigns the parameters it names (those it does not name
    /// keep their values).
    pub sets: Vec<Vec<Assignment>>,
}

/// One `ParameterAssignment` of a value set.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// `parameterRef`.
    pub name: String,
    /// `value`, as written.
    pub value: String,
    /// Where the assignment is.
    pub pos: Pos,
}

/// A `ParameterAssignment`'s value: as written, or an expression `${...}` (a dialect of
/// Vector's Euro NCAP files, `${0.6/2-0.36}`, which esmini evaluates) evaluated to its value's
/// text ([`Value::to_text`]); an expression reads no parameter (the assignment's own scope
/// has none).
///
/// # Errors
/// Invalid at the attribute for an expression that does not evaluate (naming why).
fn assigned_value(text: &Text, a: Node<'_, '_>, value: &str) -> Result<String, XoscError> {
    let Some(inner) = value.strip_prefix("${").and_then(|v| v.strip_suffix('}')) else {
        return Ok(value.to_string());
    };
    expr::eval(inner, &|_| None)
        .map(|v| v.to_text())
        .map_err(|e| XoscError::Invalid {
            pos: text.attr_pos(a, "value"),
            reason: format!("the value {value:?} does not evaluate: {e}"),
        })
}

/// A single parameter's distribution. Bounds are inclusive; numbers are finite.
#[derive(Debug, Clone, PartialEq)]
pub enum Dist {
    /// `DistributionSet`: the `Element` values as written, at least one.
    Set(Vec<String>),
    /// `DistributionRange`: `lo`, `lo + step`, ... up to `hi` (`Range` `lowerLimit`,
    /// `upperLimit`; `stepWidth` > 0; at most [`MAX_LEVELS`] levels).
    Range {
        /// `lowerLimit`.
        lo: f64,
        /// `upperLimit`, at least `lo`.
        hi: f64,
        /// `stepWidth`, positive.
        step: f64,
    },
    /// `UniformDistribution` over `Range`.
    Uniform {
        /// `lowerLimit`.
        lo: f64,
        /// `upperLimit`, at least `lo`.
        hi: f64,
    },
    /// `NormalDistribution`, truncated to the optional `Range`.
    Normal {
        /// `expectedValue`.
        mean: f64,
        /// `variance` (the square of the standard deviation), more than 0.
        variance: f64,
        /// `Range` `lowerLimit`.
        lo: Option<f64>,
        /// `Range` `upperLimit`.
        hi: Option<f64>,
    },
    /// `LogNormalDistribution`, truncated to the optional `Range`: `ln X` is normal with mean
    /// `mu` = `expectedValue` and standard deviation `sigma` = √`variance`, i.e. the two
    /// attributes are read as the parameters of the underlying normal distribution (the
    /// reading of `std::lognormal_distribution` and of the OpenSCENARIO interpreter of
    /// scenario_simulator_v2; the User Guide does not say). The mean of `X` itself is
    /// `exp(mu + sigma² / 2)`.
    LogNormal {
        /// `expectedValue`: the mean of `ln X`.
        mu: f64,
        /// √`variance`: the standard deviation of `ln X`, more than 0.
        sigma: f64,
        /// `Range` `lowerLimit`.
        lo: Option<f64>,
        /// `Range` `upperLimit`.
        hi: Option<f64>,
    },
    /// `Histogram`: bins `(lo, hi, weight)` with `lo < hi`, ordered and not overlapping
    /// (`Bin` `Range` and `weight`); weights at least 0 and not all 0.
    Histogram(Vec<(f64, f64, f64)>),
    /// `ProbabilityDistributionSet`: `(value as written, weight)`; weights at least 0 and not
    /// all 0.
    ProbabilitySet(Vec<(String, f64)>),
    /// `PoissonDistribution`, truncated to the optional `Range`.
    Poisson {
        /// `expectedValue` (λ), at least 0.
        expected: f64,
        /// `Range` `lowerLimit`.
        lo: Option<f64>,
        /// `Range` `upperLimit`.
        hi: Option<f64>,
    },
}

impl Dist {
    /// The discrete levels as parameter texts: a `Set`'s elements, a `ProbabilitySet`'s values,
    /// a `Range`'s levels (numbers as [`Value::to_text`] writes them; `hi` is included when the
    /// steps reach it, see [`range_levels`]). `None` for continuous distributions, histograms
    /// and Poisson.
    pub fn levels(&self) -> Option<Vec<String>> {
        match self {
            Dist::Set(v) => Some(v.clone()),
            Dist::ProbabilitySet(v) => Some(v.iter().map(|(s, _)| s.clone()).collect()),
            Dist::Range { lo, hi, step } => Some(
                range_levels(*lo, *hi, *step)?
                    .into_iter()
                    .map(|x| Value::Num(x).to_text())
                    .collect(),
            ),
            _ => None,
        }
    }

    /// The bounds of the values drawn: a `Range`'s or `Uniform`'s limits, a truncating
    /// `Range` when both limits are given, a histogram's first and last bin edges. `None` for
    /// sets and untruncated distributions.
    pub fn range(&self) -> Option<(f64, f64)> {
        match self {
            Dist::Range { lo, hi, .. } | Dist::Uniform { lo, hi } => Some((*lo, *hi)),
            Dist::Normal { lo, hi, .. }
            | Dist::LogNormal { lo, hi, .. }
            | Dist::Poisson { lo, hi, .. } => Some(((*lo)?, (*hi)?)),
            Dist::Histogram(bins) => Some((bins.first()?.0, bins.last()?.1)),
            Dist::Set(_) | Dist::ProbabilitySet(_) => None,
        }
    }
}

/// Digits after the decimal point of `x` as Rust writes it (never in exponent form).
fn decimals(x: f64) -> usize {
    let s = format!("{x}");
    s.find('.').map_or(0, |i| s.len() - i - 1)
}

/// How a range's levels are computed.
enum Plan {
    /// Exact decimals: level `i` is `(l + i * s) / scale`.
    Exact { l: f64, s: f64, scale: f64, n: u64 },
    /// Level `i` is `lo + i * step`, at most `hi`.
    Float { n: u64 },
}

fn plan(lo: f64, hi: f64, step: f64) -> Option<Plan> {
    if !(lo.is_finite() && hi.is_finite() && step.is_finite()) || step <= 0.0 || lo > hi {
        return None;
    }
    let d = decimals(lo).max(decimals(hi)).max(decimals(step));
    if d <= 9 {
        let scale = 10f64.powi(d as i32);
        let (l, h, s) = (
            (lo * scale).round(),
            (hi * scale).round(),
            (step * scale).round(),
        );
        let limit = 2f64.powi(53);
        if l.abs() < limit && h.abs() < limit && s >= 1.0 && s < limit {
            let n = ((h - l) / s).floor() as u64 + 1;
            return (n <= MAX_LEVELS).then_some(Plan::Exact { l, s, scale, n });
        }
    }
    let k = (hi - lo) / step;
    let whole = k.floor();
    let steps = if k - whole > 1.0 - 1e-9 {
        whole + 1.0
    } else {
        whole
    };
    if !steps.is_finite() || steps + 1.0 > MAX_LEVELS as f64 {
        return None;
    }
    Some(Plan::Float {
        n: steps as u64 + 1,
    })
}

/// How many levels [`range_levels`] gives, without computing them.
pub fn range_count(lo: f64, hi: f64, step: f64) -> Option<u64> {
    match plan(lo, hi, step)? {
        Plan::Exact { n, .. } | Plan::Float { n } => Some(n),
    }
}

/// `lo`, `lo + step`, ... up to `hi` (inclusive), or `None` when `step` is not positive, the
/// bounds are not finite or ordered, or there would be more than [`MAX_LEVELS`].
///
/// When `lo`, `hi` and `step` have at most 9 decimals the levels are exact decimals
/// (1.1 to 1.5 by 0.2 is 1.1, 1.3, 1.5, not 1.5000000000000002); otherwise they are
/// `lo + i * step` and `hi` is included when the steps reach it within 1e-9 of a step.
pub fn range_levels(lo: f64, hi: f64, step: f64) -> Option<Vec<f64>> {
    Some(match plan(lo, hi, step)? {
        Plan::Exact { l, s, scale, n } => (0..n).map(|i| (l + i as f64 * s) / scale).collect(),
        Plan::Float { n } => (0..n).map(|i| (lo + i as f64 * step).min(hi)).collect(),
    })
}

/// Whether `doc` is a parameter value distribution file: an `<OpenSCENARIO>` root holding a
/// `<ParameterValueDistribution>`.
pub fn is_variation(doc: &Document<'_>) -> bool {
    let root = doc.root_element();
    root.has_tag_name("OpenSCENARIO")
        && root
            .children()
            .any(|c| c.has_tag_name("ParameterValueDistribution"))
}

fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

/// Reads a parameter value distribution file.
///
/// # Errors
/// [`XoscError::Xml`] for malformed XML; Invalid for a root other than `<OpenSCENARIO>`, a
/// scenario or catalog given instead ("this is a scenario, not a parameter value
/// distribution"), a missing or repeated element or attribute, a number that is not one, a
/// bound or weight out of range, a parameter varied twice; Unsupported for
/// `UserDefinedDistribution`, unknown elements and attributes.
pub fn read_variation(text: &Text) -> Result<VariationFile, XoscError> {
    let doc = text.parse()?;
    let root = text.open_root(doc)?;
    if elements(root).any(|c| c.has_tag_name("Storyboard")) {
        return Err(text.invalid(
            root,
            "this is a scenario, not a parameter value distribution",
        ));
    }
    if elements(root).any(|c| c.has_tag_name("Catalog")) {
        return Err(text.invalid(
            root,
            "this is a catalog, not a parameter value distribution",
        ));
    }
    let mut pvd = None;
    for c in elements(root) {
        match c.tag_name().name() {
            "FileHeader" => {}
            "ParameterValueDistribution" if pvd.is_none() => pvd = Some(c),
            "ParameterValueDistribution" => {
                return Err(
                    text.invalid(c, "a second <ParameterValueDistribution>; a file holds one")
                )
            }
            other => {
                return Err(text.unsupported(
                    c,
                    format!(
                        "<{other}> in a parameter value distribution file: it holds \
                         <FileHeader> and <ParameterValueDistribution>"
                    ),
                ))
            }
        }
    }
    let Some(pvd) = pvd else {
        return Err(text.invalid(
            root,
            "no <ParameterValueDistribution>: this is not a parameter value distribution",
        ));
    };
    read_pvd(text, pvd)
}

fn read_pvd(text: &Text, pvd: Node<'_, '_>) -> Result<VariationFile, XoscError> {
    check_attrs(text, pvd, &[])?;
    let mut scenario = None;
    let mut body = None;
    for c in elements(pvd) {
        match c.tag_name().name() {
            "ScenarioFile" if scenario.is_none() => {
                check_attrs(text, c, &["filepath"])?;
                let path = required(text, c, "filepath")?.to_string();
                scenario = Some((path, text.attr_pos(c, "filepath")));
            }
            "Deterministic" | "Stochastic" if body.is_none() => body = Some(c),
            name @ ("ScenarioFile" | "Deterministic" | "Stochastic") => {
                return Err(text.invalid(
                    c,
                    format!("a second <{name}>: <ParameterValueDistribution> holds one <ScenarioFile> and one <Deterministic> or <Stochastic>"),
                ))
            }
            other => {
                return Err(text.unsupported(
                    c,
                    format!("<{other}> in <ParameterValueDistribution>: it holds <ScenarioFile> and <Deterministic> or <Stochastic>"),
                ))
            }
        }
    }
    let Some((scenario_file, scenario_pos)) = scenario else {
        return Err(text.invalid(
            pvd,
            "<ParameterValueDistribution> needs a <ScenarioFile filepath>",
        ));
    };
    let Some(body) = body else {
        return Err(text.invalid(
            pvd,
            "<ParameterValueDistribution> needs <Deterministic> or <Stochastic>",
        ));
    };
    let (kind, params, multi) = if body.has_tag_name("Deterministic") {
        check_attrs(text, body, &[])?;
        let (params, multi) = read_deterministic(text, body)?;
        (Kind::Deterministic, params, multi)
    } else {
        let (kind, params) = read_stochastic(text, body)?;
        (kind, params, Vec::new())
    };
    check_unique(&params, &multi)?;
    Ok(VariationFile {
        scenario_file,
        scenario_pos,
        kind,
        params,
        multi,
    })
}

/// Invalid when a parameter is varied by two distributions (a value set may name a parameter
/// in several of its sets).
fn check_unique(params: &[Varied], multi: &[ValueSets]) -> Result<(), XoscError> {
    let twice = |name: &str, pos: &Pos, first: &Pos| XoscError::Invalid {
        pos: pos.clone(),
        reason: format!(
            "parameter {name} is varied twice (first at line {})",
            first.line
        ),
    };
    let mut seen: Vec<(&str, &Pos)> = Vec::new();
    for v in params {
        if let Some((_, first)) = seen.iter().find(|(n, _)| *n == v.name) {
            return Err(twice(&v.name, &v.pos, first));
        }
        seen.push((&v.name, &v.pos));
    }
    for m in multi {
        let before = seen.len();
        for a in m.sets.iter().flatten() {
            if let Some((_, first)) = seen[..before].iter().find(|(n, _)| *n == a.name) {
                return Err(twice(&a.name, &a.pos, first));
            }
            if !seen[before..].iter().any(|(n, _)| *n == a.name) {
                seen.push((&a.name, &a.pos));
            }
        }
    }
    Ok(())
}

fn read_deterministic(
    text: &Text,
    node: Node<'_, '_>,
) -> Result<(Vec<Varied>, Vec<ValueSets>), XoscError> {
    let mut params = Vec::new();
    let mut multi = Vec::new();
    for c in elements(node) {
        match c.tag_name().name() {
            "DeterministicSingleParameterDistribution" => {
                check_attrs(text, c, &["parameterName"])?;
                let name = required(text, c, "parameterName")?.to_string();
                let d = only_child(text, c, &["DistributionSet", "DistributionRange"])?;
                let dist = match d.tag_name().name() {
                    "DistributionSet" => read_set(text, d)?,
                    _ => read_range_dist(text, d)?,
                };
                params.push(Varied {
                    name,
                    pos: text.pos(c),
                    dist,
                });
            }
            "DeterministicMultiParameterDistribution" => {
                check_attrs(text, c, &[])?;
                let v = only_child(text, c, &["ValueSetDistribution"])?;
                multi.push(ValueSets {
                    pos: text.pos(c),
                    sets: read_value_sets(text, v)?,
                });
            }
            other => {
                return Err(text.unsupported(
                    c,
                    format!(
                        "<{other}> in <Deterministic>: it holds \
                         <DeterministicSingleParameterDistribution> and \
                         <DeterministicMultiParameterDistribution>"
                    ),
                ))
            }
        }
    }
    Ok((params, multi))
}

fn read_stochastic(text: &Text, node: Node<'_, '_>) -> Result<(Kind, Vec<Varied>), XoscError> {
    check_attrs(text, node, &["numberOfTestRuns", "randomSeed"])?;
    let runs = number(text, node, "numberOfTestRuns")?;
    if runs.fract() != 0.0 || !(1.0..=f64::from(u32::MAX)).contains(&runs) {
        return Err(XoscError::Invalid {
            pos: text.attr_pos(node, "numberOfTestRuns"),
            reason: format!(
                "numberOfTestRuns = {runs}: a whole number of runs from 1 to {} is needed",
                u32::MAX
            ),
        });
    }
    let random_seed = opt_number(text, node, "randomSeed")?;
    let mut params = Vec::new();
    for c in elements(node) {
        if c.tag_name().name() != "StochasticDistribution" {
            return Err(text.unsupported(
                c,
                format!(
                    "<{}> in <Stochastic>: it holds <StochasticDistribution>",
                    c.tag_name().name()
                ),
            ));
        }
        check_attrs(text, c, &["parameterName"])?;
        let name = required(text, c, "parameterName")?.to_string();
        let d = only_child(
            text,
            c,
            &[
                "ProbabilityDistributionSet",
                "NormalDistribution",
                "LogNormalDistribution",
                "UniformDistribution",
                "PoissonDistribution",
                "Histogram",
            ],
        )?;
        params.push(Varied {
            name,
            pos: text.pos(c),
            dist: read_stochastic_dist(text, d)?,
        });
    }
    if params.is_empty() {
        return Err(text.invalid(
            node,
            "<Stochastic> needs at least one <StochasticDistribution>",
        ));
    }
    // `runs` was checked to be a whole number within u32's range above.
    Ok((
        Kind::Stochastic {
            runs: runs as u32,
            random_seed,
        },
        params,
    ))
}

/// The one element child of `node`, which must be one of `allowed`.
fn only_child<'a, 'i>(
    text: &Text,
    node: Node<'a, 'i>,
    allowed: &[&str],
) -> Result<Node<'a, 'i>, XoscError> {
    let here = node.tag_name().name();
    let mut found = None;
    for c in elements(node) {
        let name = c.tag_name().name();
        if name == "UserDefinedDistribution" {
            let ty = c.attribute("type").unwrap_or_default();
            return Err(text.unsupported(
                c,
                format!(
                    "<UserDefinedDistribution type={ty:?}>: its meaning is tool-specific; \
                     paracosm reads {}",
                    allowed.join(", ")
                ),
            ));
        }
        if !allowed.contains(&name) {
            return Err(text.unsupported(
                c,
                format!(
                    "<{name}> in <{here}>: it holds one of {}",
                    allowed.join(", ")
                ),
            ));
        }
        if found.is_some() {
            return Err(text.invalid(
                c,
                format!("a second distribution in <{here}>: it holds one"),
            ));
        }
        found = Some(c);
    }
    found.ok_or_else(|| {
        text.invalid(
            node,
            format!("<{here}> needs one of {}", allowed.join(", ")),
        )
    })
}

fn read_set(text: &Text, node: Node<'_, '_>) -> Result<Dist, XoscError> {
    check_attrs(text, node, &[])?;
    let mut values = Vec::new();
    for e in elements(node) {
        if e.tag_name().name() != "Element" {
            return Err(text.unsupported(
                e,
                format!(
                    "<{}> in <DistributionSet>: it holds <Element value>",
                    e.tag_name().name()
                ),
            ));
        }
        check_attrs(text, e, &["value"])?;
        values.push(required(text, e, "value")?.to_string());
    }
    if values.is_empty() {
        return Err(text.invalid(
            node,
            "an empty <DistributionSet>: it needs at least one <Element value>",
        ));
    }
    Ok(Dist::Set(values))
}

fn read_range_dist(text: &Text, node: Node<'_, '_>) -> Result<Dist, XoscError> {
    check_attrs(text, node, &["stepWidth"])?;
    let step = number(text, node, "stepWidth")?;
    if step <= 0.0 {
        return Err(XoscError::Invalid {
            pos: text.attr_pos(node, "stepWidth"),
            reason: format!("stepWidth = {step}: it must be positive"),
        });
    }
    let (lo, hi) = match range_child(text, node)? {
        (Some(lo), Some(hi)) => (lo, hi),
        _ => {
            return Err(text.invalid(
                node,
                "<DistributionRange> needs a <Range lowerLimit upperLimit>",
            ))
        }
    };
    if range_count(lo, hi, step).is_none() {
        return Err(text.invalid(
            node,
            format!("the range {lo} to {hi} by {step} has more than {MAX_LEVELS} levels"),
        ));
    }
    Ok(Dist::Range { lo, hi, step })
}

fn read_stochastic_dist(text: &Text, d: Node<'_, '_>) -> Result<Dist, XoscError> {
    let nonneg = |attr: &str| -> Result<f64, XoscError> {
        let x = number(text, d, attr)?;
        if x < 0.0 {
            return Err(XoscError::Invalid {
                pos: text.attr_pos(d, attr),
                reason: format!("{attr} = {x}: it must be at least 0"),
            });
        }
        Ok(x)
    };
    // A variance of 0 is one value, not a distribution: a parameter to vary needs a spread.
    let positive = |attr: &str| -> Result<f64, XoscError> {
        let x = nonneg(attr)?;
        if x == 0.0 {
            return Err(XoscError::Invalid {
                pos: text.attr_pos(d, attr),
                reason: format!(
                    "{attr} = 0: the distribution is one value, which paracosm cannot vary; \
                     give a positive {attr}, or the value itself in the scenario's \
                     ParameterDeclaration"
                ),
            });
        }
        Ok(x)
    };
    Ok(match d.tag_name().name() {
        "ProbabilityDistributionSet" => read_probability_set(text, d)?,
        "Histogram" => read_histogram(text, d)?,
        "UniformDistribution" => {
            check_attrs(text, d, &[])?;
            match range_child(text, d)? {
                (Some(lo), Some(hi)) => Dist::Uniform { lo, hi },
                _ => {
                    return Err(text.invalid(
                        d,
                        "<UniformDistribution> needs a <Range lowerLimit upperLimit>",
                    ))
                }
            }
        }
        "NormalDistribution" => {
            check_attrs(text, d, &["expectedValue", "variance"])?;
            let mean = number(text, d, "expectedValue")?;
            let variance = positive("variance")?;
            let (lo, hi) = range_child(text, d)?;
            Dist::Normal {
                mean,
                variance,
                lo,
                hi,
            }
        }
        "LogNormalDistribution" => {
            check_attrs(text, d, &["expectedValue", "variance"])?;
            let mu = number(text, d, "expectedValue")?;
            let sigma = positive("variance")?.sqrt();
            let (lo, hi) = range_child(text, d)?;
            Dist::LogNormal { mu, sigma, lo, hi }
        }
        _ => {
            check_attrs(text, d, &["expectedValue"])?;
            let expected = nonneg("expectedValue")?;
            let (lo, hi) = range_child(text, d)?;
            Dist::Poisson { expected, lo, hi }
        }
    })
}

/// A weight attribute: a number at least 0.
fn weight(text: &Text, node: Node<'_, '_>) -> Result<f64, XoscError> {
    let w = number(text, node, "weight")?;
    if w < 0.0 {
        return Err(XoscError::Invalid {
            pos: text.attr_pos(node, "weight"),
            reason: format!("weight = {w}: weights must be at least 0"),
        });
    }
    Ok(w)
}

/// Refuses weights whose sum is not a finite number: each weight is finite, but two of
/// 1e308 sum to infinity, and every level's share of the draw would then be 0 or NaN (the
/// last level drawn every time).
fn weights_sum(
    text: &Text,
    d: Node<'_, '_>,
    weights: impl Iterator<Item = f64>,
) -> Result<(), XoscError> {
    let total: f64 = weights.sum();
    if total.is_finite() {
        return Ok(());
    }
    Err(text.invalid(
        d,
        format!(
            "<{}>'s weights sum to {total}, past the largest number: scale them down (only \
             their ratios count)",
            d.tag_name().name()
        ),
    ))
}

fn read_probability_set(text: &Text, d: Node<'_, '_>) -> Result<Dist, XoscError> {
    check_attrs(text, d, &[])?;
    let mut out = Vec::new();
    for e in elements(d) {
        if e.tag_name().name() != "Element" {
            return Err(text.unsupported(
                e,
                format!(
                    "<{}> in <ProbabilityDistributionSet>: it holds <Element value weight>",
                    e.tag_name().name()
                ),
            ));
        }
        check_attrs(text, e, &["value", "weight"])?;
        out.push((required(text, e, "value")?.to_string(), weight(text, e)?));
    }
    weights_sum(text, d, out.iter().map(|(_, w)| *w))?;
    if out.iter().all(|(_, w)| *w == 0.0) {
        return Err(text.invalid(
            d,
            "<ProbabilityDistributionSet> needs at least one <Element> with a positive weight",
        ));
    }
    Ok(Dist::ProbabilitySet(out))
}

fn read_histogram(text: &Text, d: Node<'_, '_>) -> Result<Dist, XoscError> {
    check_attrs(text, d, &[])?;
    let mut bins: Vec<(f64, f64, f64)> = Vec::new();
    for b in elements(d) {
        if b.tag_name().name() != "Bin" {
            return Err(text.unsupported(
                b,
                format!(
                    "<{}> in <Histogram>: it holds <Bin weight>",
                    b.tag_name().name()
                ),
            ));
        }
        check_attrs(text, b, &["weight"])?;
        let w = weight(text, b)?;
        let (lo, hi) = match range_child(text, b)? {
            (Some(lo), Some(hi)) => (lo, hi),
            _ => return Err(text.invalid(b, "<Bin> needs a <Range lowerLimit upperLimit>")),
        };
        if lo == hi {
            return Err(text.invalid(b, format!("the bin {lo} to {hi} is empty")));
        }
        if let Some(&(plo, phi, _)) = bins.last() {
            if lo < phi {
                return Err(text.invalid(
                    b,
                    format!("the bin {lo} to {hi} starts before the previous bin ({plo} to {phi}) ends: bins must be in order and not overlap"),
                ));
            }
        }
        bins.push((lo, hi, w));
    }
    weights_sum(text, d, bins.iter().map(|&(_, _, w)| w))?;
    if bins.iter().all(|&(_, _, w)| w == 0.0) {
        return Err(text.invalid(
            d,
            "<Histogram> needs at least one <Bin> with a positive weight",
        ));
    }
    Ok(Dist::Histogram(bins))
}

/// The optional single `<Range lowerLimit upperLimit>` child of `node` (its only allowed
/// child), checked `lo <= hi`.
fn range_child(text: &Text, node: Node<'_, '_>) -> Result<(Option<f64>, Option<f64>), XoscError> {
    let mut out = (None, None);
    let mut seen = false;
    for r in elements(node) {
        if r.tag_name().name() != "Range" || seen {
            return Err(text.unsupported(
                r,
                format!(
                    "<{}> in <{}>: it holds one <Range>",
                    r.tag_name().name(),
                    node.tag_name().name()
                ),
            ));
        }
        seen = true;
        check_attrs(text, r, &["lowerLimit", "upperLimit"])?;
        let lo = number(text, r, "lowerLimit")?;
        let hi = number(text, r, "upperLimit")?;
        if lo > hi {
            return Err(text.invalid(r, format!("lowerLimit {lo} is above upperLimit {hi}")));
        }
        out = (Some(lo), Some(hi));
    }
    Ok(out)
}

fn read_value_sets(text: &Text, node: Node<'_, '_>) -> Result<Vec<Vec<Assignment>>, XoscError> {
    check_attrs(text, node, &[])?;
    let mut sets = Vec::new();
    for s in elements(node) {
        if s.tag_name().name() != "ParameterValueSet" {
            return Err(text.unsupported(
                s,
                format!(
                    "<{}> in <ValueSetDistribution>: it holds <ParameterValueSet>",
                    s.tag_name().name()
                ),
            ));
        }
        check_attrs(text, s, &[])?;
        let mut set: Vec<Assignment> = Vec::new();
        for a in elements(s) {
            if a.tag_name().name() != "ParameterAssignment" {
                return Err(text.unsupported(
                    a,
                    format!(
                        "<{}> in <ParameterValueSet>: it holds <ParameterAssignment>",
                        a.tag_name().name()
                    ),
                ));
            }
            check_attrs(text, a, &["parameterRef", "value"])?;
            let name = required(text, a, "parameterRef")?.to_string();
            if set.iter().any(|x| x.name == name) {
                return Err(text.invalid(
                    a,
                    format!("parameter {name} is assigned twice in one <ParameterValueSet>"),
                ));
            }
            let value = assigned_value(text, a, required(text, a, "value")?)?;
            set.push(Assignment {
                name,
                value,
                pos: text.pos(a),
            });
        }
        if set.is_empty() {
            return Err(text.invalid(
                s,
                "an empty <ParameterValueSet>: it needs at least one <ParameterAssignment>",
            ));
        }
        sets.push(set);
    }
    if sets.is_empty() {
        return Err(text.invalid(
            node,
            "an empty <ValueSetDistribution>: it needs at least one <ParameterValueSet>",
        ));
    }
    Ok(sets)
}

/// `node`'s numeric attribute `attr`, required.
fn number(text: &Text, node: Node<'_, '_>, attr: &str) -> Result<f64, XoscError> {
    opt_number(text, node, attr)?.ok_or_else(|| {
        text.invalid(
            node,
            format!("<{}> needs the attribute {attr}", node.tag_name().name()),
        )
    })
}

/// `node`'s numeric attribute `attr`: a finite number or a constant `${expr}`.
fn opt_number(text: &Text, node: Node<'_, '_>, attr: &str) -> Result<Option<f64>, XoscError> {
    let Some(v) = node.attribute(attr) else {
        return Ok(None);
    };
    let bad = |reason: String| XoscError::Invalid {
        pos: text.attr_pos(node, attr),
        reason: format!("{attr} = {v:?}: {reason}"),
    };
    let t = v.trim();
    if let Some(inner) = t.strip_prefix("${").and_then(|r| r.strip_suffix('}')) {
        return match expr::eval(inner, &|_| None) {
            Ok(Value::Num(x)) => Ok(Some(x)),
            Ok(other) => Err(bad(format!(
                "the expression is {}, not a number",
                other.to_text()
            ))),
            Err(e) => Err(bad(format!(
                "{} (a parameter value distribution declares no parameters)",
                e.reason
            ))),
        };
    }
    if t.starts_with('$') {
        return Err(bad(
            "a parameter value distribution declares no parameters; write the number".into(),
        ));
    }
    parse_number(t)
        .map(Some)
        .ok_or_else(|| bad("not a number".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(body: &str) -> Text {
        Text::new(
            "v.xosc",
            format!(
                "\u{feff}<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<OpenSCENARIO>\n  \
                 <FileHeader revMajor=\"1\" revMinor=\"3\" date=\"2021-07-06T10:00:00\" description=\"d\" author=\"a\"/>\n  \
                 <ParameterValueDistribution>\n    <ScenarioFile filepath=\"./concrete_scenarios/s.xosc\" />\n\
                 {body}\n  </ParameterValueDistribution>\n</OpenSCENARIO>"
            ),
        )
    }

    fn read(body: &str) -> Result<VariationFile, XoscError> {
        read_variation(&file(body))
    }

    fn single(dist: &str) -> String {
        format!(
            "<Deterministic><DeterministicSingleParameterDistribution parameterName=\"p\">{dist}\
             </DeterministicSingleParameterDistribution></Deterministic>"
        )
    }

    fn stochastic(dist: &str) -> String {
        format!("<Stochastic numberOfTestRuns=\"10\" randomSeed=\"42\"><StochasticDistribution parameterName=\"p\">{dist}</StochasticDistribution></Stochastic>")
    }

    fn dist_of(body: &str) -> Dist {
        match read(body) {
            Ok(v) => v.params[0].dist.clone(),
            Err(e) => panic!("{e}"),
        }
    }

    fn error(body: &str) -> String {
        match read(body) {
            Err(e) => e.to_string(),
            Ok(v) => panic!("read {v:?}"),
        }
    }

    #[test]
    fn alks_crossing_pedestrian() {
        // alks_scenario_4_2_3_crossing_pedestrian_variation.xosc, abridged.
        let v = read(
            r#"<Deterministic>
      <DeterministicSingleParameterDistribution parameterName="Road">
        <DistributionSet>
          <Element value="./road_networks/alks_road_straight.xodr" />
          <Element value="./road_networks/alks_road_left_radius_250m.xodr" />
        </DistributionSet>
      </DeterministicSingleParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="Ego_InitSpeed_Ve0_kph">
        <!--Variation between 5 kph and 60 kph with a step width of 5 kph-->
        <DistributionRange stepWidth="5.0">
          <Range lowerLimit="5.0" upperLimit="60.0" />
        </DistributionRange>
      </DeterministicSingleParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="Ego_InitPosition_LaneId">
        <DistributionSet><Element value="4" /><Element value="-4" /></DistributionSet>
      </DeterministicSingleParameterDistribution>
    </Deterministic>"#,
        )
        .unwrap();
        assert_eq!(v.scenario_file, "./concrete_scenarios/s.xosc");
        assert_eq!((v.scenario_pos.line, v.scenario_pos.col), (5, 29));
        assert_eq!(v.kind, Kind::Deterministic);
        assert_eq!(v.params.len(), 3);
        assert!(v.multi.is_empty());
        let speeds = v.params[1].dist.levels().unwrap();
        assert_eq!(speeds.len(), 12);
        assert_eq!(speeds.first().map(String::as_str), Some("5"));
        assert_eq!(speeds.last().map(String::as_str), Some("60"));
        assert_eq!(v.params[1].dist.range(), Some((5.0, 60.0)));
        assert_eq!(v.params[2].dist.levels().unwrap(), ["4", "-4"]);
        assert_eq!(v.params[0].dist.range(), None);
        assert_eq!(v.params[2].pos.line, 19);
    }

    #[test]
    fn value_sets() {
        // esmini resources/xosc/cut-in_parameter_set.xosc, abridged.
        let v = read(
            r#"<Deterministic>
      <DeterministicMultiParameterDistribution>
        <ValueSetDistribution>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="HostVehicle" value="car_blue" />
            <ParameterAssignment parameterRef="TargetVehicle" value="car_yellow" />
          </ParameterValueSet>
          <ParameterValueSet>
            <ParameterAssignment parameterRef="TargetVehicle" value="van_red" />
          </ParameterValueSet>
        </ValueSetDistribution>
      </DeterministicMultiParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="TargetSpeedFactor">
        <DistributionRange stepWidth="0.2"><Range lowerLimit="1.1" upperLimit="1.5" /></DistributionRange>
      </DeterministicSingleParameterDistribution>
    </Deterministic>"#,
        )
        .unwrap();
        assert_eq!(v.multi.len(), 1);
        let sets = &v.multi[0].sets;
        assert_eq!(sets.len(), 2);
        assert_eq!(
            (sets[0][1].name.as_str(), sets[0][1].value.as_str()),
            ("TargetVehicle", "car_yellow")
        );
        assert_eq!(sets[1].len(), 1);
        assert_eq!(v.params[0].dist.levels().unwrap(), ["1.1", "1.3", "1.5"]);
        let twice = r#"<Deterministic><DeterministicMultiParameterDistribution><ValueSetDistribution>
            <ParameterValueSet><ParameterAssignment parameterRef="a" value="1"/></ParameterValueSet>
          </ValueSetDistribution></DeterministicMultiParameterDistribution>
          <DeterministicSingleParameterDistribution parameterName="a"><DistributionSet><Element value="2"/></DistributionSet></DeterministicSingleParameterDistribution></Deterministic>"#;
        assert!(error(twice).contains("parameter a is varied twice"));
        let dup = r#"<Deterministic><DeterministicMultiParameterDistribution><ValueSetDistribution>
            <ParameterValueSet><ParameterAssignment parameterRef="a" value="1"/><ParameterAssignment parameterRef="a" value="2"/></ParameterValueSet>
          </ValueSetDistribution></DeterministicMultiParameterDistribution></Deterministic>"#;
        assert!(error(dup).contains("assigned twice"));
        let empty = "<Deterministic><DeterministicMultiParameterDistribution><ValueSetDistribution/></DeterministicMultiParameterDistribution></Deterministic>";
        assert!(error(empty).contains("empty <ValueSetDistribution>"));
        // Vector's CPRA_Cm variation: an assignment's value written as an expression.
        let set = |value: &str| {
            format!(
                r#"<Deterministic><DeterministicMultiParameterDistribution><ValueSetDistribution>
            <ParameterValueSet><ParameterAssignment parameterRef="a" value="{value}"/></ParameterValueSet>
          </ValueSetDistribution></DeterministicMultiParameterDistribution></Deterministic>"#
            )
        };
        let v = read(&set("${0.6/2-0.36}")).unwrap();
        let got: f64 = v.multi[0].sets[0][0].value.parse().unwrap();
        assert_eq!(got, 0.6 / 2.0 - 0.36);
        assert!(error(&set("${$b + 1}")).contains("does not evaluate"));
    }

    #[test]
    fn ranges() {
        assert_eq!(range_levels(5.0, 60.0, 5.0).map(|l| l.len()), Some(12));
        assert_eq!(range_levels(0.0, 1.0, 0.1).map(|l| l.len()), Some(11));
        assert_eq!(range_levels(0.0, 0.95, 0.1).map(|l| l.len()), Some(10));
        assert_eq!(range_levels(2.0, 2.0, 1.0), Some(vec![2.0]));
        assert_eq!(
            range_levels(-1.0, 1.0, 0.5),
            Some(vec![-1.0, -0.5, 0.0, 0.5, 1.0])
        );
        let fine = range_levels(0.0, 1.0, 1.0 / 3.0).unwrap();
        assert_eq!(fine.len(), 4);
        assert!(fine.iter().all(|x| *x <= 1.0));
        assert_eq!(
            range_levels(0.0, 999_999.0, 1.0).map(|l| l.len()),
            Some(1_000_000)
        );
        assert_eq!(range_levels(0.0, 1_000_000.0, 1.0), None);
        assert_eq!(range_count(5.0, 60.0, 5.0), Some(12));
        assert_eq!(range_count(0.0, 1.0, 1e-9), None);
        assert_eq!(range_levels(0.0, 1e300, 1e-300), None);
        assert_eq!(range_levels(1.0, 0.0, 1.0), None);
        assert_eq!(range_levels(0.0, 1.0, 0.0), None);
        assert!(error(&single(r#"<DistributionRange stepWidth="0"><Range lowerLimit="0" upperLimit="1"/></DistributionRange>"#)).contains("must be positive"));
        assert!(error(&single(r#"<DistributionRange stepWidth="1"><Range lowerLimit="2" upperLimit="1"/></DistributionRange>"#)).contains("above upperLimit"));
        assert!(error(&single(r#"<DistributionRange stepWidth="1e-6"><Range lowerLimit="0" upperLimit="10"/></DistributionRange>"#)).contains("more than 1000000 levels"));
        assert!(error(&single(r#"<DistributionRange stepWidth="1"/>"#)).contains("needs a <Range"));
        let d = dist_of(&single(
            r#"<DistributionRange stepWidth="${10 / 4}"><Range lowerLimit="0" upperLimit="5"/></DistributionRange>"#,
        ));
        assert_eq!(d.levels().unwrap(), ["0", "2.5", "5"]);
        assert!(error(&single(r#"<DistributionRange stepWidth="$step"><Range lowerLimit="0" upperLimit="5"/></DistributionRange>"#)).contains("declares no parameters"));
        assert!(error(&single(r#"<DistributionRange stepWidth="${$s}"><Range lowerLimit="0" upperLimit="5"/></DistributionRange>"#)).contains("parameter $s is not declared"));
        assert!(error(&single(r#"<DistributionRange stepWidth="fast"><Range lowerLimit="0" upperLimit="5"/></DistributionRange>"#)).contains("not a number"));
        assert!(error(&single(r#"<DistributionRange stepWidth="1"><Range lowerLimit="0" upperLimit="INF"/></DistributionRange>"#)).contains("not a number"));
    }

    #[test]
    fn stochastic_kinds() {
        let v = read(&stochastic(
            r#"<UniformDistribution><Range lowerLimit="1" upperLimit="3"/></UniformDistribution>"#,
        ))
        .unwrap();
        assert_eq!(
            v.kind,
            Kind::Stochastic {
                runs: 10,
                random_seed: Some(42.0)
            }
        );
        assert_eq!(v.params[0].dist, Dist::Uniform { lo: 1.0, hi: 3.0 });
        assert_eq!(v.params[0].dist.levels(), None);
        let d = dist_of(&stochastic(
            r#"<NormalDistribution expectedValue="30" variance="4"><Range lowerLimit="20" upperLimit="40"/></NormalDistribution>"#,
        ));
        assert_eq!(
            d,
            Dist::Normal {
                mean: 30.0,
                variance: 4.0,
                lo: Some(20.0),
                hi: Some(40.0)
            }
        );
        assert_eq!(d.range(), Some((20.0, 40.0)));
        let d = dist_of(&stochastic(
            r#"<NormalDistribution expectedValue="30" variance="4"/>"#,
        ));
        assert_eq!(d.range(), None);
        let d = dist_of(&stochastic(
            r#"<LogNormalDistribution expectedValue="1" variance="0.25"/>"#,
        ));
        assert_eq!(
            d,
            Dist::LogNormal {
                mu: 1.0,
                sigma: 0.5,
                lo: None,
                hi: None
            }
        );
        let d = dist_of(&stochastic(
            r#"<PoissonDistribution expectedValue="3"><Range lowerLimit="0" upperLimit="10"/></PoissonDistribution>"#,
        ));
        assert_eq!(
            d,
            Dist::Poisson {
                expected: 3.0,
                lo: Some(0.0),
                hi: Some(10.0)
            }
        );
        let d = dist_of(&stochastic(
            r#"<Histogram><Bin weight="1"><Range lowerLimit="0" upperLimit="1"/></Bin><Bin weight="3"><Range lowerLimit="1" upperLimit="2"/></Bin></Histogram>"#,
        ));
        assert_eq!(d, Dist::Histogram(vec![(0.0, 1.0, 1.0), (1.0, 2.0, 3.0)]));
        assert_eq!(d.range(), Some((0.0, 2.0)));
        let d = dist_of(&stochastic(
            r#"<ProbabilityDistributionSet><Element value="car" weight="0.3"/><Element value="truck" weight="0.7"/></ProbabilityDistributionSet>"#,
        ));
        assert_eq!(d.levels().unwrap(), ["car", "truck"]);
        let no_seed = read("<Stochastic numberOfTestRuns=\"3\"><StochasticDistribution parameterName=\"p\"><UniformDistribution><Range lowerLimit=\"1\" upperLimit=\"3\"/></UniformDistribution></StochasticDistribution></Stochastic>").unwrap();
        assert_eq!(
            no_seed.kind,
            Kind::Stochastic {
                runs: 3,
                random_seed: None
            }
        );
    }

    #[test]
    fn stochastic_errors() {
        assert!(error(&stochastic(
            r#"<NormalDistribution expectedValue="30" variance="-4"/>"#
        ))
        .contains("variance = -4: it must be at least 0"));
        // One value is no distribution: refused at the attribute (it was an empty interval
        // found by the campaign, without a line).
        for tag in ["NormalDistribution", "LogNormalDistribution"] {
            let e = error(&stochastic(&format!(
                r#"<{tag} expectedValue="20" variance="0"/>"#
            )));
            assert!(
                e.contains("variance = 0: the distribution is one value"),
                "{e}"
            );
            assert!(e.contains("v.xosc:6:"), "{e}");
        }
        assert!(
            error(&stochastic(r#"<NormalDistribution expectedValue="30"/>"#))
                .contains("needs the attribute variance")
        );
        assert!(
            error(&stochastic(r#"<PoissonDistribution expectedValue="-1"/>"#))
                .contains("at least 0")
        );
        assert!(error(&stochastic(r#"<UniformDistribution/>"#)).contains("needs a <Range"));
        assert!(error(&stochastic(
            r#"<Histogram><Bin weight="1"><Range lowerLimit="0" upperLimit="2"/></Bin><Bin weight="1"><Range lowerLimit="1" upperLimit="3"/></Bin></Histogram>"#
        ))
        .contains("must be in order"));
        assert!(error(&stochastic(
            r#"<Histogram><Bin weight="0"><Range lowerLimit="0" upperLimit="2"/></Bin></Histogram>"#
        ))
        .contains("positive weight"));
        assert!(error(&stochastic(
            r#"<Histogram><Bin weight="1"><Range lowerLimit="2" upperLimit="2"/></Bin></Histogram>"#
        ))
        .contains("is empty"));
        assert!(error(&stochastic(r#"<ProbabilityDistributionSet><Element value="a" weight="-1"/></ProbabilityDistributionSet>"#)).contains("at least 0"));
        assert!(error(&stochastic(r#"<ProbabilityDistributionSet><Element value="a" weight="0"/></ProbabilityDistributionSet>"#)).contains("positive weight"));
        assert!(error(&stochastic(r#"<ProbabilityDistributionSet/>"#)).contains("positive weight"));
        assert!(error(&stochastic(r#"<ProbabilityDistributionSet><Element value="a" weight="1e308"/><Element value="b" weight="1e308"/></ProbabilityDistributionSet>"#)).contains("scale them down"));
        assert!(error(&stochastic(
            r#"<Histogram><Bin weight="1e308"><Range lowerLimit="0" upperLimit="1"/></Bin><Bin weight="1e308"><Range lowerLimit="1" upperLimit="2"/></Bin></Histogram>"#
        ))
        .contains("scale them down"));
        let e = read(&stochastic(
            r#"<UserDefinedDistribution type="mine">x</UserDefinedDistribution>"#,
        ))
        .unwrap_err();
        assert!(matches!(e, XoscError::Unsupported { .. }), "{e}");
        assert!(e
            .to_string()
            .contains("UserDefinedDistribution type=\"mine\""));
        assert!(error(&stochastic(r#"<GammaDistribution/>"#)).contains("<GammaDistribution> in <StochasticDistribution>: it holds one of ProbabilityDistributionSet"));
        let zero_runs = r#"<Stochastic numberOfTestRuns="0"><StochasticDistribution parameterName="p"><UniformDistribution><Range lowerLimit="1" upperLimit="3"/></UniformDistribution></StochasticDistribution></Stochastic>"#;
        assert!(error(zero_runs).contains("from 1"));
        assert!(error(r#"<Stochastic numberOfTestRuns="2.5"/>"#).contains("whole number"));
        assert!(error(r#"<Stochastic numberOfTestRuns="2"/>"#)
            .contains("at least one <StochasticDistribution>"));
        assert!(error(r#"<Stochastic/>"#).contains("needs the attribute numberOfTestRuns"));
        let two = r#"<UniformDistribution><Range lowerLimit="1" upperLimit="3"/></UniformDistribution><UniformDistribution><Range lowerLimit="1" upperLimit="3"/></UniformDistribution>"#;
        assert!(error(&stochastic(two)).contains("a second distribution"));
    }

    #[test]
    fn deterministic_errors() {
        let e = read(&single(r#"<UserDefinedDistribution type="x"/>"#)).unwrap_err();
        assert!(matches!(e, XoscError::Unsupported { .. }));
        assert!(error(&single("<DistributionSet/>")).contains("empty <DistributionSet>"));
        assert!(error(&single("")).contains("needs one of DistributionSet, DistributionRange"));
        assert!(error(&single(
            r#"<NormalDistribution expectedValue="1" variance="1"/>"#
        ))
        .contains("<NormalDistribution> in <DeterministicSingleParameterDistribution>"));
        assert!(
            error(r#"<Deterministic><Foo/></Deterministic>"#).contains("<Foo> in <Deterministic>")
        );
        assert!(error(&single(
            r#"<DistributionSet><Element value="1" weight="2"/></DistributionSet>"#
        ))
        .contains("has no attribute weight"));
        assert!(error(&single(
            r#"<DistributionSet><Item value="1"/></DistributionSet>"#
        ))
        .contains("<Item> in <DistributionSet>"));
        let twice = r#"<Deterministic>
          <DeterministicSingleParameterDistribution parameterName="a"><DistributionSet><Element value="1"/></DistributionSet></DeterministicSingleParameterDistribution>
          <DeterministicSingleParameterDistribution parameterName="a"><DistributionSet><Element value="2"/></DistributionSet></DeterministicSingleParameterDistribution>
        </Deterministic>"#;
        let e = error(twice);
        assert!(
            e.contains("parameter a is varied twice (first at line 7)"),
            "{e}"
        );
        assert!(e.starts_with("v.xosc:8:"), "{e}");
        // An empty Deterministic is allowed by the XSD (no parameter varies).
        assert!(read("<Deterministic/>").unwrap().params.is_empty());
    }

    #[test]
    fn file_shape() {
        let scenario = Text::new(
            "s.xosc",
            "<OpenSCENARIO><FileHeader/><ParameterDeclarations/><Storyboard/></OpenSCENARIO>",
        );
        let e = read_variation(&scenario).unwrap_err();
        assert!(matches!(e, XoscError::Invalid { .. }));
        assert!(e
            .to_string()
            .contains("this is a scenario, not a parameter value distribution"));
        assert!(!is_variation(scenario.parse().unwrap()));
        let catalog = Text::new(
            "c.xosc",
            "<OpenSCENARIO><FileHeader/><Catalog name=\"x\"/></OpenSCENARIO>",
        );
        assert!(read_variation(&catalog)
            .unwrap_err()
            .to_string()
            .contains("this is a catalog"));
        let other = Text::new("o.xml", "<OpenDRIVE/>");
        assert!(read_variation(&other)
            .unwrap_err()
            .to_string()
            .contains("root element is <OpenDRIVE>"));
        let none = Text::new("n.xosc", "<OpenSCENARIO><FileHeader/></OpenSCENARIO>");
        assert!(read_variation(&none)
            .unwrap_err()
            .to_string()
            .contains("no <ParameterValueDistribution>"));
        let broken = Text::new("b.xosc", "<OpenSCENARIO>");
        assert!(matches!(
            read_variation(&broken),
            Err(XoscError::Xml { .. })
        ));
        let t = file("<Deterministic/>");
        assert!(is_variation(t.parse().unwrap()));
        let no_file = Text::new("x.xosc", "<OpenSCENARIO><ParameterValueDistribution><Deterministic/></ParameterValueDistribution></OpenSCENARIO>");
        assert!(read_variation(&no_file)
            .unwrap_err()
            .to_string()
            .contains("needs a <ScenarioFile filepath>"));
        let no_body = Text::new("x.xosc", "<OpenSCENARIO><ParameterValueDistribution><ScenarioFile filepath=\"a\"/></ParameterValueDistribution></OpenSCENARIO>");
        assert!(read_variation(&no_body)
            .unwrap_err()
            .to_string()
            .contains("needs <Deterministic> or <Stochastic>"));
        assert!(
            error("<Deterministic/><Stochastic numberOfTestRuns=\"1\"/>")
                .contains("a second <Stochastic>")
        );
        assert!(matches!(
            read("<Extra/>"),
            Err(XoscError::Unsupported { .. })
        ));
        let extra_root = Text::new(
            "x.xosc",
            "<OpenSCENARIO><Entities/><ParameterValueDistribution/></OpenSCENARIO>",
        );
        assert!(matches!(
            read_variation(&extra_root),
            Err(XoscError::Unsupported { .. })
        ));
    }
}
