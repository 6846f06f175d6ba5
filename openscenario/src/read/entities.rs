//! `RoadNetwork` and `Entities`.

use std::path::PathBuf;

use roxmltree::Node;

use super::{Catalogs, Reader};
use crate::error::XoscError;
use crate::model::{Entity, EntityKind, Located, Performance};
use crate::params::Scope;
use crate::quantity::Quantity;
use crate::text::Text;
use crate::xml::{child, choice, elements, need, only};

/// `RoadNetwork`: the `LogicFile` path, resolved against the scenario's folder.
pub(super) fn road_network(
    r: &Reader<'_>,
    node: Option<Node<'_, '_>>,
) -> Result<Option<Located<String>>, XoscError> {
    let Some(node) = node else { return Ok(None) };
    let mut out = None;
    for c in elements(node) {
        match c.tag_name().name() {
            "LogicFile" => {
                let path = r.scope.string(r.text, c, "filepath")?;
                let mut file = super::join(&r.dir, &path);
                if !file.exists() {
                    if let Some((found, why)) = map_elsewhere(r, &file) {
                        r.note(
                            c,
                            format!("the map {path:?} {why}: read from {}", found.display()),
                        );
                        file = found;
                    }
                }
                out = Some(Located {
                    pos: r.text.pos(c),
                    item: file.display().to_string(),
                });
            }
            "SceneGraphFile" => r.note(c, crate::support::SCENE_GRAPH.note),
            "TrafficSignals" => r.note(c, crate::support::SIGNAL_CONTROLLERS.note),
            "UsedArea" => {}
            other => {
                return Err(r
                    .text
                    .unsupported(c, format!("<{other}> in <RoadNetwork> is not supported")))
            }
        }
    }
    Ok(out)
}

/// Where a map that is not at `file` is found, and why there: CARLA's scenarios name a town
/// (`Town01`), which CARLA loads itself, so its OpenDRIVE file beside the scenario
/// (`Town01.xodr`) stands for it; else the file of that name (with `.xodr` when it has no
/// extension) in the folder of maps (`--maps`, [`crate::FileSet::with_maps`]).
fn map_elsewhere(r: &Reader<'_>, file: &std::path::Path) -> Option<(PathBuf, String)> {
    let bare = file.extension().is_none();
    if bare && file.with_extension("xodr").is_file() {
        let why = "is named without its extension, as CARLA names its towns".to_string();
        return Some((file.with_extension("xodr"), why));
    }
    let name = std::path::Path::new(file.file_name()?);
    r.files.maps().iter().find_map(|dir| {
        let at = dir.join(name);
        let at = if bare { at.with_extension("xodr") } else { at };
        at.is_file().then(|| {
            (
                at,
                format!(
                    "is not beside the scenario; found in --maps {}",
                    dir.display()
                ),
            )
        })
    })
}

