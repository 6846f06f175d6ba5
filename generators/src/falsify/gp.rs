//! Gaussian-process regression with a Matérn 5/2 kernel, for Bayesian optimisation.
//!
//! The model (Rasmussen and Williams, "Gaussian Processes for Machine Learning", MIT Press
//! 2006, ch. 2 and 5): `y = f(x) + ε` with `f ~ GP(0, k)`, `ε ~ N(0, σ_n²)`, on targets
//! standardised to mean 0 and (population) standard deviation 1, as scikit-learn's
//! `GaussianProcessRegressor(normalize_y=True)` does. The kernel is Matérn with `ν = 5/2` and one
//! length scale per input (ARD):
//!
//! `k(x, x') = σ_f² (1 + √5 r + 5 r² / 3) exp(−√5 r)`, `r² = Σ_i ((x_i − x'_i) / ℓ_i)²`
//!
//! (Rasmussen and Williams, eq. 4.17). The Cholesky factor and the solves are faer's. The
//! hyper-parameters `θ = (ln ℓ_1, …, ln ℓ_p, ln σ_f², ln σ_n²)` maximise the log marginal
//! likelihood (eq. 5.8) with its gradient (eq. 5.9), by argmin's L-BFGS from several starts
//! inside box bounds ([`fit_hyper`]).

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use faer::linalg::solvers::{DenseSolveCore, Llt, Solve};
use faer::{Mat, Side};

const SQRT5: f64 = 2.236_067_977_499_79;

/// Why a Gaussian process cannot be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpError {
    /// The inputs are not `n × p` with `n >= 1`, or a target or input is not finite.
    #[error("Gaussian process: {0}")]
    Shape(String),
    /// The covariance matrix is not positive definite even with jitter added.
    #[error("Gaussian process: the covariance matrix is not positive definite")]
    NotPositiveDefinite,
}

/// Hyper-parameters of the Matérn 5/2 process, on the log scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Hyper {
    /// `ln ℓ_i`, one per input dimension (length scales in input units).
    pub log_length: Vec<f64>,
    /// `ln σ_f²`, the signal variance of the standardised targets.
    pub log_signal: f64,
    /// `ln σ_n²`, the noise variance of the standardised targets.
    pub log_noise: f64,
}

impl Hyper {
    /// The parameters as one vector `(ln ℓ_1, …, ln ℓ_p, ln σ_f², ln σ_n²)`.
    pub fn to_vec(&self) -> Vec<f64> {
        let mut v = self.log_length.clone();
        v.push(self.log_signal);
        v.push(self.log_noise);
        v
    }

    /// The inverse of [`Hyper::to_vec`] (`v` has `p + 2` entries).
    pub fn from_slice(v: &[f64]) -> Self {
        let p = v.len() - 2;
        Hyper {
            log_length: v[..p].to_vec(),
            log_signal: v[p],
            log_noise: v[p + 1],
        }
    }
}

/// `k / σ_f²` and `(5/3)(1 + √5 r) exp(−√5 r)` (the factor of the derivatives) at `r²`.
fn matern52(r2: f64) -> (f64, f64) {
    let r = r2.sqrt();
    let e = (-SQRT5 * r).exp();
    (
        (1.0 + SQRT5 * r + 5.0 / 3.0 * r2) * e,
        5.0 / 3.0 * (1.0 + SQRT5 * r) * e,
    )
}

/// `Σ_i ((a_i − b_i) / ℓ_i)²`.
fn scaled_r2(a: &[f64], b: &[f64], inv_len: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .zip(inv_len)
        .map(|((x, y), l)| ((x - y) * l).powi(2))
        .sum()
}

/// A Gaussian process conditioned on data (see the module docs).
pub struct Gp {
    x: Vec<f64>,
    p: usize,
    hyper: Hyper,
    inv_len: Vec<f64>,
    signal: f64,
    y_mean: f64,
    y_std: f64,
    llt: Llt<f64>,
    /// `(K + σ_n² I)⁻¹ y` on the standardised targets.
    alpha: Vec<f64>,
    /// The jitter added to the diagonal beyond `σ_n²` (0 unless the factorisation needed it).
    jitter: f64,
}

/// `(mean, population standard deviation)` of `y`; a standard deviation of 0 becomes 1, as in
/// scikit-learn.
fn standardisation(y: &[f64]) -> (f64, f64) {
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    let std = var.sqrt();
    (mean, if std > 0.0 { std } else { 1.0 })
}

