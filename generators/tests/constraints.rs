//! A constrained space: no generator ever emits a forbidden point, and the covering suites
//! cover every t-tuple a valid point holds (issue "Coverage of the valid space").

use std::sync::Arc;

use paracosm_generators::coverage::kwise_coverage;
use paracosm_generators::{Assignment, FnConstraint, Param, ParamSpace, Point, Strategy, Value};
use proptest::prelude::*;

/// Three discrete parameters and two intervals; forbidden: level `(a, b)` of the first two
/// parameters together, and `x + y > limit` on the third parameter's level 0.
fn space(pair: (i64, i64), limit: f64, continuous: bool) -> ParamSpace {
    let levels = |n: i64| (0..n).map(Value::Int).collect::<Vec<_>>();
    let mut params = vec![
        Param::levels("p", levels(3)),
        Param::levels("q", levels(4)),
        Param::levels("r", levels(2)),
    ];
    if continuous {
        params.push(Param::interval("x", 0.0, 1.0, "m"));
        params.push(Param::interval("y", 0.0, 1.0, "m"));
    }
    let (a, b) = pair;
    ParamSpace::new(params).unwrap().with_constraints(vec![
        Arc::new(FnConstraint::new("pair", move |v: &Assignment| {
            !(v.get("p") == Some(&Value::Int(a)) && v.get("q") == Some(&Value::Int(b)))
        })),
        Arc::new(FnConstraint::new("corner", move |v: &Assignment| {
            v.get("r") != Some(&Value::Int(0))
                || v.real("x").unwrap_or(0.0) + v.real("y").unwrap_or(0.0) <= limit
        })),
    ])
}

fn asked(strategy: Strategy, s: &ParamSpace, seed: u64, n: usize) -> Vec<Point> {
    let mut g = strategy.build_sized(s, seed, n as u64, 2).unwrap();
    match g.batch() {
        None => g.ask(n).unwrap(),
        Some(b) => {
            let mut out = Vec::new();
            while out.len() < n {
                let pts = g.ask(b).unwrap();
                let told: Vec<(Point, f64)> = pts
                    .iter()
                    .map(|p| (p.clone(), p.continuous.iter().sum::<f64>() - 1.0))
                    .collect();
                g.tell(&told);
                out.extend(pts);
            }
            out
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]

    #[test]
    fn no_generator_ever_emits_a_forbidden_point(
        a in 0i64..3, b in 0i64..4, limit in 0.3f64..1.5, seed in 0u64..1000,
    ) {
        let mixed = space((a, b), limit, true);
        for strategy in Strategy::LIST {
            if matches!(strategy, Strategy::Points | Strategy::FullFactorial) {
                continue;
            }
            let n = if strategy.is_adaptive() { 40 } else { 200 };
            for p in asked(strategy, &mixed, seed, n) {
                prop_assert!(mixed.is_valid(&p).unwrap(), "{strategy} emitted {p:?}");
            }
        }
        let discrete = space((a, b), limit, false);
        let all = asked(Strategy::FullFactorial, &discrete, seed, 22);
        prop_assert_eq!(all.len(), 22);
        for p in &all {
            prop_assert!(discrete.is_valid(p).unwrap());
        }
        // Past the 22 valid combinations of 24 the design has nothing more to give.
        let mut g = Strategy::FullFactorial.build(&discrete, 0).unwrap();
        prop_assert!(g.ask(23).is_err());
    }

    #[test]
    fn the_covering_suites_cover_every_valid_pair_and_no_forbidden_one(
        a in 0i64..3, b in 0i64..4, seed in 0u64..1000,
    ) {
        let s = space((a, b), 0.8, true);
        for strategy in Strategy::SUITES {
            // A budget past the array's rows (the random k-wise array has about 90 to 130
            // here, from Proposition 3.2 at δ = 0.01), so every row runs: with 60, seed 139
            // left a pair of the kwise array's later rows out. Seed 677 found a row whose
            // points past its block all broke the corner constraint when they leaped by the
            // number of rows (96, a multiple of the Halton bases 2 and 3).
            let pts = asked(strategy, &s, seed, 200);
            let c = kwise_coverage(&s, &pts, 2, 10).unwrap();
            // 3·4 + 3·2 + 4·2 = 26 pairs, one of them forbidden.
            prop_assert_eq!((c.covered, c.total, c.forbidden), (25, 25, 1), "{} {:?}", strategy, c.missing);
        }
    }
}

#[test]
fn a_given_point_that_breaks_a_constraint_is_refused_by_its_index() {
    let s = space((1, 2), 0.8, true);
    let ok = Point {
        discrete: vec![0, 0, 1],
        continuous: vec![0.9, 0.9],
    };
    let bad = Point {
        discrete: vec![1, 2, 1],
        continuous: vec![0.1, 0.1],
    };
    let Err(e) = Strategy::build_given(&s, vec![ok, bad]) else {
        panic!("a forbidden point was accepted");
    };
    assert_eq!(
        e.to_string(),
        "point 1 breaks pair: breaks pair: a test is never run on a forbidden point"
    );
}
