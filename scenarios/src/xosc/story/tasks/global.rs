//! Global actions: `EnvironmentAction` sets the world's light, fog and road friction
//! ([`WorldEnv`]); `AddEntityAction` and `DeleteEntityAction` put an entity into the
//! scenario or take it out ([`Actor::present`]); `ParameterSetAction`, `ParameterModifyAction`, `VariableSetAction` and
//! `VariableModifyAction` change the values that `ParameterCondition` and
//! `VariableCondition` read.

use paracosm_openscenario::model::Environment;
use paracosm_openscenario::params::ParamType;
use paracosm_openscenario::Value as XValue;

use super::super::*;

/// The illuminance at which paracosm's light is nominal ([`paracosm_engine::NOMINAL_LIGHT`],
/// where a camera's fixed exposure is calibrated), lux: direct sunlight is 32,000–100,000 lx.
pub const NOMINAL_ILLUMINANCE_LX: f64 = 50_000.0;

/// The road friction coefficient of an OpenSCENARIO map before any `RoadCondition` scales
/// it (dry asphalt).
pub const MAP_FRICTION: f64 = 0.8;

/// A parameter's or variable's declared type and value now, as text
/// ([`XValue::to_text`]).
#[derive(Debug, Clone)]
pub struct Stored {
    /// Its name.
    pub name: String,
    /// Its declared type.
    pub ty: ParamType,
    /// Its value now.
    pub text: String,
}

/// The world's environment as the storyboard's `EnvironmentAction`s have set it: each part
/// `None` until one sets it (the world's own default holds).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WorldEnv {
    /// The time of day, s after midnight, at simulated time `.1` (s), running on with it
    /// when `.2` (`animation`).
    pub time_of_day: Option<(f64, f64, bool)>,
    /// The sun: illuminance, lux, and elevation, rad.
    pub sun: Option<(f64, f64)>,
    /// The fog's visual range, m.
    pub visual_range_m: Option<f64>,
    /// The precipitation: its type (`dry`, `rain`, `snow`) and intensity, mm/h.
    pub precipitation: Option<(String, f64)>,
    /// The factor on the road's friction.
    pub friction_scale: Option<f64>,
}

impl WorldEnv {
    /// Takes the parts of `env` that it gives, set at simulated time `t` (s).
    pub fn apply(&mut self, env: &Environment, t: f64) {
        if let Some((secs, animation)) = env.time_of_day {
            self.time_of_day = Some((secs, t, animation));
        }
        if env.sun.is_some() {
            self.sun = env.sun;
        }
        if env.fog_visual_range_m.is_some() {
            self.visual_range_m = env.fog_visual_range_m;
        }
        if env.precipitation.is_some() {
            self.precipitation.clone_from(&env.precipitation);
        }
        if env.friction_scale.is_some() {
            self.friction_scale = env.friction_scale;
        }
    }

    /// The light at simulated time `t` (s), `[0, 1]` (`None`: no action has set it):
    /// `0.5 · E / E₀` clipped to `[0, 1]`, with `E₀` = [`NOMINAL_ILLUMINANCE_LX`] and `E` the
    /// sun's illuminance while its elevation is above 0 (0 below the horizon), else, from
    /// the time of day `h` (hours), `E₀ · max(0, sin(π (h − 6) / 12))`: dark from 18:00 to
    /// 6:00, nominal at noon.
    pub fn light(&self, t: f64) -> Option<f64> {
        let lux = match (self.sun, self.time_of_day) {
            (Some((lux, elevation)), _) => {
                if elevation > 0.0 {
                    lux
                } else {
                    0.0
                }
            }
            (None, Some((secs, at, animation))) => {
                let now = if animation { secs + (t - at) } else { secs };
                let h = now.rem_euclid(86_400.0) / 3600.0;
                NOMINAL_ILLUMINANCE_LX * (std::f64::consts::PI * (h - 6.0) / 12.0).sin().max(0.0)
            }
            (None, None) => return None,
        };
        Some((paracosm_engine::NOMINAL_LIGHT * lux / NOMINAL_ILLUMINANCE_LX).clamp(0.0, 1.0))
    }

