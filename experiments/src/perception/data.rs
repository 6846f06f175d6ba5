//! Reading a data set written by `paracosm-fuzz dataset` at 160 × 120: its frames with their
//! boxes (`annotations.json`), class masks and network inputs, and batches of them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use candle_core::{Device, Tensor};
use rayon::prelude::*;

use super::{
    centre_targets, preprocess, road_targets, BoxPx, Task, CAR_CATEGORY, HEIGHT, MIN_AREA, OUT_H,
    OUT_W, WIDTH,
};
use crate::training_error::{OrData, TrainingError};

/// Values of one network input: `3 × 120 × 160`.
pub(crate) const PIXELS: usize = 3 * HEIGHT * WIDTH;
/// Values of one target map: `30 × 40`.
pub(crate) const CELLS: usize = OUT_H * OUT_W;

/// One frame of a data set.
pub(crate) struct Frame {
    /// The test it belongs to.
    pub(crate) test: u64,
    /// Its time in the test, s.
    pub(crate) t_s: f64,
    /// The camera image.
    pub(crate) image: PathBuf,
    /// The class mask.
    pub(crate) mask: PathBuf,
    /// The cars' visible boxes with at least [`MIN_AREA`] pixels.
    pub(crate) cars: Vec<BoxPx>,
    /// Each of `cars`' actor index among the scenario's cars.
    pub(crate) car_actors: Vec<u64>,
    /// Other boxes (pedestrians, obstacles) with at least [`MIN_AREA`] pixels: category and box.
    pub(crate) others: Vec<(u64, BoxPx)>,
}

/// The frames of a data set, in `frames.csv`'s order, with their boxes from
/// `annotations.json`.
pub(crate) fn frames(data: &Path) -> Result<Vec<Frame>, TrainingError> {
    let ann_path = data.join("annotations.json");
    let ann: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&ann_path).map_err(|source| {
            TrainingError::Read {
                path: ann_path.clone(),
                source,
            }
        })?)?;
    let mut by_image: HashMap<String, Frame> = Default::default();
    let images = ann["images"]
        .as_array()
        .or_data("annotations.json: no images")?;
    let mut ids = HashMap::new();
    for im in images {
        let (w, h) = (im["width"].as_u64(), im["height"].as_u64());
        if (w, h) != (Some(WIDTH as u64), Some(HEIGHT as u64)) {
            return Err(TrainingError::Data(format!(
                "{}: images are {w:?} × {h:?}; the networks read {WIDTH} × {HEIGHT} \
                 (paracosm-fuzz dataset --width {WIDTH} --height {HEIGHT})",
                ann_path.display()
            )));
        }
        let file = im["file_name"]
            .as_str()
            .or_data("an image without file_name")?;
        ids.insert(
            im["id"].as_u64().or_data("an image without id")?,
            file.to_owned(),
        );
        by_image.insert(
            file.to_owned(),
            Frame {
                test: im["test"].as_u64().or_data("an image without test")?,
                t_s: im["t_s"].as_f64().or_data("an image without t_s")?,
                image: data.join(file),
                mask: data.join(im["mask_file"].as_str().or_data("no mask_file")?),
                cars: Vec::new(),
                car_actors: Vec::new(),
                others: Vec::new(),
            },
        );
    }
    for a in ann["annotations"].as_array().or_data("no annotations")? {
        let area = a["area"].as_u64().unwrap_or(0);
        if area < MIN_AREA {
            continue;
        }
        let b = a["bbox"].as_array().or_data("an annotation without bbox")?;
        let b: Vec<f64> = b.iter().filter_map(serde_json::Value::as_f64).collect();
        let b: BoxPx = b
            .try_into()
            .map_err(|_| TrainingError::Data("a bbox of other than 4".to_owned()))?;
        let id = a["image_id"].as_u64().or_data("no image_id")?;
        let f = by_image
            .get_mut(&ids[&id])
            .or_data("an annotation of no image")?;
        match a["category_id"].as_u64() {
            Some(CAR_CATEGORY) => {
                f.cars.push(b);
                f.car_actors.push(a["actor"].as_u64().unwrap_or(u64::MAX));
            }
            Some(c) => f.others.push((c, b)),
            None => {
                return Err(TrainingError::Data(
                    "an annotation without category_id".to_owned(),
                ))
            }
        }
    }
    let mut out: Vec<Frame> = by_image.into_values().collect();
    out.sort_by(|a, b| {
        (a.test, a.t_s)
            .partial_cmp(&(b.test, b.t_s))
            .expect("finite")
    });
    Ok(out)
}