fn check(x: &[f64], p: usize, y: &[f64]) -> Result<usize, GpError> {
    if p == 0 || y.is_empty() || x.len() != y.len() * p {
        return Err(GpError::Shape(format!(
            "{} inputs of dimension {p} for {} targets",
            x.len(),
            y.len()
        )));
    }
    if !x.iter().chain(y).all(|v| v.is_finite()) {
        return Err(GpError::Shape("an input or a target is not finite".into()));
    }
    Ok(y.len())
}

/// `K + (σ_n² + jitter) I` for `x` (`n × p`).
fn covariance(x: &[f64], p: usize, h: &Hyper, jitter: f64) -> Mat<f64> {
    let n = x.len() / p;
    let inv_len: Vec<f64> = h.log_length.iter().map(|l| (-l).exp()).collect();
    let (sf, sn) = (h.log_signal.exp(), h.log_noise.exp());
    Mat::from_fn(n, n, |i, j| {
        let r2 = scaled_r2(&x[i * p..(i + 1) * p], &x[j * p..(j + 1) * p], &inv_len);
        sf * matern52(r2).0 + if i == j { sn + jitter } else { 0.0 }
    })
}

/// The Cholesky factor of `covariance(x, h, jitter)`, adding jitter `1e-10 σ_f²`, ten times
/// more each time, up to `1e-4 σ_f²`, when the matrix is not numerically positive definite.
fn factor(x: &[f64], p: usize, h: &Hyper) -> Result<(Llt<f64>, f64), GpError> {
    let mut jitter = 0.0;
    loop {
        if let Ok(l) = covariance(x, p, h, jitter).llt(Side::Lower) {
            return Ok((l, jitter));
        }
        jitter = if jitter == 0.0 {
            1e-10 * h.log_signal.exp()
        } else {
            jitter * 10.0
        };
        if jitter > 1e-4 * h.log_signal.exp() {
            return Err(GpError::NotPositiveDefinite);
        }
    }
}

fn solve(llt: &Llt<f64>, b: &[f64]) -> Vec<f64> {
    let rhs = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    let s = llt.solve(&rhs);
    (0..b.len()).map(|i| s[(i, 0)]).collect()
}

impl Gp {
    /// The process with hyper-parameters `hyper` conditioned on inputs `x` (`n × p`,
    /// row-major) and targets `y` (`n`).
    ///
    /// # Errors
    /// [`GpError::Shape`] for mismatched or non-finite data; [`GpError::NotPositiveDefinite`]
    /// when the covariance cannot be factored.
    pub fn fit(x: &[f64], p: usize, y: &[f64], hyper: &Hyper) -> Result<Self, GpError> {
        check(x, p, y)?;
        if hyper.log_length.len() != p {
            return Err(GpError::Shape(format!(
                "{} length scales for dimension {p}",
                hyper.log_length.len()
            )));
        }
        let (y_mean, y_std) = standardisation(y);
        let ys: Vec<f64> = y.iter().map(|v| (v - y_mean) / y_std).collect();
        let (llt, jitter) = factor(x, p, hyper)?;
        let alpha = solve(&llt, &ys);
        Ok(Gp {
            x: x.to_vec(),
            p,
            inv_len: hyper.log_length.iter().map(|l| (-l).exp()).collect(),
            signal: hyper.log_signal.exp(),
            hyper: hyper.clone(),
            y_mean,
            y_std,
            llt,
            alpha,
            jitter,
        })
    }

    /// The hyper-parameters.
    pub fn hyper(&self) -> &Hyper {
        &self.hyper
    }

    /// Jitter added to the covariance's diagonal beyond the noise (0 unless needed).
    pub fn jitter(&self) -> f64 {
        self.jitter
    }

    /// Training points.
    pub fn len(&self) -> usize {
        self.alpha.len()
    }

    /// Whether there is no training point (never: [`Gp::fit`] needs one).
    pub fn is_empty(&self) -> bool {
        self.alpha.is_empty()
    }

    /// `k(x*, x_i)` for every training point, on the standardised scale.
    fn cross(&self, xs: &[f64]) -> Vec<f64> {
        self.x
            .chunks_exact(self.p)
            .map(|xi| self.signal * matern52(scaled_r2(xs, xi, &self.inv_len)).0)
            .collect()
    }

    /// Posterior mean and variance of the latent `f(x*)` (without the noise), in the
    /// targets' units (variance: their square), at one input `xs` (`p` values).
    pub fn predict(&self, xs: &[f64]) -> (f64, f64) {
        let k = self.cross(xs);
        let mean: f64 = k.iter().zip(&self.alpha).map(|(a, b)| a * b).sum();
        let v = solve(&self.llt, &k);
        let var = (self.signal - k.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>()).max(0.0);
        (
            self.y_mean + self.y_std * mean,
            self.y_std * self.y_std * var,
        )
    }

