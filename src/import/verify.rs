//! `poser import --verify`: the source scene rendered by its own renderer (Mitsuba 3's
//! `scalar_rgb`, through `backends/mitsuba/render_source.py`, or Cycles through
//! `backends/blender/render_source.py`) against the imported scene rendered by the native
//! renderer, at a small size, compared per channel and per region. The one idea: an import
//! that changed what the scene looks like fails loudly.
//!
//! Both renders are of the first view (Mitsuba's first sensor or the Blender scene's camera at
//! its first frame; poser's pose 0 and first camera), at the same field of view and size, with
//! the same samples per pixel. The verdict
//! is the relative difference of each channel's mean; the regions (a 4 × 4 grid) are printed to
//! show where a difference sits, and are not part of the verdict (at a few dozen samples per
//! pixel a region's noise is several per cent).

use crate::backend::{Backend, RenderOptions, python};
use crate::model::Model;
use std::path::{Path, PathBuf};

/// The Mitsuba driver that renders a scene file as it is (`backends/mitsuba/render_source.py`).
pub const MITSUBA_SOURCE_DRIVER: &str = include_str!("../../backends/mitsuba/render_source.py");

/// The Cycles driver that renders a `.blend` as it is (`backends/blender/render_source.py`).
pub const BLENDER_SOURCE_DRIVER: &str = include_str!("../../backends/blender/render_source.py");

/// The file an import came from, and so the renderer that renders it as it is.
#[derive(Debug, Clone, Copy)]
pub enum Source<'a> {
    /// A Mitsuba 3 scene file, rendered by Mitsuba 3.
    Mitsuba(&'a Path),
    /// A Blender file, rendered by Cycles.
    Blender(&'a Path),
}

impl Source<'_> {
    /// The renderer's name, as `--verify` prints it.
    pub fn renderer(&self) -> &'static str {
        match self {
            Source::Mitsuba(_) => "Mitsuba 3",
            Source::Blender(_) => "Cycles",
        }
    }
}

/// A channel darker than this share of the brightest channel's mean, in the source, is not
/// compared (a relative difference of nearly nothing is noise).
const BLACK: f64 = 1e-3;

/// The comparison of two images of the same size.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Per channel: the source's mean, the imported scene's mean.
    pub means: [(f64, f64); 3],
    /// Per region (row-major, `grid` × `grid`), per channel: relative difference
    /// (imported − source) / source mean of the whole channel, so that dark regions do not blow up.
    pub regions: Vec<[f64; 3]>,
    pub grid: usize,
}

impl Comparison {
    /// Relative difference of a channel's mean, `None` when the channel is black in the source.
    pub fn channel(&self, c: usize) -> Option<f64> {
        let top = self.means.iter().map(|m| m.0).fold(0.0, f64::max);
        let (s, n) = self.means[c];
        (s > BLACK * top && s > 0.0).then(|| (n - s) / s)
    }

    /// The worst channel's relative difference (absolute).
    pub fn worst(&self) -> f64 {
        (0..3)
            .filter_map(|c| self.channel(c))
            .map(f64::abs)
            .fold(0.0, f64::max)
    }

    /// The lines `poser import --verify` prints.
    pub fn lines(&self) -> Vec<String> {
        let name = ["R", "G", "B"];
        let mut out = Vec::new();
        let mut l = String::from("mean per channel (source → imported):");
        for (c, (name, (s, n))) in name.iter().zip(self.means).enumerate() {
            match self.channel(c) {
                Some(d) => l.push_str(&format!("  {name} {s:.4} → {n:.4} ({:+.2} %)", 100.0 * d)),
                None => l.push_str(&format!("  {name} black")),
            }
        }
        out.push(l);
        out.push(format!(
            "per region ({0} × {0}, top row first; % of the channel's mean, R/G/B):",
            self.grid
        ));
        for row in self.regions.chunks(self.grid) {
            let cells: Vec<String> = row
                .iter()
                .map(|r| {
                    format!(
                        "{:+.1}/{:+.1}/{:+.1}",
                        100.0 * r[0],
                        100.0 * r[1],
                        100.0 * r[2]
                    )
                })
                .collect();
            out.push(format!("  {}", cells.join("  ")));
        }
        out
    }
}

