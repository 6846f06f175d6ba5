//! The load's analyses of a scenario's open parameters, for every front end: which inputs
//! each parameter changes, found by building the scene of each of its other values and
//! comparing it with the scene of the representative values ([`compare`]; [`probe`] does it
//! for any [`crate::FrontEnd`], a program's load with its own budget). A parameter that
//! changes nothing and that no code reads is left out of coverage with a warning; one that
//! cannot affect the ego (a colour, the light, a friction where no vehicle goes) is named in a
//! warning or listed as camera-only (LANGUAGE.md, "Warnings").

mod compare;
mod probe;

use std::collections::BTreeSet;

pub use compare::{same_host_inputs, scene_changes, unread_streams, world_changes, Change};
pub use probe::{probe, Probed};

use crate::scenario::{CameraOnly, Warning};
use crate::scene::Scene;

/// What [`analyse`] needs.
pub struct Inputs<'a> {
    /// Each parameter's name and where it is declared (`file:line:col`), in the space's
    /// order.
    pub params: &'a [(String, String)],
    /// What each parameter's other values changed, by parameter.
    pub changes: &'a [Vec<Change>],
    /// Whether code of the scenario reads the parameter where no scene shows it (a program's
    /// lambda, `def` or expression reading its variable), by parameter: such a parameter is
    /// never called unused. A front end without code gives all `false`.
    pub read_in_code: &'a [bool],
    /// Whether an `Stl` formula reads the `light` signal.
    pub stl_reads_light: bool,
    /// The scene of the representative values (for the cars' and obstacles' names).
    pub scene: &'a Scene,
}

/// The findings: warnings, the parameters no object reads (by index), and those only a camera
/// sees.
pub struct Usage {
    /// Warnings, in parameter order.
    pub warnings: Vec<Warning>,
    /// Indices of the parameters that change nothing.
    pub unused: Vec<usize>,
    /// Parameters only a camera sees.
    pub camera_only: Vec<CameraOnly>,
}

/// Whether a change cannot affect the ego: a friction where no vehicle can be, or what only a
/// camera sees (a colour; the light, unless an `Stl` formula reads it).
pub fn inert(c: &Change, stl_reads_light: bool) -> bool {
    match c {
        Change::Friction { driven, .. } => !driven,
        Change::Colour(_) | Change::ObstacleColour(_) => true,
        Change::Light => !stl_reads_light,
        Change::Other => false,
    }
}

/// Classifies every parameter by what it changes.
pub fn analyse(i: Inputs<'_>) -> Usage {
    let mut usage = Usage {
        warnings: Vec::new(),
        unused: Vec::new(),
        camera_only: Vec::new(),
    };
    for (k, (name, site)) in i.params.iter().enumerate() {
        let changes = &i.changes[k];
        if i.read_in_code[k] {
            continue;
        }
        if changes.is_empty() {
            usage.unused.push(k);
            usage.warnings.push(Warning {
                at: site.clone(),
                message: format!(
                    "`{name}` is sampled but no object uses it: every value builds the same \
                     world, so coverage leaves it out (summary.json lists it under unused_params)"
                ),
            });
            continue;
        }
        let undriven = |c: &Change| matches!(c, Change::Friction { driven: false, .. });
        if changes.iter().all(undriven) {
            let pieces: BTreeSet<String> = changes
                .iter()
                .filter_map(|c| match c {
                    Change::Friction { piece, .. } => Some(piece.clone()),
                    _ => None,
                })
                .collect();
            usage.warnings.push(Warning {
                at: site.clone(),
                message: format!(
                    "`{name}` sets the friction of {}, where no vehicle can be during a test (the \
                     ego cannot get there within the horizon even at full throttle, and no car's \
                     route crosses it): it cannot affect the ego",
                    pieces.into_iter().collect::<Vec<_>>().join(", ")
                ),
            });
            continue;
        }
        if changes.iter().all(|c| inert(c, i.stl_reads_light)) {
            let mut sets: Vec<String> = Vec::new();
            for c in changes {
                let s = match c {
                    Change::Light => "the light".to_owned(),
                    Change::Colour(car) => format!(
                        "the colour of {}",
                        i.scene.car_name(*car).unwrap_or("a car")
                    ),
                    Change::ObstacleColour(k) => format!(
                        "the colour of {}",
                        i.scene.obstacle_name(*k).unwrap_or("an obstacle")
                    ),
                    _ => continue,
                };
                if !sets.contains(&s) {
                    sets.push(s);
                }
            }
            usage.camera_only.push(CameraOnly {
                param: name.clone(),
                at: site.clone(),
                sets: sets.join(" and "),
            });
        }
    }
    usage
}

/// The findings of the analyses of `front_end`, whose code reads nothing its scenes do not
/// show (an OpenSCENARIO file, a Rust function), its tests lasting `horizon_s`: [`probe`] and
/// [`analyse`] for its parameters, named and placed by `sites` (`(name, file:line:col)` in
/// the space's order). Nothing is found when the space's first point builds no scene.
pub fn findings_of(
    front_end: &dyn crate::FrontEnd,
    sites: &[(String, String)],
    horizon_s: f64,
) -> crate::front_end::Findings {
    let Some(probed) = probe(front_end, horizon_s) else {
        return crate::front_end::Findings::default();
    };
    let unprobed: Vec<bool> = probed.probed.iter().map(|p| !p).collect();
    let found = analyse(Inputs {
        params: sites,
        changes: &probed.changes,
        read_in_code: &unprobed,
        stl_reads_light: false,
        scene: &probed.base,
    });
    crate::front_end::Findings {
        warnings: found.warnings,
        unused_params: (found.unused.iter()).map(|&k| sites[k].0.clone()).collect(),
        camera_only: found.camera_only,
    }
}
