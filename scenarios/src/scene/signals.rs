//! The signals a scene publishes to its monitors, and the checks that every signal a
//! monitor reads is published, named without clashes, and present in the test.

use paracosm_engine::behaviour::{ActorRef, GraphBuilder, Output, Probe};
use paracosm_engine::rx::{Node, StreamId};

use super::{LoadError, LoadErrorKind, SType, Scene, Site};

/// The outputs of an actor that `Stl` formulas may read as `<variable>.<output>`.
const ACTOR_SIGNALS: [(&str, Output); 7] = [
    ("pos", Output::Pos),
    ("vel", Output::Vel),
    ("speed", Output::Speed),
    ("heading", Output::Heading),
    ("collision", Output::Collision),
    ("collided", Output::Collided),
    ("separation", Output::Separation),
];

/// Whether `s` names a published signal of `out` (whose streams carry vectors as `vector`
/// says): a stream of numbers or bools by its name, a vector's component by `name.x`, `.y`,
/// `.z`.
///
/// # Errors
/// A vector named whole, or a component of a number.
fn known_signal(
    out: &[(String, StreamId)],
    vector: &[Option<bool>],
    s: &str,
) -> Result<bool, LoadError> {
    if super::builtin_signals::ALL.contains(&s) {
        return Ok(true);
    }
    for ((n, _), v) in out.iter().zip(vector) {
        let component = s
            .strip_prefix(n.as_str())
            .is_some_and(|c| [".x", ".y", ".z"].contains(&c));
        match (n == s, component, v) {
            (true, _, Some(true)) => {
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "`{s}` is a vector: a formula compares numbers, so write `{s}.x`, \
                     `{s}.y` or `{s}.z`"
                    ),
                ))
            }
            (false, true, Some(false)) => {
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "`{n}` is a number, with no component `{}`: write `{n}`",
                        &s[n.len() + 1..]
                    ),
                ))
            }
            (true, _, _) | (_, true, _) => return Ok(true),
            _ => {}
        }
    }
    Ok(false)
}

