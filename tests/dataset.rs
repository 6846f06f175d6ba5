//! `paracosm-fuzz dataset` (issue 20, requirement 1): training data from a campaign with a
//! teacher. The files agree with each other (index, COCO, images, depth, masks), do not depend
//! on `--jobs`, record the teacher's control, and bad settings are refused with exit 2.

use std::collections::BTreeMap;
use std::path::Path;

mod common;
use common::{expect_code, fuzz};

fn export(out: &Path, jobs: &str, extra: &[&str]) {
    let mut args = vec![
        "dataset",
        "pedestrian-crossing",
        "--budget",
        "3",
        "--rate",
        "4",
        "--jobs",
        jobs,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = fuzz(&args);
    expect_code(&o, 0);
}

/// Every file under `dir`, by relative path, with its bytes.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for sub in ["images", "depth", "masks"] {
        for e in std::fs::read_dir(dir.join(sub)).unwrap() {
            let p = e.unwrap().path();
            let name = format!("{sub}/{}", p.file_name().unwrap().to_string_lossy());
            out.insert(name, std::fs::read(&p).unwrap());
        }
    }
    for f in ["frames.csv", "annotations.json", "dataset.json"] {
        out.insert(f.to_owned(), std::fs::read(dir.join(f)).unwrap());
    }
    out
}

#[test]
fn a_data_set_is_consistent_and_the_same_for_any_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    export(&one, "1", &[]);
    export(&two, "2", &[]);
    let (a, b) = (tree(&one), tree(&two));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "same files"
    );
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs between --jobs 1 and 2");
    }

    // The index: one row per frame, files that exist, parameters as in results.jsonl.
    let mut rows = csv::Reader::from_path(one.join("frames.csv")).unwrap();
    let header: Vec<String> = rows.headers().unwrap().iter().map(String::from).collect();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let rows: Vec<csv::StringRecord> = rows.records().map(Result::unwrap).collect();
    let results: Vec<serde_json::Value> = std::fs::read_to_string(one.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(results.len(), 3);
    let coco: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("annotations.json")).unwrap()).unwrap();
    let images = coco["images"].as_array().unwrap();
    assert_eq!(images.len(), rows.len());
    // 4 Hz over a run of up to 15 s: frames at 0, 0.25, 0.5, ... s.
    assert!(rows.len() >= 3 * 4, "{} frames", rows.len());
    let mut braked = false;
    for (r, image) in rows.iter().zip(images) {
        let test: usize = r[col("test")].parse().unwrap();
        let frame: f64 = r[col("frame")].parse().unwrap();
        let t: f64 = r[col("t_s")].parse().unwrap();
        assert!((t - frame * 0.25).abs() < 1e-9, "frame {frame} at {t} s");
        for p in ["walking_speed", "trigger_distance"] {
            let v: f64 = r[col(p)].parse().unwrap();
            assert_eq!(v, results[test]["params"][p].as_f64().unwrap(), "{p}");
        }
        assert_eq!(r[col("status")], *results[test]["status"].as_str().unwrap());
        assert_eq!(image["file_name"].as_str().unwrap(), &r[col("image")]);
        for f in ["image", "depth", "mask"] {
            assert!(one.join(&r[col(f)]).is_file(), "{}", &r[col(f)]);
        }
        let throttle: f64 = r[col("throttle")].parse().unwrap();
        let steering: f64 = r[col("steering")].parse().unwrap();
        assert!((-1.0..=1.0).contains(&throttle) && (-1.0..=1.0).contains(&steering));
        braked |= throttle < -0.5;
    }
    // The teacher (aeb) brakes hard for the pedestrian in one of the three tests at least:
    // the index records its control, not a placeholder.
    assert!(braked, "no frame records the teacher braking");

    // Each frame's files agree: sky in the mask exactly where the depth is infinite, and
    // every COCO box encloses pixels of its class in the mask.
    let annotations = coco["annotations"].as_array().unwrap();
    assert!(!annotations.is_empty());
    for (i, r) in rows.iter().enumerate() {
        let depth: ndarray::Array2<f32> =
            ndarray_npy::read_npy(one.join(&r[col("depth")])).unwrap();
        let mask = image::open(one.join(&r[col("mask")])).unwrap().to_luma8();
        let rgb = image::open(one.join(&r[col("image")])).unwrap().to_rgb8();
        assert_eq!(depth.dim(), (240, 320));
        assert_eq!((mask.width(), mask.height()), (320, 240));
        assert_eq!((rgb.width(), rgb.height()), (320, 240));
        for ((y, x), d) in depth.indexed_iter() {
            let class = mask.get_pixel(x as u32, y as u32).0[0];
            assert!(class <= 7);
            assert_eq!(class == 0, d.is_infinite(), "frame {i} ({x}, {y})");
        }
        for a in annotations.iter().filter(|a| a["image_id"] == i) {
            let b: Vec<u32> = a["bbox"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as u32)
                .collect();
            let class = a["category_id"].as_u64().unwrap() as u8;
            let inside = (b[1]..b[1] + b[3])
                .flat_map(|y| (b[0]..b[0] + b[2]).map(move |x| (x, y)))
                .filter(|&(x, y)| mask.get_pixel(x, y).0[0] == class)
                .count() as u64;
            assert_eq!(inside, a["area"].as_u64().unwrap(), "frame {i}: {a}");
            // The edges are tight: the box's first row and column show the actor.
            assert!((b[0]..b[0] + b[2]).any(|x| mask.get_pixel(x, b[1]).0[0] == class));
            assert!((b[1]..b[1] + b[3]).any(|y| mask.get_pixel(b[0], y).0[0] == class));
        }
    }
    // The pedestrian is labelled (class 6) in some frame.
    assert!(annotations.iter().any(|a| a["category_id"] == 6));
}