/// The class mask at `path`: `120 × 160` class ids, row-major.
pub(crate) fn read_mask(path: &Path) -> Result<Vec<u8>, TrainingError> {
    let m = image::open(path)
        .map_err(|source| TrainingError::Image {
            path: path.to_path_buf(),
            source,
        })?
        .to_luma8();
    if m.dimensions() != (WIDTH as u32, HEIGHT as u32) {
        return Err(TrainingError::Data(format!(
            "{}: not {WIDTH} × {HEIGHT}",
            path.display()
        )));
    }
    Ok(m.into_raw())
}

/// The network's input for the camera image at `path` ([`preprocess`]).
pub(crate) fn read_input(path: &Path) -> Result<Vec<f32>, TrainingError> {
    let rgb = image::open(path)
        .map_err(|source| TrainingError::Image {
            path: path.to_path_buf(),
            source,
        })?
        .to_rgb8();
    Ok(preprocess(&rgb))
}

/// Inputs `[n × 3·120·160]` and targets `[n × 30·40]`, row-major.
pub(crate) struct Set {
    /// The inputs, [`PIXELS`] values a frame.
    pub(crate) inputs: Vec<f32>,
    /// The targets, [`CELLS`] values a frame.
    pub(crate) targets: Vec<f32>,
    /// Each frame's test.
    pub(crate) tests: Vec<u64>,
    /// Each frame's class mask.
    pub(crate) masks: Vec<Vec<u8>>,
    /// Each frame's visible cars.
    pub(crate) cars: Vec<Vec<BoxPx>>,
}

/// The inputs and `task`'s targets of `frames`, read in parallel.
pub(crate) fn load(task: Task, frames: &[Frame]) -> Result<Set, TrainingError> {
    let rows: Vec<(Vec<f32>, Vec<f32>, Vec<u8>)> = frames
        .par_iter()
        .map(|f| {
            let x = read_input(&f.image)?;
            let mask = read_mask(&f.mask)?;
            let y = match task {
                Task::Road => road_targets(&mask),
                Task::Vehicles => centre_targets(&f.cars),
            };
            Ok((x, y, mask))
        })
        .collect::<Result<_, TrainingError>>()?;
    let mut s = Set {
        inputs: Vec::with_capacity(rows.len() * PIXELS),
        targets: Vec::with_capacity(rows.len() * CELLS),
        tests: frames.iter().map(|f| f.test).collect(),
        masks: Vec::new(),
        cars: frames.iter().map(|f| f.cars.clone()).collect(),
    };
    for (x, y, m) in rows {
        s.inputs.extend(x);
        s.targets.extend(y);
        s.masks.push(m);
    }
    Ok(s)
}

/// The frames `idx` of `s` as tensors: inputs `[n, 3, 120, 160]` and targets
/// `[n, 1, 30, 40]`.
pub(crate) fn batch(
    s: &Set,
    idx: &[usize],
    dev: &Device,
) -> Result<(Tensor, Tensor), TrainingError> {
    let mut x = Vec::with_capacity(idx.len() * PIXELS);
    let mut y = Vec::with_capacity(idx.len() * CELLS);
    for &i in idx {
        x.extend_from_slice(&s.inputs[i * PIXELS..(i + 1) * PIXELS]);
        y.extend_from_slice(&s.targets[i * CELLS..(i + 1) * CELLS]);
    }
    let n = idx.len();
    Ok((
        Tensor::from_vec(x, (n, 3, HEIGHT, WIDTH), dev)?,
        Tensor::from_vec(y, (n, 1, OUT_H, OUT_W), dev)?,
    ))
}
