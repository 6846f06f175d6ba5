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

    /// The fog density `[0, 1]` of the visual range `V` (`None`: not set): the inverse of
    /// [`paracosm_engine::visibility_m`] (Koschmieder's `V = 3.912 / σ`, `σ = fog ·`
    /// [`paracosm_engine::FOG_EXTINCTION_PER_M`]), clipped to `[0, 1]` (a range under
    /// 7.8 m is paracosm's densest fog).
    pub fn fog(&self) -> Option<f64> {
        self.visual_range_m
            .map(|v| (3.912 / (v * paracosm_engine::FOG_EXTINCTION_PER_M)).clamp(0.0, 1.0))
    }

    /// The road's friction coefficient: [`MAP_FRICTION`] times the friction scale factor
    /// (`None`: not set).
    pub fn friction(&self) -> Option<f64> {
        self.friction_scale.map(|f| MAP_FRICTION * f)
    }
}

impl Storyboard {
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
