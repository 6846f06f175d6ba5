//! The camera renderer on fixed scenes: golden images with tolerances, depth against
//! geometry, fog and light. These tests need a GPU adapter; on a machine without a GPU, Mesa's
//! lavapipe (Debian `mesa-vulkan-drivers`, installed by `scripts/test`) provides one. They
//! never skip: without an adapter they fail.
#![cfg(feature = "render")]

use std::path::{Path, PathBuf};

use paracosm_engine::network::{Network, PieceKind};
use paracosm_engine::render::{CameraPose, RenderJob, RenderObject, Renderer, NOMINAL_LIGHT};
use paracosm_engine::Size;
use paracosm_engine::{CameraFrame, CameraSpec};

fn renderer() -> std::sync::Arc<Renderer> {
    Renderer::shared().expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)")
}

const WHITE: [f32; 3] = [0.92, 0.92, 0.92];
const RED: [f32; 3] = [0.75, 0.08, 0.07];

fn car_at(x: f64, z: f64, albedo: [f32; 3]) -> RenderObject {
    RenderObject {
        base_m: [x, 0.0, z],
        size: Size {
            length_m: 4.5,
            width_m: 1.9,
            height_m: 1.7,
        },
        heading_rad: 0.0,
        albedo,
        class: paracosm_engine::SemanticClass::Car,
        actor: 0,
    }
}

/// The ego camera at the start of lane 1 of a straight 4-lane road, 10 m in.
fn pose() -> CameraPose {
    CameraPose {
        chassis_m: [10.0, 0.5, 1.75],
        heading_rad: 0.0,
    }
}

fn render(
    network: &Network,
    camera: &CameraSpec,
    pose: CameraPose,
    objects: &[RenderObject],
    light: f64,
    fog: f64,
) -> CameraFrame {
    let r = renderer();
    let scene = r.scene(network);
    let mut view = r.view(camera).unwrap();
    r.render_one(RenderJob {
        scene: &scene,
        view: &mut view,
        pose,
        objects,
        light,
        fog,
        t_s: 0.0,
        noise_seed: 0,
    })
    .unwrap()
}