/// `Entities`: every `ScenarioObject`, then every `EntitySelection` (into `r.selections`).
pub(super) fn read(
    r: &mut Reader<'_>,
    catalogs: &Catalogs,
    node: Option<Node<'_, '_>>,
) -> Result<Vec<Entity>, XoscError> {
    let mut out: Vec<Entity> = Vec::new();
    // Trailers named by `TrailerRef`: (tow, the trailer's name, where it is named).
    let mut refs: Vec<(usize, String, crate::Pos)> = Vec::new();
    for obj in node.into_iter().flat_map(elements) {
        if obj.tag_name().name() == "EntitySelection" {
            continue;
        }
        if obj.tag_name().name() != "ScenarioObject" {
            return Err(r.text.unsupported(
                obj,
                format!(
                    "<{}> is not supported; paracosm reads <ScenarioObject>",
                    obj.tag_name().name()
                ),
            ));
        }
        let name = r.scope.string(r.text, obj, "name")?;
        if out.iter().any(|e| e.name == name) {
            return Err(r
                .text
                .invalid(obj, format!("a second entity is named {name:?}")));
        }
        let group = &crate::support::ENTITY_OBJECT;
        const BODIES: &[&str] = crate::support::ENTITY_OBJECT.read;
        if let Some(c) =
            elements(obj).find(|c| group.refused.iter().any(|(n, _)| c.has_tag_name(*n)))
        {
            return Err(crate::xml::refusal(r.text, obj, c, group));
        }
        only(r.text, obj, &[BODIES, &["ObjectController"]].concat())?;
        let bodies: Vec<Node<'_, '_>> = elements(obj)
            .filter(|c| BODIES.contains(&c.tag_name().name()))
            .collect();
        let [body] = bodies[..] else {
            return Err(r.text.invalid(
                obj,
                format!(
                    "a scenario object holds one of {}",
                    crate::xml::list(BODIES)
                ),
            ));
        };
        let tag = body.tag_name().name();
        let read = if tag == "CatalogReference" {
            catalogs.read_entry(r, body, &["Vehicle", "Pedestrian", "MiscObject"], object)?
        } else {
            object(r, body)?
        };
        let mut controllers = Vec::new();
        for oc in elements(obj).filter(|c| c.has_tag_name("ObjectController")) {
            // The ObjectController's own name (1.2+, what objectControllerRef names), else
            // its controller's.
            let name = match r.scope.opt_string(r.text, oc, "name")? {
                Some(own) => {
                    controller(r, catalogs, oc)?;
                    own
                }
                None => controller(r, catalogs, oc)?,
            };
            if controllers.contains(&name) {
                return Err(r.text.invalid(
                    oc,
                    format!("a second <ObjectController> of this entity is named {name:?}"),
                ));
            }
            controllers.push(name);
        }
        push_combination(
            r,
            (&mut out, &mut refs),
            (obj, body),
            (name, read, controllers),
        )?;
    }
    resolve_trailer_refs(&mut out, refs)?;
    check_combinations(&out)?;
    let selections = selections(r, &out, node)?;
    r.selections = std::rc::Rc::new(selections);
    Ok(out)
}

/// Pushes entity `name` (its `ScenarioObject` and body elements `at`), read as `read`, with
/// its controller, onto `out`; and each trailer written in it as an entity of its own, named
/// as esmini names it (the tow's name and `+`), after its tow. A trailer named by a
/// `TrailerRef` is recorded in `refs` (tow, name, where it is named).
///
/// # Errors
/// Invalid for a name another entity has.
fn push_combination(
    r: &mut Reader<'_>,
    (out, refs): (&mut Vec<Entity>, &mut Vec<(usize, String, crate::Pos)>),
    (obj, body): (Node<'_, '_>, Node<'_, '_>),
    (name, read, controllers): (String, Body, Vec<String>),
) -> Result<(), XoscError> {
    let mut pos = r.text.pos(obj);
    let (mut name, mut read, mut controllers) = (name, read, controllers);
    loop {
        for n in std::mem::take(&mut read.notes) {
            r.note(body, n);
        }
        if out.iter().any(|e| e.name == name) {
            return Err(r
                .text
                .invalid(obj, format!("a second entity is named {name:?}")));
        }
        let towed = read.trailer.take();
        let index = out.len();
        out.push(Entity {
            name: name.clone(),
            kind: read.kind,
            dimensions_m: read.dimensions_m,
            centre_m: read.centre_m,
            box_pos: read.box_pos,
            controllers: std::mem::take(&mut controllers),
            performance: read.performance,
            pos: pos.clone(),
            hitch_dx_m: read.hitch_dx_m,
            coupler_dx_m: read.coupler_dx_m,
            refpoint_dx_m: read.refpoint_dx_m,
            trailer: None,
        });
        std::rc::Rc::make_mut(&mut r.names).push(name.clone());
        match towed {
            None => return Ok(()),
            Some(Towed::Entity(other, at)) => {
                refs.push((index, other, at));
                return Ok(());
            }
            Some(Towed::Body(b)) => {
                out[index].trailer = Some(index + 1);
                name = format!("{name}+");
                pos = b.pos.clone();
                read = *b;
            }
        }
    }
}