/// Compare `imported` against `source` (same size): channel means and a `grid` × `grid` split.
pub fn compare(
    source: &crate::image::Linear,
    imported: &crate::image::Linear,
    grid: usize,
) -> Result<Comparison, String> {
    if (source.width, source.height) != (imported.width, imported.height) {
        return Err(format!(
            "the source renders {}×{} and the imported scene {}×{}",
            source.width, source.height, imported.width, imported.height
        ));
    }
    let (w, h) = (source.width as usize, source.height as usize);
    let grid = grid.clamp(1, w.min(h).max(1));
    let mean = |img: &crate::image::Linear, x0: usize, x1: usize, y0: usize, y1: usize| {
        let mut s = [0.0f64; 3];
        for y in y0..y1 {
            for x in x0..x1 {
                let p = img.rgb[y * w + x];
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        let n = ((x1 - x0) * (y1 - y0)).max(1) as f64;
        s.map(|v| v / n)
    };
    let (ms, mi) = (mean(source, 0, w, 0, h), mean(imported, 0, w, 0, h));
    let mut regions = Vec::with_capacity(grid * grid);
    for gy in 0..grid {
        for gx in 0..grid {
            let (x0, x1) = (gx * w / grid, (gx + 1) * w / grid);
            let (y0, y1) = (gy * h / grid, (gy + 1) * h / grid);
            let (a, b) = (mean(source, x0, x1, y0, y1), mean(imported, x0, x1, y0, y1));
            regions.push([0, 1, 2].map(|c| {
                if ms[c] > 0.0 {
                    (b[c] - a[c]) / ms[c]
                } else {
                    0.0
                }
            }));
        }
    }
    Ok(Comparison {
        means: [0, 1, 2].map(|c| (ms[c], mi[c])),
        regions,
        grid,
    })
}

/// Render the source file as it is (Mitsuba: its first sensor; Blender: the scene camera at
/// the first frame; resized to `width` × `height`, `spp` samples per pixel) into
/// `work/source.exr`.
pub fn render_source(
    source: Source,
    width: u32,
    height: u32,
    spp: u32,
    work: &Path,
) -> Result<PathBuf, String> {
    let (module, script, flag, file) = match source {
        Source::Mitsuba(xml) => ("mitsuba", MITSUBA_SOURCE_DRIVER, "--xml", xml),
        Source::Blender(blend) => ("bpy", BLENDER_SOURCE_DRIVER, "--blend", blend),
    };
    python::require_module(module)?;
    let driver = python::embedded_script(work, "render_source.py", script)?;
    let out = work.join("source.exr");
    let o = python::command(&driver)
        .arg(flag)
        .arg(file)
        .args([
            "--width",
            &width.to_string(),
            "--height",
            &height.to_string(),
        ])
        .args(["--spp", &spp.to_string()])
        .arg("--out")
        .arg(&out)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python::interpreter().display()))?;
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        let tail: Vec<&str> = err.lines().rev().take(12).collect();
        return Err(format!(
            "{} could not render {} ({}):\n{}",
            source.renderer(),
            file.display(),
            o.status,
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        ));
    }
    Ok(out)
}

/// Render `model` (already at the verification size, daylight pinned by the caller) natively:
/// pose 0, `spp` samples; returns its first image.
pub fn render_native(model: &Model, spp: u32, work: &Path) -> Result<PathBuf, String> {
    let report = Backend::Native.render(
        model,
        &work.join("native"),
        &RenderOptions {
            samples: Some(spp),
            poses: Some(vec![0]),
            ..Default::default()
        },
    )?;
    report
        .images
        .into_iter()
        .next()
        .ok_or_else(|| "the imported scene rendered no image".to_string())
}

/// The whole check: `model` is the imported scene at the verification size; the source is
/// rendered at its first camera's size.
pub fn verify(source: Source, model: &Model, spp: u32, work: &Path) -> Result<Comparison, String> {
    let cam = model
        .cameras
        .first()
        .ok_or_else(|| "the imported scene has no camera".to_string())?;
    if model.poses.is_empty() {
        return Err("the imported scene has no pose".into());
    }
    let rendered = render_source(source, cam.width, cam.height, spp, work)?;
    let native = render_native(model, spp, work)?;
    compare(
        &crate::image::read_exr(&rendered)?,
        &crate::image::read_exr(&native)?,
        4,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Linear;

    fn flat(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Linear {
        Linear {
            width: w,
            height: h,
            rgb: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    #[test]
    fn channel_means_and_regions() {
        let a = flat(8, 8, |_, _| [1.0, 0.5, 0.0]);
        // Brighter by 10 % in red in the top-left quarter only.
        let b = flat(8, 8, |x, y| {
            if x < 4 && y < 4 {
                [1.1, 0.5, 0.0]
            } else {
                [1.0, 0.5, 0.0]
            }
        });
        let c = compare(&a, &b, 2).unwrap();
        assert!((c.channel(0).unwrap() - 0.025).abs() < 1e-6);
        assert_eq!(c.channel(1), Some(0.0));
        assert_eq!(c.channel(2), None, "black in the source: not compared");
        assert!((c.regions[0][0] - 0.1).abs() < 1e-6);
        assert_eq!(c.regions[3][0], 0.0);
        assert!((c.worst() - 0.025).abs() < 1e-6);
        assert!(c.lines()[0].contains("B black"));
        assert!(compare(&a, &flat(4, 8, |_, _| [0.0; 3]), 2).is_err());
    }
}
