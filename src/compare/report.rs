//! The `poser compare` report: per backend, time, target-position error and radiometry; per
//! pair of backends, radiometric differences. Written as Markdown, JSON and a PNG bar chart.

use serde::Serialize;

/// One backend's results over all images of the scene.
#[derive(Debug, Clone, Serialize, Default)]
pub struct BackendResult {
    pub backend: String,
    /// `None` when the backend rendered; the error message otherwise.
    pub error: Option<String>,
    /// Wall-clock seconds of the render (including start-up).
    pub seconds: f64,
    pub images: usize,
    /// Disk targets measured / expected.
    pub targets_measured: usize,
    pub targets_expected: usize,
    /// Position error of measured target centroids against the exact truth, px.
    pub target_rms_px: Option<f64>,
    pub target_max_px: Option<f64>,
    /// Mean linear value per channel over all pixels of all images.
    pub mean_rgb: [f64; 3],
}

/// Radiometric comparison of two backends over the same images.
#[derive(Debug, Clone, Serialize, Default)]
pub struct PairResult {
    pub a: String,
    pub b: String,
    /// (mean_b − mean_a)/mean_a per channel, over all pixels of all images.
    pub mean_rel_diff: [f64; 3],
    /// RMS over pixels of (b − a), divided by the mean of a (luminance), per image averaged.
    pub rms_rel_diff: f64,
    /// Difference images written (PNG, |b − a| scaled).
    pub diff_images: Vec<String>,
}

#[derive(Debug, Clone, Serialize, Default)]
pub struct Report {
    pub scene: String,
    pub samples: u32,
    pub backends: Vec<BackendResult>,
    pub pairs: Vec<PairResult>,
}

fn opt(v: Option<f64>, prec: usize) -> String {
    v.map(|x| format!("{x:.prec$}"))
        .unwrap_or_else(|| "–".into())
}

impl Report {
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "# poser compare: {}\n\nSamples per pixel: {}\n\n",
            self.scene, self.samples
        );
        s.push_str("| backend | status | time (s) | images | targets | RMS (px) | max (px) | mean R | mean G | mean B |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
        for b in &self.backends {
            let status = match &b.error {
                None => "ok".to_string(),
                Some(e) => format!(
                    "failed: {}",
                    e.lines().next().unwrap_or("").replace('|', "/")
                ),
            };
            s.push_str(&format!(
                "| {} | {} | {:.2} | {} | {}/{} | {} | {} | {:.5} | {:.5} | {:.5} |\n",
                b.backend,
                status,
                b.seconds,
                b.images,
                b.targets_measured,
                b.targets_expected,
                opt(b.target_rms_px, 4),
                opt(b.target_max_px, 4),
                b.mean_rgb[0],
                b.mean_rgb[1],
                b.mean_rgb[2]
            ));
        }
        if !self.pairs.is_empty() {
            s.push_str("\n| pair | Δmean R | Δmean G | Δmean B | per-pixel RMS / mean |\n|---|---|---|---|---|\n");
            for p in &self.pairs {
                s.push_str(&format!(
                    "| {} vs {} | {:+.2} % | {:+.2} % | {:+.2} % | {:.3} |\n",
                    p.b,
                    p.a,
                    100.0 * p.mean_rel_diff[0],
                    100.0 * p.mean_rel_diff[1],
                    100.0 * p.mean_rel_diff[2],
                    p.rms_rel_diff
                ));
            }
        }
        s
    }

    /// A bar chart (no text; the Markdown carries the numbers): for each backend, target RMS
    /// error (px, left group, full height = 0.25 px) and G-channel mean relative to the first
    /// backend (right group, full height = ±10 %).
    pub fn plot_png(&self) -> image::RgbImage {
        let (w, h) = (60 + 60 * self.backends.len() as u32 * 2, 200u32);
        let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
        let colors = [
            [31u8, 119, 180],
            [255, 127, 14],
            [44, 160, 44],
            [214, 39, 40],
        ];
        let mid = h / 2;
        for x in 0..w {
            img.put_pixel(x, h - 10, image::Rgb([0, 0, 0]));
        }
        let base = self.backends.first().map(|b| b.mean_rgb[1]).unwrap_or(0.0);
        let n = self.backends.len() as u32;
        for (i, b) in self.backends.iter().enumerate() {
            let c = image::Rgb(colors[i % colors.len()]);
            let x0 = 20 + 50 * i as u32;
            let v = b.target_rms_px.unwrap_or(0.0).min(0.25) / 0.25;
            let top = (h - 10) - ((h - 20) as f64 * v) as u32;
            for x in x0..x0 + 40 {
                for y in top..h - 10 {
                    img.put_pixel(x, y, c);
                }
            }
            let x1 = 40 + 50 * (n + i as u32);
            if base > 0.0 {
                let r = ((b.mean_rgb[1] - base) / base).clamp(-0.1, 0.1) / 0.1;
                let y_end = (mid as f64 - r * (mid as f64 - 10.0)) as u32;
                let (ya, yb) = if y_end < mid {
                    (y_end, mid)
                } else {
                    (mid, y_end.max(mid + 1))
                };
                for x in x1..x1 + 40 {
                    for y in ya..yb {
                        img.put_pixel(x, y, c);
                    }
                    img.put_pixel(x, mid, image::Rgb([0, 0, 0]));
                }
            }
        }
        img
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_lists_every_backend_and_pair() {
        let r = Report {
            scene: "s.toml".into(),
            samples: 16,
            backends: vec![
                BackendResult {
                    backend: "native".into(),
                    target_rms_px: Some(0.0123),
                    mean_rgb: [0.1, 0.2, 0.3],
                    ..Default::default()
                },
                BackendResult {
                    backend: "mitsuba".into(),
                    error: Some("no module\nmore".into()),
                    ..Default::default()
                },
            ],
            pairs: vec![PairResult {
                a: "native".into(),
                b: "mitsuba".into(),
                mean_rel_diff: [0.01, -0.02, 0.0],
                ..Default::default()
            }],
        };
        let md = r.to_markdown();
        assert!(md.contains("| native | ok |"));
        assert!(md.contains("0.0123"));
        assert!(md.contains("failed: no module |"));
        assert!(md.contains("mitsuba vs native | +1.00 % | -2.00 %"));
        let png = r.plot_png();
        assert_eq!(png.height(), 200);
    }
}
