use super::*;

/// The inverse of a 3 × 3 matrix by its adjugate (independent of faer).
fn inverse3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |r: usize, s: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (s1, s2) = ((s + 1) % 3, (s + 2) % 3);
        m[r1][s1] * m[r2][s2] - m[r1][s2] * m[r2][s1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let mut inv = [[0.0; 3]; 3];
    for (r, row) in inv.iter_mut().enumerate() {
        for (s, v) in row.iter_mut().enumerate() {
            *v = c(s, r) / det;
        }
    }
    inv
}

/// A 3-point posterior worked out from the formulas: `μ* = ȳ + s k*ᵀ K⁻¹ (y − ȳ)/s` and
/// `σ*² = s² (σ_f² − k*ᵀ K⁻¹ k*)`, with the kernel written out by hand.
#[test]
fn a_three_point_posterior_matches_the_formulas() {
    let x = [0.0, 0.4, 1.0];
    let y = [1.0, 3.0, 2.0];
    let (ell, sf2, sn2) = (0.5f64, 1.3f64, 0.01f64);
    let k = |a: f64, b: f64| {
        let r = (a - b).abs() / ell;
        sf2 * (1.0 + 5f64.sqrt() * r + 5.0 * r * r / 3.0) * (-(5f64.sqrt()) * r).exp()
    };
    let mut km = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            km[i][j] = k(x[i], x[j]) + if i == j { sn2 } else { 0.0 };
        }
    }
    let inv = inverse3(km);
    let mean = 2.0;
    let s = (2.0f64 / 3.0).sqrt();
    let ys: Vec<f64> = y.iter().map(|v| (v - mean) / s).collect();
    let hyper = Hyper {
        log_length: vec![ell.ln()],
        log_signal: sf2.ln(),
        log_noise: sn2.ln(),
    };
    let gp = Gp::fit(&x, 1, &y, &hyper).unwrap();
    for xs in [0.2, 0.7, 1.3] {
        let ks: Vec<f64> = x.iter().map(|xi| k(xs, *xi)).collect();
        let mut mu = 0.0;
        let mut quad = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                mu += ks[i] * inv[i][j] * ys[j];
                quad += ks[i] * inv[i][j] * ks[j];
            }
        }
        let (m, v) = gp.predict(&[xs]);
        assert!((m - (mean + s * mu)).abs() < 1e-12, "{xs}: {m}");
        assert!((v - s * s * (sf2 - quad)).abs() < 1e-12, "{xs}: {v}");
        // The gradient form agrees with the plain one and with finite differences.
        let (m2, sd, dm, dsd) = gp.predict_with_gradient(&[xs]);
        assert!((m2 - m).abs() < 1e-12 && (sd * sd - v).abs() < 1e-12);
        let h = 1e-6;
        let (mp, vp) = gp.predict(&[xs + h]);
        let (mm, vm) = gp.predict(&[xs - h]);
        assert!((dm[0] - (mp - mm) / (2.0 * h)).abs() < 1e-5, "{xs}");
        assert!(
            (dsd[0] - (vp.sqrt() - vm.sqrt()) / (2.0 * h)).abs() < 1e-5,
            "{xs}"
        );
    }
}

fn reference() -> serde_json::Value {
    serde_json::from_str(include_str!("../../../tests/data/gp_sklearn.json")).unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Posterior means and standard deviations, the log marginal likelihood and its gradient
/// against scikit-learn 1.9.1 on the same data (experiments/bench/gp_reference.py wrote
/// the reference): within 1e-6.
#[test]
fn matches_scikit_learn() {
    let r = reference();
    let x: Vec<f64> = r["x"].as_array().unwrap().iter().flat_map(floats).collect();
    let y = floats(&r["y"]);
    let queries: Vec<Vec<f64>> = r["queries"]
        .as_array()
        .unwrap()
        .iter()
        .map(floats)
        .collect();
    for case in r["fixed"].as_array().unwrap() {
        let h = &case["hyper"];
        let hyper = Hyper {
            log_length: floats(&h["length"]).iter().map(|v| v.ln()).collect(),
            log_signal: h["signal"].as_f64().unwrap().ln(),
            log_noise: h["noise"].as_f64().unwrap().ln(),
        };
        let gp = Gp::fit(&x, 2, &y, &hyper).unwrap();
        assert_eq!(gp.jitter(), 0.0);
        let noise = h["noise"].as_f64().unwrap() * {
            let (_, s) = standardisation(&y);
            s * s
        };
        for (q, (m, sd)) in queries.iter().zip(
            floats(&case["mean"])
                .into_iter()
                .zip(floats(&case["std_with_noise"])),
        ) {
            let (mu, var) = gp.predict(q);
            assert!((mu - m).abs() < 1e-6, "mean at {q:?}: {mu} against {m}");
            assert!(
                ((var + noise).sqrt() - sd).abs() < 1e-6,
                "sd at {q:?}: {} against {sd}",
                (var + noise).sqrt()
            );
        }
        let (lml, grad) = log_marginal_likelihood(&x, 2, &y, &hyper).unwrap();
        assert!((lml - case["lml"].as_f64().unwrap()).abs() < 1e-6, "{lml}");
        for (g, e) in grad.iter().zip(floats(&case["lml_gradient"])) {
            assert!((g - e).abs() < 1e-6, "gradient {grad:?} against {e}");
        }
    }
    // Maximising the same likelihood within the same bounds gets at least as high as
    // scikit-learn's L-BFGS-B with 8 restarts.
    let starts = [
        Hyper {
            log_length: vec![0.5f64.ln(); 2],
            log_signal: 0.0,
            log_noise: 1e-3f64.ln(),
        },
        Hyper {
            log_length: vec![0.1f64.ln(), 2f64.ln()],
            log_signal: 1.0,
            log_noise: 1e-5f64.ln(),
        },
    ];
    let best = fit_hyper(&x, 2, &y, &starts, &HyperBounds::default(), 200).unwrap();
    let (lml, _) = log_marginal_likelihood(&x, 2, &y, &best).unwrap();
    let theirs = r["optimised"]["lml"].as_f64().unwrap();
    assert!(
        lml >= theirs - 1e-6,
        "{lml} against scikit-learn's {theirs}: {best:?}"
    );
}

#[test]
fn bad_data_is_an_error_not_a_panic() {
    let h = Hyper {
        log_length: vec![0.0],
        log_signal: 0.0,
        log_noise: -5.0,
    };
    assert!(Gp::fit(&[], 1, &[], &h).is_err());
    assert!(Gp::fit(&[0.1, 0.2], 1, &[1.0], &h).is_err());
    assert!(Gp::fit(&[0.1], 1, &[f64::NAN], &h).is_err());
    // Repeated inputs with tiny noise still factor (jitter).
    let tiny = Hyper {
        log_noise: -40.0,
        ..h
    };
    let gp = Gp::fit(&[0.3, 0.3, 0.3], 1, &[1.0, 1.0, 1.0], &tiny).unwrap();
    assert!(gp.predict(&[0.3]).0.is_finite());
}
