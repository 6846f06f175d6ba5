//! OpenSCENARIO front end: a scenario file read by `paracosm-openscenario` becomes a
//! [`Scenario`] whose tests each read the file's text (kept from the load) with the test's
//! parameter values and build a [`Scene`]: the map of its `RoadNetwork`, the ego vehicle
//! (driven by the system under test) and every other entity as a scripted car or pedestrian,
//! whose motion the storyboard runtime ([`story`]) computes step by step and hands to the
//! engine as place actions.
//!
//! Published signals (for `Stl` and `Monitor`): [`HEADWAY_SIGNAL`], [`GAP_SIGNAL`] and
//! [`LANE_EDGE_SIGNAL`], the R157-style measures of the ego.

mod campaign;
mod describe;
mod host_inputs;
pub(crate) use host_inputs::StoryInputs;
pub mod motion;

mod space;
pub mod story;

pub use campaign::{campaign_scenario, inspect, inspect_in, inspect_with_map, Inspection, XoscRef};
pub use space::{open_param, value_sets_param, varied_param};

use std::path::PathBuf;
use std::sync::Arc;

use paracosm_engine::behaviour::{Action as Sink, ActorRef, Output};
use paracosm_engine::network::{Lane, Location, PieceId};
use paracosm_engine::rx::{Func, Host, HostError, Node, Runtime, StreamId, Value};
use paracosm_engine::sut::{AebConfig, SutConfig};
use paracosm_engine::{CarSpec, EgoSpec, PedestrianSpec, Size, VehicleParams, DEFAULT_DT_S};
use paracosm_generators::{Assignment, ParamSpace};
use paracosm_openscenario::model::{self as m, Action, EntityKind};
use paracosm_openscenario::read_scenario_in;

use crate::front_end::FrontEnd;
use crate::map_files::{Base, MapFiles};
use crate::scenario::Warning;
use crate::scene::{LoadError, LoadErrorKind, Scene, Site, TestSettings};
use crate::{MonitorSpec, Scenario, ScenarioError};

use story::{RouteAsk, Storyboard};

/// The ego's time headway to the nearest entity ahead in its lane, s (`inf` with none).
pub const HEADWAY_SIGNAL: &str = "ego_headway_s";
/// The ego's following distance to the nearest entity ahead in its lane, between bounding
/// boxes, m (`inf` with none).
pub const GAP_SIGNAL: &str = "ego_gap_m";
/// The distance from the ego's side to its lane's nearer edge, m (negative once over it).
pub const LANE_EDGE_SIGNAL: &str = "ego_lane_edge_m";
/// The longest test, s: a storyboard ends at its stop trigger, or here.
pub const HORIZON_CAP_S: f64 = 3600.0;
/// How far ahead the ego's route is planned, m (at most: it ends where its lanes end). The
/// ALKS free-driving road is a little over 5 km, which a route of 3 km left the ego to leave
/// at 3 km, failing the test off-road; each test plans its route, so a longer one costs
/// setup time on every long road (20 km made the crossing pedestrian's campaign 1.8 times
/// slower on its 10 km roads).
const ROUTE_M: f64 = 6000.0;

/// The parameter values of one test as OpenSCENARIO overrides (`name`, typed value), from the
/// test's assignment (a value set's level expands to its parameters, for example).
pub type Overrides = Arc<
    dyn Fn(&Assignment) -> Result<Vec<(String, paracosm_openscenario::Value)>, OverrideError>
        + Send
        + Sync,
>;

/// Why a test's values cannot be written as overrides (a value set that is not
/// `Name=value, ...`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct OverrideError(pub String);

/// What a campaign over an OpenSCENARIO scenario needs.
pub struct Source {
    /// The scenario file (`Storyboard`), parsed again for every test with its values, from
    /// its text kept in [`Source::files`].
    pub template: PathBuf,
    /// The OpenSCENARIO files the campaign's load has read (the variation file, the
    /// scenario): the scenario's catalogs join them at load, and every test reads these
    /// texts, not the disk.
    pub files: Arc<paracosm_openscenario::FileSet>,
    /// The campaign's name for it: the file's name with its options (`a.xosc --open ...`).
    pub name: String,
    /// The folder its input files are named relative to ([`relative_to`]): the campaign
    /// file's, so its fingerprint is the same from any folder.
    pub files_base: PathBuf,
    /// What the campaign's reading of the file found before the scenario loads (a variation
    /// file's limits): the scenario's own warnings follow them.
    pub warnings: Vec<Warning>,
    /// The space of the test's parameters.
    pub space: ParamSpace,
    /// Where each parameter of the space is set, in its order (`file:line:col` of its
    /// distribution, `--open Name=...`): the load's warnings about it name it.
    pub param_sites: Vec<String>,
    /// The overrides of one test.
    pub overrides: Overrides,
    /// Whether the storyboard moves the ego as it moves every other entity (its `Init`, its
    /// trajectories and actions; no system under test drives it): to replay a test exported
    /// by `paracosm-fuzz export`, or to run a file as esmini does with its controllers off.
    pub scripted_ego: bool,
    /// `--ego NAME`: the vehicle the system under test drives, when the file does not say
    /// plainly ([`ego_of`]).
    pub ego: Option<String>,
    /// `--horizon`: the longest test, s (finite, `> 0`); without it a test ends at the
    /// storyboard's stop trigger, and a storyboard without one is refused.
    pub horizon_s: Option<f64>,
    /// `--ego-speed`: the set speed of the system under test, m/s, for a file that asks the
    /// ego no speed ([`check_the_ego_is_asked_to_drive`]).
    pub ego_speed_mps: Option<f64>,
}

/// An OpenSCENARIO error as a load error.
fn xosc_error(e: paracosm_openscenario::XoscError) -> ScenarioError {
    ScenarioError::Load(LoadError::new(LoadErrorKind::Files, e.to_string()))
}

fn worlds_error(message: String) -> ScenarioError {
    ScenarioError::Load(LoadError::new(LoadErrorKind::Worlds, message))
}

