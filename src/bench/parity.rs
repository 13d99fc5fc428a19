//! `poser bench parity`: every shipped scene rendered by every backend at a reduced size, and
//! whether they agree — the table a person porting a scene between Blender and Mitsuba reads
//! first. Each scene goes through [`crate::compare::run`] (the same code as `poser compare`).
//!
//! | setting | quick (`--quick`) | full |
//! |---|---|---|
//! | scenes | `scenarios/*.toml`, `scenarios/lessons/*.toml` | the same |
//! | size | 1/10 of each camera's resolution | 1/4 |
//! | samples per pixel | 16 | 64 |
//! | poses | the first | the first |
//! | native daylight | traced (`render.daylight = "traced"`) under an open surface (`render.surface_from_below = "open"`): the transport all three share; the water column's and the reflecting surface's differences from it are measured in `docs/column.md` | the same |
//!
//! A pair of backends **agrees** when, in every channel, the image means differ by at most
//! [`TOLERANCE`] plus a noise allowance computed from the images: three standard errors of the
//! mean of a difference of independent per-pixel noise, `3 · rms(b − a)/mean(a) / √N` over the
//! `N` pixels (an upper bound, since the per-pixel RMS also holds any real difference). A scene
//! whose images are black in every backend (nothing lit at the first pose) is reported `dark`.
//! A channel darker than [`BLACK_CHANNEL`] of the brightest channel in both backends of a pair
//! is black in any image of the scene (red under 30 m of water): it is shown, not compared.
//! A backend that refuses a scene (caustics) is reported `refused`, with its reason.

use crate::backend::{Backend, RenderOptions};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Largest difference of image means between two backends that counts as agreement, before
/// the noise allowance (issue 15's "a few percent" for radiometry).
pub const TOLERANCE: f64 = 0.02;

/// Below this mean (in every channel and backend) an image counts as black: nothing reaches
/// the camera at the first pose (a deep scene without lights). Dim is not dark: the relative
/// comparison and its noise allowance hold at any exposure.
const DARK: f64 = 1e-6;

/// A channel whose mean is below this share of the image's brightest channel (in both
/// backends of a pair) is not compared: at any exposure that shows the scene it is black, and
/// its mean is made of the rare paths that reach it (two_gas_dive's red: 1e-5 of its green).
pub const BLACK_CHANNEL: f64 = 1e-3;

/// The parity runs compare the transport the three backends share: daylight traced, and the
/// sea surface open from below (Mitsuba and Cycles have no Snell's window; the difference is
/// measured on the column, `poser explain` and docs/column.md).
pub const PARITY_SETS: [&str; 2] = [
    "render.daylight=\"traced\"",
    "render.surface_from_below=\"open\"",
];

/// The size and sampling of a run.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Form {
    pub scale: f64,
    pub samples: u32,
}

impl Form {
    pub fn new(quick: bool) -> Form {
        if quick {
            Form {
                scale: 0.1,
                samples: 16,
            }
        } else {
            Form {
                scale: 0.25,
                samples: 64,
            }
        }
    }
}

/// One backend on one scene.
#[derive(Debug, Clone, Serialize)]
pub struct BackendRow {
    pub backend: String,
    /// Why it could not render the scene, if it could not.
    pub refused: Option<String>,
    pub seconds: f64,
    pub mean_rgb: [f64; 3],
    /// Disk targets measured / expected, and their RMS error against the exact truth (px).
    pub targets: (usize, usize),
    pub target_rms_px: Option<f64>,
}

/// One pair of backends on one scene.
#[derive(Debug, Clone, Serialize)]
pub struct PairRow {
    pub a: String,
    pub b: String,
    /// (mean_b − mean_a)/mean_a per channel.
    pub rel_diff: [f64; 3],
    /// The noise allowance added to [`TOLERANCE`] (relative).
    pub allowance: f64,
    /// Channels black in both backends ([`BLACK_CHANNEL`]): not compared.
    pub black: [bool; 3],
    pub agree: bool,
}

/// One scene.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub scene: String,
    pub form: Form,
    pub width: usize,
    pub height: usize,
    pub backends: Vec<BackendRow>,
    pub pairs: Vec<PairRow>,
    /// `agree`, `differ`, `dark` or `refused` (some backend refused; the others are compared).
    pub status: String,
}

