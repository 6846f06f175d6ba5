//! The coverage science the paper states, measured: Proposition 3.2's bound against the
//! empirical cover time of random k-wise families, and dispersion and star discrepancy against
//! `n` for random, Halton and Sobol points with slopes fitted against theory (§3.1–3.2).

use std::path::{Path, PathBuf};

use paracosm::report::plot::{xy_plot, Series, XyStyle};
use paracosm_generators::coverage::{dispersion, star_discrepancy, DispersionOptions, StarOptions};
use paracosm_generators::covering::{random_kwise_rows, random_until_covered};
use paracosm_generators::{Halton, ParamSpace, Sobol};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Result;

/// A covering model: level counts and strength `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Levels of each parameter.
    pub levels: Vec<u32>,
    /// Strength `t`.
    pub t: usize,
}

impl Model {
    /// `2^N, t = 2` style name: `N×v` for equal levels, the list otherwise.
    pub fn name(&self) -> String {
        let first = self.levels[0];
        let levels = if self.levels.iter().all(|&v| v == first) {
            format!("{first}^{}", self.levels.len())
        } else {
            format!("{:?}", self.levels)
        };
        format!("{levels}, t = {}", self.t)
    }
}

/// The twelve models of the Proposition 3.2 study: binary with 4 to 64 parameters at `t = 2`
/// and 8 to 32 at `t = 3` (Proposition 3.2 proper), and four mixed-level models (its union
/// bound form).
pub fn prop32_models() -> Vec<Model> {
    let mut m: Vec<Model> = [4usize, 8, 16, 32, 64]
        .iter()
        .map(|&n| Model {
            levels: vec![2; n],
            t: 2,
        })
        .collect();
    m.extend([8usize, 16, 32].iter().map(|&n| Model {
        levels: vec![2; n],
        t: 3,
    }));
    m.push(Model {
        levels: vec![3; 6],
        t: 2,
    });
    m.push(Model {
        levels: vec![2, 3, 4, 5, 6, 7],
        t: 2,
    });
    m.push(Model {
        levels: vec![4; 8],
        t: 2,
    });
    m.push(Model {
        levels: vec![3; 5],
        t: 3,
    });
    m
}

/// One row of the Proposition 3.2 table.
#[derive(Debug, Clone, PartialEq)]
pub struct Prop32Row {
    /// The model's name.
    pub model: String,
    /// Failure probability `δ`.
    pub delta: f64,
    /// The bound's rows `m(δ)` (Proposition 3.2, or its union-bound form for mixed levels).
    pub bound: u64,
    /// Empirical `(1 − δ)`-quantile of the cover time, rows.
    pub quantile: f64,
    /// Share of seeds whose cover time exceeded the bound (the bound promises `<= δ`).
    pub miss_rate: f64,
    /// Seeds.
    pub seeds: u64,
}

/// The `q`-quantile of sorted `v` (linear interpolation, as numpy's default).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * q;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// Cover times (rows of uniformly random rows until every t-tuple is covered) of `model` for
/// seeds `0..seeds`, sorted.
///
/// # Errors
/// When the covering code refuses the model.
pub fn cover_times(model: &Model, seeds: u64) -> Result<Vec<f64>> {
    let mut v = Vec::with_capacity(seeds as usize);
    for s in 0..seeds {
        let a = random_until_covered(&model.levels, model.t, s, 1 << 20)
            .map_err(|e| paracosm::Error::Internal(e.to_string()))?;
        v.push(a.len() as f64);
    }
    v.sort_by(f64::total_cmp);
    Ok(v)
}

