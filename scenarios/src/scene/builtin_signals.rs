//! Names of the signals the runner publishes to monitors at every step: part of the scene
//! model, since monitors (`Stl`, `Monitor`) and published signals are checked against them
//! when a scene is built.

/// Ego vehicle centre, `x`, in metres.
pub const EGO_X_M: &str = "ego_x_m";
/// Ego vehicle centre, `z`, in metres.
pub const EGO_Z_M: &str = "ego_z_m";
/// Ego speed along its heading, m/s.
pub const EGO_SPEED_MPS: &str = "ego_speed_mps";
/// `1.0` while the ego vehicle touches a pedestrian or a car, else `0.0`.
pub const EGO_CONTACT: &str = "ego_contact";
/// Smallest distance between the ego body and a pedestrian or a car, metres (`0`
/// touching).
pub const EGO_SEPARATION_M: &str = "ego_separation_m";
/// Path time to collision of the ego vehicle, seconds (`+inf` when nothing in its path
/// closes in; `paracosm_engine::ttc`).
pub const EGO_TTC_S: &str = "ego_ttc_s";
/// `1.0` while the centre of the ego vehicle's footprint is on no driving surface of the
/// network (a sidewalk, an island, the ground beside the road or past a dead end), else
/// `0.0`.
pub const EGO_OFFROAD: &str = "ego_offroad";
/// Signed distance from the ego's footprint centre to the edge of the driving surface,
/// metres: `> 0` on it, `<= 0` off it.
pub const EGO_ROAD_EDGE_M: &str = "ego_road_edge_m";
/// Lateral offset of the ego's centre from the centre line of the nearest lane in its
/// direction of travel, metres, positive to the right.
pub const EGO_LANE_OFFSET_M: &str = "ego_lane_offset_m";
/// Fog density, `[0, 1]`.
pub const FOG: &str = "fog";
/// Light intensity, `[0, 1]`.
pub const LIGHT: &str = "light";
/// Every signal, for `Stl` formulas.
pub const ALL: [&str; 11] = [
    EGO_X_M,
    EGO_Z_M,
    EGO_SPEED_MPS,
    EGO_CONTACT,
    EGO_SEPARATION_M,
    EGO_TTC_S,
    EGO_OFFROAD,
    EGO_ROAD_EDGE_M,
    EGO_LANE_OFFSET_M,
    FOG,
    LIGHT,
];