/// The entity the system under test drives: the vehicle `named` (`--ego NAME`), else the one
/// given CARLA's `external_control` (its ego agent's controller), else the one
/// whose controller the storyboard activates, else the one named `Ego` or `hero` (any
/// case), else the scenario's only vehicle. With `any_vehicle` (the storyboard moves every
/// entity, so nothing is tested of the ego) the first vehicle stands in when none is plainly
/// the ego.
///
/// # Errors
/// [`ScenarioError::Load`]: `named` is no vehicle of the scenario; the scenario has no
/// vehicle; or several vehicles and none plainly the ego (the message lists them and asks
/// for `--ego NAME`).
pub fn ego_of(
    s: &m::Scenario,
    named: Option<&str>,
    any_vehicle: bool,
) -> Result<usize, ScenarioError> {
    let vehicle = |i: &usize| matches!(s.entities[*i].kind, EntityKind::Vehicle(_));
    let vehicles: Vec<usize> = (0..s.entities.len()).filter(vehicle).collect();
    let list = || {
        vehicles
            .iter()
            .map(|&i| s.entities[i].name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(name) = named {
        return vehicles
            .iter()
            .copied()
            .find(|&i| s.entities[i].name == name)
            .ok_or_else(|| {
                worlds_error(format!(
                    "{}: the ego named {name:?} (--ego, or Import's ego=) is not a vehicle of the \
                     scenario (its vehicles: {})",
                    s.file,
                    list()
                ))
            });
    }
    // CARLA's controller of the ego's agent, assigned in Init or a story.
    let agent = s
        .init
        .iter()
        .map(|(e, na)| (*e, &na.action))
        .chain(
            s.stories
                .iter()
                .flat_map(|st| &st.acts)
                .flat_map(|a| &a.groups)
                .flat_map(|g| g.maneuvers.iter().map(move |mv| (g, mv)))
                .flat_map(|(g, mv)| mv.events.iter().map(move |ev| (g, ev)))
                .flat_map(|(g, ev)| ev.actions.iter().map(move |na| (g, na)))
                .filter_map(|(g, na)| g.actors.first().map(|&e| (e, &na.action))),
        )
        .find_map(|(e, a)| match a {
            Action::AssignController { kind: Some(k), .. } if k == "external_control" => Some(e),
            _ => None,
        });
    let activated = s
        .stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .find_map(|g| {
            let activates = g
                .maneuvers
                .iter()
                .flat_map(|mv| &mv.events)
                .any(|ev| ev.actions.iter().any(|na| hands_to_a_driver(&na.action)));
            activates.then(|| g.actors.first().copied()).flatten()
        });
    let by_name = || {
        vehicles
            .iter()
            .copied()
            .find(|&i| ["ego", "hero"].contains(&s.entities[i].name.to_ascii_lowercase().as_str()))
    };
    let only = || (vehicles.len() == 1).then(|| vehicles[0]);
    let first = || any_vehicle.then(|| vehicles.first().copied()).flatten();
    agent
        .filter(vehicle)
        .or(activated.filter(vehicle))
        .or_else(by_name)
        .or_else(only)
        .or_else(first)
        .ok_or_else(|| {
            worlds_error(if vehicles.is_empty() {
                format!(
                    "{}: the scenario has no vehicle for the system under test to drive",
                    s.file
                )
            } else {
                format!(
                    "{}: which vehicle is the ego? None is named Ego or hero and the storyboard \
                     activates no controller: name it with --ego NAME (in a program, \
                     Import(..., ego = \"NAME\")) (the scenario's vehicles: {})",
                    s.file,
                    list()
                )
            })
        })
}

/// What paracosm refuses in `s` (an action it cannot perform as written), and what it
/// performs otherwise than written (as warnings): the ego's storyboard actions (the system
/// under test drives it), controllers of other entities, the model's own notes.
///
/// # Errors
/// [`ScenarioError::Load`] naming the element's line and column.
pub fn check(s: &m::Scenario, ego: Option<usize>) -> Result<Vec<Warning>, ScenarioError> {
    if let Some(t) = s.tilts.first() {
        return Err(worlds_error(format!(
            "{}: {}. paracosm's engine cannot tilt a body: a tilted entity's footprint on the \
             road (a bicycle lying on its side, a pedestrian lying down) is not its upright \
             box, so its collisions would be misjudged. paracosm-fuzz xosc lists the file",
            t.pos,
            t.text.split(':').next().unwrap_or(&t.text)
        )));
    }
    let mut warnings: Vec<Warning> = s
        .notes
        .iter()
        .map(|n| Warning {
            at: n.pos.to_string(),
            message: n.text.clone(),
        })
        .collect();
    let mut each = |who: &[usize], na: &m::NamedAction, init: bool| -> Result<(), ScenarioError> {
        if na.action.is_global() {
            // On the world, not on the actors. A traffic signal no system under test sees.
            if let (Some(e), Action::TrafficSignalState { signal, .. }) = (ego, &na.action) {
                return Err(worlds_error(format!(
                    "{}: this TrafficSignalStateAction sets traffic signal {signal:?}, which the \
                     system under test driving {} would neither see nor obey: paracosm draws no \
                     traffic signals and its systems under test read none. Run the file with \
                     --scripted-ego (the storyboard's conditions read the signals' states)",
                    na.pos, s.entities[e].name
                )));
            }
            warnings.extend(global_otherwise(na));
            return Ok(());
        }
        for &e in who {
            if let Some(message) = performed_otherwise(s, na, (e, ego), init)? {
                warnings.push(Warning {
                    at: na.pos.to_string(),
                    message,
                });
            }
        }
        Ok(())
    };
    for (e, na) in &s.init {
        each(&[*e], na, true)?;
    }
    for na in &s.init_global {
        each(&[], na, true)?;
    }
    for g in s
        .stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
    {
        if g.select_triggering {
            return Err(worlds_error(format!(
                "{}: maneuver group {:?} selects its actors from the triggering entities \
                 (selectTriggeringEntities=\"true\"), which paracosm does not support: name \
                 the actors with EntityRef",
                s.file, g.name
            )));
        }
        for na in g
            .maneuvers
            .iter()
            .flat_map(|mv| &mv.events)
            .flat_map(|e| &e.actions)
        {
            each(&g.actors, na, false)?;
        }
    }
    Ok(warnings)
}

/// Who is in the scenario (`AddEntityAction`, `DeleteEntityAction`): an entity is in it
/// from the start when `Init` places it (a `Private` block of its own) or adds it, as esmini
/// activates entities. The ego vehicle `ego` is the test's vehicle under test, always in its
/// world. A warning names each entity that is never in the scenario (esmini leaves it out
/// too).
///
/// # Errors
/// [`ScenarioError::Load`] naming the file, or the action's line and column: the ego not in
/// the scenario from the start, or an `AddEntityAction` or `DeleteEntityAction` on it after
/// `Init`.
pub fn check_presence(s: &m::Scenario, ego: usize) -> Result<Vec<Warning>, ScenarioError> {
    let mut present = vec![false; s.entities.len()];
    for (e, _) in &s.init {
        present[*e] = true;
    }
    for na in &s.init_global {
        match na.action {
            Action::AddEntity { entity, .. } => present[entity] = true,
            Action::DeleteEntity { entity } if entity == ego => return Err(on_the_ego(na)),
            Action::DeleteEntity { entity } => present[entity] = false,
            _ => {}
        }
    }
    if !present[ego] {
        return Err(worlds_error(format!(
            "{}: the ego {:?} is not in the scenario at the start: Init neither places it (a \
             Private block of its own) nor adds it (AddEntityAction), and the ego is the \
             vehicle under test, in the test's world from its start",
            s.file, s.entities[ego].name
        )));
    }
    let mut added = present;
    for na in story_actions(s) {
        match na.action {
            Action::AddEntity { entity, .. } | Action::DeleteEntity { entity } if entity == ego => {
                return Err(on_the_ego(na))
            }
            Action::AddEntity { entity, .. } => added[entity] = true,
            _ => {}
        }
    }
    // A trailer is in the scenario with its tow (esmini activates a combination whole).
    for e in 0..s.entities.len() {
        let mut next = s.entities[e].trailer.filter(|_| added[e]);
        for _ in 0..s.entities.len() {
            let Some(k) = next else { break };
            added[k] = true;
            next = s.entities[k].trailer;
        }
    }
    Ok((0..s.entities.len())
        .filter(|&e| !added[e])
        .map(|e| Warning {
            at: s.file.clone(),
            message: format!(
                "{} is never in the scenario: Init does not place it and no AddEntityAction \
                 adds it, so it is left out of the test's world (as esmini leaves it out)",
                s.entities[e].name
            ),
        })
        .collect())
}

/// The refusal of an `AddEntityAction` or `DeleteEntityAction` `na` on the ego.
fn on_the_ego(na: &m::NamedAction) -> ScenarioError {
    worlds_error(format!(
        "{}: this {} adds or deletes the ego, the vehicle under test, which is in the test's \
         world throughout: paracosm cannot take it out",
        na.pos,
        na.action.kind_name()
    ))
}

/// How paracosm performs global action `na`: as written, or with a warning for what its world
/// does not model. Rain and snow are modelled by how far they let the camera and the range
/// sensor see ([`story::precipitation_extinction_per_m`], added to the fog's extinction);
/// the rest of what they do to an image (streaks, spray, a wet road's reflections) is named
/// in a warning.
fn global_otherwise(na: &m::NamedAction) -> Option<Warning> {
    let Action::Environment(env) = &na.action else {
        return None;
    };
    let (kind, mm) = env
        .precipitation
        .as_ref()
        .filter(|(k, mm)| k != "dry" && *mm > 0.0)?;
    let alone_m = 3.912 / story::precipitation_extinction_per_m(kind, *mm);
    Some(Warning {
        at: na.pos.to_string(),
        message: format!(
            "{kind} ({mm} mm/h) is modelled by its extinction (ITU-R P.1814): the camera and the \
             range sensor see as through fog of a {alone_m:.0} m visual range, added to the \
             fog's; its streaks, spray, drops on the lens and the wet road's reflections are not \
             modelled"
        ),
    })
}

/// How paracosm performs action `na` on entity `e` (`ego`: the entity the system under test
/// drives; `init`: in `Init`): `None` as written, `Some(note)` otherwise (a warning at load).
///
/// # Errors
/// [`ScenarioError::Load`] naming the action's line and column: a deactivation of the driven ego's controller, or an action
/// on the driven ego that paracosm cannot hand its system (all but a `SpeedAction`, a
/// `LaneChangeAction` or `AssignRouteAction` after `Init`, an `ActivateControllerAction`, and
/// in `Init` a `TeleportAction` or `AssignRouteAction`).
fn performed_otherwise(
    s: &m::Scenario,
    na: &m::NamedAction,
    (e, ego): (usize, Option<usize>),
    init: bool,
) -> Result<Option<String>, ScenarioError> {
    let name = &s.entities[e].name;
    let driven = Some(e) == ego;
    Ok(match &na.action {
        Action::ActivateController { .. } => return activated(s, na, (e, ego)),
        Action::AssignController { .. } => return assigned(s, na, (e, ego), init),
        // Every value inactive (noted where read; an active one is refused there).
        Action::OverrideController => None,
        // The lights of a vehicle: noted where read.
        Action::Appearance(_) => None,
        // Hidden from the system under test's camera or sensors: paracosm cannot hide an
        // entity from them, so a test under a system would test a world it does not sense.
        Action::Visibility {
            graphics, sensors, ..
        } if ego.is_some() && !driven && !(*graphics && *sensors) => {
            return Err(worlds_error(format!(
                "{}: this VisibilityAction hides {name} from the {} of the system under test, \
                 which paracosm cannot do: its camera and range sensor see every entity. Run the \
                 file with --scripted-ego (no system senses the world)",
                na.pos,
                if *sensors { "camera" } else { "sensors" }
            )));
        }
        Action::Visibility {
            graphics, sensors, ..
        } if !(driven || *graphics && *sensors) => Some(format!(
            "{name} is hidden here, which paracosm does not model: no system under test senses \
             the world (--scripted-ego)"
        )),
        Action::Visibility { .. } if !driven => None,
        // The engine couples a trailer to its tow for a whole test.
        Action::Trailer(_) => {
            return Err(worlds_error(format!(
                "{}: this {} couples or uncouples a trailer while the test runs, which \
                 paracosm's engine does not do: a trailer and its tow are coupled for a whole \
                 test (a vehicle's <Trailer>), their contact no collision",
                na.pos,
                na.action.kind_name()
            )))
        }
        // Its place, its initial speed and its route (the lanes it plans through).
        Action::Teleport(_) | Action::AssignRoute { .. } if init && driven => None,
        // An untimed trajectory: the system's route (a timed one asks a time the system
        // under test would not keep).
        Action::FollowTrajectory { timing: None, .. } if driven => None,
        // Its initial speed in Init; later, the set speed of the system under test (a
        // profile: its set speed over time).
        Action::Speed { .. } | Action::SpeedProfile(_) if driven => None,
        // Later, the route of the system under test: into the lane, or along the route's
        // roads.
        Action::LaneChange { .. } | Action::AssignRoute { .. } | Action::AcquirePosition(_)
            if !init && driven =>
        {
            None
        }
        // A route along its lane at the offset (also in Init: where it starts to drive).
        Action::LaneOffset { .. } if driven => None,
        _ if driven => {
            return Err(worlds_error(format!(
                "{}: the system under test drives {name}, and paracosm cannot hand it this {}: \
                 its storyboard asks it of the ego only as a SpeedAction or a \
                 SpeedProfileAction (the system's set speed), a LaneChangeAction, a LaneOffsetAction, an AssignRouteAction or an \
                 untimed FollowTrajectoryAction (the system's route), an \
                 ActivateControllerAction, or in Init a TeleportAction or an \
                 AssignRouteAction. Run the file with --scripted-ego to have the storyboard \
                 move the ego, or name another vehicle with --ego",
                na.pos,
                na.action.kind_name()
            )))
        }
        _ => None,
    })
}

/// How paracosm performs `ActivateControllerAction` `na` on entity `e` ([`performed_otherwise`]):
/// on the ego a system under test drives, the hand-over (of the whole ego, noted when only a
/// domain is activated); on another entity nothing, since the storyboard moves it (noted).
///
/// # Errors
/// [`ScenarioError::Load`] naming the action's line and column: a deactivation of the driven
/// ego's controller; CARLA's autopilot; the activation of a controller the storyboard
/// assigned that paracosm cannot run ([`assigned_driver`]).
fn activated(
    s: &m::Scenario,
    na: &m::NamedAction,
    (e, ego): (usize, Option<usize>),
) -> Result<Option<String>, ScenarioError> {
    let name = &s.entities[e].name;
    let driven = Some(e) == ego;
    Ok(match &na.action {
        Action::ActivateController {
            lateral,
            longitudinal,
        } if driven => match (lateral, longitudinal) {
            (Some(false), Some(false)) => {
                return Err(worlds_error(format!(
                    "{}: this ActivateControllerAction deactivates the controller of {name}, \
                     handing it back to the storyboard, which paracosm cannot do: the system \
                     under test drives the ego from its activation to the end. Run the file \
                     with --scripted-ego to have the storyboard move the ego",
                    na.pos
                )));
            }
            (Some(false), _) | (_, Some(false)) => {
                let (only, too) = if *lateral == Some(false) {
                    ("longitudinal", "steering")
                } else {
                    ("lateral", "speed")
                };
                Some(format!(
                    "this ActivateControllerAction activates only the {only} control of {name}: \
                     paracosm hands the system under test the whole ego, its {too} too"
                ))
            }
            _ => None,
        },
        // CARLA's autopilot (its Traffic Manager) drives a vehicle activated so.
        Action::ActivateController { .. } if s.carla && na.action.hands_over() => {
            return Err(worlds_error(format!(
                "{}: this ActivateControllerAction starts CARLA's autopilot on {name}, which \
                 paracosm does not have: the storyboard would leave {name} at its speed \
                 instead of driving it through the town",
                na.pos
            )));
        }
        // A controller the storyboard assigned it, which paracosm cannot run.
        Action::ActivateController { .. } if na.action.hands_over() => {
            if let Some(what) = assigned_driver(s, e, ego.is_none()) {
                return Err(worlds_error(format!(
                    "{}: this ActivateControllerAction activates a controller of {name} \
                     that paracosm cannot run (the storyboard assigns it {what}): paracosm \
                     moves an entity other than the ego a system under test drives only by \
                     the storyboard. Have a system under test drive {name} (without \
                     --scripted-ego, or --ego {name})",
                    na.pos
                )));
            }
            Some(format!(
                "{name} has no controller in paracosm: the storyboard moves it, and its \
                 ActivateControllerAction does nothing"
            ))
        }
        Action::ActivateController { .. } => Some(format!(
            "{name} has no controller in paracosm: the storyboard moves it, and its \
             ActivateControllerAction does nothing"
        )),
        _ => None,
    })
}

/// Whether `a` hands its entity to a driver other than the storyboard: an activation, or an
/// assignment that activates a controller of a kind other than [`STORYBOARD_CONTROLLERS`]
/// (CARLA's NPC controller, assigned in a story, marks no ego).
fn hands_to_a_driver(a: &Action) -> bool {
    match a {
        Action::AssignController { kind, .. } => {
            a.hands_over()
                && !kind.as_deref().is_some_and(|k| {
                    STORYBOARD_CONTROLLERS.contains(&k) || story::STRAIGHT_CONTROLLERS.contains(&k)
                })
        }
        _ => a.hands_over(),
    }
}

/// CARLA's controller of a vehicle that follows the storyboard's actions along its lane
/// (scenario_runner's `NpcVehicleControl`), and esmini's (`DefaultController`): paracosm's
/// storyboard moves an entity so.
pub const STORYBOARD_CONTROLLERS: [&str; 2] = ["npc_vehicle_control", "DefaultController"];

/// How paracosm performs `AssignControllerAction` `na` on entity `e` ([`performed_otherwise`]):
/// on the ego a system under test drives, that system is its controller; on any other
/// entity, a controller of [`STORYBOARD_CONTROLLERS`] is the storyboard's motion, one not
/// activated does nothing yet, and under `--scripted-ego` CARLA's `external_control` (its
/// ego's agent) is the storyboard's motion too.
///
/// # Errors
/// [`ScenarioError::Load`] naming the action's line and column: an activated controller of
/// another kind on an entity the storyboard moves.
fn assigned(
    s: &m::Scenario,
    na: &m::NamedAction,
    (e, ego): (usize, Option<usize>),
    init: bool,
) -> Result<Option<String>, ScenarioError> {
    let Action::AssignController {
        controller,
        kind,
        lateral,
        longitudinal,
    } = &na.action
    else {
        return Ok(None);
    };
    let name = &s.entities[e].name;
    let what = controller_named(controller, kind.as_deref());
    if Some(e) == ego {
        let activated = (*lateral, *longitudinal);
        let part = match activated {
            (Some(true), Some(true)) => String::new(),
            _ if !na.action.hands_over() => format!(
                " (this assignment{} activates nothing: the system drives {name} from an \
                 ActivateControllerAction on it, or from the start without one)",
                if init { " in Init" } else { "" }
            ),
            (Some(true), _) => ", its speed too (this action activates only steering)".into(),
            _ => ", its steering too (this action activates only speed)".into(),
        };
        return Ok(Some(format!(
            "the system under test is the controller of {name}: it drives in place of {what}{part}"
        )));
    }
    if !na.action.hands_over() {
        return Ok(Some(format!(
            "{what} is assigned to {name} but not activated: the storyboard moves {name}"
        )));
    }
    let plain = kind
        .as_deref()
        .is_some_and(|k| STORYBOARD_CONTROLLERS.contains(&k));
    // CARLA's controller of the ego: the system under test, which --scripted-ego replaces
    // by the storyboard.
    let scripted_ego = ego.is_none() && kind.as_deref() == Some("external_control");
    if plain || scripted_ego {
        return Ok(Some(format!(
            "the storyboard moves {name} along its lane at the speeds its actions set, in \
             place of {what}"
        )));
    }
    if kind
        .as_deref()
        .is_some_and(|k| story::STRAIGHT_CONTROLLERS.contains(&k))
    {
        return Ok(Some(format!(
            "the storyboard moves {name} straight along its heading at the speeds its actions \
             set, as {what} drives (its speed only, the steering left straight); its speed \
             changes follow the actions' dynamics, not CARLA's full throttle"
        )));
    }
    Err(worlds_error(format!(
        "{}: this AssignControllerAction has {what} drive {name}, which paracosm cannot run: \
         it moves an entity other than the ego a system under test drives only by the \
         storyboard (its actions along its lane, as a controller of kind {} does). Give the \
         ego to a system under test (--ego {name}), or leave this entity to the storyboard",
        na.pos,
        STORYBOARD_CONTROLLERS.join(" or ")
    )))
}

/// The first controller `s` assigns entity `e` (in `Init` or a story) that paracosm's
/// storyboard cannot stand for: one of a kind other than [`STORYBOARD_CONTROLLERS`] (and, with
/// `scripted` — no system under test — other than CARLA's `external_control`, the ego's agent
/// the storyboard replaces), as `controller NAME (KIND)`.
fn assigned_driver(s: &m::Scenario, e: usize, scripted: bool) -> Option<String> {
    let stories = (s.stories.iter())
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .filter(|g| g.actors.contains(&e))
        .flat_map(|g| &g.maneuvers)
        .flat_map(|mv| &mv.events)
        .flat_map(|ev| &ev.actions);
    let init = s.init.iter().filter(|(i, _)| *i == e).map(|(_, na)| na);
    init.chain(stories).find_map(|na| match &na.action {
        Action::AssignController {
            controller, kind, ..
        } => {
            let k = kind.as_deref().unwrap_or("");
            let plain = STORYBOARD_CONTROLLERS.contains(&k)
                || story::STRAIGHT_CONTROLLERS.contains(&k)
                || (scripted && k == "external_control");
            (!plain).then(|| controller_named(controller, kind.as_deref()))
        }
        _ => None,
    })
}

/// `controller NAME (KIND)`, or `controller NAME` when its kind is not said.
fn controller_named(controller: &str, kind: Option<&str>) -> String {
    match kind {
        Some(k) => format!("controller {controller} ({k})"),
        None => format!("controller {controller}"),
    }
}

/// The scenario of `source`: its space, the `aeb` system under test (which keeps the ego's
/// initial speed as its set speed), a collision monitor and the off-road monitor, and a
/// horizon of [`HORIZON_CAP_S`] that the storyboard's stop trigger cuts short.
///
/// # Errors
/// [`ScenarioError::Load`] naming the file, line and column: the file does not read with its
/// declared values, its map does not load, the scene cannot be built, or it holds an action
/// paracosm does not perform ([`check`]).
pub fn scenario(source: Source) -> Result<Scenario, ScenarioError> {
    let model = read_scenario_in(&source.files, &source.template, &[]).map_err(xosc_error)?;
    let ego = ego_of(&model, source.ego.as_deref(), source.scripted_ego)?;
    let mut warnings = check(&model, (!source.scripted_ego).then_some(ego))?;
    warnings.extend(check_presence(&model, ego)?);
    if !source.scripted_ego {
        check_the_ego_is_asked_to_drive(&model, ego, source.ego_speed_mps)?;
    } else if source.ego_speed_mps.is_some() {
        return Err(worlds_error(
            "--ego-speed is the set speed of a system under test, and with --scripted-ego none \
             drives: the storyboard moves the ego at the speeds the file asks"
                .into(),
        ));
    }
    let horizon_s = horizon(&model, source.horizon_s)?;
    // The failure map's axes: the intervals first, then the parameters with most levels.
    let mut axes: Vec<&paracosm_generators::Param> = source.space.params().iter().collect();
    axes.sort_by_key(|p| match &p.domain {
        paracosm_generators::Domain::Interval { .. } => 0,
        paracosm_generators::Domain::Levels(l) => usize::MAX - l.len(),
    });
    let map_axes = axes.iter().take(2).map(|p| p.name.clone()).collect();
    // The model's LogicFile path is already joined with the scenario's folder.
    let dir = PathBuf::new();
    let mut front_end = XoscFrontEnd {
        template: source.template.clone(),
        overrides: source.overrides,
        maps: MapFiles::sharing(Base::Folder(dir), source.files.clone()),
        scripted_ego: source.scripted_ego,
        ego: source.ego.clone(),
        ego_speed_mps: source.ego_speed_mps,
        horizon_s,
        map_axes,
        space: source.space,
        source: crate::front_end::Source::default(),
        findings: crate::front_end::Findings::default(),
    };
    // The scene of the declared values: the map loads, the Init places every entity.
    let model = Arc::new(model);
    let (scene, host) = front_end.build(model.clone())?;
    drop(scene);
    // What the storyboard performs otherwise than written (a target at its road's end).
    let story_notes: Vec<Warning> = (host.sb.notes().iter())
        .map(|(at, message)| Warning {
            at: at.clone(),
            message: message.clone(),
        })
        .collect();
    // Every map a level can choose is read now, fingerprinted with the rest of the file set,
    // and shared by the tests: a campaign is one fixed scenario.
    front_end.read_every_map()?;
    // What each parameter changes, as a program's load finds it: one the storyboard and the
    // scene never read is left out of coverage, with the warning a program gets.
    let names: Vec<(String, String)> = (front_end.space.params().iter())
        .zip(&source.param_sites)
        .map(|(p, site)| (p.name.clone(), site.clone()))
        .collect();
    let mut findings = crate::analysis::findings_of(&front_end, &names, horizon_s);
    warnings.append(&mut findings.warnings);
    warnings.extend(front_end.maps.warnings().into_iter().map(|w| Warning {
        at: model.file.clone(),
        message: w,
    }));
    warnings.extend(source.warnings);
    warnings.extend(story_notes);
    findings.warnings = warnings;
    front_end.findings = findings;
    front_end.source = crate::front_end::Source {
        name: source.name,
        description: format!(
            "OpenSCENARIO {}.{} scenario {}",
            model.version.0, model.version.1, model.file
        ),
        text: Arc::from(
            source
                .files
                .text(&source.template)
                .map_err(xosc_error)?
                .text
                .as_str(),
        ),
        files: (front_end.maps.inputs().into_iter())
            .map(|f| crate::InputFile {
                path: input_name(&source.files_base, source.files.maps(), &f.path),
                ..f
            })
            .collect(),
        ego: Some({
            let e = &model.entities[ego];
            let [l, w, h] = e.dimensions_m;
            format!("{}, {l} × {w} × {h} m", e.name)
        }),
        map_axes_by_relevance: true,
    };
    Scenario::new(Arc::new(front_end))
}

/// How a campaign names input file `path`: relative to the folder `base` ([`relative_to`]), or,
/// when it lies outside it, relative to the folder of maps it was found in (`--maps`), as
/// `--maps/NAME`: the same from any folder and for any `--maps` path to the same folder.
fn input_name(base: &std::path::Path, maps: &[PathBuf], path: &str) -> String {
    let named = relative_to(base, path);
    if named != path {
        return named;
    }
    (maps.iter())
        .map(|d| relative_to(d, path))
        .find(|r| r != path)
        .map_or(named, |r| format!("--maps/{r}"))
}

/// `path` relative to the folder `base` when it lies inside it (both resolved by the file
/// system), else `path` as it is: a campaign's input files are named the same from any
/// folder, so its fingerprint is too.
pub fn relative_to(base: &std::path::Path, path: &str) -> String {
    let canon = |p: &std::path::Path| {
        std::fs::canonicalize(if p.as_os_str().is_empty() {
            std::path::Path::new(".")
        } else {
            p
        })
    };
    match (canon(base), canon(std::path::Path::new(path))) {
        (Ok(b), Ok(p)) => p
            .strip_prefix(&b)
            .map_or_else(|_| path.to_owned(), |r| r.display().to_string()),
        _ => path.to_owned(),
    }
}

/// The front end of an OpenSCENARIO scenario: the file read with each test's values.
struct XoscFrontEnd {
    template: PathBuf,
    overrides: Overrides,
    maps: MapFiles,
    /// [`Source::scripted_ego`].
    scripted_ego: bool,
    /// [`Source::ego`].
    ego: Option<String>,
    /// [`Source::ego_speed_mps`].
    ego_speed_mps: Option<f64>,
    /// The longest test, s ([`horizon`]).
    horizon_s: f64,
    /// The failure map's axes (the intervals first, then the parameters with most levels).
    map_axes: Vec<String>,
    /// [`Source::space`].
    space: ParamSpace,
    /// What the load read.
    source: crate::front_end::Source,
    /// What the load found.
    findings: crate::front_end::Findings,
}

/// Refuses a scenario that never asks the ego `ego`, which a system under test drives, for a
/// speed (no `SpeedAction` on it, in `Init` or a story) when no set speed is `given`
/// (`--ego-speed`, finite and `> 0`): the system would hold the ego still, and a test whose
/// ego never moves tests nothing the file describes. CARLA's files leave the ego's speed to
/// the agent that drives it. A speed the file asks (whatever its value: a parameter's level
/// may be 0, which the test's end judges, [`MOVED_M`]) and one given are refused together.
///
/// # Errors
/// [`ScenarioError::Load`]: naming the ego's `ScenarioObject` when no speed is asked and none
/// given; naming the file's `SpeedAction` when both are; `given` not finite and `> 0`.
pub fn check_the_ego_is_asked_to_drive(
    model: &m::Scenario,
    ego: usize,
    given: Option<f64>,
) -> Result<(), ScenarioError> {
    let e = &model.entities[ego];
    if given.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
        return Err(worlds_error(format!(
            "--ego-speed must be a speed > 0 m/s, not {}",
            given.unwrap_or_default()
        )));
    }
    let speed = |na: &&m::NamedAction| matches!(na.action, Action::Speed { .. });
    let in_init = (model.init.iter())
        .filter(|(i, _)| *i == ego)
        .map(|(_, na)| na)
        .find(speed);
    let in_stories = (model.stories.iter())
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .filter(|g| g.actors.contains(&ego))
        .flat_map(|g| &g.maneuvers)
        .flat_map(|mv| &mv.events)
        .flat_map(|ev| &ev.actions)
        .find(speed);
    match (in_init.or(in_stories), given) {
        (None, Some(_)) | (Some(_), None) => Ok(()),
        (Some(na), Some(_)) => Err(worlds_error(format!(
            "{}: the file asks the ego {} its speed here, and --ego-speed is for a file that \
             asks none: leave it out, or open the file's speed parameter with --open",
            na.pos, e.name
        ))),
        (None, None) => Err(worlds_error(format!(
            "{}: the file asks the ego {} no speed (no SpeedAction on it): the system under \
             test would have no set speed and hold it still, and a test whose ego never moves \
             tests nothing the file describes. Give the system its set speed with --ego-speed \
             M/S (CARLA's files leave it to the agent that drives the ego)",
            e.pos, e.name
        ))),
    }
}

/// The longest test of `model`, s: `given` (`--horizon`), else [`HORIZON_CAP_S`] when the
/// storyboard has a stop trigger that ends it sooner, or is read as CARLA's (its stories'
/// end ends it).
///
/// # Errors
/// [`ScenarioError::Load`]: `given` is not a finite number `> 0`, or the storyboard has no
/// stop trigger (or an empty one) and no horizon is given: its tests would never end (they
/// ran to the cap before, and read as passes).
pub fn horizon(model: &m::Scenario, given: Option<f64>) -> Result<f64, ScenarioError> {
    match given {
        Some(h) if h.is_finite() && h > 0.0 => Ok(h),
        Some(h) => Err(worlds_error(format!(
            "{}: --horizon {h} s must be a finite number of seconds > 0",
            model.file
        ))),
        // CARLA's scenario ends with its stories ([`m::Scenario::carla`]).
        None if !model.carla && model.stop.as_ref().is_none_or(|t| t.0.is_empty()) => {
            Err(worlds_error(format!(
                "{}: the storyboard has no stop trigger, so nothing ends a test: give \
                 --horizon SECONDS (in a program, test(horizon = ...))",
                model.file
            )))
        }
        None => Ok(HORIZON_CAP_S),
    }
}

impl FrontEnd for XoscFrontEnd {
    fn space(&self) -> &ParamSpace {
        &self.space
    }

    fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let overrides = match assignment {
            Some(a) => (self.overrides)(a).map_err(|e| worlds_error(e.0))?,
            None => Vec::new(),
        };
        let model =
            read_scenario_in(&self.maps.xosc, &self.template, &overrides).map_err(xosc_error)?;
        let (scene, mut host) = self.build(Arc::new(model))?;
        run(&scene, &mut host);
        Ok(())
    }

    fn source(&self) -> crate::front_end::Source {
        self.source.clone()
    }

    fn findings(&self) -> crate::front_end::Findings {
        self.findings.clone()
    }
}

