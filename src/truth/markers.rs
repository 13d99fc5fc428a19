//! The truth as marker (GCP) files that outside photogrammetry software imports: where every
//! target point lands in every image, keyed by a marker label and the image's file name, and
//! the points' known 3D coordinates under the same labels.
//!
//! | file | contents |
//! |---|---|
//! | `markers/markers.csv` | a `#` line naming the pixel convention, then `marker,image,x,y`: one row per visible target point per image, pixels with centres at +0.5 (poser's and COLMAP's convention) |
//! | `markers/gcp.csv` | a `#` line naming the frame, then `label,x,y,z`: every target point in the world frame, metres (x east, y north, z up), for a package's reference (GCP) import |
//!
//! The rows are the truth's observations ([`super::Observation`], the G channel), as in
//! `points.csv`. A marker's label is its target point's id (`board/7`, a code number, a
//! points-file name); an id that two targets share is written `target/id`. `image` is the
//! file the package loads: `<image>.jpg` or `.png` of the camera images (`OUT/camera/`) when
//! the scene has a `[sensor]`, else the backends' preview `<image>.png`.

use super::{Truth, csv_field};
use crate::model::{Model, SensorFormat};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The marker label of each (target, id): the id, or `target/id` where another target has the
/// same id.
fn labels(model: &Model) -> BTreeMap<(String, String), String> {
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for t in &model.targets {
        for p in &t.points {
            *count.entry(p.id.as_str()).or_default() += 1;
        }
    }
    let mut out = BTreeMap::new();
    for t in &model.targets {
        for p in &t.points {
            let label = if count[p.id.as_str()] > 1 {
                format!("{}/{}", t.name, p.id)
            } else {
                p.id.clone()
            };
            out.insert((t.name.clone(), p.id.clone()), label);
        }
    }
    out
}

/// The file name outside software sees for image `name`.
pub fn image_file(model: &Model, name: &str) -> String {
    let ext = match model.sensor.as_ref().map(|s| s.format) {
        Some(SensorFormat::Jpeg(_)) => "jpg",
        _ => "png",
    };
    format!("{name}.{ext}")
}

/// The marker files as (relative path, bytes).
pub fn files(model: &Model, truth: &Truth) -> Vec<(String, Vec<u8>)> {
    let labels = labels(model);
    let label = |target: &str, id: &str| {
        labels
            .get(&(target.to_string(), id.to_string()))
            .cloned()
            .unwrap_or_else(|| format!("{target}/{id}"))
    };
    let mut csv = String::from(
        "# pixel convention: the top-left pixel's centre is at (0.5, 0.5), x right, y down \
         (poser's and COLMAP's); in OpenCV's (centres at integers) each is 0.5 less, as in \
         opencv/points.csv\n\
         marker,image,x,y\n",
    );
    for im in &truth.images {
        let file = csv_field(&image_file(model, &im.name));
        for o in &im.points {
            let m = csv_field(&label(&o.target, &o.id));
            let _ = writeln!(csv, "{m},{file},{},{}", o.u, o.v);
        }
    }
    let mut gcp = String::from(
        "# world frame: metres, x east, y north, z up (poser's scene frame); labels as in markers.csv\n\
         label,x,y,z\n",
    );
    for t in &model.targets {
        for p in &t.points {
            let _ = writeln!(
                gcp,
                "{},{},{},{}",
                csv_field(&label(&t.name, &p.id)),
                p.world.x,
                p.world.y,
                p.world.z
            );
        }
    }
    vec![
        ("markers/markers.csv".into(), csv.into_bytes()),
        ("markers/gcp.csv".into(), gcp.into_bytes()),
    ]
}
