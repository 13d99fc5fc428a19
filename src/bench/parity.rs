//! `poser bench parity`: every shipped scene rendered by every backend at a reduced size, and
//! whether they agree — the table a person porting a scene between Blender and Mitsuba reads
//! first. Each scene goes through [`crate::compare::run`] (the same code as `poser compare`).
//!
//! | setting | quick (`--quick`) | full |
//! |---|---|---|
//! | scenes | `scenarios/*.toml`, `scenarios/lessons/*.toml` | the same |
//! | size | 1/10 of each camera's resolution | 1/4 |
//! | samples per pixel | 16 (two renders of 8, two seeds) | 64 (two of 32) |
//! | poses | the first | the first |
//! | native daylight | traced (`render.daylight = "traced"`) under an open surface (`render.surface_from_below = "open"`): the transport all three share; the water column's and the reflecting surface's differences from it are measured in `docs/column.md` | the same |
//!
//! A pair of backends **agrees** when, in every channel, the image means differ by at most
//! [`TOLERANCE`] plus a noise allowance measured in the run: three standard errors of the
//! difference of the means. Each backend renders the scene twice, at half the samples and two
//! seeds; the two renders' per-pixel differences give its own noise ([`noise_of`]), which no
//! real difference between backends can widen (the difference of two backends' pixels, used
//! before, also held their legitimate per-pixel differences: a 32 × 24 checkerboard's edges,
//! filtered differently, kept the allowance at 9 % after 65 536 samples while the means
//! agreed within 0.7 %). A scene
//! whose images are black in every backend (nothing lit at the first pose) is reported `dark`.
//! A channel darker than [`BLACK_CHANNEL`] of the brightest channel in both backends of a pair
//! is black in any image of the scene (red under 30 m of water): it is shown, not compared.
//! A backend that refuses a scene (caustics) is reported `refused`, with its reason.
//!
//! A pair that agrees only because its noise allowance is wide has decided nothing: a pair is
//! **decided** when its allowance is at most [`DECISIVE`], so that a difference of
//! `TOLERANCE + DECISIVE` (3 %) would fail it. The table shows such a pair as `undecided`,
//! never `yes`. `--decisive` renders each scene again with four times the samples until every
//! compared pair is decided or differs, or the next round would pass the scene's time budget
//! ([`run_decisive`]); the allowance falls as 1/√samples.

use crate::backend::{Backend, RenderOptions};
use crate::compare::LinearImage;
use crate::model::Model;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Largest difference of image means between two backends that counts as agreement, before
/// the noise allowance (issue 15's "a few percent" for radiometry).
pub const TOLERANCE: f64 = 0.02;

/// The largest noise allowance with which a pair's agreement means something: with it, a
/// difference of 3 % fails the pair.
pub const DECISIVE: f64 = 0.01;

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
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BackendRow {
    pub backend: String,
    /// Why it could not render the scene, if it could not.
    pub refused: Option<String>,
    pub seconds: f64,
    pub mean_rgb: [f64; 3],
    /// Targets (disks and checkerboard corners) measured / expected, and their RMS error
    /// against the exact truth (px).
    pub targets: (usize, usize),
    pub target_rms_px: Option<f64>,
}

/// One pair of backends on one scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
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
    /// The allowance is at most [`DECISIVE`]: the agreement (or not) means something.
    pub decided: bool,
}

impl PairRow {
    /// `yes`, `**no**` or `undecided` (agrees, but only within a wide allowance).
    pub fn verdict(&self) -> &'static str {
        match (self.agree, self.decided) {
            (false, _) => "**no**",
            (true, true) => "yes",
            (true, false) => "undecided",
        }
    }
}

/// One scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row {
    pub scene: String,
    pub form: Form,
    pub width: usize,
    pub height: usize,
    pub backends: Vec<BackendRow>,
    pub pairs: Vec<PairRow>,
    /// `agree`, `differ`, `undecided` (every pair agrees, some only within a wide allowance),
    /// `dark` or `refused` (some backend refused; the others are compared and agree).
    pub status: String,
    /// Wall time of the scene's renders, all rounds (s).
    pub seconds: f64,
    /// The scene whose renders this row is: the two render the same model at the first pose
    /// ([`first_pose_model`]), so they were rendered once.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub same_as: Option<String>,
}

