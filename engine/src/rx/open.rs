use serde::{Deserialize, Serialize};

/// The values a test case gives an open input stream (paper §3.1 and §3.3).
///
/// A test case closes every open stream. A constant parameter gives one value for the whole
/// test; a time-varying one (`over_time=`) is described by a few coordinates of the parameter
/// space and evaluated at each step, so a 900-step fog profile costs 2–4 dimensions, not 900.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpenStream {
    /// The same value at every step.
    Constant(super::Value),
    /// `Piecewise(k)`: `values[j]` during `[j·T/k, (j+1)·T/k)` for horizon `T = horizon_s`; the
    /// last value holds after `T`. Stays inside the parameter's range.
    Piecewise {
        /// The `k` values, in the parameter's unit.
        values: Vec<f64>,
        /// The test's horizon, in seconds, `> 0`.
        horizon_s: f64,
    },
    /// `Polynomial(deg)`: the Bernstein polynomial `Σ_i c_i · C(deg,i) s^i (1-s)^(deg-i)`
    /// with `s = clamp(t / T, 0, 1)`. The Bernstein form keeps the value inside the range of
    /// its coefficients, so a coefficient box inside `[lo, hi]` keeps the stream in
    /// `[lo, hi]` at every step; the coefficients are the `deg + 1` sampled coordinates.
    Polynomial {
        /// The `deg + 1` Bernstein coefficients, in the parameter's unit.
        coefficients: Vec<f64>,
        /// The test's horizon, in seconds, `> 0`.
        horizon_s: f64,
    },
}

impl OpenStream {
    /// The value at time `t_s` (seconds since the start).
    pub fn at(&self, t_s: f64) -> super::Value {
        match self {
            OpenStream::Constant(v) => v.clone(),
            OpenStream::Piecewise { values, horizon_s } => {
                let k = values.len();
                let j = ((t_s / horizon_s * k as f64).floor().max(0.0) as usize).min(k - 1);
                super::Value::Num(values[j])
            }
            OpenStream::Polynomial {
                coefficients,
                horizon_s,
            } => {
                let s = (t_s / horizon_s).clamp(0.0, 1.0);
                super::Value::Num(bernstein(coefficients, s))
            }
        }
    }
}

/// `Σ_i c_i · C(n,i) s^i (1-s)^(n-i)` by de Casteljau's algorithm (stable, stays in the
/// coefficients' hull).
fn bernstein(c: &[f64], s: f64) -> f64 {
    let mut b = c.to_vec();
    for r in 1..b.len() {
        for i in 0..b.len() - r {
            b[i] = b[i] * (1.0 - s) + b[i + 1] * s;
        }
    }
    b[0]
}