/// Hitches each trailer named by a `TrailerRef` (`refs`: tow, name, where it is named) to its
/// tow, once every entity of `out` is read.
///
/// # Errors
/// Invalid at the reference for a name no entity has, or an entity that is no trailer (no
/// `TrailerCoupler`, or the tow itself).
fn resolve_trailer_refs(
    out: &mut [Entity],
    refs: Vec<(usize, String, crate::Pos)>,
) -> Result<(), XoscError> {
    for (tow, other, at) in refs {
        let Some(k) = out.iter().position(|e| e.name == other) else {
            return Err(XoscError::Invalid {
                pos: at,
                reason: format!("no entity is named {other:?}"),
            });
        };
        if out[k].coupler_dx_m.is_none() || k == tow {
            return Err(XoscError::Invalid {
                pos: at,
                reason: format!(
                    "{other:?} is no trailer of {:?}: a trailer is another vehicle with a <TrailerCoupler>",
                    out[tow].name
                ),
            });
        }
        out[tow].trailer = Some(k);
    }
    Ok(())
}

/// Checks the vehicle combinations of `entities`: a trailer is towed by one vehicle at a
/// time, and no combination tows itself round (a chain of trailers that comes back to its
/// first vehicle).
///
/// # Errors
/// Invalid at the second tow of a trailer, or at a vehicle whose chain comes back to it.
fn check_combinations(entities: &[Entity]) -> Result<(), XoscError> {
    for (i, e) in entities.iter().enumerate() {
        let Some(t) = e.trailer else { continue };
        if let Some(j) = (0..i).find(|&j| entities[j].trailer == Some(t)) {
            return Err(XoscError::Invalid {
                pos: e.pos.clone(),
                reason: format!(
                    "{:?} tows {:?}, which {:?} tows already: a trailer has one tow",
                    e.name, entities[t].name, entities[j].name
                ),
            });
        }
        let mut at = Some(t);
        for _ in 0..entities.len() {
            match at {
                Some(k) if k == i => {
                    return Err(XoscError::Invalid {
                        pos: e.pos.clone(),
                        reason: format!("{:?}'s chain of trailers comes back to it", e.name),
                    })
                }
                Some(k) => at = entities[k].trailer,
                None => break,
            }
        }
    }
    Ok(())
}

/// Each `EntitySelection` of `Entities` (OpenSCENARIO 1.0+): its name and its members, the
/// entities its `Members` name by `EntityRef` (an entity, or another selection, whose
/// members it takes) or by `ByType` (every entity of that `objectType`), in the order of
/// the entities, each once.
///
/// # Errors
/// Invalid for a name taken by an entity or another selection, a member named nowhere, a
/// selection that includes itself (through others), an unknown `objectType`, or a selection
/// of no entity; unsupported for `objectType="external"`.
fn selections(
    r: &Reader<'_>,
    entities: &[Entity],
    node: Option<Node<'_, '_>>,
) -> Result<Vec<(String, Vec<usize>)>, XoscError> {
    let nodes: Vec<Node<'_, '_>> = node
        .into_iter()
        .flat_map(elements)
        .filter(|n| n.has_tag_name("EntitySelection"))
        .collect();
    let mut named: Vec<(String, Node<'_, '_>)> = Vec::new();
    for n in &nodes {
        let name = r.scope.string(r.text, *n, "name")?;
        if r.names.contains(&name) || named.iter().any(|(m, _)| *m == name) {
            return Err(r.text.invalid(
                *n,
                format!("a second entity or selection is named {name:?}"),
            ));
        }
        only(r.text, *n, &["Members"])?;
        named.push((name, *n));
    }
    let mut out = Vec::new();
    for k in 0..named.len() {
        let mut members = vec![false; entities.len()];
        select(r, entities, &named, k, &mut vec![k], &mut members)?;
        let members: Vec<usize> = (0..entities.len()).filter(|&i| members[i]).collect();
        if members.is_empty() {
            return Err(r
                .text
                .invalid(named[k].1, "this entity selection selects no entity"));
        }
        out.push((named[k].0.clone(), members));
    }
    Ok(out)
}

