use proptest::prelude::*;

use super::*;

/// O(n^(2d+1)) brute force: every box whose faces lie on point coordinates or the cube's
/// boundary, checked against every point.
fn brute(points: &[f64], d: usize) -> f64 {
    let coords: Vec<Vec<f64>> = (0..d)
        .map(|k| {
            let mut c: Vec<f64> = points.chunks_exact(d).map(|p| p[k]).collect();
            c.extend([0.0, 1.0]);
            c.sort_by(f64::total_cmp);
            c.dedup();
            c
        })
        .collect();
    let mut best: f64 = 0.0;
    let mut b = EmptyBox {
        lo: vec![0.0; d],
        hi: vec![0.0; d],
    };
    fn rec(k: usize, d: usize, coords: &[Vec<f64>], b: &mut EmptyBox, pts: &[f64], best: &mut f64) {
        if k == d {
            if b.is_empty_of(pts) {
                *best = best.max(b.volume());
            }
            return;
        }
        for (i, &lo) in coords[k].iter().enumerate() {
            for &hi in &coords[k][i + 1..] {
                b.lo[k] = lo;
                b.hi[k] = hi;
                rec(k + 1, d, coords, b, pts, best);
            }
        }
    }
    rec(0, d, &coords, &mut b, points, &mut best);
    best
}

/// Points on a coarse grid so that ties and boundary values are frequent.
fn grid_points(d: usize, max_n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(0u8..=8, d..=d * max_n).prop_map(move |raw| {
        let n = raw.len() / d;
        raw[..n * d].iter().map(|&v| f64::from(v) / 8.0).collect()
    })
}

fn check(points: &[f64], d: usize) -> Result<(), TestCaseError> {
    let r = dispersion(points, d, &DispersionOptions::default()).unwrap();
    let b = brute(points, d);
    prop_assert!(r.exact);
    prop_assert!(
        (r.lower - b).abs() < 1e-12,
        "d={} fast {} brute {}",
        d,
        r.lower,
        b
    );
    prop_assert_eq!(r.lower, r.upper);
    prop_assert!(r.witness.is_empty_of(points));
    prop_assert!((r.witness.volume() - r.lower).abs() < 1e-15);
    Ok(())
}

proptest! {
    #[test]
    fn exact_1d_matches_brute_force(points in grid_points(1, 12)) {
        check(&points, 1)?;
    }

    #[test]
    fn exact_2d_matches_brute_force(points in grid_points(2, 9)) {
        check(&points, 2)?;
    }

    #[test]
    fn exact_2d_matches_brute_force_on_fine_coordinates(
        raw in prop::collection::vec(0.0f64..1.0, 2..24),
    ) {
        let n = raw.len() / 2;
        check(&raw[..2 * n], 2)?;
    }

    #[test]
    fn exact_3d_matches_brute_force(points in grid_points(3, 5)) {
        check(&points, 3)?;
    }

    #[test]
    fn exact_4d_matches_brute_force(points in grid_points(4, 4)) {
        check(&points, 4)?;
    }

    #[test]
    fn the_bracket_contains_the_exact_value(
        raw in prop::collection::vec(0.0f64..1.0, 9..60),
    ) {
        let d = 3;
        let n = raw.len() / d;
        let pts = &raw[..n * d];
        let exact = dispersion(pts, d, &DispersionOptions::default()).unwrap();
        let opts = DispersionOptions {
            exact_max_points: vec![0],
            bracket_regions: 2_000,
            ..DispersionOptions::default()
        };
        let b = dispersion(pts, d, &opts).unwrap();
        prop_assert!(b.witness.is_empty_of(pts));
        prop_assert!(b.lower <= exact.lower + 1e-12 && exact.lower <= b.upper + 1e-12,
            "{} <= {} <= {}", b.lower, exact.lower, b.upper);
    }
}

#[test]
fn empty_and_boundary_only_sets_leave_the_whole_cube() {
    for d in 1..=4 {
        let r = dispersion(&[], d, &DispersionOptions::default()).unwrap();
        assert_eq!(r.lower, 1.0);
        let corner: Vec<f64> = vec![0.0; d];
        assert_eq!(
            dispersion(&corner, d, &DispersionOptions::default())
                .unwrap()
                .upper,
            1.0
        );
    }
}

