//! Ground-truth labels of a camera frame: the semantic class and the actor of every pixel, as
//! the renderer draws them (feature `render` fills them; see [`crate::CameraFrame::labels`]),
//! and the 2-D bounding boxes they give.
//!
//! A pixel's label is one `u32`: the [`SemanticClass`] id in the low 8 bits and, for an actor,
//! `1 +` its index in its kind's set (car, pedestrian or obstacle `k` is `k + 1`) in the high
//! 24 bits; the static world and the sky have 0 there. Labels are geometric truth: fog and
//! light change the image, not the labels; what lies beyond the camera's `far_m` is sky, as in
//! the depth map (depth `+inf` exactly where the class is [`SemanticClass::Sky`]).

use serde::{Deserialize, Serialize};

/// The semantic classes of the segmentation mask, with stable ids (the mask's pixel values,
/// the COCO category ids of a dataset, `paracosm-fuzz dataset`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum SemanticClass {
    /// 0: nothing within the far clip: the sky.
    Sky = 0,
    /// 1: grass beside the roads and the island of a roundabout.
    Ground = 1,
    /// 2: asphalt, lanes and junction areas.
    Road = 2,
    /// 3: painted lines: edge lines, lane dividers, the centre line, stop lines.
    LaneMarking = 3,
    /// 4: raised sidewalks and their curbs.
    Sidewalk = 4,
    /// 5: an NPC car.
    Car = 5,
    /// 6: a pedestrian.
    Pedestrian = 6,
    /// 7: a static obstacle.
    Obstacle = 7,
}

impl SemanticClass {
    /// Every class, in id order.
    pub const ALL: [SemanticClass; 8] = [
        SemanticClass::Sky,
        SemanticClass::Ground,
        SemanticClass::Road,
        SemanticClass::LaneMarking,
        SemanticClass::Sidewalk,
        SemanticClass::Car,
        SemanticClass::Pedestrian,
        SemanticClass::Obstacle,
    ];

    /// Its id, `0..=7`: the mask's pixel value.
    pub fn id(self) -> u8 {
        self as u8
    }

    /// The class with id `id`, `None` outside `0..=7`.
    pub fn from_id(id: u8) -> Option<SemanticClass> {
        SemanticClass::ALL.get(usize::from(id)).copied()
    }

    /// Its name: `sky`, `ground`, `road`, `lane_marking`, `sidewalk`, `car`, `pedestrian`,
    /// `obstacle`.
    pub fn name(self) -> &'static str {
        match self {
            SemanticClass::Sky => "sky",
            SemanticClass::Ground => "ground",
            SemanticClass::Road => "road",
            SemanticClass::LaneMarking => "lane_marking",
            SemanticClass::Sidewalk => "sidewalk",
            SemanticClass::Car => "car",
            SemanticClass::Pedestrian => "pedestrian",
            SemanticClass::Obstacle => "obstacle",
        }
    }

    /// Whether it is an actor (car, pedestrian, obstacle): what gets bounding boxes.
    pub fn is_actor(self) -> bool {
        matches!(
            self,
            SemanticClass::Car | SemanticClass::Pedestrian | SemanticClass::Obstacle
        )
    }
}

/// The label of actor `index` (its place in its kind's set) of class `class`.
pub fn actor_label(class: SemanticClass, index: usize) -> u32 {
    u32::from(class.id()) | ((index as u32 + 1) << 8)
}

/// The class of a pixel label (an unknown id reads as [`SemanticClass::Sky`]).
pub fn class_of(label: u32) -> SemanticClass {
    SemanticClass::from_id((label & 0xFF) as u8).unwrap_or(SemanticClass::Sky)
}

/// The actor of a pixel label: its index in its kind's set, `None` for the world and the sky.
pub fn actor_of(label: u32) -> Option<usize> {
    match label >> 8 {
        0 => None,
        k => Some(k as usize - 1),
    }
}

/// The 2-D bounding box of one actor in a frame, from the pixels labelled with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ObjectBox {
    /// Its class ([`SemanticClass::is_actor`]).
    pub class: SemanticClass,
    /// Its index in its kind's set (car `k` of the scenario, pedestrian `k`, ...).
    pub actor: usize,
    /// Left edge, pixels from the image's left side (the first column it covers).
    pub x0: u32,
    /// Top edge, pixels from the top (the first row it covers).
    pub y0: u32,
    /// Right edge, exclusive: `x1 - x0` is the box's width in pixels.
    pub x1: u32,
    /// Bottom edge, exclusive: `y1 - y0` is the box's height in pixels.
    pub y1: u32,
    /// How many pixels show it (its visible area, occlusion included).
    pub pixels: u64,
}

/// The boxes of every actor visible in a `width`-wide label image (`labels` is `height ×
/// width`, row-major), ordered by class then actor index.
pub fn boxes(labels: &[u32], width: u32) -> Vec<ObjectBox> {
    let mut found: std::collections::BTreeMap<(SemanticClass, usize), ObjectBox> =
        std::collections::BTreeMap::new();
    if width == 0 {
        return Vec::new();
    }
    for (i, &label) in labels.iter().enumerate() {
        let Some(actor) = actor_of(label) else {
            continue;
        };
        let class = class_of(label);
        let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
        found
            .entry((class, actor))
            .and_modify(|b| {
                b.x0 = b.x0.min(x);
                b.y0 = b.y0.min(y);
                b.x1 = b.x1.max(x + 1);
                b.y1 = b.y1.max(y + 1);
                b.pixels += 1;
            })
            .or_insert(ObjectBox {
                class,
                actor,
                x0: x,
                y0: y,
                x1: x + 1,
                y1: y + 1,
                pixels: 1,
            });
    }
    found.into_values().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_round_trip_and_boxes_enclose_their_pixels() {
        for c in SemanticClass::ALL {
            assert_eq!(SemanticClass::from_id(c.id()), Some(c));
            assert_eq!(class_of(u32::from(c.id())), c);
            assert_eq!(actor_of(u32::from(c.id())), None);
        }
        assert_eq!(SemanticClass::from_id(8), None);
        let car3 = actor_label(SemanticClass::Car, 3);
        assert_eq!(
            (class_of(car3), actor_of(car3)),
            (SemanticClass::Car, Some(3))
        );
        // A 4 × 3 image: car 3 at (1,0),(2,1); pedestrian 0 at (3,2).
        let road = u32::from(SemanticClass::Road.id());
        let ped = actor_label(SemanticClass::Pedestrian, 0);
        let labels = [
            road, car3, road, road, //
            road, road, car3, road, //
            road, road, road, ped,
        ];
        let b = boxes(&labels, 4);
        assert_eq!(b.len(), 2);
        assert_eq!((b[0].x0, b[0].y0, b[0].x1, b[0].y1), (1, 0, 3, 2));
        assert_eq!(b[0].pixels, 2);
        assert_eq!((b[1].class, b[1].actor), (SemanticClass::Pedestrian, 0));
        assert_eq!((b[1].x0, b[1].y0, b[1].x1, b[1].y1), (3, 2, 4, 3));
    }
}
