//! The monitors a scene asks for ([`MonitorSpec`]): the scene model's own vocabulary, which
//! every front end fills and the runner builds into oracles for each test.

use paracosm_oracles::{
    CollisionMonitor, DistanceMonitor, Monitor, OffRoadMonitor, Over, StreamMonitor,
    TimeToFailureMonitor,
};

use super::builtin_signals as signal;

/// A monitor a scenario asks for, built fresh for each test.
#[derive(Debug, Clone, PartialEq)]
pub enum MonitorSpec {
    /// `CollisionMonitor(v)`: no contact between the ego vehicle and a pedestrian or a car.
    /// Robustness: minimum separation in metres.
    Collision {
        /// Key in results files, default `collision`.
        name: String,
    },
    /// `DistanceMonitor(v, minD)`: the ego vehicle travels at least `min_distance_m` metres.
    /// Robustness: `D - minD` in metres.
    Distance {
        /// Key in results files, default `distance`.
        name: String,
        /// `minD`, in metres.
        min_distance_m: f64,
    },
    /// `OffRoadMonitor(v)`: the ego vehicle's footprint centre stays on the driving surface.
    /// Robustness: the smallest signed distance to the surface's edge, in metres.
    OffRoad {
        /// Key in results files, default `offroad`.
        name: String,
        /// Added by default to a program that declares none (LANGUAGE.md, "Monitors"): it
        /// judges every test, but steers a falsifier only once it fails (see
        /// [`Scenario::passive_monitors`]).
        implicit: bool,
    },
    /// `Stl(formula)`: a signal temporal logic property of the runner's signals
    /// ([`paracosm_oracles::stl`]), judged at time 0 and settled online.
    Stl {
        /// Key in results files, default `stl`.
        name: String,
        /// The formula's text (parsed when the program loads).
        formula: String,
    },
    /// `Monitor(stream, name=, unit=, over=)`: a user-written monitor whose robustness is the
    /// stream's value taken `over` the test ([`paracosm_oracles::StreamMonitor`]).
    Stream {
        /// Key in results files.
        name: String,
        /// The runner's signal carrying the stream's values
        /// ([`paracosm_engine::WorldSpec::published`]).
        signal: String,
        /// The values' unit, as the program gave it (for reports).
        unit: Option<String>,
        /// How the values become one robustness.
        over: Over,
    },
    /// `Assert(stream_of_bool, name=)`: the stream's truth value must hold at every event;
    /// robustness `±1`.
    Assert {
        /// Key in results files.
        name: String,
        /// The runner's signal carrying the stream's values.
        signal: String,
    },
    /// `TimeToFailure(m, minT)`: `m` first fails no earlier than `min_s` seconds.
    /// Robustness in seconds (see [`TimeToFailureMonitor`]).
    TimeToFailure {
        /// Key in results files, default `time_to_failure`.
        name: String,
        /// The wrapped monitor.
        inner: Box<MonitorSpec>,
        /// `minT`, seconds.
        min_s: f64,
    },
}

impl MonitorSpec {
    /// The name of a `Monitor` or an `Assert` (also when wrapped in `TimeToFailure`) and the
    /// signal of the stream it judges, with whether that must carry bools (`Assert`) rather
    /// than numbers (`Monitor`); `None` for the other monitors.
    pub fn judged_stream(&self) -> Option<(&str, &str, bool)> {
        match self {
            MonitorSpec::Stream { name, signal, .. } => Some((name, signal, false)),
            MonitorSpec::Assert { name, signal } => Some((name, signal, true)),
            MonitorSpec::TimeToFailure { inner, .. } => inner.judged_stream(),
            _ => None,
        }
    }

    /// `CollisionMonitor` named `collision`.
    pub fn collision() -> Self {
        MonitorSpec::Collision {
            name: "collision".into(),
        }
    }

    /// `DistanceMonitor` named `distance`.
    pub fn distance(min_distance_m: f64) -> Self {
        MonitorSpec::Distance {
            name: "distance".into(),
            min_distance_m,
        }
    }

    /// The default `OffRoadMonitor` every program gets unless it declares one or opts out.
    pub fn implicit_off_road() -> Self {
        MonitorSpec::OffRoad {
            name: "offroad".into(),
            implicit: true,
        }
    }

    /// Whether it judges leaving the road (an `OffRoadMonitor`, wrapped or not).
    pub fn judges_off_road(&self) -> bool {
        match self {
            MonitorSpec::OffRoad { .. } => true,
            MonitorSpec::TimeToFailure { inner, .. } => inner.judges_off_road(),
            _ => false,
        }
    }