/// Marks in `members` the entities selection `named[k]` selects; `path` holds the
/// selections being expanded (a selection met again includes itself).
fn select(
    r: &Reader<'_>,
    entities: &[Entity],
    named: &[(String, Node<'_, '_>)],
    k: usize,
    path: &mut Vec<usize>,
    members: &mut [bool],
) -> Result<(), XoscError> {
    let Some(list) = child(named[k].1, "Members") else {
        return Ok(());
    };
    for m in elements(list) {
        match m.tag_name().name() {
            "EntityRef" => {
                let name = r.scope.string(r.text, m, "entityRef")?;
                if let Some(i) = r.names.iter().position(|n| *n == name) {
                    members[i] = true;
                } else if let Some(j) = named.iter().position(|(n, _)| *n == name) {
                    if path.contains(&j) {
                        return Err(XoscError::Invalid {
                            pos: r.text.attr_pos(m, "entityRef"),
                            reason: format!("selection {name:?} includes itself"),
                        });
                    }
                    path.push(j);
                    select(r, entities, named, j, path, members)?;
                    path.pop();
                } else {
                    r.entity(m, "entityRef")?;
                }
            }
            "ByType" => {
                let kind = r.scope.string(r.text, m, "objectType")?;
                if kind == "external" {
                    return Err(XoscError::Unsupported {
                        pos: r.text.attr_pos(m, "objectType"),
                        reason: "a selection of external objects is not supported: paracosm's \
                                 world holds the scenario's own entities only"
                            .into(),
                    });
                }
                if !crate::model::OBJECT_TYPES.contains(&kind.as_str()) {
                    return Err(XoscError::Invalid {
                        pos: r.text.attr_pos(m, "objectType"),
                        reason: format!(
                            "objectType is one of {}, external, not {kind:?}",
                            crate::model::OBJECT_TYPES.join(", ")
                        ),
                    });
                }
                for (i, e) in entities.iter().enumerate() {
                    members[i] |= e.kind.object_type() == kind;
                }
            }
            other => {
                return Err(r.text.unsupported(
                    m,
                    format!(
                    "<{other}> in a selection's <Members>: paracosm reads <EntityRef> and <ByType>"
                ),
                ))
            }
        }
    }
    Ok(())
}

/// A `Vehicle`, `Pedestrian` or `MiscObject` as read: its kind, bounding box (dimensions,
/// centre, where its dimensions are written), notes, `Performance`, and, for a vehicle, its
/// hitch, coupler and the trailer it tows.
struct Body {
    kind: EntityKind,
    dimensions_m: [f64; 3],
    centre_m: [f64; 3],
    box_pos: crate::Pos,
    notes: Vec<String>,
    performance: Performance,
    /// `TrailerHitch dx`, m.
    hitch_dx_m: Option<f64>,
    /// `TrailerCoupler dx`, m.
    coupler_dx_m: Option<f64>,
    /// esmini's `refpoint_x_offset` property, m ([`crate::model::Entity::refpoint_dx_m`]).
    refpoint_dx_m: Option<f64>,
    /// The trailer it tows from the start, if any.
    trailer: Option<Towed>,
    /// Where the object's element is written.
    pos: crate::Pos,
}

/// A vehicle's `Trailer`: a vehicle written in it (inline or from a catalog), or a
/// `TrailerRef` to another entity (its name, where the reference is written).
enum Towed {
    Body(Box<Body>),
    Entity(String, crate::Pos),
}