    /// As [`Gp::predict`], with the gradients of the mean and of the standard deviation with
    /// respect to `xs`: `(mean, sd, d mean / dx, d sd / dx)`, in the targets' units.
    pub fn predict_with_gradient(&self, xs: &[f64]) -> (f64, f64, Vec<f64>, Vec<f64>) {
        let p = self.p;
        let n = self.len();
        let mut k = vec![0.0; n];
        // dk_i / dx_j = −σ_f² (5/3)(1 + √5 r) e^{−√5 r} (x_j − x_ij) / ℓ_j².
        let mut dk = vec![0.0; n * p];
        for (i, xi) in self.x.chunks_exact(p).enumerate() {
            let (kv, g) = matern52(scaled_r2(xs, xi, &self.inv_len));
            k[i] = self.signal * kv;
            for j in 0..p {
                dk[i * p + j] = -self.signal * g * (xs[j] - xi[j]) * self.inv_len[j].powi(2);
            }
        }
        let mean: f64 = k.iter().zip(&self.alpha).map(|(a, b)| a * b).sum();
        let v = solve(&self.llt, &k);
        let var = (self.signal - k.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>()).max(0.0);
        let sd = var.sqrt();
        let mut dmean = vec![0.0; p];
        let mut dvar = vec![0.0; p];
        for i in 0..n {
            for j in 0..p {
                dmean[j] += dk[i * p + j] * self.alpha[i];
                dvar[j] -= 2.0 * dk[i * p + j] * v[i];
            }
        }
        let dsd: Vec<f64> = dvar
            .iter()
            .map(|d| if sd > 1e-12 { d / (2.0 * sd) } else { 0.0 })
            .collect();
        (
            self.y_mean + self.y_std * mean,
            self.y_std * sd,
            dmean.iter().map(|d| self.y_std * d).collect(),
            dsd.iter().map(|d| self.y_std * d).collect(),
        )
    }
}

/// The log marginal likelihood of the standardised targets of `y` under `hyper` and its
/// gradient with respect to `(ln ℓ_1, …, ln ℓ_p, ln σ_f², ln σ_n²)` (Rasmussen and Williams,
/// eqs. 5.8 and 5.9): `−½ yᵀα − Σ ln L_ii − (n/2) ln 2π` and `½ tr((ααᵀ − K⁻¹) ∂K/∂θ_j)`.
///
/// # Errors
/// As [`Gp::fit`].
pub fn log_marginal_likelihood(
    x: &[f64],
    p: usize,
    y: &[f64],
    hyper: &Hyper,
) -> Result<(f64, Vec<f64>), GpError> {
    let n = check(x, p, y)?;
    let (y_mean, y_std) = standardisation(y);
    let ys: Vec<f64> = y.iter().map(|v| (v - y_mean) / y_std).collect();
    let (llt, _) = factor(x, p, hyper)?;
    let alpha = solve(&llt, &ys);
    let l = llt.L();
    let log_det_half: f64 = (0..n).map(|i| l[(i, i)].ln()).sum();
    let fit: f64 = ys.iter().zip(&alpha).map(|(a, b)| a * b).sum();
    let lml = -0.5 * fit - log_det_half - 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    let kinv = llt.inverse();
    let inv_len: Vec<f64> = hyper.log_length.iter().map(|v| (-v).exp()).collect();
    let (sf, sn) = (hyper.log_signal.exp(), hyper.log_noise.exp());
    let mut grad = vec![0.0; p + 2];
    for i in 0..n {
        for j in 0..n {
            // W = ααᵀ − K⁻¹, symmetric.
            let w = alpha[i] * alpha[j] - kinv[(i, j)];
            let (xi, xj) = (&x[i * p..(i + 1) * p], &x[j * p..(j + 1) * p]);
            let (kv, g) = matern52(scaled_r2(xi, xj, &inv_len));
            for d in 0..p {
                // ∂k/∂ ln ℓ_d = σ_f² (5/3)(1 + √5 r) e^{−√5 r} ((x_d − x'_d) / ℓ_d)².
                grad[d] += 0.5 * w * sf * g * ((xi[d] - xj[d]) * inv_len[d]).powi(2);
            }
            grad[p] += 0.5 * w * sf * kv;
            if i == j {
                grad[p + 1] += 0.5 * w * sn;
            }
        }
    }
    Ok((lml, grad))
}

