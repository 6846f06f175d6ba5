//! One line of `results.jsonl`.

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use paracosm_generators::{Assignment, ParamSpace, Point};
use paracosm_oracles::Verdict;

/// A test's outcome class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Every monitor passed.
    Pass,
    /// At least one monitor failed.
    Fail,
    /// The test could not be run to a verdict (invalid world, system under test failure,
    /// internal error); `error` says why.
    Error,
}

/// A monitor's verdict as written to the results file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MonitorResult {
    /// Whether the monitor's property held.
    pub passed: bool,
    /// Robustness in the monitor's unit; `> 0` satisfied. Non-finite values are written as
    /// `null` (JSON has no infinity); [`RunRecord::from_line`] reads a `null` back as `+inf`
    /// when the monitor passed and `-inf` when it failed.
    #[serde(deserialize_with = "f64_or_null")]
    pub robustness: f64,
    /// Time of the first violation in seconds since the start, or `null`.
    pub first_violation_s: Option<f64>,
    /// `true` when the test stopped early (another monitor failed) before this monitor had
    /// settled: its verdict covers the run up to the stop only. Written only when true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub cut_short: bool,
}

impl MonitorResult {
    /// The verdict as written, with `cut_short` as given.
    pub fn new(v: &Verdict, cut_short: bool) -> Self {
        MonitorResult {
            passed: v.passed,
            robustness: v.robustness,
            first_violation_s: v.first_violation_s,
            cut_short,
        }
    }
}

impl From<&Verdict> for MonitorResult {
    fn from(v: &Verdict) -> Self {
        MonitorResult::new(v, false)
    }
}

/// One test's record: a line of `results.jsonl` (see DESIGN.md, "Files a run writes").
///
/// Field order is the line's key order. `wall_ms` is the only field that depends on the
/// machine and the moment; it comes last so that tools can drop it to compare runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunRecord {
    /// The campaign that wrote it: the first 16 hex digits of its fingerprint
    /// (`CampaignFile::tag`). `--resume` and `merge` refuse a record whose tag is not the
    /// campaign's. Left out (`None`) by runs outside a campaign folder (the Python package's
    /// `Scenario.run`, the library's `Campaign::run`), and in files written before it existed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub campaign: Option<String>,
    /// Test index in the campaign, `0..budget`.
    pub id: u64,
    /// The test's own seed, derived from the campaign seed and `id` ([`crate::campaign::seed::test_seed`]).
    pub seed: u64,
    /// The strategy that proposed the point.
    pub strategy: String,
    /// The point in normalised coordinates (`continuous` in `[0, 1)`, `discrete` level indices).
    pub point: Point,
    /// The point's values by parameter name, in the parameters' units; `null` only when the
    /// point does not decode (then `status` is `error`).
    pub params: Option<Assignment>,
    /// Pass, fail or error.
    pub status: Status,
    /// Each monitor's verdict, by monitor name, in the scenario's order.
    #[serde(serialize_with = "ordered_map")]
    pub monitors: Vec<(String, MonitorResult)>,
    /// Measurements by name (units in the name: `_m`, `_s`), e.g. `min_distance_m`,
    /// `distance_travelled_m`, `time_to_failure_s`.
    #[serde(serialize_with = "ordered_map")]
    pub metrics: Vec<(String, f64)>,
    /// Why the test ended in `error`, else `null`.
    pub error: Option<String>,
    /// What the program printed during the test (`print`), in order; the key is left out
    /// when it printed nothing.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub log: Vec<String>,
    /// Wall-clock time of the test in milliseconds. Machine-dependent.
    pub wall_ms: f64,
    /// The monitors that count only where they fail, by name (the scenario's
    /// `passive_monitors`: the default `OffRoadMonitor`), for [`RunRecord::robustness`]. Not
    /// written: whoever makes or reads a record for a scenario sets it.
    #[serde(skip)]
    pub passive: Vec<String>,
}

/// The fields of a results line, as read back (`params` is rebuilt from `point`). Unknown
/// keys are refused: a line with them was not written by paracosm.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Line {
    #[serde(default)]
    campaign: Option<String>,
    id: u64,
    seed: u64,
    strategy: String,
    point: Point,
    params: serde_json::Value,
    status: Status,
    #[serde(deserialize_with = "pairs")]
    monitors: Vec<(String, MonitorResult)>,
    #[serde(deserialize_with = "metric_pairs")]
    metrics: Vec<(String, f64)>,
    error: Option<String>,
    #[serde(default)]
    log: Vec<String>,
    #[serde(deserialize_with = "f64_or_null")]
    wall_ms: f64,
}