/// The model a parity run renders of `scene` in `form` (first pose), as JSON, without what
/// does not reach an image: the name, description, source, lesson, dive plan and network. Two
/// scenes with equal values render the same images.
pub fn first_pose_model(scene: &Path, form: Form) -> Result<serde_json::Value, String> {
    let model = crate::scene::load(scene, &PARITY_SETS.map(String::from))
        .map_err(|f| f.render())?
        .model
        .with_resolution_scale(form.scale);
    let mut v = serde_json::to_value(&model).map_err(|e| e.to_string())?;
    if let Some(m) = v.as_object_mut() {
        for key in [
            "name",
            "description",
            "source",
            "lesson",
            "diver",
            "network",
        ] {
            m.remove(key);
        }
        if let Some(p) = m.get_mut("poses").and_then(|p| p.as_array_mut()) {
            p.truncate(1);
        }
    }
    Ok(v)
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

/// Render `scene` with `backends` in `form` into `out` and compare them: each backend renders
/// twice, at half the samples and two seeds (`out/seed_a`, `out/seed_b`), so that its own
/// noise is measured ([`noise_of`]) and not guessed from the difference of two backends.
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
        samples: Some((form.samples / 2).max(1)),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    let (dir_a, dir_b) = (out.join("seed_a"), out.join("seed_b"));
    let report = crate::compare::run(&model, backends, &dir_a, &opts)?;
    let mut other = model.clone();
    other.render.seed = model.render.seed.wrapping_add(SECOND_SEED);
    let second = crate::compare::run(&other, backends, &dir_b, &opts)?;
    let (width, height) = model
        .cameras
        .first()
        .map_or((0, 0), |c| (c.width as usize, c.height as usize));
    let mut backend_rows = Vec::new();
    let mut var_of_mean = Vec::new();
    for (b, b2) in report.backends.iter().zip(&second.backends) {
        let refused = b.error.clone().or_else(|| b2.error.clone());
        let var = if refused.is_none() {
            noise_of(&model, &b.backend, &dir_a, &dir_b)?
        } else {
            [0.0; 3]
        };
        var_of_mean.push((b.backend.clone(), var));
        let (measured, target_rms_px) = targets_of_both(&b.targets, &b2.targets);
        backend_rows.push(BackendRow {
            backend: b.backend.clone(),
            refused,
            seconds: b.seconds + b2.seconds,
            mean_rgb: [0, 1, 2].map(|c| 0.5 * (b.mean_rgb[c] + b2.mean_rgb[c])),
            targets: (measured, b.targets_expected),
            target_rms_px,
        });
    }
    let pairs = compare_pairs(&report, &backend_rows, &var_of_mean);
    let dark = backend_rows
        .iter()
        .filter(|b| b.refused.is_none())
        .all(|b| b.mean_rgb.iter().all(|&m| m < DARK));
    let status = if dark {
        "dark"
    } else if pairs.iter().any(|p| !p.agree) {
        "differ"
    } else if pairs.iter().any(|p| !p.decided) {
        "undecided"
    } else if backend_rows.iter().any(|b| b.refused.is_some()) {
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
        seconds: backend_rows.iter().map(|b| b.seconds).sum(),
        backends: backend_rows,
        pairs,
        status: status.into(),
        same_as: None,
    })
}

/// The targets found in both renders of a backend, and the RMS of their offsets from the truth
/// averaged over the two: a disk's centroid is linear in the pixels but for its background
/// plane, so this is, within that, the offset measured in the mean of the two images (all the
/// samples), not in one half of them (a corner's fit nearly so).
fn targets_of_both(
    a: &[crate::compare::TargetResidual],
    b: &[crate::compare::TargetResidual],
) -> (usize, Option<f64>) {
    let d2: Vec<f64> = a
        .iter()
        .filter_map(|ta| {
            let tb = b.iter().find(|t| t.id == ta.id && t.image == ta.image)?;
            let (oa, ob) = (ta.offset?, tb.offset?);
            let m = [0.5 * (oa[0] + ob[0]), 0.5 * (oa[1] + ob[1])];
            Some(m[0] * m[0] + m[1] * m[1])
        })
        .collect();
    let rms = (!d2.is_empty()).then(|| (d2.iter().sum::<f64>() / d2.len() as f64).sqrt());
    (d2.len(), rms)
}

/// The second render's seed, added to the scene's: far from the first's, whose views take
/// consecutive seeds (Mitsuba's `render.seed + view`).
const SECOND_SEED: u64 = 0x9e37_79b9;

/// The variance of one backend's image mean (the mean of its two renders), per channel: the
/// images' means are averaged over the cameras, so it is the sum of each image's
/// [`variance_of_mean`] over the number of images squared.
fn noise_of(model: &Model, backend: &str, a: &Path, b: &Path) -> Result<[f64; 3], String> {
    let mut sum = [0.0; 3];
    let mut images = 0usize;
    for cam in 0..model.cameras.len() {
        let name = format!("{}.exr", model.image_name(0, cam));
        let (pa, pb) = (a.join(backend).join(&name), b.join(backend).join(&name));
        if !(pa.exists() && pb.exists()) {
            continue;
        }
        let (ia, ib) = (LinearImage::read(&pa)?, LinearImage::read(&pb)?);
        if ia.rgb.len() != ib.rgb.len() {
            return Err(format!(
                "{backend}: its two renders of {name} differ in size"
            ));
        }
        let v = variance_of_mean(&ia.rgb, &ib.rgb);
        for c in 0..3 {
            sum[c] += v[c];
        }
        images += 1;
    }
    let k = (images.max(1) as f64).powi(2);
    Ok(sum.map(|s| s / k))
}

