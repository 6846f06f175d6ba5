//! Time to collision of the ego vehicle with the actors in its path.

/// An actor as the time-to-collision test sees it: a box on the ground moving in a straight
/// line at constant velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mover {
    /// Centre on the ground `[x, z]`, metres.
    pub pos_m: [f64; 2],
    /// Velocity `[x, z]`, m/s.
    pub velocity_mps: [f64; 2],
    /// Heading in rad (the engine's convention: counter-clockwise from above, `0` along `+x`).
    pub heading_rad: f64,
    /// Half length along the heading and half width across it, metres.
    pub half_size_m: [f64; 2],
}

/// Unit vector along `heading` in `[x, z]` (counter-clockwise from above: `z` decreases for
/// positive headings).
fn forward(heading_rad: f64) -> [f64; 2] {
    [heading_rad.cos(), -heading_rad.sin()]
}

/// Path time to collision, in seconds: the smallest `gap / closing speed` over the `others`
/// whose box overlaps the ego's path (the ego's width, straight ahead) and who come closer
/// along it. `gap` is the distance between the boxes along the ego's heading; `0` when they
/// already overlap. `+inf` when nothing in the path is closing in.
///
/// This is the classic constant-velocity TTC of car following (Hayward 1972, "Near-miss
/// determination through use of a scale of danger"), restricted to the ego's straight path:
/// an actor about to cross the path does not count until it is in it.
pub fn time_to_collision_s(ego: &Mover, others: &[Mover]) -> f64 {
    let f = forward(ego.heading_rad);
    let right = [-f[1], f[0]];
    let along = |v: [f64; 2]| v[0] * f[0] + v[1] * f[1];
    let across = |v: [f64; 2]| v[0] * right[0] + v[1] * right[1];
    let ego_speed = along(ego.velocity_mps);
    others
        .iter()
        .filter_map(|o| {
            let rel = [o.pos_m[0] - ego.pos_m[0], o.pos_m[1] - ego.pos_m[1]];
            // The other box's half extents along and across the ego's heading.
            let d = o.heading_rad - ego.heading_rad;
            let [l, w] = o.half_size_m;
            let half_along = (d.cos() * l).abs() + (d.sin() * w).abs();
            let half_across = (d.sin() * l).abs() + (d.cos() * w).abs();
            if along(rel) <= 0.0 || across(rel).abs() > ego.half_size_m[1] + half_across {
                return None;
            }
            let gap = along(rel) - ego.half_size_m[0] - half_along;
            let closing = ego_speed - along(o.velocity_mps);
            if gap <= 0.0 {
                Some(0.0)
            } else if closing > 0.0 {
                Some(gap / closing)
            } else {
                None
            }
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn car(x: f64, z: f64, vx: f64, heading: f64) -> Mover {
        Mover {
            pos_m: [x, z],
            velocity_mps: [vx, 0.0],
            heading_rad: heading,
            half_size_m: [2.25, 0.9],
        }
    }

    #[test]
    fn following_a_slower_car_is_gap_over_closing_speed() {
        let ego = car(0.0, 0.0, 12.0, 0.0);
        // 20 m centre to centre, 4.5 m of car lengths: 15.5 m gap closing at 4 m/s.
        let ttc = time_to_collision_s(&ego, &[car(20.0, 0.0, 8.0, 0.0)]);
        assert!((ttc - 15.5 / 4.0).abs() < 1e-12);
        // A faster lead, a car behind, and a car in the next lane do not count.
        let others = [
            car(20.0, 0.0, 14.0, 0.0),
            car(-20.0, 0.0, 0.0, 0.0),
            car(20.0, 3.5, 0.0, 0.0),
        ];
        assert_eq!(time_to_collision_s(&ego, &others), f64::INFINITY);
    }

    #[test]
    fn a_crossing_pedestrian_counts_once_in_the_path_and_overlap_is_zero() {
        let ego = car(0.0, 0.0, 10.0, 0.0);
        let ped = |z: f64| Mover {
            pos_m: [12.25, z],
            velocity_mps: [0.0, -1.5],
            heading_rad: std::f64::consts::FRAC_PI_2,
            half_size_m: [0.3, 0.3],
        };
        assert_eq!(time_to_collision_s(&ego, &[ped(3.0)]), f64::INFINITY);
        assert!((time_to_collision_s(&ego, &[ped(0.5)]) - 0.97).abs() < 1e-12);
        assert_eq!(time_to_collision_s(&ego, &[car(4.0, 0.0, 0.0, 0.0)]), 0.0);
    }

    #[test]
    fn heading_follows_the_engine_convention() {
        // Heading +90°: forward is -z. A stopped car 20 m toward -z is ahead.
        let h = std::f64::consts::FRAC_PI_2;
        let ego = Mover {
            velocity_mps: [0.0, -10.0],
            ..car(0.0, 0.0, 0.0, h)
        };
        let ttc = time_to_collision_s(&ego, &[car(0.0, -20.0, 0.0, h)]);
        assert!((ttc - 1.55).abs() < 1e-12, "{ttc}");
    }
}