#[test]
fn a_teachers_own_camera_is_the_one_the_metadata_describes() {
    // `vision` sees through its own 160 × 120 camera: annotations.json and dataset.json said
    // 320 × 240 (the dataset's default) while the images were 160 × 120.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    let o = fuzz(&[
        "dataset",
        "pedestrian-crossing",
        "--budget",
        "1",
        "--rate",
        "1",
        "--sut",
        "vision",
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 0);
    let coco: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("annotations.json")).unwrap()).unwrap();
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("dataset.json")).unwrap()).unwrap();
    let images = coco["images"].as_array().unwrap();
    assert!(!images.is_empty());
    for image in images {
        let png = image::open(out.join(image["file_name"].as_str().unwrap())).unwrap();
        assert_eq!(image["width"].as_u64().unwrap(), u64::from(png.width()));
        assert_eq!(image["height"].as_u64().unwrap(), u64::from(png.height()));
        assert_eq!(
            manifest["camera"]["width"].as_u64().unwrap(),
            u64::from(png.width())
        );
        assert_eq!(
            manifest["camera"]["height"].as_u64().unwrap(),
            u64::from(png.height())
        );
    }
    assert_ne!(manifest["camera"]["width"], 320, "{}", manifest["camera"]);
    assert_eq!(manifest["camera_of"], "teacher");
}

#[test]
fn bad_dataset_settings_exit_2_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    let o = |extra: &[&str]| {
        let mut args = vec![
            "dataset",
            "pedestrian-crossing",
            "--budget",
            "2",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        fuzz(&args)
    };
    for (extra, reason) in [
        (&["--rate", "0"][..], "--rate 0 must be a positive"),
        (&["--rate", "nan"][..], "--rate NaN must be a positive"),
        (
            &["--strategy", "falsify-nm"][..],
            "invalid value 'falsify-nm' for '--strategy",
        ),
        (
            &["--strategy", "points"][..],
            "invalid value 'points' for '--strategy",
        ),
        (&["--width", "0"][..], "outside 1..=4096"),
        (&["--sut", "lidar"][..], "unknown system under test"),
        (
            &["--steer-noise", "1.5"][..],
            "--steer-noise 1.5 must be in [0, 1]",
        ),
        (
            &["--steer-noise", "nan"][..],
            "--steer-noise NaN must be in [0, 1]",
        ),
        (
            &["--noise-hold", "0"][..],
            "--noise-hold 0 must be a positive",
        ),
        (
            &[
                "--learner-onnx",
                "assets/models/pilotnet.onnx",
                "--teacher-share",
                "1.5",
            ][..],
            "--teacher-share 1.5 must be in [0, 1]",
        ),
        (
            &["--teacher-share", "0.5"][..],
            "the following required arguments were not provided",
        ),
        (
            &["--learner-onnx", "no/such/model.onnx"][..],
            "--learner-onnx:",
        ),
    ] {
        let r = o(extra);
        expect_code(&r, 2);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains(reason), "{extra:?}: {err}");
    }
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    let r = o(&[]);
    expect_code(&r, 2);
    assert!(String::from_utf8_lossy(&r.stderr).contains("is not empty"));
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
}

/// The columns `steering` and `applied_steering` of `dir/frames.csv`.
fn steering(dir: &Path) -> Vec<(f64, f64)> {
    let mut rows = csv::Reader::from_path(dir.join("frames.csv")).unwrap();
    let header: Vec<String> = rows.headers().unwrap().iter().map(String::from).collect();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let (s, a) = (col("steering"), col("applied_steering"));
    rows.records()
        .map(|r| {
            let r = r.unwrap();
            (r[s].parse().unwrap(), r[a].parse().unwrap())
        })
        .collect()
}

