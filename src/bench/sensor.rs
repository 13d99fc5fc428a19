//! `poser bench sensor`: what an image at the camera's own noise costs, per scene and daylight
//! estimator, measured on the shipped survey scenes at full size (`--quick`: quarter size).
//!
//! | mode | the native render's settings |
//! |---|---|
//! | `traced` | `render.daylight = "traced"`: daylight by random walks through the water, as Mitsuba and Cycles do |
//! | `column` | `render.daylight = "auto"` (the solved water column where it applies), no denoiser |
//! | `column+denoise` | as `column`, with the illumination denoiser (`render.denoise = "illumination"`, σ = 2 px) |
//!
//! Each (scene, mode) renders pose 0 three times with `poser render` in a child process (so no
//! cache of one render helps the next, and the CPU time is the child's, user + system): at the
//! two pilot sample counts, and both first poses at the second. The sensor stage (the scene's
//! `[sensor]`, else the default one) reports the render noise against the sensor's
//! ([`crate::sensor::RenderNoise`]); its `samples_needed` (variance ∝ 1/spp) gives the samples
//! to the sensor's noise. CPU per sample is the slope between the pilots; an image rendered
//! alone costs its start-up (scene load, texture bake, BVH, water column, truth) plus its
//! samples; an image in a survey costs what the second pose added, plus its extra samples.
//! `mean vs traced` is each mode's image mean (the denoised image where there is one) against
//! the traced render's at the same pilot: the bias of the estimator, within the traced
//! render's own noise.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The survey scenes the bench covers (paths under the repository root).
pub const SCENES: [&str; 6] = [
    "scenarios/reef_strip.toml",
    "scenarios/paper_survey.toml",
    "scenarios/lessons/scuba_survey.toml",
    "scenarios/two_gas_dive.toml",
    "scenarios/dome_orbit.toml",
    "scenarios/lessons/archaeology.toml",
];

/// The three estimators compared: name and `--set` overrides.
pub const MODES: [(&str, &[&str]); 3] = [
    ("traced", &["render.daylight=traced", "render.denoise=none"]),
    ("column", &["render.denoise=none"]),
    (
        "column+denoise",
        &["render.denoise=illumination", "render.denoise_radius=2"],
    ),
];

/// How a bench run is set up.
#[derive(Debug, Clone)]
pub struct Options {
    /// Resolution scale of the scenes' cameras (1: as shipped).
    pub scale: f64,
    /// The two pilot sample counts (the second also renders the survey's second pose).
    pub pilots: [u32; 2],
    /// Only the scenes whose file name contains this.
    pub only: Option<String>,
    /// The `poser` binary that renders.
    pub poser: PathBuf,
    /// Where the renders go.
    pub out: PathBuf,
}

/// One scene in one mode.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row {
    pub scene: String,
    pub mode: String,
    /// The daylight estimator the render used (`column` or `traced`, with why for `traced`
    /// where the mode asked for the column).
    pub daylight: String,
    pub width: u32,
    pub height: u32,
    pub pilots: [u32; 2],
    /// Render noise / sensor noise (RMS over the image) at the second pilot.
    pub ratio_rms: f64,
    pub ratio_median: f64,
    /// Samples per pixel to reach the sensor's noise (by the render's own variance).
    pub spp_needed: u64,
    /// The sensor's own relative noise (median over the image).
    pub sensor_relative: f64,
    /// Denoised modes: the denoiser's bias, relative RMS ([`denoiser_bias`]). Where it exceeds
    /// the sensor's noise, no sample count brings the image to the sensor's noise.
    pub bias: Option<f64>,
    /// CPU seconds per sample per pixel of the whole image.
    pub cpu_per_spp_s: f64,
    /// CPU seconds of a render before its first sample (its intercept).
    pub startup_cpu_s: f64,
    /// CPU seconds of one image at the sensor's noise rendered alone (start-up included).
    pub alone_cpu_s: f64,
    /// CPU seconds per image at the sensor's noise within a survey (start-up shared).
    pub survey_image_cpu_s: f64,
    /// Mean of the image per channel at the second pilot.
    pub mean: [f64; 3],
    /// The mean against the traced render's, per channel (relative; 0 for `traced`).
    pub mean_vs_traced: [f64; 3],
}

