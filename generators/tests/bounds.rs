//! Property tests: every generator stays inside the space, and decoding stays inside each
//! parameter's interval and level list.

use paracosm_generators::{Domain, Param, ParamSpace, Strategy as Sampler, Value};
use proptest::prelude::*;

/// A random mixed space: up to 6 intervals with arbitrary finite bounds and up to 4 enums.
fn space() -> impl Strategy<Value = ParamSpace> {
    let interval = (-1e6f64..1e6, 1e-3f64..1e6).prop_map(|(lo, w)| (lo, lo + w));
    (
        prop::collection::vec(interval, 0..6),
        prop::collection::vec(1usize..7, 0..4),
    )
        .prop_map(|(intervals, levels)| {
            let mut params: Vec<Param> = intervals
                .iter()
                .enumerate()
                .map(|(i, &(lo, hi))| Param::interval(&format!("c{i}"), lo, hi, "m"))
                .collect();
            params.extend(levels.iter().enumerate().map(|(i, &n)| {
                Param::levels(&format!("d{i}"), (0..n as i64).map(Value::Int).collect())
            }));
            ParamSpace::new(params).unwrap()
        })
}

proptest! {
    #[test]
    fn generated_points_decode_inside_their_domains(
        space in space(),
        strategy in prop::sample::select(Sampler::ALL.to_vec()),
        seed in any::<u64>(),
        n in 1usize..64,
    ) {
        let pts = strategy.build(&space, seed).unwrap().ask(n).unwrap();
        prop_assert_eq!(pts.len(), n);
        for p in &pts {
            prop_assert!(p.continuous.iter().all(|u| (0.0..1.0).contains(u)));
            let a = space.decode(p).unwrap();
            for (param, (_, v)) in space.params().iter().zip(a.iter()) {
                match (&param.domain, v) {
                    (Domain::Interval { lo, hi }, Value::Real(x)) => {
                        prop_assert!(*lo <= *x && *x <= *hi, "{} not in [{}, {}]", x, lo, hi);
                    }
                    (Domain::Levels(levels), v) => prop_assert!(levels.contains(v)),
                    (d, v) => prop_assert!(false, "value {:?} does not match domain {:?}", v, d),
                }
            }
        }
    }

    #[test]
    fn asking_twice_equals_asking_once(
        space in space(),
        strategy in prop::sample::select(Sampler::ALL.to_vec()),
        seed in any::<u64>(),
        a in 0usize..20,
        b in 0usize..20,
    ) {
        let mut g = strategy.build(&space, seed).unwrap();
        let mut split = g.ask(a).unwrap();
        split.extend(g.ask(b).unwrap());
        let whole = strategy.build(&space, seed).unwrap().ask(a + b).unwrap();
        prop_assert_eq!(split, whole);
    }
}