#[test]
fn a_centre_point_leaves_half_the_square() {
    let r = dispersion(&[0.5, 0.5], 2, &DispersionOptions::default()).unwrap();
    assert_eq!(r.lower, 0.5);
    assert!(r.witness.is_empty_of(&[0.5, 0.5]));
}

#[test]
fn halton_dispersion_shrinks_like_one_over_n() {
    use crate::{Generator, Halton, ParamSpace};
    let space = ParamSpace::unit_cube(2);
    let pts: Vec<f64> = Halton::new(&space)
        .ask(4096)
        .unwrap()
        .into_iter()
        .flat_map(|p| p.continuous)
        .collect();
    let small = dispersion(&pts[..2 * 256], 2, &DispersionOptions::default()).unwrap();
    let large = dispersion(&pts, 2, &DispersionOptions::default()).unwrap();
    // n · dispersion stays bounded (paper Proposition 3.3): within [1, 8] here.
    for (n, r) in [(256.0, &small), (4096.0, &large)] {
        let c = n * r.lower;
        assert!((1.0..8.0).contains(&c), "n·dispersion = {c} at n = {n}");
    }
}

#[test]
fn bad_input_is_an_error() {
    assert!(matches!(
        dispersion(&[0.1, 1.5], 2, &DispersionOptions::default()),
        Err(CoverageError::OutsideUnitCube {
            row: 0,
            column: 1,
            ..
        })
    ));
    assert!(dispersion(&[0.1, 0.2, 0.3], 2, &DispersionOptions::default()).is_err());
    assert!(dispersion(&[0.1], 0, &DispersionOptions::default()).is_err());
}

#[test]
fn past_the_search_limits_the_bracket_is_the_widest_empty_slab_and_one() {
    // 3 points in d = 40: the widest gap of any coordinate bounds the dispersion from below.
    let d = 40;
    let mut pts = vec![0.5; 3 * d];
    pts[7] = 0.1; // point 0, axis 7: gaps 0.1, 0.4, 0.5 on axis 7 ...
    pts[d + 7] = 0.2;
    pts[2 * d + 7] = 0.9; // ... axis 7 has gaps 0.1, 0.1, 0.7, 0.1: the widest, 0.7
    let r = dispersion(&pts, d, &DispersionOptions::default()).unwrap();
    assert!((r.lower - 0.7).abs() < 1e-12, "{r:?}");
    assert_eq!(r.upper, 1.0);
    assert!(!r.exact);
    assert!(r.method.contains("search limits"), "{}", r.method);
    // The witness is empty and has the reported volume.
    assert!((r.witness.volume() - 0.7).abs() < 1e-12);
    // In d = 8 with many points, the cost rule picks the same fallback.
    let many: Vec<f64> = (0..8 * 10_000)
        .map(|i| ((i * 7919) % 10_007) as f64 / 10_007.0)
        .collect();
    let r = dispersion(&many, 8, &DispersionOptions::default()).unwrap();
    assert!(
        r.method.contains("search limits") && r.upper == 1.0,
        "{}",
        r.method
    );
}

/// The exact sweep tells its progress, up to its whole work, and gives what it gives without
/// it.
#[test]
fn the_exact_sweep_reports_its_progress_to_the_end() {
    let pts = crate::Halton::new(&crate::ParamSpace::unit_cube(3)).unit_points(0, 300);
    let seen = std::sync::Mutex::new(Vec::new());
    let with = dispersion_with_progress(&pts, 3, &DispersionOptions::default(), &|done, total| {
        seen.lock().unwrap().push((done, total));
    })
    .unwrap();
    let without = dispersion(&pts, 3, &DispersionOptions::default()).unwrap();
    assert_eq!(with.lower, without.lower);
    let seen = seen.into_inner().unwrap();
    // Two sides of the supporting points (those strictly inside the cube: Halton's first is
    // the origin), each reported once, from 0 to the total.
    let inside = pts
        .chunks_exact(3)
        .filter(|p| p.iter().all(|&x| 0.0 < x && x < 1.0))
        .count() as u64;
    assert_eq!(inside, 299);
    assert!(seen.iter().all(|&(_, t)| t == 2 * inside), "{seen:?}");
    assert_eq!(seen.iter().map(|s| s.0).max(), Some(2 * inside));
    assert_eq!(seen.len() as u64, 2 * inside + 1);
}