/// The Proposition 3.2 study: for every model and `δ` in `deltas`, the bound against the
/// empirical cover time over `seeds` seeds; an empirical CDF plot of `T / m(δ_min)` per model
/// into `out` (`prop32_cdf.png` and `.svg`).
///
/// # Errors
/// When a model is refused or a plot cannot be written.
pub fn prop32_study(
    models: &[Model],
    deltas: &[f64],
    seeds: u64,
    out: &Path,
) -> Result<(Vec<Prop32Row>, Vec<PathBuf>)> {
    let mut rows = Vec::new();
    let mut series: Vec<Series> = Vec::new();
    let dmin = deltas.iter().copied().fold(1.0, f64::min);
    for model in models {
        let times = cover_times(model, seeds)?;
        for &delta in deltas {
            let bound = random_kwise_rows(&model.levels, model.t, delta)
                .map_err(|e| paracosm::Error::Internal(e.to_string()))?
                .rows;
            let misses = times.iter().filter(|&&t| t > bound as f64).count();
            rows.push(Prop32Row {
                model: model.name(),
                delta,
                bound,
                quantile: quantile(&times, 1.0 - delta),
                miss_rate: misses as f64 / seeds as f64,
                seeds,
            });
        }
        let m = random_kwise_rows(&model.levels, model.t, dmin)
            .map_err(|e| paracosm::Error::Internal(e.to_string()))?
            .rows as f64;
        let n = times.len() as f64;
        series.push((
            model.name(),
            times
                .iter()
                .enumerate()
                .map(|(i, t)| (t / m, (i + 1) as f64 / n))
                .collect(),
        ));
    }
    std::fs::create_dir_all(out).map_err(|e| paracosm::Error::Internal(e.to_string()))?;
    let plots = xy_plot(
        &out.join("prop32_cdf"),
        (
            &format!(
                "Random k-wise cover time over its Proposition 3.2 bound m(δ = {dmin}), {seeds} seeds"
            ),
            "cover time / m(δ)",
            "share of seeds covered",
        ),
        ((0.0, 1.2), (0.0, 1.0)),
        &series,
        XyStyle::Lines,
    )
    .map_err(|e| paracosm::Error::Internal(e.to_string()))?;
    Ok((rows, plots.to_vec()))
}

/// A point sampler of the dispersion study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampler {
    /// Uniform random points (ChaCha8, seed given).
    Random(u64),
    /// The Halton sequence from index 0.
    Halton,
    /// Owen-scrambled Sobol points, seed 0.
    Sobol,
    /// The continuous half of a (2, ε)-covering suite (PARACOSM §3.2, `--strategy ipog`) over
    /// [`SUITE_LEVELS`] and `d` continuous parameters: one Halton block per row of the IPOG
    /// array ([`suite_blocks`]); measured as the paper's condition 2 asks, by the worst row's
    /// block.
    Suite,
}

/// The discrete parameters of [`Sampler::Suite`]: four with three levels each (paracosm's
/// strength-2 IPOG array has 11 rows for them; the smallest possible has 9).
pub const SUITE_LEVELS: [u32; 4] = [3, 3, 3, 3];

/// The continuous points of each row of a strength-2 IPOG (k, ε)-covering suite over
/// [`SUITE_LEVELS`] and `d` unit intervals with `⌊n / rows⌋` points per row (at least 1), as
/// `paracosm-fuzz --strategy ipog` makes them: one `m × d` row-major block per array row.
///
/// # Errors
/// When the space or the array cannot be built (never for these levels).
pub fn suite_blocks(n: usize, d: usize) -> Result<Vec<Vec<f64>>> {
    use paracosm_generators::covering::{ArrayKind, CoveringSuite};
    use paracosm_generators::{Param, Value};
    let internal = |e: String| paracosm::Error::Internal(e);
    let mut params: Vec<Param> = SUITE_LEVELS
        .iter()
        .enumerate()
        .map(|(k, &l)| {
            Param::levels(
                &format!("level{k}"),
                (0..i64::from(l)).map(Value::Int).collect(),
            )
        })
        .collect();
    params.extend((0..d).map(|k| Param::interval(&format!("x{k}"), 0.0, 1.0, "")));
    let space = ParamSpace::new(params).map_err(|e| internal(e.to_string()))?;
    let rows = CoveringSuite::new(&space, 2, ArrayKind::Ipog, 1, 0)
        .map_err(|e| internal(e.to_string()))?
        .rows();
    let per_row = (n / rows).max(1) as u64;
    let suite = CoveringSuite::new(&space, 2, ArrayKind::Ipog, per_row, 0)
        .map_err(|e| internal(e.to_string()))?;
    let mut blocks = vec![Vec::with_capacity(per_row as usize * d); rows];
    for j in 0..suite.len() {
        blocks[(j % rows as u64) as usize].extend(suite.point(j).continuous);
    }
    Ok(blocks)
}

