//! The reader's tables: for each of the standard's choice groups (OpenSCENARIO 1.3's schema,
//! `xsd:choice`), the elements paracosm reads there and those it refuses, each refusal with
//! why; and what it reads but does not apply, which it notes at load. The reader decides by
//! these tables ([`crate::xml::choice`] takes a [`Choice`], and each note below is the text
//! the reader gives), and docs/openscenario.md's lists are rendered from them
//! ([`markdown`]): a test fails when the two differ.

use std::fmt::Write as _;

/// One of the standard's choice groups: the element `parent` holds exactly one of its
/// members.
#[derive(Debug, Clone, Copy)]
pub struct Choice {
    /// The element holding the choice, as the schema names it (its type's name where the
    /// element's own name varies).
    pub parent: &'static str,
    /// The members paracosm reads.
    pub read: &'static [&'static str],
    /// The members of the standard paracosm refuses at load, each with why (a clause).
    pub refused: &'static [(&'static str, &'static str)],
}

/// Something read but not applied: the load goes on with a warning at the element.
#[derive(Debug, Clone, Copy)]
pub struct Noted {
    /// What is read, as the docs name it (markdown).
    pub what: &'static str,
    /// The note the reader gives at the element.
    pub note: &'static str,
}

/// `<Action>`: a private, global or user-defined action.
pub const ACTION: Choice = Choice {
    parent: "Action",
    read: &["PrivateAction", "GlobalAction"],
    refused: &[(
        "UserDefinedAction",
        "what it does is the writing tool's own, which paracosm cannot know",
    )],
};

/// `<PrivateAction>`.
pub const PRIVATE_ACTION: Choice = Choice {
    parent: "PrivateAction",
    read: &[
        "LongitudinalAction",
        "LateralAction",
        "VisibilityAction",
        "SynchronizeAction",
        "ActivateControllerAction",
        "ControllerAction",
        "TeleportAction",
        "RoutingAction",
        "AppearanceAction",
        "TrailerAction",
    ],
    refused: &[],
};

/// `<LongitudinalAction>`.
pub const LONGITUDINAL_ACTION: Choice = Choice {
    parent: "LongitudinalAction",
    read: &[
        "SpeedAction",
        "LongitudinalDistanceAction",
        "SpeedProfileAction",
    ],
    refused: &[],
};

/// `<LateralAction>`.
pub const LATERAL_ACTION: Choice = Choice {
    parent: "LateralAction",
    read: &[
        "LaneChangeAction",
        "LaneOffsetAction",
        "LateralDistanceAction",
    ],
    refused: &[],
};

/// `<RoutingAction>`.
pub const ROUTING_ACTION: Choice = Choice {
    parent: "RoutingAction",
    read: &[
        "AssignRouteAction",
        "FollowTrajectoryAction",
        "AcquirePositionAction",
    ],
    refused: &[(
        "RandomRouteAction",
        "a route the simulator draws at random is not reproducible from the file; paracosm's \
         tests vary what the file's parameters open",
    )],
};

/// `<TrailerAction>`.
pub const TRAILER_ACTION: Choice = Choice {
    parent: "TrailerAction",
    read: &["ConnectTrailerAction", "DisconnectTrailerAction"],
    refused: &[],
};

/// `<AppearanceAction>`.
pub const APPEARANCE_ACTION: Choice = Choice {
    parent: "AppearanceAction",
    read: &["LightStateAction", "AnimationAction"],
    refused: &[],
};

/// `<GlobalAction>`.
pub const GLOBAL_ACTION: Choice = Choice {
    parent: "GlobalAction",
    read: &[
        "EnvironmentAction",
        "EntityAction",
        "InfrastructureAction",
        "ParameterAction",
        "VariableAction",
    ],
    refused: &[
        (
            "SetMonitorAction",
            "paracosm's verdicts are its own monitors' (a program's `Monitor`), not the file's",
        ),
        (
            "TrafficAction",
            "sources, sinks, swarms and areas of traffic are not simulated: every entity of a \
             test is one the file names",
        ),
    ],
};

/// `<EnvironmentAction>`.
pub const ENVIRONMENT_ACTION: Choice = Choice {
    parent: "EnvironmentAction",
    read: &["Environment", "CatalogReference"],
    refused: &[],
};

/// `<EntityAction>`.
pub const ENTITY_ACTION: Choice = Choice {
    parent: "EntityAction",
    read: &["AddEntityAction", "DeleteEntityAction"],
    refused: &[],
};