    /// The fog density `[0, 1]` of the fog's visual range `V` and the precipitation
    /// (`None`: neither is set): the extinction coefficients add, `σ = 3.912 / V +
    /// σ_precipitation` (1/m, Koschmieder's law for the fog; [`precipitation_extinction_per_m`]),
    /// and the density is the inverse of [`paracosm_engine::visibility_m`] (`σ = fog ·`
    /// [`paracosm_engine::FOG_EXTINCTION_PER_M`]), clipped to `[0, 1]` (a range under 7.8 m
    /// is paracosm's densest fog).
    pub fn fog(&self) -> Option<f64> {
        if self.visual_range_m.is_none() && self.precipitation.is_none() {
            return None;
        }
        let fog = self.visual_range_m.map_or(0.0, |v| 3.912 / v);
        let wet = (self.precipitation.as_ref())
            .map_or(0.0, |(kind, mm)| precipitation_extinction_per_m(kind, *mm));
        Some(((fog + wet) / paracosm_engine::FOG_EXTINCTION_PER_M).clamp(0.0, 1.0))
    }

    /// The road's friction coefficient: [`MAP_FRICTION`] times the friction scale factor
    /// (`None`: not set).
    pub fn friction(&self) -> Option<f64> {
        self.friction_scale.map(|f| MAP_FRICTION * f)
    }
}

/// The wavelength the camera's visibility is taken at, nm: green light, where the eye and a
/// camera are most sensitive (the meteorological visual range is defined for it).
pub const VISIBLE_WAVELENGTH_NM: f64 = 550.0;

/// The extinction coefficient of precipitation `kind` (`rain`, `snow`; `dry` and anything
/// else: 0) of intensity `mm_per_h` (mm/h, `>= 0`), 1/m: ITU-R P.1814 (2007), §2, the
/// specific attenuation of free-space optical links, `γ = k·R^α` dB/km: rain `k = 1.076`,
/// `α = 0.67`; snow (dry snow, the stronger) `k = 5.42·10⁻⁵·λ + 5.4958776`, `α = 1.38`, at
/// `λ` = [`VISIBLE_WAVELENGTH_NM`]; converted as `σ = γ / (10·log₁₀e) / 1000`. For example,
/// 1 mm/h of rain is 2.5·10⁻⁴ /m (a visual range of 16 km alone), 25 mm/h 2.1·10⁻³ /m
/// (1.8 km), and 1 mm/h of snow 1.3·10⁻³ /m (3.1 km). Streaks, spray, drops on the lens and
/// a wet road's reflections are not modelled.
pub fn precipitation_extinction_per_m(kind: &str, mm_per_h: f64) -> f64 {
    let r = mm_per_h.max(0.0);
    let db_per_km = match kind {
        "rain" => 1.076 * r.powf(0.67),
        "snow" => (5.42e-5 * VISIBLE_WAVELENGTH_NM + 5.495_877_6) * r.powf(1.38),
        _ => 0.0,
    };
    db_per_km / (10.0 * std::f64::consts::LOG10_E) / 1000.0
}

impl Storyboard {
    /// The state traffic signal `signal` (an id or name) shows now, as the storyboard's
    /// actions last set it; `None` before one does.
    pub(in crate::xosc::story) fn signal_state(&self, signal: &str) -> Option<&str> {
        (self.signals.iter())
            .find(|(s, _)| s == signal)
            .map(|(_, st)| st.as_str())
    }