    /// Whether it can fail a car that stops and waits: a `DistanceMonitor`, or the program's
    /// own `Monitor`, `Assert` or `Stl` (which may check progress; paracosm cannot tell). A
    /// `CollisionMonitor` or an `OffRoadMonitor`, wrapped in `TimeToFailure` or not, cannot:
    /// a car that never moves never collides and never leaves the road.
    pub fn can_fail_a_stopped_car(&self) -> bool {
        match self {
            MonitorSpec::Collision { .. } | MonitorSpec::OffRoad { .. } => false,
            MonitorSpec::TimeToFailure { inner, .. } => inner.can_fail_a_stopped_car(),
            MonitorSpec::Distance { .. }
            | MonitorSpec::Stl { .. }
            | MonitorSpec::Stream { .. }
            | MonitorSpec::Assert { .. } => true,
        }
    }

    /// Whether it reads the runner's signal `name` (an `Stl` formula naming it).
    pub fn reads_signal(&self, name: &str) -> bool {
        self.signals().iter().any(|s| s == name)
    }

    /// The runner's signals it reads, by name: an `Stl` formula's, a user monitor's stream.
    pub fn signals(&self) -> Vec<String> {
        match self {
            MonitorSpec::Stl { formula, .. } => paracosm_oracles::stl::parse(formula)
                .map(|f| f.signals())
                .unwrap_or_default(),
            MonitorSpec::Stream { signal, .. } | MonitorSpec::Assert { signal, .. } => {
                vec![signal.clone()]
            }
            MonitorSpec::TimeToFailure { inner, .. } => inner.signals(),
            _ => Vec::new(),
        }
    }

    /// Whether the monitor it builds ([`MonitorSpec::build`]) reads the runner's signal
    /// `name` (see [`super::builtin_signals`]): the built-in monitors their own, an `Stl`
    /// formula or a user monitor those it names.
    pub fn reads_runner_signal(&self, name: &str) -> bool {
        match self {
            MonitorSpec::Collision { .. } => {
                [signal::EGO_CONTACT, signal::EGO_SEPARATION_M].contains(&name)
            }
            MonitorSpec::Distance { .. } => [signal::EGO_X_M, signal::EGO_Z_M].contains(&name),
            MonitorSpec::OffRoad { .. } => {
                [signal::EGO_OFFROAD, signal::EGO_ROAD_EDGE_M].contains(&name)
            }
            MonitorSpec::TimeToFailure { inner, .. } => inner.reads_runner_signal(name),
            MonitorSpec::Stl { .. } | MonitorSpec::Stream { .. } | MonitorSpec::Assert { .. } => {
                self.reads_signal(name)
            }
        }
    }

    /// Its key in results files.
    pub fn name(&self) -> &str {
        match self {
            MonitorSpec::Collision { name }
            | MonitorSpec::Distance { name, .. }
            | MonitorSpec::OffRoad { name, .. }
            | MonitorSpec::Stl { name, .. }
            | MonitorSpec::Stream { name, .. }
            | MonitorSpec::Assert { name, .. }
            | MonitorSpec::TimeToFailure { name, .. } => name,
        }
    }

    /// A fresh monitor reading the runner's signals (see [`signal`]), for a test of
    /// `horizon_s` seconds: an `Stl` formula's bounds past it are lowered to it
    /// ([`paracosm_oracles::stl::Formula::clamped`]; the verdict is the same, the memory
    /// O(horizon samples)).
    pub fn build(&self, horizon_s: f64) -> Box<dyn Monitor> {
        match self {
            MonitorSpec::Collision { name } => Box::new(CollisionMonitor::new(
                name,
                signal::EGO_CONTACT,
                signal::EGO_SEPARATION_M,
            )),
            MonitorSpec::Distance {
                name,
                min_distance_m,
            } => Box::new(DistanceMonitor::new(
                name,
                signal::EGO_X_M,
                signal::EGO_Z_M,
                *min_distance_m,
            )),
            MonitorSpec::OffRoad { name, .. } => Box::new(OffRoadMonitor::new(
                name,
                signal::EGO_OFFROAD,
                signal::EGO_ROAD_EDGE_M,
            )),
            MonitorSpec::Stl { name, formula } => Box::new(paracosm_oracles::stl::StlMonitor::new(
                name,
                paracosm_oracles::stl::parse(formula)
                    .expect("checked when the program loaded")
                    .clamped(horizon_s)
                    .0,
            )),
            MonitorSpec::Stream {
                name, signal, over, ..
            } => Box::new(StreamMonitor::new(name, signal, *over)),
            MonitorSpec::Assert { name, signal } => {
                Box::new(StreamMonitor::assertion(name, signal))
            }
            MonitorSpec::TimeToFailure { name, inner, min_s } => Box::new(
                TimeToFailureMonitor::new(name, inner.build(horizon_s), *min_s),
            ),
        }
    }
}