impl Sampler {
    /// The first `n` points in `d` dimensions, `n × d` row-major (for [`Sampler::Suite`], its
    /// rows' blocks one after the other).
    ///
    /// # Errors
    /// Sobol past its capacity.
    pub fn points(self, n: usize, d: usize) -> Result<Vec<f64>> {
        let space = ParamSpace::unit_cube(d);
        Ok(match self {
            Sampler::Suite => suite_blocks(n, d)?.concat(),
            Sampler::Random(seed) => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                (0..n * d).map(|_| rng.random::<f64>()).collect()
            }
            Sampler::Halton => Halton::new(&space).unit_points(0, n),
            Sampler::Sobol => Sobol::new(&space, 0)
                .and_then(|s| s.unit_points(0, n))
                .map_err(|e| paracosm::Error::Internal(e.to_string()))?,
        })
    }

    /// `random`, `halton`, `sobol` or `suite`.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Random(_) => "random",
            Sampler::Halton => "halton",
            Sampler::Sobol => "sobol",
            Sampler::Suite => "suite",
        }
    }
}

/// One measurement of the dispersion study.
#[derive(Debug, Clone, PartialEq)]
pub struct Measure {
    /// `random`, `halton`, `sobol` or `suite`.
    pub sampler: &'static str,
    /// Dimension.
    pub d: usize,
    /// Points (for [`Sampler::Suite`], rows × points per row: at most the `n` asked for).
    pub n: usize,
    /// Dispersion bracket `[lower, upper]` (equal when exact).
    pub dispersion: (f64, f64),
    /// Star discrepancy bracket `[lower, upper]` (equal when exact).
    pub star: (f64, f64),
}

/// Dispersion and star discrepancy of `sampler`'s first `n` points in `d` dimensions (of a
/// suite's worst row block: brackets `[largest lower end, largest upper end]`), exact where
/// `dispersion_exact` and `star_exact` allow (as [`DispersionOptions::exact_max_points`] and
/// [`StarOptions::exact_max_points`]).
///
/// # Errors
/// As [`Sampler::points`].
pub fn measure(
    sampler: Sampler,
    d: usize,
    n: usize,
    dispersion_exact: &[usize],
    star_exact: [usize; 4],
) -> Result<Measure> {
    // A suite is measured by its worst row (PARACOSM §3.1's condition 2).
    let sets = match sampler {
        Sampler::Suite => suite_blocks(n, d)?,
        s => vec![s.points(n, d)?],
    };
    let internal =
        |e: paracosm_generators::coverage::CoverageError| paracosm::Error::Internal(e.to_string());
    let mut worst = Measure {
        sampler: sampler.name(),
        d,
        n: sets.iter().map(|s| s.len() / d).sum(),
        dispersion: (0.0, 0.0),
        star: (0.0, 0.0),
    };
    for pts in &sets {
        let disp = dispersion(
            pts,
            d,
            &DispersionOptions {
                exact_max_points: dispersion_exact.to_vec(),
                ..DispersionOptions::default()
            },
        )
        .map_err(internal)?;
        let star = star_discrepancy(
            pts,
            d,
            &StarOptions {
                exact_max_points: star_exact,
                ..StarOptions::default()
            },
        )
        .map_err(internal)?;
        worst.dispersion = (
            worst.dispersion.0.max(disp.lower),
            worst.dispersion.1.max(disp.upper),
        );
        worst.star = (worst.star.0.max(star.lower), worst.star.1.max(star.upper));
    }
    Ok(worst)
}

/// The least-squares slope of `ln y` against `ln x`.
pub fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

/// Log–log plot of one quantity against `n`, one series per sampler and dimension
/// (`log10` on both axes).
///
/// # Errors
/// When the plot cannot be written.
pub fn log_plot(
    stem: &Path,
    title: &str,
    y_label: &str,
    series: &[Series],
) -> Result<Vec<PathBuf>> {
    let logged: Vec<Series> = series
        .iter()
        .map(|(name, pts)| {
            (
                name.clone(),
                pts.iter().map(|(x, y)| (x.log10(), y.log10())).collect(),
            )
        })
        .collect();
    let (mut xl, mut xh, mut yl, mut yh) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (_, pts) in &logged {
        for &(x, y) in pts {
            xl = xl.min(x);
            xh = xh.max(x);
            yl = yl.min(y);
            yh = yh.max(y);
        }
    }
    let plots = xy_plot(
        stem,
        (title, "log10 n", y_label),
        ((xl - 0.1, xh + 0.1), (yl - 0.2, yh + 0.2)),
        &logged,
        XyStyle::Lines,
    )
    .map_err(|e| paracosm::Error::Internal(e.to_string()))?;
    Ok(plots.to_vec())
}