fn road() -> Network {
    Network::single_segment(200.0, 4, 1.0).unwrap()
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// Compares `frame` with `tests/golden/NAME.png`: the mean absolute difference over all
/// channels must be at most 1.5 levels and the 99th percentile at most 24 levels (renderers
/// differ in rasterisation rules at edges, not in colour). On failure writes
/// `NAME-actual.png` and `NAME-difference.png` beside the reference. `PARACOSM_BLESS=1`
/// (re)writes the reference.
fn assert_golden(name: &str, frame: &CameraFrame) {
    let reference = golden_dir().join(format!("{name}.png"));
    if std::env::var_os("PARACOSM_BLESS").is_some() {
        frame.save_png(&reference).unwrap();
        return;
    }
    let expected = image::open(&reference)
        .unwrap_or_else(|e| panic!("{}: {e} (PARACOSM_BLESS=1 writes it)", reference.display()))
        .to_rgb8();
    assert_eq!(
        (expected.width(), expected.height()),
        (frame.width, frame.height),
        "{name}: size"
    );
    let mut diffs: Vec<u8> = expected
        .as_raw()
        .iter()
        .zip(&frame.rgb)
        .map(|(a, b)| a.abs_diff(*b))
        .collect();
    let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
    let difference: Vec<u8> = diffs.iter().map(|&d| d.saturating_mul(4)).collect();
    diffs.sort_unstable();
    let p99 = diffs[diffs.len() * 99 / 100];
    if mean > 1.5 || p99 > 24 {
        let actual = golden_dir().join(format!("{name}-actual.png"));
        let diff_path = golden_dir().join(format!("{name}-difference.png"));
        frame.save_png(&actual).unwrap();
        image::RgbImage::from_raw(frame.width, frame.height, difference)
            .unwrap()
            .save(&diff_path)
            .unwrap();
        panic!(
            "{name}: mean difference {mean:.2} levels (at most 1.5), 99th percentile {p99} (at \
             most 24); wrote {} and {}",
            actual.display(),
            diff_path.display()
        );
    }
}

#[test]
fn an_adapter_is_found() {
    let r = Renderer::new().expect("no GPU adapter: these tests must not skip");
    eprintln!("adapter: {}", r.adapter());
    assert!(!r.adapter().is_empty());
}

#[test]
fn the_gl_backend_renders_what_vulkan_renders() {
    // llvmpipe's OpenGL (through EGL) has no depth-buffer copies and cannot render R32Float:
    // depth goes through the R32Uint colour target on both backends.
    let gl = Renderer::with_backends(paracosm_engine::render::Backends::GL)
        .expect("a GL adapter (Mesa's llvmpipe through EGL)");
    let vk = Renderer::with_backends(paracosm_engine::render::Backends::VULKAN)
        .expect("a Vulkan adapter (lavapipe)");
    let frame = |r: &Renderer| {
        let scene = r.scene(&road());
        let mut view = r.view(&CameraSpec::default()).unwrap();
        r.render_one(RenderJob {
            scene: &scene,
            view: &mut view,
            pose: pose(),
            objects: &[car_at(35.0, 1.75, RED)],
            light: 0.5,
            fog: 0.1,
            t_s: 0.0,
            noise_seed: 0,
        })
        .unwrap()
    };
    let (a, b) = (frame(&gl), frame(&vk));
    let mean = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / a.rgb.len() as f64;
    assert!(mean < 1.5, "mean difference {mean} levels");
    let same_depth = a
        .depth_m
        .iter()
        .zip(&b.depth_m)
        .filter(|(x, y)| x == y || (x.is_finite() && (*x - *y).abs() < 1e-3 * x.abs()))
        .count();
    assert!(
        same_depth as f64 > 0.99 * a.depth_m.len() as f64,
        "{same_depth} of {} depths agree",
        a.depth_m.len()
    );
}

/// The white car 22 m ahead on the straight road, at nominal light and `fog`.
fn straight_road_car(fog: f64) -> CameraFrame {
    render(
        &road(),
        &CameraSpec::default(),
        pose(),
        &[car_at(35.0, 1.75, WHITE)],
        NOMINAL_LIGHT,
        fog,
    )
}

#[test]
fn golden_straight_road_with_a_white_car_ahead() {
    assert_golden("straight_road_car", &straight_road_car(0.0));
}

#[test]
fn golden_straight_road_in_fog() {
    assert_golden("straight_road_car_fog_0.8", &straight_road_car(0.8));
}

#[test]
fn golden_cross_intersection_at_dusk() {
    let mut n = Network::new();
    let a = n
        .add(
            "a",
            PieceKind::Segment {
                length_m: 60.0,
                lanes: 2,
                friction: 1.0,
            },
        )
        .unwrap();
    let x = n
        .add(
            "x",
            PieceKind::CrossIntersection {
                lanes: 2,
                friction: 1.0,
            },
        )
        .unwrap();
    n.connect(a, 1, x, 2).unwrap();
    let frame = render(
        &n,
        &CameraSpec {
            focal_mm: 18.0,
            ..CameraSpec::default()
        },
        CameraPose {
            chassis_m: [40.0, 0.5, 1.75],
            heading_rad: 0.0,
        },
        &[
            car_at(70.0, -1.75, RED),
            RenderObject {
                base_m: [55.0, 0.15, 5.0],
                size: Size {
                    length_m: 0.5,
                    width_m: 0.5,
                    height_m: 1.8,
                },
                heading_rad: 0.0,
                albedo: [0.75, 0.22, 0.18],
                class: paracosm_engine::SemanticClass::Pedestrian,
                actor: 0,
            },
        ],
        0.3,
        0.0,
    );
    assert_golden("cross_intersection_dusk", &frame);
}

#[test]
fn depth_is_the_distance_along_the_optical_axis() {
    let camera = CameraSpec {
        pitch_rad: 0.0,
        ..CameraSpec::default()
    };
    let frame = render(
        &road(),
        &camera,
        pose(),
        &[car_at(35.0, 1.75, WHITE)],
        0.6,
        0.0,
    );
    // The camera sits 0.5 m ahead of the chassis at x = 10, so the car's rear face (x = 32.75)
    // is 22.25 m away, straight ahead at the image centre.
    let d = frame.depth_at(160, 118);
    assert!((d - 22.25).abs() < 0.05, "depth {d}");
    // The sky has no depth.
    assert_eq!(frame.depth_at(160, 2), f32::INFINITY);
    // A road pixel below the centre lies on the ground, 0.5 m below the chassis centre.
    let (u, v) = (160.0, 200.0);
    let depth = f64::from(frame.depth_at(160, 200));
    let p = camera.camera_to_vehicle(camera.back_project(u + 0.5, v + 0.5, depth));
    assert!((p[1] + 0.5).abs() < 0.02, "vehicle-frame point {p:?}");
}

fn contrast(frame: &CameraFrame, car: (u32, u32), background: (u32, u32)) -> f64 {
    let a = frame.rgb_at(car.0, car.1);
    let b = frame.rgb_at(background.0, background.1);
    a.iter()
        .zip(&b)
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
}

#[test]
fn fog_fades_the_car_into_the_sky_and_light_scales_the_image() {
    let objects = [car_at(35.0, 1.75, RED)];
    let at = |fog: f64, light: f64| {
        render(
            &road(),
            &CameraSpec::default(),
            pose(),
            &objects,
            light,
            fog,
        )
    };
    let car_px = (160, 112);
    let sky_px = (160, 5);
    let clear = contrast(&at(0.0, 0.6), car_px, sky_px);
    let misty = contrast(&at(0.2, 0.6), car_px, sky_px);
    let dense = contrast(&at(0.8, 0.6), car_px, sky_px);
    assert!(clear > misty && misty > dense, "{clear} {misty} {dense}");
    assert!(
        dense < 10.0,
        "22 m in fog 0.8 is beyond the 9.8 m visibility: {dense}"
    );
    let mean =
        |f: &CameraFrame| f.rgb.iter().map(|&v| f64::from(v)).sum::<f64>() / f.rgb.len() as f64;
    let dark = mean(&at(0.0, 0.15));
    let nominal = mean(&at(0.0, 0.6));
    assert!((dark / nominal - 0.25).abs() < 0.03, "{dark} {nominal}");
}

#[test]
fn many_views_render_in_one_batch_like_one_at_a_time() {
    let r = renderer();
    let network = road();
    let scene = r.scene(&network);
    let camera = CameraSpec::default();
    let objects = [car_at(35.0, 1.75, WHITE)];
    let mut views: Vec<_> = (0..4).map(|_| r.view(&camera).unwrap()).collect();
    let mut jobs: Vec<RenderJob<'_>> = views
        .iter_mut()
        .enumerate()
        .map(|(i, view)| RenderJob {
            scene: &scene,
            view,
            pose: CameraPose {
                chassis_m: [10.0 + i as f64, 0.5, 1.75],
                heading_rad: 0.0,
            },
            objects: &objects,
            light: 0.6,
            fog: 0.0,
            t_s: 0.0,
            noise_seed: 0,
        })
        .collect();
    let batch = r.render(&mut jobs).unwrap();
    for (i, frame) in batch.iter().enumerate() {
        let single = render(
            &network,
            &camera,
            CameraPose {
                chassis_m: [10.0 + i as f64, 0.5, 1.75],
                heading_rad: 0.0,
            },
            &objects,
            0.6,
            0.0,
        );
        assert_eq!(frame.rgb, single.rgb, "view {i}");
        assert_eq!(frame.depth_m, single.depth_m, "view {i}");
    }
    assert_ne!(batch[0].rgb, batch[3].rgb, "the views moved");
}

/// Issue 15: an NPC car's collider and its drawing have one size (length, width, height, in
/// one axis order). Seen from behind, the car's rear face in the image is as wide and as high
/// as the collider's rear face, projected through the camera's intrinsics; and the drawn box
/// matches the collider's extents.
#[test]
fn an_npc_cars_collider_and_its_drawing_agree() {
    use paracosm_engine::behaviour::GraphBuilder;
    use paracosm_engine::rx::{Node, Value};
    use paracosm_engine::{CarSpec, Lane, PieceId, Simulation};
    let network = road();
    let start = network.on_lane(PieceId(0), Lane::Driving(1), 10.0).unwrap();
    let car_at = network.on_lane(PieceId(0), Lane::Driving(1), 40.0).unwrap();
    let mut g = GraphBuilder::new();
    let still = g.push(Node::Const(Value::Num(0.0)));
    let cars = vec![CarSpec {
        path: network.route(&car_at, &[], 100.0).unwrap(),
        speed: still,
        color: "white".into(),
        size: Size::CAR,
        enabled: true,
        lane_change: None,
        lane_offsets_m: vec![],
        name: String::new(),
        keep_distance_m: None,
        tow: None,
    }];
    let spec = standing_world(network, start, g, cars, vec![]);
    let mut sim = Simulation::new(&spec).unwrap();
    let camera = CameraSpec {
        width: 640,
        height: 480,
        pitch_rad: 0.0,
        ..CameraSpec::default()
    };
    sim.attach_camera(&camera, 0).unwrap();

    // The collider: half extents along length, height, width.
    let [hl, hh, hw] = sim.car_collider_half_extents_m(0).unwrap();
    assert!(
        (2.0 * hl - Size::CAR.length_m).abs() < 1e-6,
        "length {}",
        2.0 * hl
    );
    assert!(
        (2.0 * hw - Size::CAR.width_m).abs() < 1e-6,
        "width {}",
        2.0 * hw
    );
    assert!(
        (2.0 * hh - Size::CAR.height_m).abs() < 1e-6,
        "height {}",
        2.0 * hh
    );
    let drawn = sim.visible_boxes()[0];
    assert_eq!(drawn.size.length_m, Size::CAR.length_m);
    assert_eq!(drawn.size.width_m, Size::CAR.width_m);

    // The image: the rear face stands 40 - 2.25 m from the start, the camera 0.5 m ahead of
    // the chassis centre.
    let frame = sim.camera_frame().unwrap();
    let ego = sim.ego_state();
    let depth = 40.0 - Size::CAR.length_m / 2.0 - (ego.pos_m[0] + camera.mount_m[0]);
    let fx = camera.focal_mm * f64::from(camera.width) / 36.0;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let on_car = |u: usize, v: usize| (f64::from(frame.depth_m[v * w + u]) - depth).abs() < 0.05;
    let rows: Vec<usize> = (0..h).filter(|&v| (0..w).any(|u| on_car(u, v))).collect();
    let (row, last) = (rows[0], *rows.last().expect("the car is in the image"));
    let middle = (row + last) / 2;
    let columns = (0..w).filter(|&u| on_car(u, middle)).count() as f64;
    let expected_width = fx * Size::CAR.width_m / depth;
    assert!(
        (columns - expected_width).abs() <= 2.0,
        "rear face {columns} px wide, the collider {expected_width:.1} px"
    );
    // The roof: the top row of the rear face is the collider's top, projected.
    let camera_y = ego.pos_m[1] + camera.mount_m[1];
    let top = 0.2 + Size::CAR.height_m;
    let cy = f64::from(camera.height) / 2.0;
    let expected_row = cy - fx * (top - camera_y) / depth;
    assert!(
        (row as f64 - expected_row).abs() <= 2.0,
        "roof at row {row}, the collider's at {expected_row:.1}"
    );
}

/// Issue 15: an `Obstacle` is drawn by the camera. A yellow box 3 m wide and 1 m high stands in
/// the ego's lane 30 m ahead; the camera sees a yellow face at the box's distance, as wide as
/// the box projected through the intrinsics; without the box, nothing stands at that depth.
#[test]
fn an_obstacle_is_drawn_by_the_camera_at_its_place_and_size() {
    use paracosm_engine::behaviour::GraphBuilder;
    use paracosm_engine::{Lane, ObstacleSpec, PieceId, Simulation};
    let network = road();
    let start = network.on_lane(PieceId(0), Lane::Driving(1), 10.0).unwrap();
    let at = network.on_lane(PieceId(0), Lane::Driving(1), 40.0).unwrap();
    let size = Size {
        length_m: 0.5,
        width_m: 3.0,
        height_m: 1.0,
    };
    let camera = CameraSpec {
        width: 640,
        height: 480,
        pitch_rad: 0.0,
        ..CameraSpec::default()
    };
    let frame_with = |obstacles: Vec<ObstacleSpec>| {
        let spec = standing_world(
            network.clone(),
            start,
            GraphBuilder::new(),
            vec![],
            obstacles,
        );
        let mut sim = Simulation::new(&spec).unwrap();
        sim.attach_camera(&camera, 0).unwrap();
        let ego_x = sim.ego_state().pos_m[0];
        (sim.camera_frame().unwrap().clone(), ego_x)
    };
    let (frame, ego_x) = frame_with(vec![ObstacleSpec {
        base_m: at.pos_m,
        heading_rad: at.heading_rad,
        size,
        color: "yellow".into(),
    }]);
    let (empty, _) = frame_with(vec![]);

    let depth = at.pos_m[0] - size.length_m / 2.0 - (ego_x + camera.mount_m[0]);
    let (w, h) = (frame.width as usize, frame.height as usize);
    let at_box = |f: &CameraFrame, u: usize, v: usize| {
        (f64::from(f.depth_m[v * w + u]) - depth).abs() < 0.05
    };
    let rows: Vec<usize> = (0..h)
        .filter(|&v| (0..w).any(|u| at_box(&frame, u, v)))
        .collect();
    assert!(!rows.is_empty(), "the obstacle is in the image");
    let middle = (rows[0] + rows[rows.len() - 1]) / 2;
    let columns: Vec<usize> = (0..w).filter(|&u| at_box(&frame, u, middle)).collect();
    let fx = camera.focal_mm * f64::from(camera.width) / 36.0;
    let expected = fx * size.width_m / depth;
    assert!(
        (columns.len() as f64 - expected).abs() <= 2.0,
        "face {} px wide, the box {expected:.1} px",
        columns.len()
    );
    // Yellow: red and green well above blue.
    let u = columns[columns.len() / 2];
    let px = &frame.rgb[(middle * w + u) * 3..(middle * w + u) * 3 + 3];
    assert!(
        px[0] > px[2].saturating_add(40) && px[1] > px[2].saturating_add(40),
        "pixel {px:?} is not yellow"
    );
    assert!(
        !(0..w).any(|u| at_box(&empty, u, middle)),
        "without the obstacle nothing stands at its distance"
    );
}

/// A world on `network` in nominal daylight without fog, the ego vehicle standing at `start`,
/// with `cars` (whose streams `g` holds) and `obstacles`.
fn standing_world(
    network: paracosm_engine::Network,
    start: paracosm_engine::Location,
    mut g: paracosm_engine::behaviour::GraphBuilder,
    cars: Vec<paracosm_engine::CarSpec>,
    obstacles: Vec<paracosm_engine::ObstacleSpec>,
) -> paracosm_engine::WorldSpec {
    use paracosm_engine::rx::{Node, Value};
    let light = g.push(Node::Const(Value::Num(paracosm_engine::NOMINAL_LIGHT)));
    let fog = g.push(Node::Const(Value::Num(0.0)));
    paracosm_engine::WorldSpec {
        dt_s: paracosm_engine::DEFAULT_DT_S,
        frictions: vec![],
        ego: paracosm_engine::EgoSpec {
            start,
            initial_speed_mps: 0.0,
            vehicle: paracosm_engine::VehicleParams::default(),
            route: vec![],
            set_speed_mps: None,
            scripted: false,
        },
        pedestrians: vec![],
        cars,
        obstacles,
        environment: paracosm_engine::EnvironmentSpec { light, fog },
        streams: g.finish().unwrap(),
        published: vec![],
        sensors: paracosm_engine::SensorSpec::defaults(),
        network,
    }
}

/// Projects a world point through `camera` on a vehicle at `pose`: `(u, v, z-depth)`.
fn project(camera: &CameraSpec, pose: CameraPose, p: [f64; 3]) -> (f64, f64, f64) {
    let (s, c) = pose.heading_rad.sin_cos();
    let fwd = [c, 0.0, -s];
    let right = [s, 0.0, c];
    let up = [0.0, 1.0, 0.0];
    let [mf, mu, mr] = camera.mount_m;
    let eye: Vec<f64> = (0..3)
        .map(|i| pose.chassis_m[i] + fwd[i] * mf + up[i] * mu + right[i] * mr)
        .collect();
    let (ps, pc) = camera.pitch_rad.sin_cos();
    let axis: Vec<f64> = (0..3).map(|i| fwd[i] * pc - up[i] * ps).collect();
    let cam_up: Vec<f64> = (0..3).map(|i| fwd[i] * ps + up[i] * pc).collect();
    let rel: Vec<f64> = (0..3).map(|i| p[i] - eye[i]).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (x, y, z) = (dot(&rel, &right), dot(&rel, &cam_up), dot(&rel, &axis));
    let f = camera.focal_px();
    (
        f64::from(camera.width) / 2.0 + f * x / z,
        f64::from(camera.height) / 2.0 - f * y / z,
        z,
    )
}

/// The eight corners of a drawn box, world metres.
fn corners(o: &RenderObject) -> Vec<[f64; 3]> {
    let (s, c) = o.heading_rad.sin_cos();
    let mut out = Vec::new();
    for a in [-0.5, 0.5] {
        for b in [-0.5, 0.5] {
            for h in [0.0, 1.0] {
                let (l, w) = (a * o.size.length_m, b * o.size.width_m);
                out.push([
                    o.base_m[0] + l * c + w * s,
                    o.base_m[1] + h * o.size.height_m,
                    o.base_m[2] - l * s + w * c,
                ]);
            }
        }
    }
    out
}

/// Requirement (issue 20, 1): the boxes come from the renderer's labels and agree with the
/// actor projected through the camera model, to a pixel on every edge.
#[test]
fn label_boxes_match_the_projected_actors() {
    use paracosm_engine::SemanticClass;
    let camera = CameraSpec::default();
    let car = RenderObject {
        actor: 2,
        heading_rad: 0.3,
        ..car_at(32.0, 3.0, WHITE)
    };
    let pedestrian = RenderObject {
        base_m: [24.0, 0.0, -2.5],
        size: Size::PEDESTRIAN,
        heading_rad: 0.0,
        albedo: [0.75, 0.22, 0.18],
        class: SemanticClass::Pedestrian,
        actor: 0,
    };
    let frame = render(&road(), &camera, pose(), &[car, pedestrian], 0.6, 0.4);
    let boxes = frame.boxes();
    assert_eq!(boxes.len(), 2, "{boxes:?}");
    for (o, b) in [(car, boxes[0]), (pedestrian, boxes[1])] {
        assert_eq!((b.class, b.actor), (o.class, o.actor));
        let (mut u0, mut v0, mut u1, mut v1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in corners(&o) {
            let (u, v, z) = project(&camera, pose(), p);
            assert!(z > 0.0);
            (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u), v1.max(v));
        }
        // Pixel i is covered when its centre i + 0.5 lies inside the projection.
        let expected = [
            (u0 - 0.5).ceil(),
            (v0 - 0.5).ceil(),
            (u1 - 0.5).floor() + 1.0,
            (v1 - 0.5).floor() + 1.0,
        ];
        let got = [b.x0, b.y0, b.x1, b.y1].map(f64::from);
        for (e, g) in expected.iter().zip(got) {
            assert!(
                (e - g).abs() <= 1.0,
                "{:?}: box {got:?}, projected {expected:?}",
                o.class
            );
        }
        assert!(b.pixels > 50, "{b:?}");
    }
}

/// Requirement (issue 20, 1): the mask agrees with the depth map on every pixel: sky exactly
/// where the depth is infinite, each surface class at its height (road 0, markings 1 cm,
/// sidewalk tops and curbs 0–15 cm, grass −2 cm), actors inside their box's depth range.
#[test]
fn the_mask_agrees_with_the_depth_map_on_every_pixel() {
    use paracosm_engine::SemanticClass;
    let camera = CameraSpec::default();
    let car = car_at(30.0, -1.75, RED);
    let frame = render(&road(), &camera, pose(), &[car], 0.6, 0.0);
    let depth_range: Vec<f64> = corners(&car)
        .iter()
        .map(|&p| project(&camera, pose(), p).2)
        .collect();
    let (near, far) = (
        depth_range.iter().copied().fold(f64::MAX, f64::min),
        depth_range.iter().copied().fold(f64::MIN, f64::max),
    );
    let mut seen = std::collections::BTreeMap::new();
    for v in 0..frame.height {
        for u in 0..frame.width {
            let class = frame.class_at(u, v);
            *seen.entry(class).or_insert(0u32) += 1;
            let d = f64::from(frame.depth_at(u, v));
            assert_eq!(class == SemanticClass::Sky, d.is_infinite(), "({u}, {v})");
            if d.is_infinite() {
                continue;
            }
            let p = camera.camera_to_vehicle(camera.back_project(
                f64::from(u) + 0.5,
                f64::from(v) + 0.5,
                d,
            ));
            let y = pose().chassis_m[1] + p[1];
            let at = |h: f64, tol: f64| (y - h).abs() < tol;
            let ok = match class {
                SemanticClass::Road => at(0.0, 0.02),
                SemanticClass::LaneMarking => at(0.01, 0.02),
                SemanticClass::Sidewalk => (-0.02..0.17).contains(&y),
                SemanticClass::Ground => at(-0.02, 0.03),
                SemanticClass::Car => (near - 0.05..far + 0.05).contains(&d),
                other => panic!("({u}, {v}): unexpected {other:?}"),
            };
            assert!(
                ok,
                "({u}, {v}) {class:?} at height {y:.3} m, depth {d:.2} m"
            );
        }
    }
    for c in [
        SemanticClass::Sky,
        SemanticClass::Road,
        SemanticClass::LaneMarking,
        SemanticClass::Sidewalk,
        SemanticClass::Ground,
        SemanticClass::Car,
    ] {
        assert!(seen.get(&c).copied().unwrap_or(0) > 20, "{c:?}: {seen:?}");
    }
}

/// Issue 21: a bend to the left drawn with its curved surfaces and markings. Beside the
/// golden image, a check that does not depend on it: the double yellow centre line, which
/// starts to the left of the camera, runs further left as it recedes (on a straight road it
/// converges toward the image centre).
#[test]
fn golden_left_bend_with_curved_markings() {
    let mut n = Network::new();
    let a = n
        .add(
            "a",
            PieceKind::Segment {
                length_m: 30.0,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    let c = n
        .add(
            "c",
            PieceKind::Clothoid {
                length_m: 20.0,
                curv_start: 0.0,
                curv_end: 1.0 / 30.0,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    let b = n
        .add(
            "b",
            PieceKind::Arc {
                radius_m: 30.0,
                angle_rad: 1.5,
                lanes: 2,
                friction: 0.8,
            },
        )
        .unwrap();
    n.connect(a, 1, c, 0).unwrap();
    n.connect(c, 1, b, 0).unwrap();
    let pose = CameraPose {
        chassis_m: [28.0, 0.5, 1.75],
        heading_rad: 0.0,
    };
    let frame = render(&n, &CameraSpec::default(), pose, &[], NOMINAL_LIGHT, 0.0);
    assert_golden("left_bend", &frame);
    // The mean column of the centre line's pixels 10 to 25 m ahead, where the bend has
    // moved it 0.5 to 6 m to the left.
    let far_centre_line = |frame: &CameraFrame| {
        let (w, h) = (frame.width, frame.height);
        let mut cols = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let [r, g, b] = frame.rgb_at(u, v);
                let d = frame.depth_at(u, v);
                // Yellow, or yellow blended with asphalt where the line is under a pixel wide.
                let paint = i32::from(r) > i32::from(b) + 30
                    && i32::from(g) > i32::from(b) + 15
                    && i32::from(r) + 10 >= i32::from(g);
                if paint && (10.0..25.0).contains(&d) {
                    cols.push(f64::from(u));
                }
            }
        }
        assert!(cols.len() > 10, "no centre line 10 to 25 m ahead");
        cols.iter().sum::<f64>() / cols.len() as f64
    };
    let straight = render(
        &Network::single_segment(200.0, 2, 0.8).unwrap(),
        &CameraSpec::default(),
        pose,
        &[],
        NOMINAL_LIGHT,
        0.0,
    );
    let (bend, ahead) = (far_centre_line(&frame), far_centre_line(&straight));
    assert!(
        bend < ahead - 6.0,
        "the far centre line at column {bend} on the bend, {ahead} on a straight road"
    );
}

/// A campaign on one OpenDRIVE map uploads the map's world once: a second test's network
/// (a clone of the first's, as each test builds) draws from the same GPU buffers, and a map
/// loaded anew has its own.
#[test]
fn a_maps_world_is_uploaded_once_and_shared_by_every_test() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios/maps/junction.xodr");
    let text = std::fs::read_to_string(&path).unwrap();
    let map = paracosm_engine::network::opendrive::import("junction.xodr", &text)
        .unwrap()
        .map;
    let mut first = Network::new();
    first.add_map("OpenDrive m", map.clone(), 0.8).unwrap();
    let second = first.clone();
    let r = renderer();
    let a = r.scene(&first);
    let b = r.scene(&second);
    assert!(a.shares_buffers_with(&b));
    let mut fresh = Network::new();
    fresh.add_map("OpenDrive m", map, 0.8).unwrap();
    assert!(!r.scene(&fresh).shares_buffers_with(&a));
    // A network of paracosm's own pieces uploads per call.
    let mut own = Network::new();
    own.add(
        "RoadSegment r",
        PieceKind::Segment {
            length_m: 50.0,
            lanes: 2,
            friction: 0.8,
        },
    )
    .unwrap();
    assert!(!r.scene(&own).shares_buffers_with(&r.scene(&own)));
}

/// A view that reads a region only ([`FrameUse`]) draws it through a scissor rectangle and
/// reads back only it and only the planes asked for: inside the region its image, depth and
/// labels are the whole frame's bit for bit (with pixel noise too: drawn for the whole frame
/// in order); outside it the image is black, and planes not asked for are empty. Reused
/// frame buffers ([`View::recycle`]) give the same frames as new ones.
#[test]
fn a_region_of_the_frame_is_the_whole_frames_pixels_bit_for_bit() {
    use paracosm_engine::render::View;
    use paracosm_engine::FrameUse;
    let r = renderer();
    let network = road();
    let scene = r.scene(&network);
    let objects = [car_at(30.0, 1.75, RED), car_at(45.0, 5.25, WHITE)];
    for noise_sigma in [0.0, 3.0] {
        let camera = CameraSpec {
            noise_sigma,
            ..CameraSpec::default()
        };
        let draw = |view: &mut View, x: f64| {
            r.render_one(RenderJob {
                scene: &scene,
                view,
                pose: CameraPose {
                    chassis_m: [x, 0.5, 1.75],
                    heading_rad: 0.02,
                },
                objects: &objects,
                light: NOMINAL_LIGHT,
                fog: 0.1,
                t_s: 0.0,
                noise_seed: 11,
            })
            .unwrap()
        };
        let region = [60, 96, 200, 104];
        let mut whole = r.view(&camera).unwrap();
        let mut image_only = r.view_for(&camera, FrameUse::image(Some(region))).unwrap();
        let with_depth = FrameUse {
            depth: true,
            labels: false,
            region: Some(region),
        };
        let mut depth_region = r.view_for(&camera, with_depth).unwrap();
        for x in [10.0, 12.5] {
            let full = draw(&mut whole, x);
            let part = draw(&mut image_only, x);
            let deep = draw(&mut depth_region, x);
            assert_eq!(part.region, region);
            assert!(part.depth_m.is_empty() && part.labels.is_empty());
            assert!(deep.labels.is_empty() && deep.depth_m.len() == full.depth_m.len());
            let (mut inside, mut car) = (0, 0);
            for v in 0..camera.height {
                for u in 0..camera.width {
                    let i = (v * camera.width + u) as usize;
                    let within = (60..260).contains(&u) && (96..200).contains(&v);
                    if within {
                        inside += 1;
                        assert_eq!(part.rgb_at(u, v), full.rgb_at(u, v), "({u}, {v})");
                        assert_eq!(deep.rgb_at(u, v), full.rgb_at(u, v), "({u}, {v})");
                        assert_eq!(deep.depth_m[i].to_bits(), full.depth_m[i].to_bits());
                        car +=
                            usize::from(full.class_at(u, v) == paracosm_engine::SemanticClass::Car);
                    } else {
                        assert_eq!(part.rgb_at(u, v), [0, 0, 0], "({u}, {v}) outside");
                        assert_eq!(deep.depth_m[i], f32::INFINITY);
                    }
                }
            }
            assert_eq!(inside, 200 * 104);
            assert!(car > 50, "the region shows the red car: {car} pixels");
            // The next frame reuses these buffers.
            image_only.recycle(part);
            depth_region.recycle(deep);
            whole.recycle(full);
        }
    }
}