/// The variance of the mean of the image `(a + b)/2`, per channel, where `a` and `b` are two
/// independent renders of one image: each pixel of `(a + b)/2` has variance `(a − b)²/4` in
/// expectation, and the N pixels are independent, so the mean's variance is their sum over N².
/// Real differences between backends do not enter it.
pub fn variance_of_mean(a: &[[f32; 3]], b: &[[f32; 3]]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            let d = x[c] as f64 - y[c] as f64;
            if d.is_finite() {
                sum[c] += 0.25 * d * d;
            }
        }
    }
    let n = a.len().min(b.len()).max(1) as f64;
    sum.map(|s| s / (n * n))
}

/// Each pair of rendering backends: the difference of their means and its allowance, three
/// standard errors of that difference from the two backends' measured noise.
fn compare_pairs(
    report: &crate::compare::report::Report,
    backends: &[BackendRow],
    var_of_mean: &[(String, [f64; 3])],
) -> Vec<PairRow> {
    let find = |name: &str| {
        let mean = backends
            .iter()
            .find(|b| b.backend == name)
            .map_or([0.0; 3], |b| b.mean_rgb);
        let var = var_of_mean
            .iter()
            .find(|(n, _)| n == name)
            .map_or([0.0; 3], |(_, v)| *v);
        (mean, var)
    };
    report
        .pairs
        .iter()
        .map(|p| {
            let ((ma, va), (mb, vb)) = (find(&p.a), find(&p.b));
            let black = [0, 1, 2].map(|c| {
                let dark =
                    |m: [f64; 3]| m[c] < BLACK_CHANNEL * m.iter().copied().fold(0.0, f64::max);
                dark(ma) && dark(mb)
            });
            let rel_diff = crate::compare::rel_diff(ma, mb);
            let allow = [0, 1, 2].map(|c| {
                if ma[c] > 0.0 {
                    3.0 * (va[c] + vb[c]).sqrt() / ma[c]
                } else {
                    f64::INFINITY
                }
            });
            let agree = (0..3).all(|c| {
                black[c] || (rel_diff[c].is_finite() && rel_diff[c].abs() <= TOLERANCE + allow[c])
            });
            let allowance = (0..3)
                .filter(|&c| !black[c])
                .map(|c| allow[c])
                .fold(0.0, f64::max);
            PairRow {
                a: p.a.clone(),
                b: p.b.clone(),
                rel_diff,
                allowance,
                black,
                agree,
                decided: allowance <= DECISIVE,
            }
        })
        .collect()
}

/// [`run_scene`] from `form`, then again with four times the samples while the scene is
/// `undecided` and the next round (estimated at four times this one) fits in `budget_s`
/// seconds of the scene's total. Each round replaces the last; the row's `seconds` counts
/// every round.
pub fn run_decisive(
    scene: &Path,
    backends: &[Backend],
    mut form: Form,
    out: &Path,
    budget_s: f64,
) -> Result<Row, String> {
    let mut spent = 0.0;
    loop {
        let mut row = run_scene(scene, backends, form, out)?;
        let round = row.seconds;
        spent += round;
        row.seconds = spent;
        if row.status != "undecided" || spent + 4.0 * round > budget_s {
            return Ok(row);
        }
        let widest = row.pairs.iter().map(|p| p.allowance).fold(0.0, f64::max);
        eprintln!(
            "  {} spp: undecided (allowance up to {:.1} %), {:.0} s; again at {} spp",
            form.samples,
            100.0 * widest,
            round,
            form.samples.saturating_mul(4)
        );
        form.samples = form.samples.saturating_mul(4);
    }
}

