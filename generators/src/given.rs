use crate::{Generator, GeneratorError, ParamSpace, Point};

/// The points of a list, in its order: tests chosen outside paracosm (a CSV file given to
/// `paracosm-fuzz --points`, an array from Python) run as a campaign like any other strategy.
///
/// Every point is checked against the space when the generator is made, so a campaign never
/// starts on a point it cannot decode.
#[derive(Debug, Clone)]
pub struct GivenPoints {
    points: Vec<Point>,
    next: usize,
}

impl GivenPoints {
    /// A generator of `points` over `space`.
    ///
    /// # Errors
    /// [`GeneratorError::PointMismatch`] naming the first point (0-based) that does not fit
    /// the space: a wrong number of coordinates, a coordinate outside `[0, 1)` or NaN, a level
    /// index out of range.
    pub fn new(space: &ParamSpace, points: Vec<Point>) -> Result<Self, GeneratorError> {
        for (i, p) in points.iter().enumerate() {
            space.decode(p).map_err(|e| match e {
                GeneratorError::PointMismatch(why) => {
                    GeneratorError::PointMismatch(format!("point {i}: {why}"))
                }
                other => other,
            })?;
        }
        Ok(GivenPoints { points, next: 0 })
    }

    /// How many points the list holds.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the list is empty.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

impl Generator for GivenPoints {
    fn name(&self) -> &'static str {
        "points"
    }

    fn ask(&mut self, n: usize) -> Result<Vec<Point>, GeneratorError> {
        let end = self.next.saturating_add(n);
        if end > self.points.len() {
            return Err(GeneratorError::CapacityExceeded {
                generator: "points",
                what: "points",
                limit: self.points.len() as u64,
                requested: end as u64,
            });
        }
        let out = self.points[self.next..end].to_vec();
        self.next = end;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Param, Value};

    #[test]
    fn gives_the_points_in_order_and_refuses_more_or_misfits() {
        let space = ParamSpace::new(vec![
            Param::interval("a", 0.0, 10.0, "m"),
            Param::levels("b", vec![Value::Text("x".into()), Value::Text("y".into())]),
        ])
        .unwrap();
        let p = |u: f64, l: u32| Point {
            discrete: vec![l],
            continuous: vec![u],
        };
        let mut g = GivenPoints::new(&space, vec![p(0.1, 0), p(0.9, 1), p(0.5, 0)]).unwrap();
        assert_eq!(g.ask(2).unwrap(), vec![p(0.1, 0), p(0.9, 1)]);
        let err = g.ask(2).unwrap_err();
        assert!(err.to_string().contains("at most 3 points"), "{err}");
        assert_eq!(g.ask(1).unwrap(), vec![p(0.5, 0)]);
        let bad = GivenPoints::new(&space, vec![p(0.1, 0), p(0.2, 2)]).unwrap_err();
        assert!(bad.to_string().contains("point 1:"), "{bad}");
        let nan = GivenPoints::new(&space, vec![p(f64::NAN, 0)]).unwrap_err();
        assert!(nan.to_string().contains("point 0:"), "{nan}");
    }
}
