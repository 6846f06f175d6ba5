//! What each open parameter of any front end changes: the scene of the space's first point
//! (every level index 0, every interval at its low end) against the scenes of the parameter's
//! other values, one parameter moved at a time.

use paracosm_generators::{ParamSpace, Point};

use super::compare::{scene_changes, Change};
use crate::front_end::FrontEnd;
use crate::scene::Scene;

/// How many other values of one parameter are probed at most, spread over its levels (a
/// parameter with thousands of levels would cost a scene each).
pub const MAX_PROBED_VALUES: usize = 8;

/// How many scenes one probe builds at most, over all parameters: the parameters past it
/// count as used (a file with many varied parameters on a large map loads in bounded time).
pub const MAX_PROBED_SCENES: usize = 96;

/// Where inside an interval a value is probed besides its ends, as a fraction of it (the
/// golden ratio's: not a round number).
const INTERIOR_FRACTION: f64 = 0.618_033_988_749_894_8;

/// The highest coordinate probed in `[0, 1)`: an interval's high end, as near as decoding
/// allows.
const HIGH_END: f64 = 1.0 - 1.0 / 1024.0;

/// What [`probe`] found.
pub struct Probed {
    /// The scene of the space's first point: the base every value is compared with.
    pub base: Scene,
    /// Per parameter of the space, in its order, what its other values changed.
    pub changes: Vec<Vec<Change>>,
    /// Per parameter, whether it was probed (`false` past [`MAX_PROBED_SCENES`]: count it as
    /// used).
    pub probed: Vec<bool>,
}

/// The other coordinates of parameter `k` to probe: up to [`MAX_PROBED_VALUES`] level
/// indices spread over its levels, or an interval's interior point and high end.
fn other_values(levels: Option<u32>) -> Vec<ProbedValue> {
    match levels {
        None => vec![
            ProbedValue::Continuous(INTERIOR_FRACTION),
            ProbedValue::Continuous(HIGH_END),
        ],
        Some(n) => {
            let others = n.saturating_sub(1) as usize;
            let picked = others.min(MAX_PROBED_VALUES);
            (0..picked)
                .map(|j| {
                    // Level 1 first and the last level last, evenly between.
                    let i = if picked <= 1 {
                        1
                    } else {
                        1 + j * (others - 1) / (picked - 1)
                    };
                    ProbedValue::Level(i as u32)
                })
                .collect()
        }
    }
}

/// One coordinate's value in a probe.
#[derive(Debug, Clone, Copy)]
enum ProbedValue {
    Level(u32),
    Continuous(f64),
}

/// The scene `front_end` builds for `point` of `space`; `None` when the values do not decode
/// or build a scene (a value the file's constraints refuse, a road that cannot be built).
fn scene_at(front_end: &dyn FrontEnd, space: &ParamSpace, point: &Point) -> Option<Scene> {
    let assignment = space.decode(point).ok()?;
    let mut scene = None;
    front_end
        .with_scene(Some(&assignment), &mut |s, _| scene = Some(s.clone()))
        .ok()?;
    scene
}

/// What each parameter of `front_end`'s space changes in its scenes, whose tests last
/// `horizon_s`: for a front end whose code reads nothing a scene does not show (an
/// OpenSCENARIO file, whose storyboard's inputs its scene keeps; a Rust function). A
/// parameter's probe stops at the first change that is not [`super::inert`]. A value
/// whose scene cannot be built counts as a change ([`Change::Other`]), and so does one whose
/// scene has no world. `None` when the space's first point builds no scene: nothing can be
/// compared with it, so every parameter counts as used.
pub fn probe(front_end: &dyn FrontEnd, horizon_s: f64) -> Option<Probed> {
    let space = front_end.space();
    let layout = space.layout();
    let first = Point {
        discrete: vec![0; layout.iter().filter(|l| l.is_some()).count()],
        continuous: vec![0.0; layout.iter().filter(|l| l.is_none()).count()],
    };
    let base = scene_at(front_end, space, &first)?;
    let mut built = 0usize;
    let mut changes = Vec::with_capacity(layout.len());
    let mut probed = Vec::with_capacity(layout.len());
    let (mut di, mut ci) = (0usize, 0usize);
    for &levels in &layout {
        let values = other_values(levels);
        if built + values.len() > MAX_PROBED_SCENES {
            changes.push(Vec::new());
            probed.push(false);
        } else {
            let mut seen = Vec::new();
            for v in values {
                let mut point = first.clone();
                match v {
                    ProbedValue::Level(i) => point.discrete[di] = i,
                    ProbedValue::Continuous(u) => point.continuous[ci] = u,
                }
                built += 1;
                match scene_at(front_end, space, &point)
                    .map(|other| scene_changes(&base, &other, horizon_s))
                {
                    Some(Ok(found)) => seen.extend(found),
                    _ => seen.push(Change::Other),
                }
                // A change the ego can feel settles it: the parameter is used, and its other
                // values would only add scenes to build.
                if seen.iter().any(|c| !super::inert(c, false)) {
                    break;
                }
            }
            changes.push(seen);
            probed.push(true);
        }
        match levels {
            Some(_) => di += 1,
            None => ci += 1,
        }
    }
    Some(Probed {
        base,
        changes,
        probed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_levels_probed_spread_from_the_second_to_the_last() {
        let levels = |n| -> Vec<u32> {
            other_values(Some(n))
                .into_iter()
                .map(|v| match v {
                    ProbedValue::Level(i) => i,
                    ProbedValue::Continuous(_) => unreachable!(),
                })
                .collect()
        };
        assert_eq!(levels(1), Vec::<u32>::new());
        assert_eq!(levels(2), vec![1]);
        assert_eq!(levels(4), vec![1, 2, 3]);
        let many = levels(1000);
        assert_eq!(many.len(), MAX_PROBED_VALUES);
        assert_eq!((many[0], many[MAX_PROBED_VALUES - 1]), (1, 999));
    }
}