/// Every shipped scene (or those whose name contains `only`), one after the other.
/// With `decisive`, each scene through [`run_decisive`] with that budget (s).
pub fn run(
    root: &Path,
    backends: &[Backend],
    quick: bool,
    only: Option<&str>,
    out: &Path,
    decisive: Option<f64>,
) -> Result<Vec<Row>, String> {
    let form = Form::new(quick);
    let mut rows: Vec<Row> = Vec::new();
    // The first-pose models rendered so far, with their rows' indices.
    let mut seen: Vec<(serde_json::Value, usize)> = Vec::new();
    for scene in shipped_scenes(root) {
        let name = scene.file_stem().unwrap_or_default().to_string_lossy();
        if only.is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let key = first_pose_model(&scene, form)?;
        if let Some(&(_, k)) = seen.iter().find(|(m, _)| *m == key) {
            let mut row = rows[k].clone();
            eprintln!("{name}: the same renders as {}", row.scene);
            row.same_as = Some(std::mem::replace(&mut row.scene, name.to_string()));
            row.seconds = 0.0;
            rows.push(row);
            continue;
        }
        let t0 = std::time::Instant::now();
        let dir = out.join(name.as_ref());
        let row = match decisive {
            Some(budget) => run_decisive(&scene, backends, form, &dir, budget)?,
            None => run_scene(&scene, backends, form, &dir)?,
        };
        seen.push((key, rows.len()));
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

/// A row's scene in the tables: `scuba_survey (= paper_survey)` for one that shares another's
/// renders.
fn label(r: &Row) -> String {
    match &r.same_as {
        Some(other) => format!("{} (= {other})", r.scene),
        None => r.scene.clone(),
    }
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
                label(r),
                b.backend
            );
        }
        if r.status == "dark" {
            let _ = writeln!(
                s,
                "| {} | {size} | all | black at the first pose | – | – |",
                label(r)
            );
            continue;
        }
        for p in &r.pairs {
            let _ = writeln!(
                s,
                "| {} | {size} | {} vs {} | {} | {:.1} | {} |",
                label(r),
                p.b,
                p.a,
                pct_compared(p),
                100.0 * (TOLERANCE + p.allowance),
                p.verdict()
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
                label(r),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic noise in [−1, 1) (a 64-bit LCG): the test needs no random crate.
    fn noise(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32
    }

    #[test]
    fn the_noise_of_a_mean_is_measured_from_two_renders_and_not_from_their_content() {
        // Two renders of a checkerboard (0 and 10), each pixel with uniform noise of
        // half-width h per channel (variance h²/3): the mean of (a + b)/2 over N pixels has
        // variance h²/3/2/N.
        let n = 40_000;
        let h = [0.5f32, 1.0, 2.0];
        let mut st = 7u64;
        let board = |i: usize| {
            if (i / 7 + i / 200).is_multiple_of(2) {
                0.0
            } else {
                10.0
            }
        };
        let mut render = || -> Vec<[f32; 3]> {
            (0..n)
                .map(|i| [0, 1, 2].map(|c| board(i) + h[c] * noise(&mut st)))
                .collect()
        };
        let (a, b) = (render(), render());
        let v = variance_of_mean(&a, &b);
        for c in 0..3 {
            let expected = (h[c] as f64).powi(2) / 3.0 / 2.0 / n as f64;
            assert!(
                (v[c] / expected - 1.0).abs() < 0.03,
                "channel {c}: {} against {expected}",
                v[c]
            );
        }
        // The same content rendered without noise has none, however strong its edges.
        let clean: Vec<[f32; 3]> = (0..n).map(|i| [board(i); 3]).collect();
        assert_eq!(variance_of_mean(&clean, &clean), [0.0; 3]);
    }

    fn backend(name: &str, mean: f64) -> BackendRow {
        BackendRow {
            backend: name.into(),
            refused: None,
            seconds: 0.0,
            mean_rgb: [mean; 3],
            targets: (0, 0),
            target_rms_px: None,
        }
    }

    #[test]
    fn a_pair_is_undecided_when_its_allowance_is_wide_and_differs_beyond_it() {
        let report = crate::compare::report::Report {
            pairs: vec![crate::compare::report::PairResult {
                a: "native".into(),
                b: "mitsuba".into(),
                ..Default::default()
            }],
            ..Default::default()
        };
        let verdict = |mb: f64, sd: f64| {
            let rows = [backend("native", 1.0), backend("mitsuba", mb)];
            let var = [
                ("native".to_string(), [sd * sd; 3]),
                ("mitsuba".to_string(), [0.0; 3]),
            ];
            let p = compare_pairs(&report, &rows, &var).remove(0);
            (p.verdict(), p.allowance)
        };
        // 1 % apart, noise 0.2 % (allowance 0.6 %): decided, agrees.
        assert_eq!(verdict(1.01, 0.002).0, "yes");
        // 1 % apart, noise 1 % (allowance 3 %): agrees only within a wide allowance.
        let (v, allowance) = verdict(1.01, 0.01);
        assert_eq!(v, "undecided");
        assert!((allowance - 0.03).abs() < 1e-12);
        // 10 % apart with that noise: differs (beyond 2 % + 3 %).
        assert_eq!(verdict(1.10, 0.01).0, "**no**");
        // 3 % apart, noise 0.2 %: decided, and differs.
        assert_eq!(verdict(1.03, 0.002).0, "**no**");
    }
}