/// `<ParameterAction>` and `<VariableAction>`.
pub const VALUE_ACTION: Choice = Choice {
    parent: "ParameterAction",
    read: &["SetAction", "ModifyAction"],
    refused: &[],
};

/// `<ModifyRule>` of a parameter or variable.
pub const MODIFY_RULE: Choice = Choice {
    parent: "ModifyRule",
    read: &["AddValue", "MultiplyByValue"],
    refused: &[],
};

/// `<TrafficSignalAction>` of an `InfrastructureAction`.
pub const TRAFFIC_SIGNAL_ACTION: Choice = Choice {
    parent: "TrafficSignalAction",
    read: &["TrafficSignalStateAction"],
    refused: &[(
        "TrafficSignalControllerAction",
        "signal controllers (their phases and timing) are not simulated; a signal's state is \
         set by a TrafficSignalStateAction",
    )],
};

/// `<SpeedActionTarget>`.
pub const SPEED_TARGET: Choice = Choice {
    parent: "SpeedActionTarget",
    read: &["RelativeTargetSpeed", "AbsoluteTargetSpeed"],
    refused: &[],
};

/// `<LaneChangeTarget>`.
pub const LANE_CHANGE_TARGET: Choice = Choice {
    parent: "LaneChangeTarget",
    read: &["RelativeTargetLane", "AbsoluteTargetLane"],
    refused: &[],
};

/// `<LaneOffsetTarget>`.
pub const LANE_OFFSET_TARGET: Choice = Choice {
    parent: "LaneOffsetTarget",
    read: &["RelativeTargetLaneOffset", "AbsoluteTargetLaneOffset"],
    refused: &[],
};

/// A trajectory's `<Shape>`.
pub const SHAPE: Choice = Choice {
    parent: "Shape",
    read: &["Polyline", "Clothoid", "ClothoidSpline", "Nurbs"],
    refused: &[],
};

/// `<RouteRef>`, and an `AssignRouteAction`'s route.
pub const ROUTE_REF: Choice = Choice {
    parent: "RouteRef",
    read: &["Route", "CatalogReference"],
    refused: &[],
};

/// A `SynchronizeAction`'s `<FinalSpeed>`.
pub const FINAL_SPEED: Choice = Choice {
    parent: "FinalSpeed",
    read: &["AbsoluteSpeed", "RelativeSpeedToMaster"],
    refused: &[],
};

/// `<Position>`.
pub const POSITION: Choice = Choice {
    parent: "Position",
    read: &[
        "WorldPosition",
        "RelativeWorldPosition",
        "RelativeObjectPosition",
        "RoadPosition",
        "RelativeRoadPosition",
        "LanePosition",
        "RelativeLanePosition",
        "RoutePosition",
        "TrajectoryPosition",
    ],
    refused: &[(
        "GeoPosition",
        "a geographic position needs the map's projection (its geoReference), which paracosm \
         does not read",
    )],
};

/// A route position's `<InRoutePosition>`.
pub const IN_ROUTE_POSITION: Choice = Choice {
    parent: "InRoutePosition",
    read: &[
        "FromCurrentEntity",
        "FromRoadCoordinates",
        "FromLaneCoordinates",
    ],
    refused: &[],
};

/// `<Condition>`.
pub const CONDITION: Choice = Choice {
    parent: "Condition",
    read: &["ByEntityCondition", "ByValueCondition"],
    refused: &[],
};

/// `<ByValueCondition>`.
pub const BY_VALUE_CONDITION: Choice = Choice {
    parent: "ByValueCondition",
    read: &[
        "ParameterCondition",
        "SimulationTimeCondition",
        "StoryboardElementStateCondition",
        "TrafficSignalCondition",
        "VariableCondition",
    ],
    refused: &[
        (
            "TimeOfDayCondition",
            "the world's clock is not kept: an EnvironmentAction's time of day sets the light \
             only",
        ),
        (
            "UserDefinedValueCondition",
            "its value is the writing tool's own, which paracosm cannot know",
        ),
        (
            "TrafficSignalControllerCondition",
            "signal controllers (their phases and timing) are not simulated",
        ),
    ],
};

/// `<EntityCondition>`.
pub const ENTITY_CONDITION: Choice = Choice {
    parent: "EntityCondition",
    read: &[
        "EndOfRoadCondition",
        "CollisionCondition",
        "OffroadCondition",
        "TimeHeadwayCondition",
        "TimeToCollisionCondition",
        "AccelerationCondition",
        "StandStillCondition",
        "SpeedCondition",
        "RelativeSpeedCondition",
        "TraveledDistanceCondition",
        "ReachPositionCondition",
        "DistanceCondition",
        "RelativeDistanceCondition",
        "RelativeClearanceCondition",
        "AngleCondition",
        "RelativeAngleCondition",
    ],
    refused: &[],
};