/// The shipped scenes: `scenarios/*.toml` then `scenarios/lessons/*.toml`, sorted.
pub fn shipped_scenes(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in ["scenarios", "scenarios/lessons"] {
        let mut v: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .map(|rd| {
                rd.filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        out.extend(v);
    }
    out
}

/// Render `scene` with `backends` in `form` into `out` and compare them.
pub fn run_scene(
    scene: &Path,
    backends: &[Backend],
    form: Form,
    out: &Path,
) -> Result<Row, String> {
    // Like for like: the native renderer traces daylight as Mitsuba and Cycles do.
    let mut model = crate::scene::load(scene, &PARITY_SETS.map(String::from))
        .map_err(|f| f.render())?
        .model
        .with_resolution_scale(form.scale);
    // Only the first pose is compared: the back ends get a model of that pose alone, so that
    // Mitsuba's XML and Cycles' scene do not carry the other poses (891 on the deformation
    // lessons, one water shape key each in Blender) for nothing.
    model.poses.truncate(1);
    let opts = RenderOptions {
        samples: Some(form.samples),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    let report = crate::compare::run(&model, backends, out, &opts)?;
    let (width, height) = model
        .cameras
        .first()
        .map_or((0, 0), |c| (c.width as usize, c.height as usize));
    let pixels = (width * height * model.cameras.len()).max(1) as f64;
    let backends: Vec<BackendRow> = report
        .backends
        .iter()
        .map(|b| BackendRow {
            backend: b.backend.clone(),
            refused: b.error.clone(),
            seconds: b.seconds,
            mean_rgb: b.mean_rgb,
            targets: (b.targets_measured, b.targets_expected),
            target_rms_px: b.target_rms_px,
        })
        .collect();
    let dark = backends
        .iter()
        .filter(|b| b.refused.is_none())
        .all(|b| b.mean_rgb.iter().all(|&m| m < DARK));
    let pairs: Vec<PairRow> = report
        .pairs
        .iter()
        .map(|p| {
            let allowance = 3.0 * p.rms_rel_diff / pixels.sqrt();
            let mean_of = |name: &str| {
                backends
                    .iter()
                    .find(|b| b.backend == name)
                    .map_or([0.0; 3], |b| b.mean_rgb)
            };
            let (ma, mb) = (mean_of(&p.a), mean_of(&p.b));
            let black = [0, 1, 2].map(|c| {
                let dark =
                    |m: [f64; 3]| m[c] < BLACK_CHANNEL * m.iter().copied().fold(0.0, f64::max);
                dark(ma) && dark(mb)
            });
            let agree = (0..3).all(|c| {
                let d = p.mean_rel_diff[c];
                black[c] || (d.is_finite() && d.abs() <= TOLERANCE + allowance)
            });
            PairRow {
                a: p.a.clone(),
                b: p.b.clone(),
                rel_diff: p.mean_rel_diff,
                allowance,
                black,
                agree,
            }
        })
        .collect();
    let status = if dark {
        "dark"
    } else if pairs.iter().any(|p| !p.agree) {
        "differ"
    } else if backends.iter().any(|b| b.refused.is_some()) {
        "refused"
    } else {
        "agree"
    };
    Ok(Row {
        scene: scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        form,
        width,
        height,
        backends,
        pairs,
        status: status.into(),
    })
}

/// Every shipped scene (or those whose name contains `only`), one after the other.
pub fn run(
    root: &Path,
    backends: &[Backend],
    quick: bool,
    only: Option<&str>,
    out: &Path,
) -> Result<Vec<Row>, String> {
    let form = Form::new(quick);
    let mut rows = Vec::new();
    for scene in shipped_scenes(root) {
        let name = scene.file_stem().unwrap_or_default().to_string_lossy();
        if only.is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let t0 = std::time::Instant::now();
        let row = run_scene(&scene, backends, form, &out.join(name.as_ref()))?;
        eprintln!(
            "{name}: {} ({:.0} s)",
            row.status,
            t0.elapsed().as_secs_f64()
        );
        rows.push(row);
    }
    Ok(rows)
}

/// Δmean R / G / B in %, with "black (±x)" for a channel not compared ([`BLACK_CHANNEL`]).
fn pct_compared(p: &PairRow) -> String {
    [0, 1, 2]
        .map(|c| {
            let v = format!("{:+.1}", 100.0 * p.rel_diff[c]);
            if p.black[c] {
                format!("black ({v})")
            } else {
                v
            }
        })
        .join(" / ")
}

/// The rows as a Markdown table: per scene, each pair's difference of means (R / G / B, %)
/// with its allowance, and each backend's target error.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scene | size, spp | pair | Δmean R / G / B (%) | allowed (%) | agree |\n|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let size = format!("{}×{}, {}", r.width, r.height, r.form.samples);
        for b in r.backends.iter().filter(|b| b.refused.is_some()) {
            let why = b.refused.as_deref().unwrap_or("");
            let why = why.lines().next().unwrap_or("").replace('|', "/");
            let short: String = why.chars().take(90).collect();
            let _ = writeln!(
                s,
                "| {} | {size} | {} | refused: {short}… | – | – |",
                r.scene, b.backend
            );
        }
        if r.status == "dark" {
            let _ = writeln!(
                s,
                "| {} | {size} | all | black at the first pose | – | – |",
                r.scene
            );
            continue;
        }
        for p in &r.pairs {
            let _ = writeln!(
                s,
                "| {} | {size} | {} vs {} | {} | {:.1} | {} |",
                r.scene,
                p.b,
                p.a,
                pct_compared(p),
                100.0 * (TOLERANCE + p.allowance),
                if p.agree { "yes" } else { "**no**" }
            );
        }
    }
    s.push_str(
        "\n| scene | backend | targets | RMS vs truth (px) | time (s) |\n|---|---|---|---|---|\n",
    );
    for r in rows {
        for b in r.backends.iter().filter(|b| b.refused.is_none()) {
            if b.targets.1 == 0 {
                continue;
            }
            let _ = writeln!(
                s,
                "| {} | {} | {}/{} | {} | {:.1} |",
                r.scene,
                b.backend,
                b.targets.0,
                b.targets.1,
                b.target_rms_px.map_or("–".into(), |v| format!("{v:.3}")),
                b.seconds
            );
        }
    }
    s
}