impl Scene {
    /// Refuses a world in which a monitor reads the outputs of a car this world leaves out
    /// (`Car(enabled = False)`): such a car is not in the test, its outputs carry no events, and
    /// the monitor would have nothing to judge. A stream depends on a car when the car's probe
    /// feeds it through any input but a `takeUntil`'s stop (a stop that never fires cuts
    /// nothing).
    ///
    /// # Errors
    /// A message naming the monitor, the car, how to read an optional car, and the monitor's
    /// `file:line:col`.
    pub(crate) fn refuse_monitors_of_absent_cars(
        &self,
        nodes: &[Node],
        published: &[(String, StreamId)],
    ) -> Result<(), LoadError> {
        let absent: Vec<usize> = self
            .cars()
            .values()
            .enumerate()
            .filter(|(_, c)| !c.enabled)
            .map(|(i, _)| i)
            .collect();
        if absent.is_empty() {
            return Ok(());
        }
        // The absent car each stream depends on, in topological order (a node's inputs come
        // before it).
        let mut reads: Vec<Option<usize>> = vec![None; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            reads[i] = match node {
                Node::Probe(p) => match p.actor {
                    ActorRef::Car(c) if absent.contains(&c.index()) => Some(c.index()),
                    _ => None,
                },
                Node::TakeUntil { src, .. } => reads.get(src.0).copied().flatten(),
                other => other
                    .inputs()
                    .iter()
                    .find_map(|s| reads.get(s.0).copied().flatten()),
            };
        }
        for (name, id) in published {
            let Some(car) = reads.get(id.0).copied().flatten() else {
                continue;
            };
            let reader = self.monitors().find(|(m, _)| {
                m.signals().iter().any(|s| {
                    s == name
                        || s.strip_prefix(name.as_str())
                            .is_some_and(|c| [".x", ".y", ".z"].contains(&c))
                })
            });
            if let Some((m, at)) = reader {
                let car_name = self.car_name(car).unwrap_or("a Car");
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                    "monitor `{}` reads {car_name}, which this world leaves out (enabled = False): \
                     the car is not in the test, its outputs have no events, and the monitor \
                     would have nothing to judge. For a car that is in some tests only, read it \
                     in a lambda through a top-level variable (`lead_speed = lead.speed`), which \
                     is None while the car is absent, and judge a stream that always fires \
                     (`tick.map(...)`)\n --> {at}",
                    m.name()
                ),
                ));
            }
        }
        Ok(())
    }

    /// Checks that every signal a monitor reads is published by the runner, the program or an
    /// actor (see [`world`]).
    ///
    /// # Errors
    /// A message naming the signal, what is published, and the monitor's `file:line:col`.
    pub fn check_signals(&self) -> Result<(), LoadError> {
        self.published(&mut self.graph().clone()).map(|_| ())
    }

    /// Refuses a `Signal` named as an actor's output (`Signal("lead.speed", ...)`: a formula
    /// reading `lead.speed` would read the Signal in the car's place) or as a component another
    /// `Signal` gives itself (`Signal("lp", lead.pos)` publishes `lp.x`, `lp.y` and `lp.z`).
    fn check_signal_names(&self) -> Result<(), LoadError> {
        let signals_at: Vec<(&String, &Site)> = self
            .signals()
            .iter()
            .filter_map(|s| Some((&s.name, s.site.as_ref()?)))
            .collect();
        // A Signal may not take an actor output's name (`Signal("lead.speed", ...)`): a formula
        // reading `lead.speed` would read the Signal in the car's place.
        for &(name, at) in &signals_at {
            let mut parts = name.split('.');
            let (Some(var), Some(field)) = (parts.next(), parts.next()) else {
                continue;
            };
            let actor = self
                .actors()
                .iter()
                .find(|o| o.site.variable.as_deref() == Some(var));
            if let (Some(o), true) = (actor, ACTOR_SIGNALS.iter().any(|(n, _)| *n == field)) {
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "Signal `{name}` takes the name of an output of {} (`{var}.{field}`), which \
                     monitors read as that actor's; give the Signal another name\n --> {at}",
                        o.name
                    ),
                ));
            }
        }
        // Nor the name of a component another Signal gives itself (`Signal("lp", lead.pos)`
        // publishes `lp.x`, `lp.y` and `lp.z`): one would hide the other.
        for (k, &(name, at)) in signals_at.iter().enumerate() {
            let whole = signals_at[..k].iter().find(|&&(other, _)| {
                [".x", ".y", ".z"]
                    .iter()
                    .any(|c| *name == format!("{other}{c}") || *other == format!("{name}{c}"))
            });
            if let Some(&(other, first)) = whole {
                let (vector, component) = if name.len() > other.len() {
                    (other, name)
                } else {
                    (name, other)
                };
                return Err(LoadError::new(
                    LoadErrorKind::Declarations,
                    format!(
                        "Signal `{name}` and Signal `{other}` (declared at {first}) clash: a vector \
                     Signal `{vector}` is published as `{vector}.x`, `{vector}.y` and `{vector}.z`, \
                     so `{component}` would read one of them; give one another name\n --> {at}"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The streams published to the monitors: those the program published (`Monitor`, `Assert`,
    /// `Signal`), then each actor output a monitor reads by name (`lead.speed`, `p.pos.x`), as a
    /// probe added to `graph`.
    ///
    /// # Errors
    /// A message naming a signal a monitor reads that is neither the runner's, the program's nor
    /// an actor's.
    pub(crate) fn published(
        &self,
        graph: &mut GraphBuilder,
    ) -> Result<Vec<(String, StreamId)>, LoadError> {
        self.check_signal_names()?;
        let mut out: Vec<(String, StreamId)> = self
            .signals()
            .iter()
            .map(|s| (s.name.clone(), s.stream))
            .collect();
        // Whether each published stream carries vectors: `Some(true)` it does, `Some(false)` it
        // carries numbers or bools, `None` unknown until the test runs (a lambda's values; the
        // check at load looks at its sample, `program::judged_kinds`).
        let types = self.stream_types();
        let mut vector: Vec<Option<bool>> = out
            .iter()
            .map(|(_, id)| match types.get(id.0) {
                Some(SType::Vec3) => Some(true),
                Some(SType::Any) | None => None,
                Some(_) => Some(false),
            })
            .collect();
        // Whether `s` names a published signal: a stream of numbers or bools by its name, a
        // vector's component by `name.x`, `.y`, `.z`; a vector named whole, or a component of a
        // number, is an error.
        let known = known_signal;
        for (m, at) in self.monitors() {
            let located = |e: String| {
                LoadError::new(
                    LoadErrorKind::Declarations,
                    format!("{} reads the signal: {e}\n --> {at}", m.name()),
                )
            };
            for s in m.signals() {
                if known(&out, &vector, &s).map_err(|e| located(e.message))? {
                    continue;
                }
                let found = s.split_once('.').and_then(|(var, rest)| {
                    let actor = self.actor_of_variable(var)?;
                    let field = rest.split('.').next()?;
                    let (_, output) = ACTOR_SIGNALS.iter().find(|(n, _)| *n == field)?;
                    Some((format!("{var}.{field}"), actor, *output))
                });
                match found {
                    Some((name, actor, output)) => {
                        let id = graph.push(Node::Probe(Probe::new(actor, output)));
                        out.push((name.clone(), id));
                        vector.push(Some(matches!(output, Output::Pos | Output::Vel)));
                        if !known(&out, &vector, &s).map_err(|e| located(e.message))? {
                            return Err(located(format!(
                                "`{s}` is no output of `{name}`; an actor's outputs are .pos.x, \
                                 .pos.y, .pos.z, .vel.x, .vel.y, .vel.z, .speed, .heading, \
                                 .collision, .collided and .separation"
                            )));
                        }
                    }
                    None => {
                        let actors: Vec<&str> = self
                            .actors()
                            .iter()
                            .filter_map(|o| o.site.variable.as_deref())
                            .collect();
                        let mine: Vec<&str> = self
                            .signals()
                            .iter()
                            .map(|s| s.name.as_str())
                            .filter(|n| !n.starts_with("monitor:"))
                            .collect();
                        return Err(LoadError::new(
                            LoadErrorKind::Declarations,
                            format!(
                            "monitor `{}` reads the signal `{s}`, which nothing publishes. The runner \
                             publishes {}; the program's Signal(...)s: {}; each actor assigned to a \
                             variable at the top level publishes <variable>.pos.x/.y/.z, .vel.x/.y/.z, \
                             .speed, .heading and .collision (actors: {})\n --> {at}",
                            m.name(),
                            super::builtin_signals::ALL.join(", "),
                            if mine.is_empty() {
                                "none".to_owned()
                            } else {
                                mine.join(", ")
                            },
                            if actors.is_empty() {
                                "none".to_owned()
                            } else {
                                actors.join(", ")
                            },
                        ),
                        ));
                    }
                }
            }
        }
        Ok(out)
    }
}