/// `<TimeToCollisionConditionTarget>`.
pub const TTC_TARGET: Choice = Choice {
    parent: "TimeToCollisionConditionTarget",
    read: &["Position", "EntityRef"],
    refused: &[],
};

/// A `CollisionCondition`'s other party.
pub const COLLISION_TARGET: Choice = Choice {
    parent: "CollisionCondition",
    read: &["EntityRef", "ByType"],
    refused: &[],
};

/// A scenario object's body (the schema's `EntityObject` group).
pub const ENTITY_OBJECT: Choice = Choice {
    parent: "ScenarioObject",
    read: &["CatalogReference", "Vehicle", "Pedestrian", "MiscObject"],
    refused: &[(
        "ExternalObjectReference",
        "an object another simulator brings has no body, route or behaviour paracosm could \
         simulate",
    )],
};

/// A vehicle's `<Trailer>` (1.3's `TrailerRef`, and esmini's `EntityRef`, name another
/// entity).
pub const TRAILER: Choice = Choice {
    parent: "Trailer",
    read: &["Trailer", "TrailerRef", "EntityRef"],
    refused: &[],
};

/// The vehicle a `Trailer` holds.
pub const TRAILER_BODY: Choice = Choice {
    parent: "Trailer > Trailer",
    read: &["CatalogReference", "Vehicle"],
    refused: &[],
};

/// An `ObjectController` or a `AssignControllerAction`'s controller.
pub const CONTROLLER: Choice = Choice {
    parent: "ObjectController",
    read: &["CatalogReference", "Controller"],
    refused: &[],
};

/// Every choice group above, in the order the docs list them.
pub const CHOICES: &[&Choice] = &[
    &ACTION,
    &PRIVATE_ACTION,
    &LONGITUDINAL_ACTION,
    &LATERAL_ACTION,
    &ROUTING_ACTION,
    &TRAILER_ACTION,
    &APPEARANCE_ACTION,
    &GLOBAL_ACTION,
    &ENVIRONMENT_ACTION,
    &ENTITY_ACTION,
    &VALUE_ACTION,
    &MODIFY_RULE,
    &TRAFFIC_SIGNAL_ACTION,
    &SPEED_TARGET,
    &LANE_CHANGE_TARGET,
    &LANE_OFFSET_TARGET,
    &SHAPE,
    &ROUTE_REF,
    &FINAL_SPEED,
    &POSITION,
    &IN_ROUTE_POSITION,
    &CONDITION,
    &BY_VALUE_CONDITION,
    &ENTITY_CONDITION,
    &TTC_TARGET,
    &COLLISION_TARGET,
    &ENTITY_OBJECT,
    &TRAILER,
    &TRAILER_BODY,
    &CONTROLLER,
];

/// A world position's `z`, `p` or `r`.
pub const WORLD_Z: Noted = Noted {
    what: "a world position's `z`, pitch (`p`) and roll (`r`)",
    note: "is not honoured: paracosm's roads are flat",
};

/// A relative position's `dz`.
pub const RELATIVE_DZ: Noted = Noted {
    what: "a relative position's `dz`",
    note: "a relative position's dz is not honoured as a height: paracosm's roads are \
           flat (in a relative object position it is turned with its entity's pitch and roll, \
           as esmini turns it, and its part along the ground is taken)",
};

/// A `TransitionDynamics`' `followingMode` other than `position`.
pub const DYNAMICS_FOLLOWING: Noted = Noted {
    what: "a transition's `followingMode` `follow`",
    note: "is followed as \"position\": the value follows the shape exactly",
};

/// A vehicle's lights or an animation.
pub const APPEARANCE: Noted = Noted {
    what: "`LightStateAction` and `AnimationAction`",
    note: "is read but not modelled: paracosm draws no vehicle lights or animations, and its \
           sensors and monitors read none",
};

/// The controller an `ActivateControllerAction` names.
pub const CONTROLLER_NAMED: Noted = Noted {
    what: "the controller an `ActivateControllerAction` names (`objectControllerRef`, \
           `controllerRef`)",
    note: "which of the entity's controllers is named makes no difference to paracosm: the \
           system under test drives the ego it hands over, and the storyboard moves the rest",
};