    /// Checks that every traffic signal the storyboard's conditions name is a signal of the
    /// map (by its id, or its name), as [`Storyboard::check_references`] checks the actions'.
    ///
    /// # Errors
    /// [`StoryError`] at the first condition that names a signal the map does not have.
    pub(in crate::xosc::story) fn check_signals(&self) -> Result<(), StoryError> {
        for c in self.triggers.iter().flatten().flatten() {
            if let ConditionKind::TrafficSignal { signal, .. } = &c.cond.kind {
                if let Some(message) = self.signal_missing(signal) {
                    return Err(StoryError {
                        at: site(&c.cond.pos),
                        message: format!("TrafficSignalCondition {:?}: {message}", c.cond.name),
                    });
                }
            }
        }
        Ok(())
    }

    /// Why the map does not have traffic signal `signal` (its `<signal>` id, or its name),
    /// naming the signals it has; `None` when it has it.
    pub(in crate::xosc::story) fn signal_missing(&self, signal: &str) -> Option<String> {
        let signals = &self.roads.map().signals;
        if signals
            .iter()
            .any(|(id, name)| id == signal || name == signal)
        {
            return None;
        }
        let ids: Vec<&str> = signals.iter().map(|(id, _)| id.as_str()).take(20).collect();
        Some(format!(
            "the map {} has no traffic signal {signal:?} (its signals' ids: {})",
            self.roads.map().source,
            if ids.is_empty() {
                "none".to_string()
            } else {
                ids.join(", ")
            }
        ))
    }

    /// Performs a global action (`action.action.is_global()`) at simulated time `t` (s).
    ///
    /// # Errors
    /// [`StoryError`] at the action when a modification's result is not of the value's
    /// declared type (an `int` multiplied by 0.5, a result out of its range).
    pub(in crate::xosc::story) fn perform_global(
        &mut self,
        action: &m::NamedAction,
        t: f64,
    ) -> Result<(), StoryError> {
        let (name, variable, new) = match &action.action {
            Action::Environment(env) => {
                self.env.apply(env, t);
                return Ok(());
            }
            Action::TrafficSignalState { signal, state } => {
                // `Init`'s are performed as the storyboard is built: checked here.
                if let Some(message) = self.signal_missing(signal) {
                    return Err(StoryError {
                        at: site(&action.pos),
                        message: format!("TrafficSignalStateAction {:?}: {message}", action.name),
                    });
                }
                match self.signals.iter_mut().find(|(s, _)| s == signal) {
                    Some(s) => s.1.clone_from(state),
                    None => self.signals.push((signal.clone(), state.clone())),
                }
                return Ok(());
            }
            // As esmini's `AddEntityAction::Start`: an entity in the scenario stays where it
            // is ("already active").
            Action::AddEntity { entity, position } => {
                if !self.actors[*entity].present {
                    self.teleport(*entity, position, &action.pos)?;
                    let st = &mut self.actors[*entity].state;
                    st.vel = [st.speed * st.pose.h.cos(), st.speed * st.pose.h.sin()];
                    self.actors[*entity].present = true;
                }
                return Ok(());
            }
            Action::DeleteEntity { entity } => {
                self.actors[*entity].present = false;
                return Ok(());
            }
            Action::SetValue {
                name,
                variable,
                value,
            } => (name, *variable, Ok(value.clone())),
            Action::ModifyValue {
                name,
                variable,
                multiply,
                by,
            } => {
                let store = if *variable {
                    &self.variables
                } else {
                    &self.params
                };
                let Some(now) = store.iter().find(|s| s.name == *name) else {
                    return Ok(());
                };
                let x: f64 = now.text.trim().parse().unwrap_or(f64::NAN);
                let y = if *multiply { x * by } else { x + by };
                (
                    name,
                    *variable,
                    now.ty.coerce(XValue::Num(y)).map_err(|e| e.0),
                )
            }
            _ => return Ok(()),
        };
        let store = if variable {
            &mut self.variables
        } else {
            &mut self.params
        };
        if let Some(s) = store.iter_mut().find(|s| s.name == *name) {
            let value = new.map_err(|message| StoryError {
                at: site(&action.pos),
                message: format!(
                    "{} {:?} on {name}: {message}",
                    action.action.kind_name(),
                    action.name
                ),
            })?;
            s.text = value.to_text();
        }
        Ok(())
    }

