//! `RoadNetwork` and `Entities`.

use roxmltree::Node;

use super::{Catalogs, Reader};
use crate::error::XoscError;
use crate::model::{Entity, EntityKind, Located};
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
                out = Some(Located {
                    pos: r.text.pos(c),
                    item: super::join(&r.dir, &path).display().to_string(),
                });
            }
            "SceneGraphFile" => r.note(c, "the 3D model (SceneGraphFile) is not drawn: paracosm draws the road from the OpenDRIVE file"),
            "TrafficSignals" => r.note(c, "traffic signal controllers are not simulated"),
            "UsedArea" => {}
            other => {
                return Err(r.text.unsupported(c, format!("<{other}> in <RoadNetwork> is not supported")))
            }
        }
    }
    Ok(out)
}

/// `Entities`: every `ScenarioObject` (an `EntitySelection` is refused).
pub(super) fn read(
    r: &mut Reader<'_>,
    catalogs: &Catalogs,
    node: Option<Node<'_, '_>>,
) -> Result<Vec<Entity>, XoscError> {
    let mut out: Vec<Entity> = Vec::new();
    for obj in node.into_iter().flat_map(elements) {
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
        const BODIES: [&str; 4] = ["CatalogReference", "Vehicle", "Pedestrian", "MiscObject"];
        only(r.text, obj, &[&BODIES[..], &["ObjectController"]].concat())?;
        let bodies: Vec<Node<'_, '_>> = elements(obj)
            .filter(|c| BODIES.contains(&c.tag_name().name()))
            .collect();
        let [body] = bodies[..] else {
            return Err(r.text.invalid(
                obj,
                format!(
                    "a scenario object holds one of {}",
                    crate::xml::list(&BODIES)
                ),
            ));
        };
        let tag = body.tag_name().name();
        let controllers: Vec<Node<'_, '_>> = elements(obj)
            .filter(|c| c.has_tag_name("ObjectController"))
            .collect();
        if controllers.len() > 1 {
            return Err(r.text.unsupported(
                controllers[1],
                "more than one <ObjectController> per entity is not supported",
            ));
        }
        let (kind, dimensions_m, centre_m, box_pos, notes) = if tag == "CatalogReference" {
            catalogs.with_entry(r, body, &["Vehicle", "Pedestrian", "MiscObject"], object)?
        } else {
            let scope = r.scope.clone();
            object(r.text, body, &scope)?
        };
        for n in notes {
            r.note(body, n);
        }
        let controller = match child(obj, "ObjectController") {
            None => None,
            Some(oc) => Some(controller(r, catalogs, oc)?),
        };
        out.push(Entity {
            name: name.clone(),
            kind,
            dimensions_m,
            centre_m,
            box_pos,
            controller,
            pos: r.text.pos(obj),
        });
        std::rc::Rc::make_mut(&mut r.names).push(name);
    }
    Ok(out)
}

/// An object's kind, bounding box (dimensions, centre, where its dimensions are written) and
/// notes.
type Object = (EntityKind, [f64; 3], [f64; 3], crate::Pos, Vec<String>);

/// A `Vehicle`, `Pedestrian` or `MiscObject` element: its kind, bounding box and notes.
fn object(text: &Text, e: Node<'_, '_>, scope: &Scope) -> Result<Object, XoscError> {
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
    // What the schema lets an object hold; a trailer hitched to a vehicle is refused (the
    // storyboard would leave it standing while its tractor drives off).
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
    if let Some(trailer) = child(e, "Trailer") {
        let towed = match child(trailer, "TrailerRef") {
            Some(r) => !scope.string(text, r, "entityRef")?.trim().is_empty(),
            None => crate::xml::elements(trailer).next().is_some(),
        };
        if towed {
            return Err(text.unsupported(
                trailer,
                "a vehicle towing a trailer is not supported: paracosm moves each entity on its own, so the trailer would be left standing",
            ));
        }
    }
    let bb = need(text, e, "BoundingBox")?;
    let dims = need(text, bb, "Dimensions")?;
    let centre = need(text, bb, "Center")?;
    let dimensions_m = [
        scope.num_in(text, dims, "length", Quantity::Size)?,
        scope.num_in(text, dims, "width", Quantity::Size)?,
        scope.num_in(text, dims, "height", Quantity::Size)?,
    ];
    if dimensions_m.iter().any(|&d| !(d > 0.0 && d <= 100.0)) {
        return Err(text.invalid(
            dims,
            format!("a bounding box's sides must be in (0, 100] m, not {dimensions_m:?}"),
        ));
    }
    let centre_m = [
        scope.num_in(text, centre, "x", Quantity::Offset)?,
        scope.num_in(text, centre, "y", Quantity::Offset)?,
        scope.num_in(text, centre, "z", Quantity::Offset)?,
    ];
    let mut notes = Vec::new();
    if child(e, "Performance").is_some() {
        notes.push(format!(
            "{}'s <Performance> limits are not applied: paracosm's vehicle model has its own",
            scope.opt_string(text, e, "name")?.unwrap_or_default()
        ));
    }
    Ok((
        kind(category),
        dimensions_m,
        centre_m,
        text.pos(dims),
        notes,
    ))
}

/// An `ObjectController`: the controller's name.
fn controller(r: &Reader<'_>, catalogs: &Catalogs, oc: Node<'_, '_>) -> Result<String, XoscError> {
    let (c, tag) = choice(r.text, oc, &["CatalogReference", "Controller"])?;
    if tag == "CatalogReference" {
        catalogs.with_entry(r, c, &["Controller"], |text, e, scope| {
            scope.string(text, e, "name")
        })
    } else {
        r.scope.string(r.text, c, "name")
    }
}