fn spread(v: impl Iterator<Item = f64> + Clone) -> f64 {
    let n = v.clone().count() as f64;
    let mean = v.clone().sum::<f64>() / n;
    (v.map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt()
}

#[test]
fn steering_noise_moves_the_car_and_the_teacher_steers_back() {
    let dir = tempfile::tempdir().unwrap();
    let (clean, noisy, noisy2) = (
        dir.path().join("clean"),
        dir.path().join("noisy"),
        dir.path().join("noisy2"),
    );
    export(&clean, "2", &[]);
    let noise = ["--steer-noise", "0.2", "--noise-hold", "0.5"];
    export(&noisy, "1", &noise);
    export(&noisy2, "2", &noise);
    let (a, b) = (tree(&noisy), tree(&noisy2));
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs between --jobs 1 and 2");
    }
    // Without noise the vehicle applies the teacher's answer.
    let c = steering(&clean);
    assert!(c.iter().all(|(s, a)| s == a));
    // With it, what the vehicle applied differs from the answer by at most the amplitude,
    // and does on most frames.
    let n = steering(&noisy);
    assert!(n.iter().all(|(s, a)| (s - a).abs() <= 0.2 + 1e-12));
    let moved = n.iter().filter(|(s, a)| (s - a).abs() > 1e-3).count();
    assert!(
        moved * 10 > n.len() * 9,
        "{moved} of {} frames perturbed",
        n.len()
    );
    // The teacher answers the drift: its steering varies far more than on the clean run,
    // and against the noise (a recovery), so the labels teach the way back.
    let (sc, sn) = (spread(c.iter().map(|p| p.0)), spread(n.iter().map(|p| p.0)));
    assert!(
        sn > 5.0 * sc + 1e-3,
        "teacher's steering spread {sn} with noise, {sc} without"
    );
    let against = n
        .iter()
        .filter(|(s, a)| (a - s).abs() > 0.05 && (a - s).signum() != s.signum())
        .count();
    let along = n
        .iter()
        .filter(|(s, a)| (a - s).abs() > 0.05 && (a - s).signum() == s.signum())
        .count();
    assert!(
        against > along,
        "teacher steered against the noise on {against} frames, with it on {along}"
    );
}

/// The named columns of `dir/frames.csv`, one row per frame.
fn columns(dir: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let mut rows = csv::Reader::from_path(dir.join("frames.csv")).unwrap();
    let header: Vec<String> = rows.headers().unwrap().iter().map(String::from).collect();
    let at: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == n).unwrap())
        .collect();
    rows.records()
        .map(|r| {
            let r = r.unwrap();
            at.iter().map(|&i| r[i].parse().unwrap()).collect()
        })
        .collect()
}

/// DAgger (`--learner-onnx`): the network drives, so the car moves exactly as when the network
/// is the system under test on its own, while the labels are the teacher's answers at the
/// network's states; with the teacher's share 1 the teacher's answers are what the car applies.
#[test]
fn a_learner_drives_and_the_teacher_labels() {
    let dir = tempfile::tempdir().unwrap();
    let (alone, dagger, teacher) = (
        dir.path().join("alone"),
        dir.path().join("dagger"),
        dir.path().join("teacher"),
    );
    export(&alone, "2", &["--sut", "pilotnet"]);
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/pilotnet.onnx");
    let model = model.to_str().unwrap();
    export(&dagger, "2", &["--learner-onnx", model]);
    export(
        &teacher,
        "1",
        &["--learner-onnx", model, "--teacher-share", "1"],
    );
    let motion = [
        "test",
        "t_s",
        "ego_x_m",
        "ego_z_m",
        "ego_heading_rad",
        "ego_speed_mps",
    ];
    let (a, d) = (columns(&alone, &motion), columns(&dagger, &motion));
    assert!(a.len() > 20, "{} frames", a.len());
    assert_eq!(a, d, "the learner's drive, frame by frame");
    // What the car applied is the network's answer; the labels are another system's.
    let (sa, sd) = (steering(&alone), steering(&dagger));
    assert!(sa.iter().zip(&sd).all(|(a, d)| a.0 == d.1));
    let relabelled = sa.iter().zip(&sd).filter(|(a, d)| a.0 != d.0).count();
    assert!(
        relabelled * 2 > sd.len(),
        "{relabelled} of {} labels differ from the network's answers",
        sd.len()
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dagger.join("dataset.json")).unwrap()).unwrap();
    assert_eq!(meta["teacher"], "aeb");
    assert_eq!(meta["learner"]["teacher_share"], 0.0);
    assert_eq!(meta["learner"]["sha256"].as_str().unwrap().len(), 64);
    // Share 1: the teacher drives at the network's rate, and applies what it labels.
    let st = steering(&teacher);
    assert!(st.iter().all(|(s, a)| s == a));
    assert_ne!(columns(&teacher, &motion), d, "another drive");
}