fn here(pos: &paracosm_openscenario::Pos, variable: &str) -> Site {
    Site {
        file: pos.file.clone(),
        line: pos.line,
        col: pos.col,
        variable: Some(variable.to_owned()),
    }
}

/// How many readings of the scenario [`XoscFrontEnd::read_every_map`] makes at most to find
/// the maps its levels choose (one per level of each parameter with levels).
pub const MAX_MAP_LEVEL_READS: usize = 256;

/// The most levels a parameter may have for [`XoscFrontEnd::read_every_map`] to read each
/// level's map at load (a road network is chosen among a few maps, not thousands).
pub const MAX_MAP_LEVELS: u32 = 64;

impl XoscFrontEnd {
    /// Reads the OpenDRIVE map of every level of every parameter with levels (each moved
    /// alone from a point of the space that reads), through the campaign's [`MapFiles`]: a variation
    /// that chooses the road network (the ALKS files' `Road`) has all its maps read, checked
    /// and fingerprinted at load, and a map edited while the campaign runs or before it
    /// resumes is not used. A level whose scenario does not read is left to its test, which
    /// ends in that error; a parameter of more than [`MAX_MAP_LEVELS`] levels, and the levels
    /// past [`MAX_MAP_LEVEL_READS`] readings, have their maps read by the first test that uses
    /// them.
    ///
    /// # Errors
    /// [`ScenarioError::Load`] for a map a level names that does not load, naming the
    /// `LogicFile`'s line and column.
    fn read_every_map(&self) -> Result<(), ScenarioError> {
        let layout = self.space.layout();
        let counts: Vec<u32> = layout.iter().flatten().copied().collect();
        // The other parameters at their middle level, first level or last level, and every
        // interval at its middle: a file's own levels may break its constraint groups (ALKS
        // 4.3.1's lateral offset of -1.75 m must be greater than -1.75 m), so a level is read
        // with the first of these that reads.
        let picks: [fn(u32) -> u32; 3] = [|n| n / 2, |_| 0, |n| n - 1];
        let bases: Vec<paracosm_generators::Point> = picks
            .iter()
            .map(|pick| paracosm_generators::Point {
                discrete: counts.iter().map(|&n| pick(n.max(1))).collect(),
                continuous: vec![0.5; layout.iter().filter(|l| l.is_none()).count()],
            })
            .collect();
        let mut reads = 0;
        for (d, &levels) in counts.iter().enumerate() {
            if levels > MAX_MAP_LEVELS {
                continue;
            }
            for level in 0..levels {
                for base in &bases {
                    if reads == MAX_MAP_LEVEL_READS {
                        return Ok(());
                    }
                    reads += 1;
                    let mut point = base.clone();
                    point.discrete[d] = level;
                    if let Some(road) = self.road_network_at(&point) {
                        self.maps.load(&road.item).map_err(|e| {
                            ScenarioError::Load(e.with_context(&format!("\n --> {}", road.pos)))
                        })?;
                        break;
                    }
                }
            }
        }
        Ok(())
    }