impl RunRecord {
    /// The test's robustness, as the falsifiers see it: [`RunRecord::cost`] with the record's
    /// `passive` monitors (`<= 0`: it failed; `+inf` when nothing counts), NaN for a test that
    /// ended in `error`. The report's colours, the failure map's scale and the triage's
    /// correlations use it, so a passing test's margin is not capped by the default off-road
    /// monitor's distance to the road's edge.
    pub fn robustness(&self) -> f64 {
        self.cost(&self.passive)
    }

    /// The names of the monitors that failed, in the scenario's order, but those cut short by
    /// another monitor's failure (their verdict covers only the run up to it).
    pub fn failed_monitors(&self) -> Vec<String> {
        self.monitors
            .iter()
            .filter(|(_, m)| !m.passed && !m.cut_short)
            .map(|(n, _)| n.clone())
            .collect()
    }

    /// The falsification cost of the test: the smallest robustness over its monitors, where
    /// the `passive` ones (see `Scenario::passive_monitors`) count only when `<= 0` and those
    /// cut short by another monitor's failure not at all (an `eventually` cut at 0.2 s reads
    /// `-inf` though the rest of the run might have met it; the failure that cut it counts);
    /// `+inf` when nothing counts, NaN for a test that ended in `error`. `<= 0` exactly when
    /// the test failed.
    pub fn cost(&self, passive: &[String]) -> f64 {
        if self.status == Status::Error {
            return f64::NAN;
        }
        self.monitors
            .iter()
            .filter(|(_, m)| !m.cut_short)
            .filter(|(n, m)| m.robustness <= 0.0 || !passive.contains(n))
            .map(|(_, m)| m.robustness)
            .fold(f64::INFINITY, f64::min)
    }

    /// Reads one line of `results.jsonl` written for a scenario with parameter space `space`
    /// (`params` is decoded again from `point`; a monitor's robustness written as `null` comes
    /// back as `+inf` if it passed and `-inf` if it failed, metrics written as `null` as NaN).
    ///
    /// # Errors
    /// serde_json's error (with its column) when the line is not a results record.
    pub fn from_line(line: &str, space: &ParamSpace) -> Result<RunRecord, serde_json::Error> {
        let l: Line = serde_json::from_str(line)?;
        let params = space.decode(&l.point).ok();
        // `params` must be what `point` decodes to: otherwise the line was edited or belongs
        // to another scenario.
        if serde_json::to_value(&params)? != l.params {
            return Err(serde::de::Error::custom(format!(
                "`params` {} do not match `point` decoded in this scenario's space ({})",
                l.params,
                serde_json::to_value(&params)?
            )));
        }
        // The status must be what the verdicts say: a line edited to read `pass` beside a
        // failed monitor would count as passed everywhere it is read back.
        let failed: Vec<&str> = l
            .monitors
            .iter()
            .filter(|(_, m)| !m.passed)
            .map(|(n, _)| n.as_str())
            .collect();
        let contradiction = match l.status {
            Status::Pass => (!failed.is_empty() || l.error.is_some()).then(|| {
                format!(
                    "`status` is \"pass\" but {}",
                    match failed.first() {
                        Some(n) => format!("monitor `{n}` failed"),
                        None => "`error` is set".to_owned(),
                    }
                )
            }),
            Status::Fail => (failed.is_empty() || l.error.is_some()).then(|| {
                "`status` is \"fail\" but no monitor failed (or `error` is set)".to_owned()
            }),
            Status::Error => (l.error.is_none() || !l.monitors.is_empty()).then(|| {
                "`status` is \"error\" but `error` is null or monitors have verdicts".to_owned()
            }),
        };
        if let Some(c) = contradiction {
            return Err(serde::de::Error::custom(format!(
                "{c}: the record contradicts itself (was it edited?)"
            )));
        }
        Ok(RunRecord {
            passive: Vec::new(),
            campaign: l.campaign,
            id: l.id,
            seed: l.seed,
            strategy: l.strategy,
            params,
            point: l.point,
            status: l.status,
            monitors: l
                .monitors
                .into_iter()
                .map(|(name, mut m)| {
                    // `null` is an infinite robustness: +inf for a monitor that passed, -inf
                    // for one that failed. Read as NaN, `f64::min` would skip it, and a failed
                    // monitor's cost would disappear from a resumed campaign.
                    if m.robustness.is_nan() {
                        m.robustness = if m.passed {
                            f64::INFINITY
                        } else {
                            f64::NEG_INFINITY
                        };
                    }
                    (name, m)
                })
                .collect(),
            metrics: l.metrics,
            error: l.error,
            log: l.log,
            wall_ms: l.wall_ms,
        })
    }
}

/// A number, or `null` read as NaN (JSON has no NaN or infinity).
pub(crate) fn f64_or_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A JSON object read as `(key, value)` pairs in file order.
struct Pairs<V>(std::marker::PhantomData<V>);