    /// The world's environment as the storyboard's `EnvironmentAction`s have set it.
    pub fn environment(&self) -> &WorldEnv {
        &self.env
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Precipitation thins the air as ITU-R P.1814 gives it: 1 mm/h of rain alone leaves a
    /// visual range of 15.8 km, 25 mm/h 1.83 km, 1 mm/h of dry snow 3.08 km; its extinction
    /// adds to the fog's; dry air and no precipitation add none.
    #[test]
    fn precipitation_adds_its_extinction_to_the_fogs() {
        let range = |kind: &str, mm: f64| 3.912 / precipitation_extinction_per_m(kind, mm);
        assert!(
            (range("rain", 1.0) - 15_790.0).abs() < 10.0,
            "{}",
            range("rain", 1.0)
        );
        assert!(
            (range("rain", 25.0) - 1_827.0).abs() < 5.0,
            "{}",
            range("rain", 25.0)
        );
        assert!(
            (range("snow", 1.0) - 3_075.0).abs() < 5.0,
            "{}",
            range("snow", 1.0)
        );
        assert_eq!(precipitation_extinction_per_m("dry", 5.0), 0.0);
        assert_eq!(precipitation_extinction_per_m("rain", 0.0), 0.0);
        let mut w = WorldEnv::default();
        w.apply(
            &Environment {
                precipitation: Some(("rain".into(), 25.0)),
                ..Environment::default()
            },
            0.0,
        );
        let rain_only = w.fog().expect("rain sets the fog density");
        assert!((paracosm_engine::visibility_m(rain_only) - 1_827.0).abs() < 5.0);
        w.apply(
            &Environment {
                fog_visual_range_m: Some(200.0),
                ..Environment::default()
            },
            0.0,
        );
        let both = paracosm_engine::visibility_m(w.fog().unwrap());
        let expected = 3.912 / (3.912 / 200.0 + precipitation_extinction_per_m("rain", 25.0));
        assert!((both - expected).abs() < 1e-6 && both < 200.0, "{both} m");
    }

    #[test]
    fn the_environments_light_fog_and_friction_follow_their_formulas() {
        let mut w = WorldEnv::default();
        assert_eq!((w.light(0.0), w.fog(), w.friction()), (None, None, None));
        w.apply(
            &Environment {
                time_of_day: Some((12.0 * 3600.0, false)),
                fog_visual_range_m: Some(3.912 / 0.25),
                friction_scale: Some(0.5),
                ..Environment::default()
            },
            0.0,
        );
        assert!(
            (w.light(100.0).unwrap() - 0.5).abs() < 1e-12,
            "nominal at noon"
        );
        assert!(
            (w.fog().unwrap() - 0.5).abs() < 1e-12,
            "visibility_m's inverse"
        );
        assert!((paracosm_engine::visibility_m(w.fog().unwrap()) - 3.912 / 0.25).abs() < 1e-9);
        assert!((w.friction().unwrap() - 0.4).abs() < 1e-12);
        // Six hours later on an animated clock: 18:00, dark.
        w.apply(
            &Environment {
                time_of_day: Some((12.0 * 3600.0, true)),
                ..Environment::default()
            },
            10.0,
        );
        assert!(w.light(10.0 + 6.0 * 3600.0).unwrap().abs() < 1e-9);
        assert!((w.light(10.0 + 3.0 * 3600.0).unwrap() - 0.5 * 0.5f64.sqrt()).abs() < 1e-9);
        // A sun overrides the clock; below the horizon it gives no light.
        w.apply(
            &Environment {
                sun: Some((100_000.0, 0.3)),
                ..Environment::default()
            },
            0.0,
        );
        assert_eq!(w.light(0.0), Some(1.0));
        w.apply(
            &Environment {
                sun: Some((100_000.0, -0.1)),
                ..Environment::default()
            },
            0.0,
        );
        assert_eq!(w.light(0.0), Some(0.0));
    }
}
