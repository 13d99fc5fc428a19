//! `poser bench column`: the solved water column's bias, scene by scene. Every shipped scene
//! where the column applies renders its first pose lit by the column and by random walks
//! through the water (traced daylight with a high bounce limit, the brute-force reference), and
//! the image means are compared per channel with their standard errors. Scenes where the column
//! does not apply are listed with the reason `poser explain` gives.
//!
//! | option | default | `--quick` |
//! |---|---|---|
//! | resolution scale | 0.05 | 0.02 |
//! | samples per pixel, both renders | 256 | 64 |
//! | `render.bounces` of the traced reference | 1000 | 1000 |
//!
//! Both renders are `poser render` child processes with `render.denoise = "none"`, strobes and
//! everything else as shipped. The standard error of a mean is `√(Σ var) / N` over the
//! `.variance.exr` beside the image (the per-pixel variance of each pixel's mean).

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The agreement the column must reach against the brute-force reference, per channel.
pub const BOUND: f64 = 0.02;

/// A channel whose traced mean is below this share of the brightest channel's is reported as
/// dark (its relative difference means nothing: the deep scenes' red).
const DARK: f64 = 1e-3;

/// How a bench run is set up.
#[derive(Debug, Clone)]
pub struct Options {
    pub scale: f64,
    pub samples: u32,
    pub bounces: u32,
    /// Only the scenes whose file name contains this.
    pub only: Option<String>,
    /// The `poser` binary that renders.
    pub poser: PathBuf,
    /// Where the renders go.
    pub out: PathBuf,
}

impl Options {
    pub fn new(quick: bool, poser: PathBuf, out: PathBuf) -> Options {
        Options {
            scale: if quick { 0.02 } else { 0.05 },
            samples: if quick { 64 } else { 256 },
            bounces: 1000,
            only: None,
            poser,
            out,
        }
    }
}

/// One shipped scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row {
    /// The scene's path under the repository.
    pub scene: String,
    /// `None`: the column applies; else why it does not (as `poser explain` says).
    pub not_applied: Option<String>,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    /// Image means per channel: column, traced reference.
    pub column: [f64; 3],
    pub traced: [f64; 3],
    /// Standard errors of those means.
    pub column_se: [f64; 3],
    pub traced_se: [f64; 3],
    /// CPU seconds of the two renders (child user + system).
    pub column_cpu_s: f64,
    pub traced_cpu_s: f64,
}

impl Row {
    /// column / traced − 1 per channel, and its standard error; `None` for a dark channel.
    pub fn difference(&self) -> [Option<(f64, f64)>; 3] {
        let top = self.traced.iter().cloned().fold(0.0, f64::max);
        std::array::from_fn(|c| {
            let (a, b) = (self.column[c], self.traced[c]);
            (b > DARK * top && b > 0.0).then(|| {
                let se = (a / b)
                    * ((self.column_se[c] / a).powi(2) + (self.traced_se[c] / b).powi(2)).sqrt();
                (a / b - 1.0, se)
            })
        })
    }

    /// Whether the renders' noise is small enough to tell: every bright channel's standard
    /// error of the difference under half of [`BOUND`]. The traced reference's noise is heavy-
    /// tailed where light reaches the camera along rare paths (dome_orbit): there its mean is
    /// not converged at any sample count the bench can afford.
    pub fn resolved(&self) -> bool {
        self.difference()
            .iter()
            .flatten()
            .all(|(_, se)| *se < 0.5 * BOUND)
    }

    /// Whether every bright channel agrees within [`BOUND`]; `None` where the column does not
    /// apply.
    pub fn within_bound(&self) -> Option<bool> {
        self.not_applied.is_none().then(|| {
            self.difference()
                .iter()
                .flatten()
                .all(|(d, _)| d.abs() <= BOUND)
        })
    }
}

/// The shipped scenes: `scenarios/*.toml` and `scenarios/lessons/*.toml`, by file name.
pub fn shipped_scenes(root: &Path) -> Result<Vec<String>, String> {
    let mut v = Vec::new();
    for dir in ["scenarios", "scenarios/lessons"] {
        let rd = std::fs::read_dir(root.join(dir)).map_err(|e| format!("{dir}: {e}"))?;
        for e in rd.filter_map(Result::ok) {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".toml") {
                v.push(format!("{dir}/{name}"));
            }
        }
    }
    v.sort_by_key(|p| Path::new(p).file_name().map(|n| n.to_os_string()));
    Ok(v)
}

/// Run the bench over the shipped scenes (those whose name contains `only`).
pub fn run(root: &Path, opts: &Options) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for scene in shipped_scenes(root)? {
        let stem = Path::new(&scene)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if opts.only.as_deref().is_some_and(|o| !stem.contains(o)) {
            continue;
        }
        rows.push(measure(root, &scene, &stem, opts)?);
    }
    Ok(rows)
}