    /// The `LogicFile` the scenario reads with the values of `point`; `None` when they do not
    /// decode or the scenario does not read with them.
    fn road_network_at(&self, point: &paracosm_generators::Point) -> Option<m::Located<String>> {
        let a = self.space.decode(point).ok()?;
        let overrides = (self.overrides)(&a).ok()?;
        let model = read_scenario_in(&self.maps.xosc, &self.template, &overrides).ok()?;
        model.road_network
    }

    /// The scene of `model` and the host that runs its storyboard: [`build_into`] a scene of
    /// daylight without fog, with a collision monitor and a horizon of [`HORIZON_CAP_S`] (the
    /// storyboard's stop trigger ends a test sooner).
    fn build(&self, model: Arc<m::Scenario>) -> Result<(Scene, StoryHost), ScenarioError> {
        let mut scene = Scene::new(None);
        scene.set_host_inputs(Arc::new(host_inputs::StoryInputs(model.clone())));
        let model = &*model;
        let at = model
            .road_network
            .as_ref()
            .map(|r| here(&r.pos, "RoadNetwork"))
            .unwrap_or_else(|| Site::of(&model.file));
        // Daylight without fog, or what the storyboard's EnvironmentActions set, read from
        // the storyboard each step (its host functions LIGHT_FN and FOG_FN).
        let sets = environment_sets(model);
        let light = (!sets.light).then(|| scene.push(Node::Const(Value::Num(DEFAULT_LIGHT))));
        let fog = (!sets.fog).then(|| scene.push(Node::Const(Value::Num(0.0))));
        let ego = ego_of(model, self.ego.as_deref(), self.scripted_ego)?;
        let mut built = build_into(&mut scene, model, &self.maps, (ego, self.scripted_ego), 0)?;
        if !self.scripted_ego {
            built.host.ego_speed(self.ego_speed_mps);
        }
        let mut from_storyboard = |f: u32| {
            let tick = scene.push(Node::Tick);
            scene.push(Node::Map {
                src: tick,
                f: Func::Host(f),
            })
        };
        let light = light.unwrap_or_else(|| from_storyboard(LIGHT_FN));
        let fog = fog.unwrap_or_else(|| from_storyboard(FOG_FN));
        scene
            .set_environment(light, fog, at.clone())
            .map_err(|e| worlds_error(e.to_string()))?;
        scene.add_monitor(MonitorSpec::collision(), at.clone());
        scene
            .set_settings(TestSettings {
                site: Some(at),
                horizon_s: Some(self.horizon_s),
                map_axes: Some(self.map_axes.clone()),
                offroad: None,
            })
            .map_err(|e| worlds_error(e.to_string()))?;
        Ok((scene, built.host))
    }
}

