//! The storyboard (OpenSCENARIO 1.3 User Guide, "Storyboard"): `Init`, stories, acts,
//! maneuver groups, maneuvers, events and their triggers.

use std::collections::HashSet;

use roxmltree::Node;

use super::{action, condition, global, Reader};
use crate::error::XoscError;
use crate::model::{
    Act, ConditionKind, Event, Maneuver, ManeuverGroup, NamedAction, Priority, Story, Trigger,
};
use crate::xml::{child, elements, need, only};

/// `Init`'s private actions (entity, action), its global actions, the stories and the stop
/// trigger.
type Storyboard = (
    Vec<(usize, NamedAction)>,
    Vec<NamedAction>,
    Vec<Story>,
    Option<Trigger>,
);

/// The `Storyboard` element: `Init`'s private actions, the stories and the stop trigger.
pub(super) fn read(r: &Reader<'_>, node: Node<'_, '_>) -> Result<Storyboard, XoscError> {
    only(r.text, node, &["Init", "Story", "StopTrigger"])?;
    let mut init = Vec::new();
    let mut init_global = Vec::new();
    let actions = need(r.text, need(r.text, node, "Init")?, "Actions")?;
    for a in elements(actions) {
        if a.tag_name().name() == "GlobalAction" {
            init_global.push(NamedAction {
                name: String::new(),
                pos: r.text.pos(a),
                action: global::global(r, a)?,
            });
            continue;
        }
        if a.tag_name().name() != "Private" {
            return Err(r.text.unsupported(
                a,
                format!(
                    "<{}> in <Init> is not supported; paracosm reads <Private> and <GlobalAction> actions",
                    a.tag_name().name()
                ),
            ));
        }
        let entity = r.entity(a, "entityRef")?;
        only(r.text, a, &["PrivateAction"])?;
        for p in elements(a) {
            init.push((
                entity,
                NamedAction {
                    name: String::new(),
                    pos: r.text.pos(p),
                    action: action::private(r, p)?,
                },
            ));
        }
    }
    let mut stories = Vec::new();
    for s in elements(node).filter(|s| s.tag_name().name() == "Story") {
        let r = &r.scoped(s)?;
        let mut acts = Vec::new();
        for a in elements(s) {
            match a.tag_name().name() {
                "Act" => acts.push(act(r, a)?),
                "ParameterDeclarations" => {}
                other => {
                    return Err(r
                        .text
                        .unsupported(a, format!("<{other}> in <Story> is not supported")))
                }
            }
        }
        stories.push(Story {
            name: name(r, s)?,
            acts,
        });
    }
    let stop = match child(node, "StopTrigger") {
        Some(t) => Some(condition::trigger(r, t)?),
        None => None,
    };
    check_references(&stories, stop.as_ref())?;
    Ok((init, init_global, stories, stop))
}

fn name(r: &Reader<'_>, node: Node<'_, '_>) -> Result<String, XoscError> {
    r.scope.string(r.text, node, "name")
}

fn count(r: &Reader<'_>, node: Node<'_, '_>) -> Result<u32, XoscError> {
    let v = r.scope.num(r.text, node, "maximumExecutionCount")?;
    if !(1.0..=1e6).contains(&v) || v.fract() != 0.0 {
        return Err(XoscError::Invalid {
            pos: r.text.attr_pos(node, "maximumExecutionCount"),
            reason: format!("maximumExecutionCount is a whole number from 1, not {v}"),
        });
    }
    Ok(v as u32)
}

fn act(r: &Reader<'_>, a: Node<'_, '_>) -> Result<Act, XoscError> {
    only(r.text, a, &["ManeuverGroup", "StartTrigger", "StopTrigger"])?;
    let mut groups = Vec::new();
    for g in elements(a).filter(|g| g.tag_name().name() == "ManeuverGroup") {
        let actors_node = need(r.text, g, "Actors")?;
        let mut actors = Vec::new();
        for e in elements(actors_node) {
            if e.tag_name().name() != "EntityRef" {
                return Err(r.text.unsupported(e, "actors are <EntityRef> elements"));
            }
            for k in r.entities(e, "entityRef")? {
                if !actors.contains(&k) {
                    actors.push(k);
                }
            }
        }
        if actors.is_empty()
            && !r
                .scope
                .bool(r.text, actors_node, "selectTriggeringEntities")?
        {
            r.note(actors_node, crate::support::NO_ACTOR.note);
        }
        let mut maneuvers = Vec::new();
        for m in elements(g) {
            match m.tag_name().name() {
                "Actors" => {}
                "Maneuver" => maneuvers.push(maneuver(&r.scoped(m)?, m)?),
                "CatalogReference" => maneuvers.push(r.catalogs.read_entry(
                    r,
                    m,
                    &["Maneuver"],
                    maneuver,
                )?),
                other => {
                    return Err(r.text.unsupported(
                        m,
                        format!("<{other}> in <ManeuverGroup> is not supported; paracosm reads <Maneuver> or a maneuver catalog's <CatalogReference>"),
                    ))
                }
            }
        }
        groups.push(ManeuverGroup {
            name: name(r, g)?,
            max_count: count(r, g)?,
            actors,
            select_triggering: r
                .scope
                .bool(r.text, actors_node, "selectTriggeringEntities")?,
            maneuvers,
        });
    }
    // The schema requires one; esmini starts an act without one at once, and so does
    // paracosm, with a note.
    let start = match child(a, "StartTrigger") {
        Some(t) => Some(condition::trigger(r, t)?),
        None => {
            r.note(a, crate::support::ACT_WITHOUT_START.note);
            None
        }
    };
    let stop = match child(a, "StopTrigger") {
        Some(t) => Some(condition::trigger(r, t)?),
        None => None,
    };
    Ok(Act {
        name: name(r, a)?,
        start,
        stop,
        groups,
    })
}

