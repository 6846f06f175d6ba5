//! How far the valid region of a constrained space is from a test set: the largest empty
//! cube centred in it.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::CoverageError;
use crate::{Generator, ParamSpace, Point, UniformRandom};

/// Uniform random points of the space [`valid_gap`] draws; the valid ones are its probes.
pub const VALID_GAP_PROBES: usize = 8192;

/// The largest empty cube centred in the valid region that [`valid_gap`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidGap {
    /// The cube's half side in unit coordinates (the L∞ distance from its centre to the
    /// nearest test), in `[0, 1]`: a lower bound of the largest such cube, as the probes
    /// are a sample.
    pub radius: f64,
    /// Its centre, a valid probe's continuous coordinates in the unit cube (`d` values).
    pub centre: Vec<f64>,
    /// The valid probes measured.
    pub probes: u64,
}

/// The largest empty L∞ ball (a cube) of the continuous coordinates whose centre lies in the
/// valid region of `space` ([`ParamSpace::with_constraints`]) and no test of `points` lies
/// inside: the dispersion restricted to the valid region, as a ball rather than a box (the
/// largest empty box inside a region of any shape has no algorithm here). Estimated from
/// below: the centres tried are the valid ones of [`VALID_GAP_PROBES`] uniform random
/// points (ChaCha8, seed 0), each measured exactly against every test (`O(probes · n · d)`,
/// parallel with rayon, the same result for any thread count). `None` for a space without
/// continuous parameters or constraints.
///
/// # Errors
/// [`CoverageError::Shape`] for points that do not fit the space; [`CoverageError::Constraints`]
/// when a constraint cannot be evaluated.
pub fn valid_gap(space: &ParamSpace, points: &[Point]) -> Result<Option<ValidGap>, CoverageError> {
    let d = space.continuous_dims();
    if d == 0 || !space.is_constrained() {
        return Ok(None);
    }
    for (r, p) in points.iter().enumerate() {
        if p.continuous.len() != d {
            return Err(CoverageError::Shape(format!(
                "row {r} has {} continuous coordinates, the space has {d}",
                p.continuous.len()
            )));
        }
    }
    let plain = space.unconstrained();
    let mut draw = UniformRandom::new(&plain, 0);
    let candidates = draw
        .ask(VALID_GAP_PROBES)
        .map_err(|e| CoverageError::Constraints(e.to_string()))?;
    let probes: Vec<Point> = candidates
        .into_par_iter()
        .map(|p| space.is_valid(&p).map(|ok| ok.then_some(p)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| CoverageError::Constraints(e.to_string()))?
        .into_iter()
        .flatten()
        .collect();
    let best = probes
        .par_iter()
        .map(|q| {
            let r = points
                .iter()
                .map(|p| {
                    (p.continuous.iter().zip(&q.continuous))
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                })
                .fold(f64::INFINITY, f64::min);
            (r.min(1.0), q)
        })
        // Largest radius; ties to the first probe, whatever the threads.
        .reduce_with(|a, b| if b.0 > a.0 { b } else { a });
    Ok(best.map(|(radius, q)| ValidGap {
        radius,
        centre: q.continuous.clone(),
        probes: probes.len() as u64,
    }))
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::{Assignment, FnConstraint};

    #[test]
    fn tests_outside_the_valid_region_do_not_cover_it() {
        // Valid: x < 0.5. Tests crowded at x >= 0.5 leave the valid half empty.
        let s = ParamSpace::unit_cube(1).with_constraints(vec![Arc::new(FnConstraint::new(
            "left",
            |a: &Assignment| a.real("x0").unwrap() < 0.5,
        ))]);
        let right: Vec<Point> = (0..50)
            .map(|i| Point {
                discrete: vec![],
                continuous: vec![0.5 + i as f64 / 100.0],
            })
            .collect();
        let g = valid_gap(&s, &right).unwrap().unwrap();
        assert!(g.radius > 0.49 && g.centre[0] < 0.01, "{g:?}");
        // Tests spread over the valid half cover it to a hundredth.
        let left: Vec<Point> = (0..50)
            .map(|i| Point {
                discrete: vec![],
                continuous: vec![i as f64 / 100.0],
            })
            .collect();
        let g = valid_gap(&s, &left).unwrap().unwrap();
        assert!(g.radius <= 0.01, "{g:?}");
        assert!(g.probes > 3800 && g.probes < 4400);
    }
}