/// Loads `model`'s OpenDRIVE map as a campaign over it would (`paracosm-fuzz xosc` checks it,
/// so that a file whose campaign would refuse its map is refused when listed too).
///
/// # Errors
/// [`ScenarioError::Load`] naming the `LogicFile`'s line and column: the scenario has no
/// `RoadNetwork` map, or the map does not load.
pub fn load_map(model: &m::Scenario) -> Result<(), ScenarioError> {
    let Some(road) = &model.road_network else {
        return Err(worlds_error(format!(
            "{}: the scenario has no RoadNetwork LogicFile: paracosm needs its OpenDRIVE map",
            model.file
        )));
    };
    MapFiles::new(Base::Folder(PathBuf::new()))
        .load(&road.item)
        .map(drop)
        .map_err(|e| ScenarioError::Load(e.with_context(&format!("\n --> {}", road.pos))))
}

/// Where an imported storyboard's host functions start in a program's graph
/// (`Import(...)`): the program's own lambdas are numbered from 0.
pub const IMPORT_HOST_BASE: u32 = 1 << 31;

/// An OpenSCENARIO scenario's world built into a scene ([`build_into`]).
pub(crate) struct Built {
    /// The host that runs its storyboard (functions from the base given).
    pub(crate) host: StoryHost,
    /// Each entity's name and actor, in the file's order.
    pub(crate) actors: Vec<(String, ActorRef)>,
}

/// Builds `model`'s world into `scene`: its OpenDRIVE map (read through `maps`) as a road
/// piece, every entity where `Init` puts it (the ego as the ego vehicle, moved by the
/// storyboard with `scripted_ego`, else driven by `aeb`), the storyboard run by host
/// function `base` at every tick, and the ego's measures published as signals
/// ([`HEADWAY_SIGNAL`], [`GAP_SIGNAL`], [`LANE_EDGE_SIGNAL`], host functions `base + 1..=3`).
/// The scene's environment, monitors and settings are the caller's.
///
/// # Errors
/// [`ScenarioError::Load`]: no map, a map that does not load, an ego not on a lane, an
/// `Init` that cannot be performed, an actor the scene refuses.
pub(crate) fn build_into(
    scene: &mut Scene,
    model: &m::Scenario,
    maps: &MapFiles,
    (ego, scripted_ego): (usize, bool),
    base: u32,
) -> Result<Built, ScenarioError> {
    let Some(road) = &model.road_network else {
        return Err(worlds_error(format!(
            "{}: the scenario has no RoadNetwork LogicFile: paracosm needs its OpenDRIVE map",
            model.file
        )));
    };
    let map = maps
        .load(&road.item)
        .map_err(|e| ScenarioError::Load(e.with_context(&format!("\n --> {}", road.pos))))?;
    let roads = paracosm_engine::network::roads::Roads::new(&map);
    let hand_over = !scripted_ego && activates_controller_of(model, ego);
    let driven = (!scripted_ego && !hand_over).then_some(ego);
    let mut sb = Storyboard::new(model, roads, driven).map_err(|e| worlds_error(e.to_string()))?;
    if hand_over {
        sb.hand_over_on_activation(ego);
    }
    let friction = if environment_sets(model).friction {
        let tick = scene.push(Node::Tick);
        scene.push(Node::Map {
            src: tick,
            f: Func::Host(base + FRICTION_FN),
        })
    } else {
        scene.push(Node::Const(Value::Num(story::MAP_FRICTION)))
    };
    let piece = add_map(scene, &map, friction, here(&road.pos, "RoadNetwork"))?;
    let placed = place_entities(scene, model, &sb, ego)?;
    let (mut sinks, probes, actors) = placed;
    if scripted_ego || hand_over {
        sinks[ego] = Some(Sink::PlaceEgo);
    }
    let ego_actor = actors[ego];
    let ego_probes =
        [Output::Pos, Output::Heading, Output::Speed].map(|o| scene.probe(ego_actor, o));
    place_ego(
        scene,
        &sb,
        (ego, &model.entities[ego], scripted_ego),
        hand_over,
        piece,
        &model.file,
    )?;
    let tick = scene.push(Node::Tick);
    // Its errors name the storyboard, not the graph's node.
    scene.graph_mut().push_at(
        Node::Perform {
            src: tick,
            f: Func::Host(base),
        },
        format!("the storyboard of {}", model.file),
    );
    for (k, signal) in [HEADWAY_SIGNAL, GAP_SIGNAL, LANE_EDGE_SIGNAL]
        .into_iter()
        .enumerate()
    {
        let id = scene.push(Node::Map {
            src: tick,
            f: Func::Host(base + k as u32 + 1),
        });
        scene.publish(signal.to_owned(), id, None);
    }
    let sb_init_speed = sb.actors[ego].state.speed.max(0.0);
    // The route `Init` asked of the driven ego is its route from the start (`place_ego`).
    sb.take_route();
    let mut reads: Vec<StreamId> = probes.clone();
    reads.extend(ego_probes);
    let host = StoryHost {
        sb,
        ego,
        base,
        scripted_ego,
        hand_over: hand_over.then_some(None),
        sinks,
        collided: probes,
        ego_probes,
        reads,
        performed: Vec::new(),
        measures: (f64::INFINITY, f64::INFINITY, f64::NAN),
        asked: None,
        most_asked_mps: sb_init_speed,
        ego_speed_mps: None,
        road_end: None,
        stuck_since: None,
        in_world: vec![true; model.entities.len()],
        log: Vec::new(),
    };
    let names = model.entities.iter().map(|e| e.name.clone());
    Ok(Built {
        host,
        actors: names.zip(actors).collect(),
    })
}

