//! paracosm's STL robustness equals RTAMT's (the reference library, discrete-time semantics)
//! on the random traces and formulas of `tests/fixtures/rtamt.json`, written by
//! `experiments/stl/compare_rtamt.py fixtures`.

use std::collections::BTreeMap;

use paracosm_oracles::stl::{parse, robustness, Trace};

fn number(v: &serde_json::Value) -> f64 {
    match v {
        serde_json::Value::String(s) if s == "inf" => f64::INFINITY,
        serde_json::Value::String(s) if s == "-inf" => f64::NEG_INFINITY,
        other => other.as_f64().expect("a number"),
    }
}

#[test]
fn robustness_equals_rtamts_on_every_sample() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/rtamt.json"
    ))
    .unwrap();
    let fixture: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cases = fixture["cases"].as_array().unwrap();
    assert!(cases.len() >= 50);
    let mut samples = 0;
    for case in cases {
        let formula = case["formula"].as_str().unwrap();
        let series =
            |k: &str| -> Vec<f64> { case[k].as_array().unwrap().iter().map(number).collect() };
        let mut signals = BTreeMap::new();
        signals.insert("a".to_owned(), series("a"));
        signals.insert("b".to_owned(), series("b"));
        let trace = Trace { dt_s: 1.0, signals };
        let ours = robustness(&parse(formula).unwrap(), &trace).unwrap();
        let theirs = series("robustness");
        assert_eq!(ours.len(), theirs.len(), "{formula}");
        for (i, (x, y)) in ours.iter().zip(&theirs).enumerate() {
            let same = x == y || (x - y).abs() <= 1e-9 * (1.0 + y.abs());
            assert!(
                same,
                "{formula} (RTAMT: {}) at sample {i}: paracosm {x}, RTAMT {y}",
                case["rtamt_formula"]
            );
            samples += 1;
        }
    }
    assert!(samples > 500, "{samples}");
}