/// A negative transition rate.
pub const NEGATIVE_RATE: Noted = Noted {
    what: "a negative transition rate (read as its magnitude: the ALKS cut-in writes \
           decelerations so)",
    note: "the target gives the direction",
};

/// A condition's name that is an expression paracosm does not evaluate.
pub const CONDITION_NAME: Noted = Noted {
    what: "a condition's name that is an expression paracosm does not evaluate (esmini's \
           expressions also join texts, `name=\"${Brake + _ + $Gap}\"`)",
    note: "is not an expression paracosm evaluates (esmini's concatenate texts); it is a label \
           nothing refers to, kept as written",
};

/// A maneuver group with no actor.
pub const NO_ACTOR: Noted = Noted {
    what: "a maneuver group with no actor",
    note: "this maneuver group names no actor (and selectTriggeringEntities is false): its \
           private actions act on nobody",
};

/// An act without a start trigger.
pub const ACT_WITHOUT_START: Noted = Noted {
    what: "an act without the `StartTrigger` the schema requires (it starts at once, as in \
           esmini)",
    note: "this act has no <StartTrigger>, which the standard requires: it starts at once",
};

/// The road network's 3D model.
pub const SCENE_GRAPH: Noted = Noted {
    what: "the road network's 3D model (`SceneGraphFile`)",
    note: "the 3D model (SceneGraphFile) is not drawn: paracosm draws the road from the \
           OpenDRIVE file",
};

/// Traffic signal controllers of the road network.
pub const SIGNAL_CONTROLLERS: Noted = Noted {
    what: "the road network's traffic signal controllers",
    note: "traffic signal controllers are not simulated",
};

/// A road condition's properties and wetness.
pub const ROAD_CONDITION: Noted = Noted {
    what: "a road condition's properties and wetness",
    note: "a road condition's properties and wetness are not modelled: its friction scale \
           factor is",
};

/// The weather's parts no model reads.
pub const WEATHER_PART: Noted = Noted {
    what:
        "the weather's `atmosphericPressure`, `temperature`, `cloudState`/`fractionalCloudCover`, \
           `Wind` and `DomeImage`",
    note: "is read but not modelled: paracosm's world has no counterpart",
};

/// The sun's azimuth.
pub const SUN_AZIMUTH: Noted = Noted {
    what: "the sun's azimuth",
    note: "the sun's azimuth is not modelled: paracosm's light is the same from every direction",
};

/// A fog's bounding box.
pub const FOG_BOX: Noted = Noted {
    what: "a fog's bounding box",
    note: "a fog's bounding box is not modelled: the fog fills the world",
};

/// An `OverrideControllerValueAction` whose values are all inactive.
pub const INACTIVE_OVERRIDE: Noted = Noted {
    what: "an `OverrideControllerValueAction` whose values are all inactive (it does nothing)",
    note: "every value of this OverrideControllerValueAction is inactive: it overrides nothing",
};

/// Every note above, in the order the docs list them.
pub const NOTED: &[&Noted] = &[
    &WORLD_Z,
    &RELATIVE_DZ,
    &DYNAMICS_FOLLOWING,
    &APPEARANCE,
    &CONTROLLER_NAMED,
    &NEGATIVE_RATE,
    &CONDITION_NAME,
    &NO_ACTOR,
    &ACT_WITHOUT_START,
    &SCENE_GRAPH,
    &SIGNAL_CONTROLLERS,
    &ROAD_CONDITION,
    &WEATHER_PART,
    &SUN_AZIMUTH,
    &FOG_BOX,
    &INACTIVE_OVERRIDE,
];

/// The tables as docs/openscenario.md lists them (markdown): each choice group with what is
/// read and what is refused and why, then what is read but not applied.
pub fn markdown() -> String {
    let code = |names: &[&str]| {
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut out = String::from("| in | read | refused, and why |\n|---|---|---|\n");
    for c in CHOICES {
        let refused = if c.refused.is_empty() {
            "none".to_string()
        } else {
            c.refused
                .iter()
                .map(|(n, why)| format!("`{n}`: {why}"))
                .collect::<Vec<_>>()
                .join("; ")
        };
        // Infallible: writing to a String.
        let _ = writeln!(out, "| `{}` | {} | {refused} |", c.parent, code(c.read));
    }
    out.push_str("\nRead but not applied, each noted at load where it is written:\n\n");
    for n in NOTED {
        let _ = writeln!(out, "- {}: `{}`", n.what, n.note);
    }
    out
}