/// Adds `map` to `scene` as one road piece, with friction [`story::MAP_FRICTION`] (or the
/// stream `friction`, when a `RoadCondition` changes it), declared at `site`: through the
/// handle the map files keep, so that every test shares the query index and collision mesh
/// the first test built.
///
/// # Errors
/// [`ScenarioError::Load`] when the scene refuses the piece.
fn add_map(
    scene: &mut Scene,
    map: &paracosm_engine::network::MapRef,
    friction: StreamId,
    site: Site,
) -> Result<PieceId, ScenarioError> {
    let piece = paracosm_engine::network::PieceKind::Map {
        map: map.clone(),
        friction: story::MAP_FRICTION,
    };
    scene
        .add_road(|n| n.add("map", piece), friction, site)
        .map_err(|e| worlds_error(e.to_string()))
}

/// The ego vehicle of `entity`: paracosm's vehicle model with the body of the entity's
/// `BoundingBox` (length × width × height, m; its centre is where the storyboard puts the
/// chassis' centre), the model's mass and actuators otherwise.
///
/// # Errors
/// [`ScenarioError::Load`] naming the box's file, line and column when a side is outside
/// the vehicle model's range ([`paracosm_engine::EGO_SIZE_RANGE_M`]).
fn ego_vehicle(entity: &m::Entity) -> Result<VehicleParams, ScenarioError> {
    let [length_m, width_m, height_m] = entity.dimensions_m;
    let size = Size {
        length_m,
        width_m,
        height_m,
    };
    VehicleParams::check_size(&size).map_err(|e| {
        let e = match e {
            paracosm_engine::EngineError::InvalidWorld(why) => why,
            other => other.to_string(),
        };
        worlds_error(format!(
            "{}: the bounding box of {} ({length_m} × {width_m} × {height_m} m) cannot be \
             the ego: {e}",
            entity.box_pos, entity.name
        ))
    })?;
    Ok(VehicleParams {
        size,
        ..VehicleParams::default()
    })
}

/// Whether `model`'s stories activate a controller of entity `e` and its `Init` does not:
/// then the storyboard moves it until the activation and the system under test drives it
/// after ([`Storyboard::hand_over_on_activation`]); activated in `Init`, the system drives
/// it from the start (a later activation changes nothing).
fn activates_controller_of(model: &m::Scenario, e: usize) -> bool {
    let in_init = (model.init.iter()).any(|(i, na)| *i == e && na.action.hands_over());
    !in_init
        && model
            .stories
            .iter()
            .flat_map(|st| &st.acts)
            .flat_map(|a| &a.groups)
            .filter(|g| g.actors.contains(&e))
            .flat_map(|g| &g.maneuvers)
            .flat_map(|mv| &mv.events)
            .flat_map(|ev| &ev.actions)
            .any(|na| na.action.hands_over())
}

/// The route of the ego `ego` from `from` (engine world `[x, z]`, m): it joins its lanes at
/// `at` advanced `ahead_m` metres, then follows them the way it faces (against a lane's
/// travel too, as the storyboard moves entities), through junctions as its
/// `AssignRouteAction` asks (else the storyboard's way), a point every 2 m for [`ROUTE_M`].
fn lane_route(
    sb: &Storyboard,
    ego: usize,
    from: [f64; 2],
    mut at: paracosm_engine::network::roads::LanePos,
    ahead_m: f64,
) -> Vec<[f64; 2]> {
    let mut route = vec![from];
    let prefer = |lane: usize| sb.route_takes(ego, lane);
    let point = |at: &paracosm_engine::network::roads::LanePos| {
        let (p, _) = sb.roads().to_engine(sb.roads().pose_of(at));
        [p[0], p[2]]
    };
    if ahead_m > 0.0 {
        if !sb.roads().advance(&mut at, ahead_m, &prefer) {
            route.push(point(&at));
            return route;
        }
        route.push(point(&at));
    }
    for _ in 0..(ROUTE_M / 2.0) as usize {
        let more = sb.roads().advance(&mut at, 2.0, &prefer);
        route.push(point(&at));
        if !more {
            break;
        }
    }
    route
}

/// The route `ask` asks of the ego `ego` from `from` (engine world `[x, z]`, m): the path it
/// gives (a trajectory handed to the system under test), its points at most 2 m apart, then
/// the lanes on from its end; or the lanes from where it joins them ([`lane_route`]).
fn route_of(sb: &Storyboard, ego: usize, from: [f64; 2], ask: &RouteAsk) -> Vec<[f64; 2]> {
    if ask.path.is_empty() {
        return lane_route(sb, ego, from, ask.join, ask.ahead_m);
    }
    let point = |p: &paracosm_engine::network::roads::Pose| {
        let (q, _) = sb.roads().to_engine(*p);
        [q[0], q[2]]
    };
    let mut route = vec![from];
    for w in ask.path.windows(2) {
        let (a, b) = (point(&w[0]), point(&w[1]));
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 2.0).ceil().max(1.0) as usize;
        route.extend((1..=n).map(|k| {
            let u = k as f64 / n as f64;
            [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])]
        }));
    }
    let end = *route.last().expect("the route has a point");
    route.extend(lane_route(sb, ego, end, ask.join, 0.0).into_iter().skip(1));
    route
}

/// Places the ego where the storyboard's `Init` put it, at its initial speed, which the
/// system under test keeps as its set speed, with a route along its lanes, with the body
/// of its `BoundingBox` ([`ego_vehicle`]). With `hand_over` its chassis is placed by the
/// storyboard until the system under test takes it over.
fn place_ego(
    scene: &mut Scene,
    sb: &Storyboard,
    (ego, entity, scripted_ego): (usize, &m::Entity, bool),
    hand_over: bool,
    piece: PieceId,
    file: &str,
) -> Result<(), ScenarioError> {
    let a = &sb.actors[ego];
    let Some(lp) = a.state.lane else {
        return Err(worlds_error(format!(
            "{file}: the ego {} does not start on a lane of the map",
            a.name
        )));
    };
    let (pos, heading) = sb.engine_pose(ego);
    let (id, _) = sb.roads().ids(lp.lane);
    let start = Location {
        pos_m: pos,
        heading_rad: heading,
        piece,
        lane: Lane::Driving(id),
        at_m: lp.s,
        through: None,
        map_lane: Some(lp.lane),
    };
    let route = match sb.init_route() {
        Some(ask) if !scripted_ego => route_of(sb, ego, [pos[0], pos[2]], ask),
        _ => lane_route(sb, ego, [pos[0], pos[2]], lp, 0.0),
    };
    let speed = a.state.speed.max(0.0);
    let vehicle = ego_vehicle(entity)?;
    scene
        .place_ego(
            EgoSpec {
                start,
                initial_speed_mps: speed,
                vehicle,
                route,
                set_speed_mps: (!scripted_ego).then_some(speed),
                scripted: scripted_ego || hand_over,
            },
            if scripted_ego {
                SutConfig::Scripted
            } else {
                SutConfig::Aeb(AebConfig::default())
            },
        )
        .map_err(|e| worlds_error(e.to_string()))
}

/// Runs the storyboard: host function 0, on every step, reads the ego and every entity's
/// contact, steps the storyboard and performs the place actions of the scripted entities;
/// functions 1–3 give the ego's measures.
pub(crate) struct StoryHost {
    sb: Storyboard,
    ego: usize,
    /// Its first host function's number ([`IMPORT_HOST_BASE`] in an importing program).
    base: u32,
    /// [`Source::scripted_ego`]: the storyboard moves the ego too, and nothing ends the test
    /// at the end of its road but the storyboard.
    scripted_ego: bool,
    /// When the storyboard moves the ego until it activates the ego's controller: `Some(None)`
    /// before the hand-over, `Some(Some((t, travelled)))` after it (its time, s, and the
    /// distance the ego had travelled then, m); `None` when the system drives from the start
    /// or the storyboard throughout.
    hand_over: Option<Option<(f64, f64)>>,
    sinks: Vec<Option<Sink>>,
    collided: Vec<StreamId>,
    ego_probes: [StreamId; 3],
    reads: Vec<StreamId>,
    performed: Vec<(Sink, Value)>,
    measures: (f64, f64, f64),
    /// The set speed last handed to the system under test ([`Storyboard::set_speed`]), m/s.
    asked: Option<f64>,
    /// The highest speed the file asked of the driven ego so far (its `Init` speed, its
    /// `SpeedAction`s), m/s.
    most_asked_mps: f64,
    /// `--ego-speed`: the set speed of the system under test where the file asks none, m/s
    /// ([`StoryHost::ego_speed`]).
    ego_speed_mps: Option<f64>,
    /// When the ego's road ended before the storyboard did, s.
    road_end: Option<f64>,
    /// Since when the world the system under test drives in stands still while the
    /// storyboard waits on conditions that only motion could change, s
    /// ([`Storyboard::stuck`], [`STUCK_S`]).
    stuck_since: Option<f64>,
    /// Whether each entity is in the test's world as the engine has it: every one at the
    /// start, then as [`StoryHost::perform_presence`] has set it.
    in_world: Vec<bool>,
    log: Vec<String>,
}

/// How far the driven ego must have travelled, m, by the end of a storyboard that asked it to
/// drive (an `Init` speed or a `SpeedAction` target above [`STILL_MPS`]) for the test to
/// count: one whose ego stood still tested nothing the file describes.
pub const MOVED_M: f64 = 0.5;
/// Speeds up to this, m/s, ask the ego to stand still ([`MOVED_M`]).
pub const STILL_MPS: f64 = 0.1;

impl StoryHost {
    /// Puts each entity that entered or left the scenario (`Init`, `AddEntityAction`,
    /// `DeleteEntityAction`: [`story::Actor::present`]) into or out of the engine's world
    /// ([`Sink::SetPresent`]); the first step takes out those `Init` did not place.
    fn perform_presence(&mut self) {
        for (e, sink) in self.sinks.iter().enumerate() {
            let present = self.sb.actors[e].present;
            let actor = match sink {
                Some(s) if e != self.ego && present != self.in_world[e] => s.actor(),
                _ => continue,
            };
            self.in_world[e] = present;
            self.performed
                .push((Sink::SetPresent(actor), Value::Bool(present)));
        }
    }