impl<'de, V: Deserialize<'de>> Visitor<'de> for Pairs<V> {
    type Value = Vec<(String, V)>;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut out = Vec::new();
        while let Some(entry) = map.next_entry()? {
            out.push(entry);
        }
        Ok(out)
    }
}

fn pairs<'de, D: Deserializer<'de>, V: Deserialize<'de>>(
    d: D,
) -> Result<Vec<(String, V)>, D::Error> {
    d.deserialize_map(Pairs(std::marker::PhantomData))
}

fn metric_pairs<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(String, f64)>, D::Error> {
    let raw: Vec<(String, Option<f64>)> = pairs(d)?;
    Ok(raw
        .into_iter()
        .map(|(k, v)| (k, v.unwrap_or(f64::NAN)))
        .collect())
}

fn ordered_map<K: Serialize, V: Serialize, S: Serializer>(
    pairs: &[(K, V)],
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let mut map = serializer.serialize_map(Some(pairs.len()))?;
    for (k, v) in pairs {
        map.serialize_entry(k, v)?;
    }
    map.end()
}

#[cfg(test)]
mod tests {
    use super::*;
    use paracosm_generators::{Param, ParamSpace};

    #[test]
    fn serialises_with_the_documented_keys_in_order_and_wall_time_last() {
        let space = ParamSpace::new(vec![Param::interval("v", 0.0, 2.0, "m/s")]).unwrap();
        let point = Point {
            discrete: vec![],
            continuous: vec![0.25],
        };
        let r = RunRecord {
            passive: Vec::new(),
            campaign: None,
            id: 3,
            seed: 9,
            strategy: "halton".into(),
            params: space.decode(&point).ok(),
            point,
            status: Status::Fail,
            monitors: vec![(
                "collision".into(),
                MonitorResult {
                    passed: false,
                    robustness: 0.0,
                    first_violation_s: Some(1.5),
                    cut_short: false,
                },
            )],
            metrics: vec![
                ("min_distance_m".into(), 0.0),
                ("time_to_failure_s".into(), 1.5),
            ],
            error: None,
            log: Vec::new(),
            wall_ms: 2.5,
        };
        let line = serde_json::to_string(&r).unwrap();
        assert_eq!(RunRecord::from_line(&line, &space).unwrap(), r);
        // Floats read back bit for bit (serde_json's float_roundtrip): a resumed campaign and
        // a replay rebuild exactly the recorded point.
        let awkward = RunRecord {
            point: Point {
                discrete: vec![],
                continuous: vec![1.0 / 3.0 + 1e-17 * 7.0],
            },
            params: None,
            ..r.clone()
        };
        let awkward = RunRecord {
            params: space.decode(&awkward.point).ok(),
            ..awkward
        };
        let back = RunRecord::from_line(&serde_json::to_string(&awkward).unwrap(), &space).unwrap();
        assert_eq!(
            back.point.continuous[0].to_bits(),
            awkward.point.continuous[0].to_bits()
        );
        assert_eq!(
            line,
            r#"{"id":3,"seed":9,"strategy":"halton","point":{"discrete":[],"continuous":[0.25]},"params":{"v":0.5},"status":"fail","monitors":{"collision":{"passed":false,"robustness":0.0,"first_violation_s":1.5}},"metrics":{"min_distance_m":0.0,"time_to_failure_s":1.5},"error":null,"wall_ms":2.5}"#
        );
    }

    #[test]
    fn an_infinite_robustness_written_null_reads_back_with_its_sign() {
        let space = ParamSpace::new(vec![Param::interval("v", 0.0, 2.0, "m/s")]).unwrap();
        let monitor = |passed: bool, robustness: f64| MonitorResult {
            passed,
            robustness,
            first_violation_s: None,
            cut_short: false,
        };
        let point = Point {
            discrete: vec![],
            continuous: vec![0.25],
        };
        let r = RunRecord {
            passive: Vec::new(),
            campaign: None,
            id: 0,
            seed: 1,
            strategy: "halton".into(),
            params: space.decode(&point).ok(),
            point,
            status: Status::Fail,
            monitors: vec![
                ("collision".into(), monitor(true, f64::INFINITY)),
                ("never".into(), monitor(false, f64::NEG_INFINITY)),
                ("offroad".into(), monitor(true, 1.75)),
            ],
            metrics: vec![],
            error: None,
            log: Vec::new(),
            wall_ms: 1.0,
        };
        let line = serde_json::to_string(&r).unwrap();
        assert!(
            line.contains(r#""never":{"passed":false,"robustness":null"#),
            "{line}"
        );
        let back = RunRecord::from_line(&line, &space).unwrap();
        assert_eq!(back, r);
        // The failed monitor's -inf is the test's cost, not skipped as a NaN would be.
        assert_eq!(back.cost(&[]), f64::NEG_INFINITY);
        assert_eq!(serde_json::to_string(&back).unwrap(), line);
    }
}
