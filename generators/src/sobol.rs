use crate::{Generator, GeneratorError, ParamSpace, Point};

/// Points available from `sobol_burley`: indices `0..2^16`.
pub const SOBOL_MAX_POINTS: u64 = 1 << 16;
/// Dimensions available from `sobol_burley` (its `NUM_DIMENSIONS`).
pub const SOBOL_MAX_DIMENSIONS: usize = sobol_burley::NUM_DIMENSIONS as usize;

/// Owen-scrambled Sobol points (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020),
/// computed by the `sobol_burley` crate in `f32` and widened to `f64`, in `[0, 1)`.
///
/// Parameter `k` in declaration order is Sobol dimension `k`; a discrete parameter with `L`
/// levels takes level `floor(L · u)`. The scramble is seeded from the campaign seed (the low
/// and high 32-bit halves xor-ed). Limits: [`SOBOL_MAX_POINTS`] points and
/// [`SOBOL_MAX_DIMENSIONS`] dimensions; past them the generator returns
/// [`GeneratorError::CapacityExceeded`] instead of wrapping.
#[derive(Debug, Clone)]
pub struct Sobol {
    levels: Vec<Option<u32>>,
    seed: u32,
    next: u64,
}

impl Sobol {
    /// A Sobol generator over `space`.
    ///
    /// # Errors
    /// [`GeneratorError::CapacityExceeded`] if the space has more than
    /// [`SOBOL_MAX_DIMENSIONS`] parameters.
    pub fn new(space: &ParamSpace, seed: u64) -> Result<Self, GeneratorError> {
        let d = space.params().len();
        if d > SOBOL_MAX_DIMENSIONS {
            return Err(GeneratorError::CapacityExceeded {
                generator: "sobol",
                what: "dimensions",
                limit: SOBOL_MAX_DIMENSIONS as u64,
                requested: d as u64,
            });
        }
        Ok(Sobol {
            levels: space.layout(),
            seed: (seed as u32) ^ ((seed >> 32) as u32),
            next: 0,
        })
    }

    /// Point `j`, or `None` past [`SOBOL_MAX_POINTS`].
    pub fn point(&self, j: u64) -> Option<Point> {
        if j >= SOBOL_MAX_POINTS {
            return None;
        }
        let mut p = Point::default();
        for (dim, levels) in self.levels.iter().enumerate() {
            let u = f64::from(sobol_burley::sample(j as u32, dim as u32, self.seed));
            match levels {
                None => p.continuous.push(u),
                Some(l) => p.discrete.push(((u * *l as f64) as u32).min(l - 1)),
            }
        }
        Some(p)
    }
}

impl Sobol {
    /// Points `start..start + n` of the unit cube as an `n × d` row-major matrix in `[0, 1)`
    /// (`d` = every parameter of the space, level indices not applied): the layout of
    /// `scipy.stats.qmc.Sobol.random`. Computed in parallel, the same on any thread count.
    ///
    /// # Errors
    /// [`GeneratorError::CapacityExceeded`] when `start + n` passes [`SOBOL_MAX_POINTS`].
    pub fn unit_points(&self, start: u64, n: usize) -> Result<Vec<f64>, GeneratorError> {
        use rayon::prelude::*;
        let end = start.saturating_add(n as u64);
        if end > SOBOL_MAX_POINTS {
            return Err(GeneratorError::CapacityExceeded {
                generator: "sobol",
                what: "points",
                limit: SOBOL_MAX_POINTS,
                requested: end,
            });
        }
        let d = self.levels.len();
        let mut out = vec![0.0; n * d];
        if d == 0 {
            return Ok(out);
        }
        out.par_chunks_mut(d).enumerate().for_each(|(r, row)| {
            let j = (start + r as u64) as u32;
            for (dim, slot) in row.iter_mut().enumerate() {
                *slot = f64::from(sobol_burley::sample(j, dim as u32, self.seed));
            }
        });
        Ok(out)
    }
}

impl Generator for Sobol {
    fn name(&self) -> &'static str {
        "sobol"
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let end = self.next + n as u64;
        if end > SOBOL_MAX_POINTS {
            return Err(GeneratorError::CapacityExceeded {
                generator: "sobol",
                what: "points",
                limit: SOBOL_MAX_POINTS,
                requested: end,
            });
        }
        let pts = (self.next..end).filter_map(|j| self.point(j)).collect();
        self.next = end;
        Ok(pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn space(d: usize) -> ParamSpace {
        ParamSpace::unit_cube(d)
    }

    /// Value stability: pins the first rows for seed 0 in two dimensions.
    #[test]
    fn first_rows_are_pinned() {
        let pts = Sobol::new(&space(2), 0).unwrap().ask(4).unwrap();
        let got: Vec<Vec<f64>> = pts.into_iter().map(|p| p.continuous).collect();
        assert_eq!(got, PINNED.map(|r| r.to_vec()).to_vec());
    }

    const PINNED: [[f64; 2]; 4] = [
        [0.26215362548828125, 0.5368943214416504],
        [0.9713137149810791, 0.46059858798980713],
        [0.6825801134109497, 0.7782303094863892],
        [0.022617220878601074, 0.10112440586090088],
    ];

    #[test]
    fn unit_points_are_the_points_of_the_sequence() {
        let s = Sobol::new(&space(3), 9).unwrap();
        let m = s.unit_points(5, 20).unwrap();
        for r in 0..20 {
            assert_eq!(
                m[r * 3..r * 3 + 3],
                s.point(5 + r as u64).unwrap().continuous[..]
            );
        }
        assert!(s.unit_points(SOBOL_MAX_POINTS - 2, 3).is_err());
        assert_eq!(s.unit_points(SOBOL_MAX_POINTS - 2, 2).unwrap().len(), 6);
    }

    #[test]
    fn more_than_two_to_the_sixteen_points_is_an_error_not_a_wrap() {
        let mut s = Sobol::new(&space(2), 1).unwrap();
        assert_eq!(s.ask(65_000).unwrap().len(), 65_000);
        let err = s.ask(1_000).unwrap_err();
        assert_eq!(
            err.to_string(),
            "sobol supports at most 65536 points, but 66000 were requested"
        );
        // The last 536 points are still there after the refused request.
        assert_eq!(s.ask(536).unwrap().len(), 536);
    }

    #[test]
    fn more_than_256_dimensions_is_an_error() {
        let err = Sobol::new(&space(257), 0).unwrap_err();
        assert!(matches!(
            err,
            GeneratorError::CapacityExceeded {
                what: "dimensions",
                ..
            }
        ));
        assert!(Sobol::new(&space(256), 0).is_ok());
    }

    #[test]
    fn one_dimension_of_a_power_of_two_prefix_is_stratified() {
        // Owen scrambling keeps the (0, m, 1)-net property: 2^k points hit each of 2^k strata once.
        let pts = Sobol::new(&space(1), 9).unwrap().ask(64).unwrap();
        let mut seen = [false; 64];
        for p in pts {
            seen[(p.continuous[0] * 64.0) as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