    /// At the end of the storyboard or at the horizon (`t`, s; `end` says which, as the
    /// message's words): an error when the driven ego travelled less
    /// than [`MOVED_M`], whether the file asked it to drive (the system under test never
    /// did) or asked it no speed above [`STILL_MPS`] with this test's values: the test tested
    /// nothing the file describes and must not read as a pass.
    ///
    /// # Errors
    /// A [`HostError`] that says so, with the speed asked and the distance travelled.
    fn check_the_ego_moved(&self, t: f64, end: &str) -> Result<(), HostError> {
        let mut travelled = self.sb.actors[self.ego].state.travelled_m;
        match self.hand_over {
            Some(None) => {
                return Err(HostError(format!(
                    "t = {t:.2} s: {end} before its ActivateControllerAction \
                     handed the ego {} to the system under test: the storyboard moved it \
                     throughout, so the test tested nothing of the system",
                    self.sb.actors[self.ego].name
                )))
            }
            Some(Some((_, then))) => travelled -= then,
            None => {}
        }
        let name = &self.sb.actors[self.ego].name;
        if self.most_asked_mps > STILL_MPS && travelled < MOVED_M {
            return Err(HostError(format!(
                "t = {t:.2} s: {end}, and the ego {name} travelled \
                 {travelled:.2} m though the file asked it to drive at up to {:.2} m/s: the \
                 system under test never drove it, so the test tested nothing the file \
                 describes",
                self.most_asked_mps
            )));
        }
        if travelled < MOVED_M {
            return Err(HostError(format!(
                "t = {t:.2} s: {end}, and the ego {name} travelled \
                 {travelled:.2} m: with this test's values the file asked it no speed above \
                 {STILL_MPS} m/s, so the system under test held it still, and a test whose ego \
                 never moves tests nothing the file describes"
            )));
        }
        Ok(())
    }
}

impl StoryHost {
    /// Gives the system under test the set speed `v`, m/s, where the file asks none
    /// (`--ego-speed`): from its first step with the ego, until a `SpeedAction` on the ego
    /// sets another.
    pub(crate) fn ego_speed(&mut self, v: Option<f64>) {
        self.ego_speed_mps = v;
    }

    /// Hands the ego to the system under test in the step (at `t`, s) whose
    /// `ActivateControllerAction` activated its controller: the storyboard stops placing it,
    /// the engine releases its chassis ([`Sink::ReleaseEgo`]) at the speed it had, which
    /// becomes the system's set speed unless a `SpeedAction` is running, and the timeline
    /// records it.
    fn hand_over_if_activated(&mut self, t: f64) {
        if self.hand_over != Some(None) || self.sb.actors[self.ego].scripted {
            return;
        }
        let a = &self.sb.actors[self.ego];
        let speed = a.state.speed.max(0.0);
        self.hand_over = Some(Some((t, a.state.travelled_m)));
        self.log.push(format!(
            "t = {t:.3} s: the system under test takes over the ego {} at {speed:.2} m/s",
            a.name
        ));
        self.sinks[self.ego] = None;
        self.performed.push((Sink::ReleaseEgo, Value::Unit));
        // What the file asks of it from now on: at least to keep the speed it has.
        self.most_asked_mps = speed;
        if self.sb.set_speed().is_none() {
            self.asked = Some(speed);
            self.performed.push((Sink::SetEgoSpeed, Value::Num(speed)));
        }
    }
}

/// How long, s, the world may stand still while the storyboard waits on conditions that only
/// motion could change before the test ends as an error ([`Storyboard::stuck`]): the system
/// under test holds the ego still (behind a stopped target, say) and the storyboard waits on
/// what can no longer happen.
pub const STUCK_S: f64 = 10.0;

impl StoryHost {
    /// An error once the world has stood still for [`STUCK_S`] while the storyboard waits on
    /// conditions that only motion could change (at `t`, s); only while the system under
    /// test drives the ego.
    ///
    /// # Errors
    /// A [`HostError`] naming the conditions waited on and since when all stands still.
    fn check_the_storyboard_can_go_on(&mut self, t: f64) -> Result<(), HostError> {
        let waited = (!self.sb.actors[self.ego].scripted)
            .then(|| self.sb.stuck(STILL_MPS))
            .flatten();
        let Some(waited) = waited else {
            self.stuck_since = None;
            return Ok(());
        };
        let since = *self.stuck_since.get_or_insert(t);
        if t - since >= STUCK_S {
            return Err(HostError(format!(
                "t = {t:.2} s: the storyboard waits on {}, which can no longer become true: \
                 every entity has stood still since t = {since:.2} s (the system under test \
                 holds the ego {} still), no scripted motion is in progress and no condition \
                 waited on reads time, so the test cannot play out as the file describes",
                waited.join(", "),
                self.sb.actors[self.ego].name
            )));
        }
        Ok(())
    }
}

impl StoryHost {
    /// At `t` (s), with the system under test driving the ego (`driven`) or the storyboard
    /// driving it until the hand-over: what happens when the ego's front comes within
    /// [`ROAD_END_MARGIN_M`] of the end of its lanes. Before any event started, or before the
    /// hand-over, the scenario cannot play out: an error. After, the test ends there (its log
    /// says so), since the ego could only leave the map, which would read as its failure.
    ///
    /// # Errors
    /// A [`HostError`] that says why the scenario cannot play out.
    fn check_the_road_goes_on(&mut self, t: f64, driven: bool) -> Result<(), HostError> {
        let before_hand_over = self.hand_over == Some(None);
        if !(driven || before_hand_over)
            || self.road_end.is_some()
            || !self.sb.road_ends_ahead(self.ego, ROAD_END_MARGIN_M)
        {
            return Ok(());
        }
        let before = if before_hand_over {
            "the storyboard handed the ego to the system under test"
        } else if !self.sb.any_event_started() {
            "any event of the storyboard started"
        } else {
            self.road_end = Some(t);
            self.log.push(format!(
                "t = {t:.2} s: the ego reached the end of its road before the storyboard's \
                 stop trigger; the test ends here"
            ));
            return Ok(());
        };
        // Nothing of the system was tested, and nothing can be: the test must not read as a
        // pass, nor as the system's failure.
        Err(HostError(format!(
            "t = {t:.2} s: the ego reached the end of its road before {before}, so the \
             scenario cannot play out (does the ego start facing the way its lane leads off \
             the map?)"
        )))
    }
}

/// The light of an OpenSCENARIO test that no `EnvironmentAction` sets (`[0, 1]`, 0.5
/// nominal daylight).
pub const DEFAULT_LIGHT: f64 = 1.0;

/// The storyboard's host functions (from its base) that give the light, the fog density and
/// the map's friction coefficient its `EnvironmentAction`s set.
const LIGHT_FN: u32 = 4;
/// See [`LIGHT_FN`].
const FOG_FN: u32 = 5;
/// See [`LIGHT_FN`].
const FRICTION_FN: u32 = 6;

/// Which of the world's light, fog and road friction an `EnvironmentAction` of the scenario
/// (in `Init` or a story) sets.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct EnvironmentSets {
    /// The light (a time of day or a sun).
    pub(crate) light: bool,
    /// The fog.
    pub(crate) fog: bool,
    /// The road's friction.
    pub(crate) friction: bool,
}

/// Every action of `model`'s stories (its events' actions, not `Init`'s), in the file's order.
fn story_actions(model: &m::Scenario) -> impl Iterator<Item = &m::NamedAction> {
    model
        .stories
        .iter()
        .flat_map(|st| &st.acts)
        .flat_map(|a| &a.groups)
        .flat_map(|g| &g.maneuvers)
        .flat_map(|mv| &mv.events)
        .flat_map(|e| &e.actions)
}

/// What the `EnvironmentAction`s of `model` set.
pub(crate) fn environment_sets(model: &m::Scenario) -> EnvironmentSets {
    let actions = model.init_global.iter().chain(story_actions(model));
    let mut sets = EnvironmentSets::default();
    for na in actions {
        if let Action::Environment(e) = &na.action {
            sets.light |= e.time_of_day.is_some() || e.sun.is_some();
            sets.fog |= e.fog_visual_range_m.is_some() || e.precipitation.is_some();
            sets.friction |= e.friction_scale.is_some();
        }
    }
    sets
}

/// How close to the end of its lanes the ego's front may come before a test ends there, m.
pub const ROAD_END_MARGIN_M: f64 = 2.0;

impl StoryHost {
    /// What host function `k` ([`LIGHT_FN`], [`FOG_FN`], [`FRICTION_FN`]) gives at the tick
    /// `args[0]` (s): the light, fog density or road friction the storyboard's
    /// `EnvironmentAction`s have set, else the world's default.
    fn environment(&self, k: u32, args: &[Value]) -> f64 {
        let env = self.sb.environment();
        match k {
            LIGHT_FN => {
                let t = args.first().and_then(Value::as_num).unwrap_or(0.0);
                env.light(t).unwrap_or(DEFAULT_LIGHT)
            }
            FOG_FN => env.fog().unwrap_or(0.0),
            _ => env.friction().unwrap_or(story::MAP_FRICTION),
        }
    }
}

impl StoryHost {
    /// Once the storyboard has ended (at `t`, s): the events the file describes that this
    /// test did not play, in its record.
    fn note_unplayed(&mut self, t: f64) {
        if !self.sb.ended {
            return;
        }
        let unplayed = self.sb.never_ran();
        if !unplayed.is_empty() {
            self.log.push(format!(
                "t = {t:.3} s: the storyboard ended; {} never started",
                unplayed.join(", ")
            ));
        }
    }
}