/// A `<Maneuver>`, read with `r`'s scope (the maneuver's own parameters in it: a catalog
/// entry's with the reference's assignments).
fn maneuver(r: &Reader<'_>, m: Node<'_, '_>) -> Result<Maneuver, XoscError> {
    if m.tag_name().name() != "Maneuver" {
        return Err(r.text.invalid(
            m,
            format!(
                "a maneuver catalog entry is a <Maneuver>, not <{}>",
                m.tag_name().name()
            ),
        ));
    }
    only(r.text, m, &["ParameterDeclarations", "Event"])?;
    let mut events = Vec::new();
    for e in elements(m).filter(|e| e.tag_name().name() == "Event") {
        only(r.text, e, &["Action", "StartTrigger"])?;
        let priority = match r.scope.string(r.text, e, "priority")?.as_str() {
            "override" | "overwrite" => Priority::Override,
            "skip" => Priority::Skip,
            "parallel" => Priority::Parallel,
            other => {
                return Err(XoscError::Invalid {
                    pos: r.text.attr_pos(e, "priority"),
                    reason: format!("priority is override, skip or parallel, not {other:?}"),
                })
            }
        };
        let mut actions = Vec::new();
        for a in elements(e).filter(|a| a.tag_name().name() == "Action") {
            let Some(p) = elements(a).next() else {
                if r.carla {
                    // scenario_runner builds no behaviour for it: it completes at once.
                    r.note(
                        a,
                        "an empty <Action> (the schema asks one action) does nothing and \
                         completes at once, as CARLA's scenario_runner reads it",
                    );
                    actions.push(NamedAction {
                        name: name(r, a)?,
                        pos: r.text.pos(a),
                        action: crate::model::Action::Nothing,
                    });
                    continue;
                }
                return Err(r.text.invalid(
                    a,
                    "an <Action> holds one <PrivateAction> or <GlobalAction>, not nothing",
                ));
            };
            // The schema's Action is a choice of one GlobalAction, UserDefinedAction or
            // PrivateAction: a second child would be silently dropped.
            if let Some(extra) = elements(a).nth(1) {
                return Err(r.text.invalid(
                    extra,
                    format!(
                        "an <Action> holds one action (the schema's choice), not a second \
                         <{}>: give each its own <Action>",
                        extra.tag_name().name()
                    ),
                ));
            }
            actions.push(NamedAction {
                name: name(r, a)?,
                pos: r.text.pos(a),
                action: match p.tag_name().name() {
                    "PrivateAction" => action::private(r, p)?,
                    "GlobalAction" => global::global(r, p)?,
                    _ => return Err(crate::xml::refusal(r.text, a, p, &crate::support::ACTION)),
                },
            });
        }
        if actions.is_empty() {
            return Err(r.text.invalid(e, "an event needs at least one <Action>"));
        }
        let max_count = match e.attribute("maximumExecutionCount") {
            Some(_) => count(r, e)?,
            None => 1,
        };
        events.push(Event {
            name: name(r, e)?,
            priority,
            max_count,
            actions,
            start: match child(e, "StartTrigger") {
                Some(t) => Some(condition::trigger(r, t)?),
                None => None,
            },
        });
    }
    Ok(Maneuver {
        name: name(r, m)?,
        events,
    })
}

/// Every `StoryboardElementStateCondition` names an element of the storyboard of the type it
/// says.
fn check_references(stories: &[Story], stop: Option<&Trigger>) -> Result<(), XoscError> {
    let mut names: HashSet<(&str, &str)> = HashSet::new();
    for s in stories {
        names.insert(("story", &s.name));
        for a in &s.acts {
            names.insert(("act", &a.name));
            for g in &a.groups {
                names.insert(("maneuverGroup", &g.name));
                for m in &g.maneuvers {
                    names.insert(("maneuver", &m.name));
                    for e in &m.events {
                        names.insert(("event", &e.name));
                        names.extend(e.actions.iter().map(|a| ("action", a.name.as_str())));
                    }
                }
            }
        }
    }
    let mut triggers: Vec<&Trigger> = stop.into_iter().collect();
    for s in stories {
        for a in &s.acts {
            triggers.extend(a.start.iter());
            triggers.extend(a.stop.iter());
            for g in &a.groups {
                for m in &g.maneuvers {
                    triggers.extend(m.events.iter().filter_map(|e| e.start.as_ref()));
                }
            }
        }
    }
    for t in triggers {
        for c in t.0.iter().flatten() {
            if let ConditionKind::ElementState {
                element_type,
                element,
                ..
            } = &c.kind
            {
                // 1.1+ may qualify a name with its parents (`Event::Action`).
                let last = element.rsplit("::").next().unwrap_or(element);
                let found = names.contains(&(element_type.as_str(), element.as_str()))
                    || names.contains(&(element_type.as_str(), last));
                if !found {
                    return Err(XoscError::Invalid {
                        pos: c.pos.clone(),
                        reason: format!("no {element_type} of the storyboard is named {element:?}"),
                    });
                }
            }
        }
    }
    Ok(())
}