/// A `Vehicle`, `Pedestrian` or `MiscObject` element read with `r` (the scenario's reader,
/// or a catalog entry's).
fn object(r: &Reader<'_>, e: Node<'_, '_>) -> Result<Body, XoscError> {
    let (text, scope) = (r.text, &r.scope);
    let tag = e.tag_name().name();
    let (category_attr, kind): (&str, fn(String) -> EntityKind) = match tag {
        "Vehicle" => ("vehicleCategory", EntityKind::Vehicle),
        "Pedestrian" => ("pedestrianCategory", EntityKind::Pedestrian),
        "MiscObject" => ("miscObjectCategory", EntityKind::MiscObject),
        other => {
            return Err(text.unsupported(
                e,
                format!("a catalog entry <{other}> is not an object; paracosm reads <Vehicle>, <Pedestrian> or <MiscObject>"),
            ))
        }
    };
    let category = scope
        .opt_string(text, e, category_attr)?
        .unwrap_or_else(|| tag.to_lowercase());
    let vehicle = tag == "Vehicle";
    crate::xml::only(
        text,
        e,
        if vehicle {
            &[
                "ParameterDeclarations",
                "BoundingBox",
                "Performance",
                "Axles",
                "Properties",
                "TrailerHitch",
                "TrailerCoupler",
                "Trailer",
            ]
        } else {
            &["ParameterDeclarations", "BoundingBox", "Properties"]
        },
    )?;
    let (hitch_dx_m, coupler_dx_m, trailer) = combination(r, e)?;
    let bb = need(text, e, "BoundingBox")?;
    let dims = need(text, bb, "Dimensions")?;
    let centre = need(text, bb, "Center")?;
    let dimensions_m = [
        scope.num_in(text, dims, "length", Quantity::Size)?,
        scope.num_in(text, dims, "width", Quantity::Size)?,
        scope.num_in(text, dims, "height", Quantity::Size)?,
    ];
    if dimensions_m.iter().any(|&d| !(0.0..=100.0).contains(&d)) {
        return Err(text.invalid(
            dims,
            format!("a bounding box's sides must be in [0, 100] m, not {dimensions_m:?}"),
        ));
    }
    let refpoint_dx_m = if vehicle {
        refpoint_offset(r, e)?
    } else {
        None
    };
    let centre_m = [
        // Taken from the reference point, as esmini moves the box.
        scope.num_in(text, centre, "x", Quantity::Offset)? - refpoint_dx_m.unwrap_or(0.0),
        scope.num_in(text, centre, "y", Quantity::Offset)?,
        scope.num_in(text, centre, "z", Quantity::Offset)?,
    ];
    let mut notes = Vec::new();
    if dimensions_m.contains(&0.0) {
        // The schema allows it (ASAM's and the generators' files write empty boxes).
        notes.push(format!(
            "{}'s bounding box has a side of 0 m ({dimensions_m:?}): the storyboard measures \
             the box as written, as esmini does, and its body in the world is 0.1 m on that \
             side so that what touches it is found (an ego needs a real size: its box is \
             refused)",
            scope.opt_string(text, e, "name")?.unwrap_or_default()
        ));
    }
    let performance = match child(e, "Performance") {
        Some(p) => performance(text, p, scope)?,
        None if vehicle => {
            notes.push(format!(
                "{} has no <Performance> (the schema asks one): esmini's defaults limit the \
                 speed changes the storyboard makes it perform (100 m/s, 10 m/s², 10 m/s²)",
                scope.opt_string(text, e, "name")?.unwrap_or_default()
            ));
            Performance::VEHICLE_DEFAULT
        }
        None => Performance::UNBOUNDED,
    };
    Ok(Body {
        kind: kind(category),
        dimensions_m,
        centre_m,
        box_pos: text.pos(dims),
        notes,
        performance,
        hitch_dx_m,
        coupler_dx_m,
        refpoint_dx_m,
        trailer,
        pos: text.pos(e),
    })
}

/// A vehicle's esmini `refpoint_x_offset` property (`<Property name="refpoint_x_offset"
/// value="…"/>` in its `Properties`), m; `None` without one.
///
/// # Errors
/// What reading a number returns (a value that is not one, or out of an offset's range).
fn refpoint_offset(r: &Reader<'_>, e: Node<'_, '_>) -> Result<Option<f64>, XoscError> {
    let (text, scope) = (r.text, &r.scope);
    let Some(props) = child(e, "Properties") else {
        return Ok(None);
    };
    for p in elements(props).filter(|p| p.has_tag_name("Property")) {
        if scope.opt_string(text, p, "name")?.as_deref() == Some("refpoint_x_offset") {
            let dx = scope.num_in(text, p, "value", Quantity::Offset)?;
            return Ok((dx != 0.0).then_some(dx));
        }
    }
    Ok(None)
}

/// A vehicle's `TrailerHitch dx` and `TrailerCoupler dx` (m) and its `Trailer`, each `None`
/// when it has none.
type Combination = (Option<f64>, Option<f64>, Option<Towed>);