impl Host for StoryHost {
    fn call(&mut self, f: u32, args: &[Value], streams: &Runtime) -> Result<Value, HostError> {
        match f.wrapping_sub(self.base) {
            0 => {
                let t = args.first().and_then(Value::as_num).unwrap_or(0.0);
                let num = |id: StreamId| streams.current(id).and_then(Value::as_num);
                let pos = match streams.current(self.ego_probes[0]) {
                    Some(Value::Vec3(p)) => *p,
                    _ => return Err(HostError("the ego's position is not known".into())),
                };
                let heading = num(self.ego_probes[1]).unwrap_or(0.0);
                let speed = num(self.ego_probes[2]).unwrap_or(0.0);
                // The system under test drives the ego now.
                let driven = !self.sb.actors[self.ego].scripted;
                if driven {
                    self.sb.observe(self.ego, pos, heading, speed, DEFAULT_DT_S);
                }
                self.check_the_road_goes_on(t, driven)?;
                for (e, id) in self.collided.iter().enumerate() {
                    let hit = matches!(streams.current(*id), Some(Value::Bool(true)));
                    self.sb.set_collided(e, hit);
                    if hit && e == self.ego && self.hand_over == Some(None) {
                        return Err(HostError(format!(
                            "t = {t:.2} s: the ego collided while the storyboard drove it, \
                             before its ActivateControllerAction handed it to the system under \
                             test: the test says nothing of the system"
                        )));
                    }
                }
                // The measures of the world at `t`, before the storyboard moves it on.
                self.measures = self.sb.measures(self.ego);
                self.sb
                    .step(t, DEFAULT_DT_S)
                    .map_err(|e| HostError(e.to_string()))?;
                // The storyboard's timeline, for the test's record.
                for (kind, name, what) in self.sb.transitions() {
                    self.log
                        .push(format!("t = {t:.3} s: {kind} {name:?} {what}"));
                }
                for said in self.sb.take_said() {
                    self.log.push(format!("t = {t:.3} s: {said}"));
                }
                self.hand_over_if_activated(t);
                // A lane change or a route of the driven ego: the system's new route.
                if let Some(ask) = self.sb.take_route() {
                    let route = route_of(&self.sb, self.ego, [pos[0], pos[2]], &ask);
                    let points = route
                        .iter()
                        .map(|p| Value::Vec3([p[0], 0.0, p[1]]))
                        .collect();
                    self.performed
                        .push((Sink::SetEgoRoute, Value::Tuple(points)));
                    self.log.push(format!(
                        "t = {t:.3} s: the system under test is given a new route ({} points, \
                         joining its lane {:.1} m ahead)",
                        route.len(),
                        ask.ahead_m
                    ));
                }
                // A SpeedAction on the driven ego: the system under test's set speed.
                let asked = (self.sb.set_speed())
                    .or(self.ego_speed_mps)
                    .filter(|_| !self.sb.actors[self.ego].scripted);
                if asked.is_some() && asked != self.asked {
                    self.asked = asked;
                    self.performed
                        .push((Sink::SetEgoSpeed, Value::Num(asked.unwrap_or(0.0))));
                }
                self.most_asked_mps = self.most_asked_mps.max(asked.unwrap_or(0.0));
                if self.sb.ended && !self.scripted_ego {
                    self.check_the_ego_moved(t, "the storyboard ended")?;
                }
                self.note_unplayed(t);
                if !self.scripted_ego {
                    self.check_the_storyboard_can_go_on(t)?;
                }
                for (e, sink) in self.sinks.iter().enumerate() {
                    if let Some(sink) = sink {
                        // Where the storyboard puts it, and its speed there (a teleport's
                        // step keeps the entity's speed, as esmini reports it).
                        let (p, h) = self.sb.engine_pose(e);
                        let v = self.sb.actors[e].state.speed;
                        self.performed.push((
                            *sink,
                            Value::Tuple(vec![Value::Vec3(p), Value::Num(h), Value::Num(v)]),
                        ));
                    }
                }
                self.perform_presence();
                Ok(Value::Unit)
            }
            1 => Ok(Value::Num(self.measures.0)),
            2 => Ok(Value::Num(self.measures.1)),
            3 => Ok(Value::Num(self.measures.2)),
            k @ (LIGHT_FN | FOG_FN | FRICTION_FN) => Ok(Value::Num(self.environment(k, args))),
            _ => Err(HostError(format!("no host function {f}"))),
        }
    }

    fn performed(&mut self) -> Vec<(Sink, Value)> {
        std::mem::take(&mut self.performed)
    }

    fn reads(&self) -> &[StreamId] {
        &self.reads
    }

    fn ended(&self) -> bool {
        self.sb.ended || self.road_end.is_some()
    }

    /// At the horizon, with the storyboard not ended: an error when an act or event still
    /// waits to start (the horizon cut the test before it played what the file describes),
    /// or when the driven ego never moved ([`StoryHost::check_the_ego_moved`]).
    fn finish(&mut self, t_s: f64) -> Result<(), HostError> {
        let waiting = self.sb.never_started();
        if !waiting.is_empty() {
            return Err(HostError(format!(
                "t = {t_s:.2} s: the horizon came before the storyboard ended, and {} never \
                 started: the test did not play what the file describes, so it cannot \
                 count as a pass (give a longer --horizon, or let the storyboard's stop \
                 trigger end it)",
                waiting.join(", ")
            )));
        }
        if self.scripted_ego || self.sb.actors[self.ego].scripted {
            return Ok(());
        }
        self.check_the_ego_moved(t_s, "the horizon came")
    }

    fn log(&mut self) -> Vec<String> {
        std::mem::take(&mut self.log)
    }
}

/// The sinks that move each entity (none for the ego), each entity's `Collided` probe, and
/// each entity's actor, in the file's order.
type Placed = (Vec<Option<Sink>>, Vec<StreamId>, Vec<ActorRef>);

/// The entity that tows entity `e` from the start ([`m::Entity::trailer`]), if any.
fn tow_of(model: &m::Scenario, e: usize) -> Option<usize> {
    model.entities.iter().position(|t| t.trailer == Some(e))
}

/// Declares every entity of `model` into `scene` where the storyboard's `Init` put it: the
/// ego as the ego vehicle (placed later), pedestrians as pedestrians, other entities as cars,
/// each standing still until the storyboard moves it.
///
/// # Errors
/// [`ScenarioError::Load`] when the scene refuses an actor.
fn place_entities(
    scene: &mut Scene,
    model: &m::Scenario,
    sb: &Storyboard,
    ego: usize,
) -> Result<Placed, ScenarioError> {
    let zero = scene.push(Node::Const(Value::Num(0.0)));
    let mut sinks = Vec::new();
    let mut probes = Vec::new();
    let mut actors = Vec::new();
    // Each entity's car in the world ([`paracosm_engine::WorldSpec::cars`]): cars are
    // declared in the entities' order, after the ones already in the scene.
    let base = (scene.actors().iter())
        .filter(|a| matches!(a.actor, ActorRef::Car(_)))
        .count();
    let mut car_index = vec![None; model.entities.len()];
    let cars = (0..model.entities.len())
        .filter(|&i| i != ego && !matches!(model.entities[i].kind, EntityKind::Pedestrian(_)));
    for (k, i) in cars.enumerate() {
        car_index[i] = Some(base + k);
    }
    for (i, ent) in model.entities.iter().enumerate() {
        let name = ent.name.clone();
        let at = here(&ent.pos, &name);
        if i == ego && (ent.trailer.is_some() || tow_of(model, i).is_some()) {
            return Err(worlds_error(format!(
                "{}: the ego {name:?} {} a trailer, which paracosm does not test: its ego is \
                 one vehicle, whose collisions, separation and time to collision would count \
                 its own combination. Name a vehicle without a trailer with --ego",
                ent.pos,
                if ent.trailer.is_some() { "tows" } else { "is" }
            )));
        }
        let (pos, heading) = sb.engine_pose(i);
        let size = Size {
            length_m: ent.dimensions_m[0].max(0.1),
            width_m: ent.dimensions_m[1].max(0.1),
            height_m: ent.dimensions_m[2].max(0.1),
        };
        let actor = if i == ego {
            scene.declare_ego(name.clone(), at)
        } else if matches!(ent.kind, EntityKind::Pedestrian(_)) {
            let a = scene.declare_pedestrian(name.clone(), at);
            scene
                .place_pedestrian(
                    a,
                    PedestrianSpec {
                        start: pos,
                        // Never walked to (the storyboard places it): it faces its Init
                        // heading from t = 0.
                        target: [pos[0] + heading.cos(), pos[1], pos[2] - heading.sin()],
                        speed: zero,
                        initial_speed_mps: sb.actors[i].state.speed.max(0.0),
                        name: format!("Pedestrian {name} ({})", ent.pos),
                    },
                )
                .map_err(|e| worlds_error(e.to_string()))?;
            a
        } else {
            let a = scene.declare_car(name.clone(), at);
            let ahead = [pos[0] + 0.5 * heading.cos(), pos[2] - 0.5 * heading.sin()];
            // Its speed stream is read only before the first step, where a car enters the
            // test at its speed: the Init's (the storyboard places it at every step).
            let init_speed = sb.actors[i].state.speed.max(0.0);
            let speed = if init_speed == 0.0 {
                zero
            } else {
                scene.push(Node::Const(Value::Num(init_speed)))
            };
            scene
                .place_car(
                    a,
                    CarSpec {
                        path: vec![[pos[0], pos[2]], ahead],
                        speed,
                        color: "white".to_owned(),
                        size,
                        enabled: true,
                        lane_change: None,
                        lane_offsets_m: vec![],
                        name: format!("Car {name} ({})", ent.pos),
                        keep_distance_m: None,
                        tow: tow_of(model, i).and_then(|t| car_index[t]),
                    },
                )
                .map_err(|e| worlds_error(e.to_string()))?;
            a
        };
        sinks.push(match actor {
            ActorRef::Car(h) => Some(Sink::PlaceCar(h)),
            ActorRef::Pedestrian(h) => Some(Sink::PlacePedestrian(h)),
            _ => None,
        });
        probes.push(scene.probe(actor, Output::Collided));
        actors.push(actor);
    }
    Ok((sinks, probes, actors))
}