fn measure(root: &Path, scene: &str, stem: &str, opts: &Options) -> Result<Row, String> {
    let path = root.join(scene);
    let model = crate::scene::load(&path, &[])
        .map_err(|f| f.render())?
        .model
        .with_resolution_scale(opts.scale);
    let cam = &model.cameras[0];
    let (column, why) = model.daylight_choice(crate::geometry::seen::views_past_seabed(&model));
    let mut row = Row {
        scene: scene.to_string(),
        not_applied: None,
        width: cam.width,
        height: cam.height,
        samples: opts.samples,
        column: [0.0; 3],
        traced: [0.0; 3],
        column_se: [0.0; 3],
        traced_se: [0.0; 3],
        column_cpu_s: 0.0,
        traced_cpu_s: 0.0,
    };
    if column.is_none() {
        let reason = why.split_once(": ").map_or(why.as_str(), |(_, r)| r);
        let reason = reason
            .strip_prefix("the column does not apply (")
            .and_then(|r| r.strip_suffix(')'))
            .unwrap_or(reason);
        row.not_applied = Some(reason.to_string());
        return Ok(row);
    }
    let bounces = format!("render.bounces={}", opts.bounces);
    let dir = opts.out.join(stem);
    let c = render(
        opts,
        &path,
        &["render.daylight=column"],
        &dir.join("column"),
    )?;
    let t = render(
        opts,
        &path,
        &["render.daylight=traced", &bounces],
        &dir.join("traced"),
    )?;
    (row.column, row.column_se, row.column_cpu_s) = c;
    (row.traced, row.traced_se, row.traced_cpu_s) = t;
    Ok(row)
}

/// One `poser render` of pose 0 in a child process: the image's mean per channel, its standard
/// error, and the child's CPU seconds.
fn render(
    opts: &Options,
    scene: &Path,
    sets: &[&str],
    out: &Path,
) -> Result<([f64; 3], [f64; 3], f64), String> {
    let _ = std::fs::remove_dir_all(out);
    let mut cmd = Command::new(&opts.poser);
    cmd.arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--scale", &opts.scale.to_string()])
        .args(["--samples", &opts.samples.to_string()])
        // `--sensor` for the variance image beside the render.
        .args(["--poses", "0", "--quiet", "--skip-truth", "--sensor"])
        .args(["--set", "render.denoise=none"]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let (_, cpu_s) = super::run_child(&mut cmd, &format!("poser render {}", scene.display()))?;
    let img = crate::image::read_exr(&out.join("img_0001.exr"))?;
    let var = crate::image::read_exr(&out.join("img_0001.variance.exr"))?;
    let n = img.rgb.len().max(1) as f64;
    let sum =
        |im: &crate::image::Linear, c: usize| im.rgb.iter().map(|p| f64::from(p[c])).sum::<f64>();
    let mean = std::array::from_fn(|c| sum(&img, c) / n);
    let se = std::array::from_fn(|c| sum(&var, c).max(0.0).sqrt() / n);
    Ok((mean, se, cpu_s))
}

/// The Markdown table of the rows.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scene | size, spp | column − traced (R / G / B) | within 2 % | CPU-s, column / traced |\n\
         |---|---|---|---|---|\n",
    );
    for r in rows {
        let name = Path::new(&r.scene)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let Some(why) = &r.not_applied {
            s.push_str(&format!(
                "| `{name}` | – | does not apply: {why} | – | – |\n"
            ));
            continue;
        }
        let diff = r
            .difference()
            .iter()
            .map(|d| match d {
                Some((d, se)) => format!("{:+.1} ± {:.1} %", 100.0 * d, 100.0 * se),
                None => "dark".into(),
            })
            .collect::<Vec<_>>()
            .join(" / ");
        s.push_str(&format!(
            "| `{name}` | {}×{}, {} | {diff} | {} | {:.0} / {:.0} |\n",
            r.width,
            r.height,
            r.samples,
            match (r.within_bound(), r.resolved()) {
                (Some(true), _) => "yes",
                (_, false) => "not resolved: the reference's noise",
                _ => "**no**",
            },
            r.column_cpu_s,
            r.traced_cpu_s
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(column: [f64; 3], traced: [f64; 3]) -> Row {
        Row {
            scene: "scenarios/x.toml".into(),
            not_applied: None,
            width: 2,
            height: 2,
            samples: 1,
            column,
            traced,
            column_se: [0.0; 3],
            traced_se: [0.0; 3],
            column_cpu_s: 0.0,
            traced_cpu_s: 0.0,
        }
    }

    #[test]
    fn a_dark_channel_is_left_out_and_the_bound_is_per_channel() {
        let r = row([1e-6, 10.1, 20.3], [2e-6, 10.0, 20.0]);
        let d = r.difference();
        assert!(d[0].is_none(), "red carries 1e-7 of blue: dark");
        assert!((d[1].unwrap().0 - 0.01).abs() < 1e-12);
        assert_eq!(r.within_bound(), Some(true));
        let r = row([1.0, 10.0, 20.5], [1.0, 10.0, 20.0]);
        assert_eq!(r.within_bound(), Some(false), "blue is 2.5 % off");
        assert!(r.resolved() && table(&[r.clone()]).contains("**no**"));
        let mut noisy = r.clone();
        noisy.traced_se = [0.0, 0.0, 0.3];
        assert!(!noisy.resolved() && table(&[noisy]).contains("not resolved"));
        let mut r = row([0.0; 3], [0.0; 3]);
        r.not_applied = Some("no water".into());
        assert_eq!(r.within_bound(), None);
        assert!(table(&[r]).contains("does not apply: no water"));
    }
}