/// The [`Combination`] of object `e` (only a vehicle may have one).
///
/// # Errors
/// Invalid for a trailer without a hitch to hitch it to, or a trailer written here without a
/// coupler; what [`trailer`] returns.
fn combination(r: &Reader<'_>, e: Node<'_, '_>) -> Result<Combination, XoscError> {
    let (text, scope) = (r.text, &r.scope);
    let dx = |name: &str| -> Result<Option<f64>, XoscError> {
        child(e, name)
            .map(|n| scope.num_in(text, n, "dx", Quantity::Offset))
            .transpose()
    };
    let (hitch_dx_m, coupler_dx_m) = (dx("TrailerHitch")?, dx("TrailerCoupler")?);
    let towed = match child(e, "Trailer") {
        None => None,
        Some(t) => trailer(r, t)?,
    };
    if towed.is_some() && hitch_dx_m.is_none() {
        return Err(text.invalid(
            e,
            "a vehicle that tows a <Trailer> needs a <TrailerHitch> (where the trailer is hitched)",
        ));
    }
    if let Some(Towed::Body(b)) = &towed {
        if b.coupler_dx_m.is_none() {
            return Err(XoscError::Invalid {
                pos: b.pos.clone(),
                reason: "a trailer needs a <TrailerCoupler> (where it is coupled to its tow)"
                    .into(),
            });
        }
    }
    Ok((hitch_dx_m, coupler_dx_m, towed))
}

/// A vehicle's `Trailer` element: a `Trailer` holding a vehicle (inline or a
/// `CatalogReference`), or a `TrailerRef` (esmini's legacy `EntityRef`) naming another
/// entity; `None` for a reference to no entity (`entityRef=""`).
///
/// # Errors
/// Invalid for an element that holds none of these, or a trailer that is not a vehicle.
fn trailer(r: &Reader<'_>, t: Node<'_, '_>) -> Result<Option<Towed>, XoscError> {
    let (c, tag) = choice(r.text, t, &crate::support::TRAILER)?;
    if tag != "Trailer" {
        let name = r.scope.string(r.text, c, "entityRef")?;
        let name = name.trim();
        return Ok((!name.is_empty())
            .then(|| Towed::Entity(name.to_owned(), r.text.attr_pos(c, "entityRef"))));
    }
    let (v, tag) = choice(r.text, c, &crate::support::TRAILER_BODY)?;
    let body = if tag == "CatalogReference" {
        r.catalogs.read_entry(r, v, &["Vehicle"], object)?
    } else {
        object(r, v)?
    };
    if !matches!(body.kind, EntityKind::Vehicle(_)) {
        return Err(r.text.invalid(v, "a trailer is a <Vehicle>"));
    }
    Ok(Some(Towed::Body(Box::new(body))))
}

/// A `Performance` element: `maxSpeed`, `maxAcceleration` and `maxDeceleration` (esmini's
/// defaults for one not given), each `> 0`; files write large values (200 m/s²) for no
/// limit, so no plausible range is asked.
///
/// # Errors
/// Invalid at a value that is not a number `> 0`.
fn performance(text: &Text, p: Node<'_, '_>, scope: &Scope) -> Result<Performance, XoscError> {
    let d = Performance::VEHICLE_DEFAULT;
    let value = |attr: &str, default: f64| -> Result<f64, XoscError> {
        let v = scope.opt_num(text, p, attr)?.unwrap_or(default);
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(XoscError::Invalid {
                pos: text.attr_pos(p, attr),
                reason: format!("{attr} must be > 0, not {v}"),
            })
        }
    };
    Ok(Performance {
        max_speed_mps: value("maxSpeed", d.max_speed_mps)?,
        max_acceleration_mps2: value("maxAcceleration", d.max_acceleration_mps2)?,
        max_deceleration_mps2: value("maxDeceleration", d.max_deceleration_mps2)?,
    })
}

/// An `ObjectController`: the controller's name.
fn controller(r: &Reader<'_>, catalogs: &Catalogs, oc: Node<'_, '_>) -> Result<String, XoscError> {
    let (c, tag) = choice(r.text, oc, &crate::support::CONTROLLER)?;
    if tag == "CatalogReference" {
        catalogs.with_entry(r, c, &["Controller"], |text, e, scope| {
            scope.string(text, e, "name")
        })
    } else {
        r.scope.string(r.text, c, "name")
    }
}