/// Box bounds of the hyper-parameters, on the log scale (inputs in the unit cube, targets
/// standardised).
#[derive(Debug, Clone, PartialEq)]
pub struct HyperBounds {
    /// `[ln ℓ_min, ln ℓ_max]` for every length scale. Default `[ln 0.01, ln 10]`.
    pub log_length: (f64, f64),
    /// `[ln σ_f² min, max]`. Default `[ln 0.01, ln 100]`.
    pub log_signal: (f64, f64),
    /// `[ln σ_n² min, max]`. Default `[ln 1e-8, ln 1]`.
    pub log_noise: (f64, f64),
}

impl Default for HyperBounds {
    fn default() -> Self {
        HyperBounds {
            log_length: (0.01f64.ln(), 10f64.ln()),
            log_signal: (0.01f64.ln(), 100f64.ln()),
            log_noise: (1e-8f64.ln(), 0.0),
        }
    }
}

impl HyperBounds {
    fn range(&self, p: usize, i: usize) -> (f64, f64) {
        if i < p {
            self.log_length
        } else if i == p {
            self.log_signal
        } else {
            self.log_noise
        }
    }
}

/// The negative log marginal likelihood over unconstrained `u`, with each `θ_i = lo + (hi −
/// lo)(1 + sin u_i) / 2` inside its bound (a smooth map onto the box, so L-BFGS needs no
/// bounds of its own).
struct NegLml<'a> {
    x: &'a [f64],
    p: usize,
    y: &'a [f64],
    bounds: &'a HyperBounds,
}

impl NegLml<'_> {
    fn theta(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .enumerate()
            .map(|(i, v)| {
                let (lo, hi) = self.bounds.range(self.p, i);
                lo + (hi - lo) * (1.0 + v.sin()) / 2.0
            })
            .collect()
    }

    fn unconstrained(&self, theta: &[f64]) -> Vec<f64> {
        theta
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let (lo, hi) = self.bounds.range(self.p, i);
                (2.0 * (t - lo) / (hi - lo) - 1.0).clamp(-1.0, 1.0).asin()
            })
            .collect()
    }

    fn eval(&self, u: &[f64]) -> (f64, Vec<f64>) {
        let theta = self.theta(u);
        match log_marginal_likelihood(self.x, self.p, self.y, &Hyper::from_slice(&theta)) {
            Ok((lml, g)) => {
                let gu = g
                    .iter()
                    .zip(u)
                    .enumerate()
                    .map(|(i, (gi, ui))| {
                        let (lo, hi) = self.bounds.range(self.p, i);
                        -gi * (hi - lo) * ui.cos() / 2.0
                    })
                    .collect();
                (-lml, gu)
            }
            Err(_) => (f64::INFINITY, vec![0.0; u.len()]),
        }
    }
}

impl CostFunction for NegLml<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, argmin::core::Error> {
        Ok(self.eval(u).0)
    }
}

impl Gradient for NegLml<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Self::Param) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.eval(u).1)
    }
}

/// The hyper-parameters that maximise the log marginal likelihood of `y` at `x` (`n × p`)
/// within `bounds`: argmin's L-BFGS (memory 7, More–Thuente line search, at most `max_iters`
/// iterations) from each of `starts` (clamped into the bounds); the best end point, or the best
/// start if no run improves on it. Deterministic.
///
/// # Errors
/// As [`Gp::fit`] when no start can be evaluated.
pub fn fit_hyper(
    x: &[f64],
    p: usize,
    y: &[f64],
    starts: &[Hyper],
    bounds: &HyperBounds,
    max_iters: u64,
) -> Result<Hyper, GpError> {
    check(x, p, y)?;
    let problem = NegLml { x, p, y, bounds };
    let mut best: Option<(f64, Vec<f64>)> = None;
    for start in starts {
        let u0 = problem.unconstrained(&start.to_vec());
        let c0 = problem.eval(&u0).0;
        if c0.is_finite() && best.as_ref().is_none_or(|(c, _)| c0 < *c) {
            best = Some((c0, u0.clone()));
        }
        let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7);
        let run = Executor::new(NegLml { x, p, y, bounds }, solver)
            .configure(|s| s.param(u0).max_iters(max_iters))
            .run();
        if let Ok(r) = run {
            let state = r.state();
            if let Some(u) = state.best_param.clone() {
                let c = state.best_cost;
                if c.is_finite() && best.as_ref().is_none_or(|(bc, _)| c < *bc) {
                    best = Some((c, u));
                }
            }
        }
    }
    let (_, u) = best.ok_or(GpError::NotPositiveDefinite)?;
    Ok(Hyper::from_slice(&problem.theta(&u)))
}

#[cfg(test)]
mod tests;