/// Run the bench; rows in scene order, modes in [`MODES`] order.
pub fn run(root: &Path, opts: &Options) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for scene in SCENES {
        let stem = Path::new(scene)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if opts.only.as_deref().is_some_and(|o| !stem.contains(o)) {
            continue;
        }
        let path = root.join(scene);
        let mut traced_mean = None;
        for (mode, sets) in MODES {
            let row = measure(&path, &stem, mode, sets, opts, traced_mean)?;
            if mode == "traced" {
                traced_mean = Some(row.mean);
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

/// What one `poser render` of pose(s) at `spp` gave: child CPU seconds and the first image's
/// render noise and mean.
struct Render {
    cpu_s: f64,
    ratio_rms: f64,
    ratio_median: f64,
    spp_needed: Option<u64>,
    mean: [f64; 3],
    /// The sensor's own relative noise (median over the image).
    sensor_relative: f64,
    /// The denoiser's bias, relative RMS, where the image is denoised ([`denoiser_bias`]).
    bias: Option<f64>,
}

fn measure(
    path: &Path,
    stem: &str,
    mode: &str,
    sets: &[&str],
    opts: &Options,
    traced_mean: Option<[f64; 3]>,
) -> Result<Row, String> {
    let [s1, s2] = opts.pilots;
    let dir = opts.out.join(stem).join(mode.replace('+', "_"));
    let one = |spp: u32, poses: &str, sub: &str| -> Result<Render, String> {
        render(
            &opts.poser,
            path,
            sets,
            opts.scale,
            spp,
            poses,
            &dir.join(sub),
        )
    };
    let a = one(s1, "0", "a")?;
    let b = one(s2, "0", "b")?;
    let two = one(s2, "0,1", "c")?;
    let per_spp = ((b.cpu_s - a.cpu_s) / f64::from(s2 - s1)).max(0.0);
    let startup = (a.cpu_s - per_spp * f64::from(s1)).max(0.0);
    let needed = b.spp_needed.unwrap_or(u64::from(s2)).max(2);
    let extra = needed as f64 - f64::from(s2);
    let second_pose = (two.cpu_s - b.cpu_s).max(0.0);
    let mean_vs = |t: [f64; 3]| std::array::from_fn(|c| b.mean[c] / t[c] - 1.0);
    // The model the renders saw: the scene with the mode's overrides, as `poser render` loads it.
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let model = crate::scene::load(path, &sets)
        .map_err(|f| f.render())?
        .model
        .with_resolution_scale(opts.scale);
    let cam = &model.cameras[0];
    Ok(Row {
        scene: stem.to_string(),
        mode: mode.to_string(),
        daylight: daylight(&model),
        width: cam.width,
        height: cam.height,
        pilots: opts.pilots,
        ratio_rms: b.ratio_rms,
        ratio_median: b.ratio_median,
        spp_needed: needed,
        sensor_relative: b.sensor_relative,
        bias: b.bias,
        cpu_per_spp_s: per_spp,
        startup_cpu_s: startup,
        alone_cpu_s: startup + per_spp * needed as f64,
        survey_image_cpu_s: (second_pose + per_spp * extra).max(per_spp * needed as f64),
        mean: b.mean,
        mean_vs_traced: traced_mean.map_or([0.0; 3], mean_vs),
    })
}

/// The native renderer's daylight estimator for `m`, as `poser explain` names it.
fn daylight(m: &crate::model::Model) -> String {
    let (column, why) = m.daylight_choice(crate::geometry::seen::views_past_seabed(m));
    if column.is_some() {
        "column".into()
    } else {
        why.split(':').next().unwrap_or(&why).to_string()
    }
}

/// One `poser render` in a child process; reads the first pose's sensor sidecar and EXR.
fn render(
    poser: &Path,
    scene: &Path,
    sets: &[&str],
    scale: f64,
    spp: u32,
    poses: &str,
    out: &Path,
) -> Result<Render, String> {
    let _ = std::fs::remove_dir_all(out);
    let mut cmd = Command::new(poser);
    cmd.arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--scale", &scale.to_string(), "--samples", &spp.to_string()])
        .args(["--poses", poses, "--sensor", "--quiet", "--skip-truth"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let (_, cpu_s) = super::run_child(&mut cmd, &format!("poser render {}", scene.display()))?;
    let sidecar = first_with(&out.join("camera"), ".sensor.json")?;
    let json: serde_json::Value = serde_json::from_slice(
        &std::fs::read(&sidecar).map_err(|e| format!("{}: {e}", sidecar.display()))?,
    )
    .map_err(|e| format!("{}: {e}", sidecar.display()))?;
    let noise = &json["render_noise"];
    let input = PathBuf::from(json["input"].as_str().unwrap_or_default());
    let img = crate::image::read_exr(&input)?;
    let n = img.rgb.len().max(1) as f64;
    let mean = std::array::from_fn(|c| img.rgb.iter().map(|p| f64::from(p[c])).sum::<f64>() / n);
    let name = input.to_string_lossy().into_owned();
    let bias = match name.strip_suffix(".denoised.exr") {
        Some(stem) => {
            let read = |suffix: &str| crate::image::read_exr(Path::new(&format!("{stem}{suffix}")));
            Some(denoiser_bias(
                &read(".exr")?,
                &read(".variance.exr")?,
                &img,
                &read(".denoised.variance.exr")?,
            ))
        }
        None => None,
    };
    Ok(Render {
        cpu_s,
        ratio_rms: noise["ratio_rms"].as_f64().unwrap_or(f64::NAN),
        ratio_median: noise["ratio_median"].as_f64().unwrap_or(f64::NAN),
        spp_needed: noise["samples_needed"].as_u64(),
        mean,
        sensor_relative: noise["sensor_relative_median"].as_f64().unwrap_or(f64::NAN),
        bias,
    })
}

/// The denoiser's bias as a relative RMS over the image, estimated without a reference: the
/// denoised image `d` differs from the unfiltered `r` by the noise it removed and by its bias,
/// `E[(d − r)²] = b² + var_r + var_d − 2 cov(d, r)`; the covariance (a pixel's own share of its
/// filter, a few per cent of `var_r` at σ = 2 px) is neglected, which overstates the variance
/// removed and so understates the bias slightly. Sums over every pixel and channel, relative to
/// `Σ r²`; 0 when the difference is all noise, or the noise (whose variance estimates are
/// themselves noisy at a few samples) hides the bias.
pub fn denoiser_bias(
    raw: &crate::image::Linear,
    raw_var: &crate::image::Linear,
    den: &crate::image::Linear,
    den_var: &crate::image::Linear,
) -> f64 {
    let (mut excess, mut energy) = (0.0f64, 0.0f64);
    for i in 0..raw.rgb.len().min(den.rgb.len()) {
        for c in 0..3 {
            let (r, d) = (f64::from(raw.rgb[i][c]), f64::from(den.rgb[i][c]));
            let v = f64::from(raw_var.rgb[i][c]) + f64::from(den_var.rgb[i][c]);
            excess += (d - r) * (d - r) - v;
            energy += r * r;
        }
    }
    if energy > 0.0 {
        (excess.max(0.0) / energy).sqrt()
    } else {
        0.0
    }
}

/// The first file (by name) in `dir` whose name ends with `suffix`.
fn first_with(dir: &Path, suffix: &str) -> Result<PathBuf, String> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.to_string_lossy().ends_with(suffix))
        .collect();
    v.sort();
    v.into_iter()
        .next()
        .ok_or_else(|| format!("{}: no *{suffix}", dir.display()))
}

/// The Markdown table of the rows.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scene | size | mode | daylight | noise ratio at pilot (RMS) | sensor noise | denoiser bias | spp to sensor noise | CPU-s per spp | start-up CPU-s | one image alone, CPU-s | per image in a survey, CPU-s | speed-up (survey) | mean vs traced (R, G, B) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let traced = rows
            .iter()
            .find(|t| t.scene == r.scene && t.mode == "traced")
            .map(|t| t.survey_image_cpu_s);
        let speedup = traced.map_or("–".into(), |t| {
            format!("{:.1}×", t / r.survey_image_cpu_s)
        });
        let vs_traced = if r.mode == "traced" {
            "–".to_string()
        } else {
            r.mean_vs_traced
                .iter()
                .map(|b| format!("{:+.1} %", 100.0 * b))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let biased = r.bias.is_some_and(|b| b > r.sensor_relative);
        s.push_str(&format!(
            "| `{}` | {}×{} | {} | {} | {:.2}× at {} spp | {:.1} % | {} | {}{} | {:.2} | {:.1} | {:.0} | {:.0} | {} | {} |\n",
            r.scene,
            r.width,
            r.height,
            r.mode,
            r.daylight,
            r.ratio_rms,
            r.pilots[1],
            100.0 * r.sensor_relative,
            match r.bias {
                None => "–".to_string(),
                Some(b) if b > 0.0 => format!("≥ {:.1} %", 100.0 * b),
                Some(_) => "not resolved".to_string(),
            },
            r.spp_needed,
            if biased { " (noise only: the bias stays)" } else { "" },
            r.cpu_per_spp_s,
            r.startup_cpu_s,
            r.alone_cpu_s,
            r.survey_image_cpu_s,
            speedup,
            vs_traced
        ));
    }
    s
}
