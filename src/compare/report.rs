//! The `poser compare` report: per backend, time, target-position error and radiometry; per
//! pair of backends, radiometric differences; the error against analytic radiometry where the
//! scene has a closed form ([`super::analytic`]). Written as Markdown, JSON and an SVG chart
//! with labelled axes, where a failed backend is marked "failed", never drawn as a bar.

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
    /// Every disk expected in its images, with its offset from the truth where it was found
    /// (G channel).
    pub targets: Vec<super::TargetResidual>,
    /// Mean linear value per channel over all pixels of all images.
    pub mean_rgb: [f64; 3],
    /// Rendered / analytic radiance − 1 per channel over the central window of the first image
    /// (pose 0, camera 0), when the scene has analytic radiometry ([`Report::analytic`]).
    pub analytic_rel: Option<[f64; 3]>,
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
    /// Analytic radiometry: `Ok` with what is compared, or why the scene has none.
    pub analytic: Option<Result<String, String>>,
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
        s.push_str(
            "Targets: measured disk centroids, checkerboard corners and Siemens star centres \
             against the exact truth \
             (RMS and max, px). \
             Mean R/G/B: linear radiance over all pixels of all images. vs analytic: \
             rendered / analytic radiance − 1 per channel.\n\n",
        );
        match &self.analytic {
            Some(Ok(what)) => s.push_str(&format!("Analytic radiometry: {what}.\n\n")),
            Some(Err(why)) => s.push_str(&format!("Analytic radiometry: none ({why}).\n\n")),
            None => {}
        }
        s.push_str("| backend | status | time (s) | images | targets | RMS (px) | max (px) | mean R | mean G | mean B | vs analytic R, G, B |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|\n");
        for b in &self.backends {
            let status = match &b.error {
                None => "ok".to_string(),
                Some(e) => format!(
                    "failed: {}",
                    e.lines().next().unwrap_or("").replace('|', "/")
                ),
            };
            let analytic = b
                .analytic_rel
                .map(|r| {
                    format!(
                        "{:+.2} %, {:+.2} %, {:+.2} %",
                        100.0 * r[0],
                        100.0 * r[1],
                        100.0 * r[2]
                    )
                })
                .unwrap_or_else(|| "–".into());
            if b.error.is_some() {
                s.push_str(&format!(
                    "| {} | {} | – | – | – | – | – | – | – | – | – |\n",
                    b.backend, status
                ));
                continue;
            }
            s.push_str(&format!(
                "| {} | {} | {:.2} | {} | {}/{} | {} | {} | {:.5} | {:.5} | {:.5} | {} |\n",
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
                b.mean_rgb[2],
                analytic
            ));
        }
        s.push_str(&self.targets_markdown());
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

    /// Per disk or checkerboard corner and image: the exact point and each backend's offset
    /// from it (Δu, Δv and its length, px), "not found" where a backend's image shows none
    /// there. Empty when no backend expected one.
    fn targets_markdown(&self) -> String {
        let shown: Vec<&BackendResult> = self
            .backends
            .iter()
            .filter(|b| b.error.is_none() && !b.targets.is_empty())
            .collect();
        if shown.is_empty() {
            return String::new();
        }
        // Every (disk, image) any backend expected, in the order met; each backend's own.
        type Key<'a> = (&'a str, &'a str);
        let mut rows: Vec<(Key, [f64; 2])> = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        let by_backend: Vec<std::collections::BTreeMap<Key, Option<[f64; 2]>>> = shown
            .iter()
            .map(|b| {
                b.targets
                    .iter()
                    .map(|t| ((t.id.as_str(), t.image.as_str()), t.offset))
                    .collect()
            })
            .collect();
        for b in &shown {
            for t in &b.targets {
                let key = (t.id.as_str(), t.image.as_str());
                if seen.insert(key) {
                    rows.push((key, t.truth));
                }
            }
        }
        let mut s = String::from(
            "\nPer target (G channel; pixel centres at +0.5, COLMAP's convention; OpenCV's \
             are these − 0.5): the exact point (a disk's image centroid, a checkerboard corner's or \
             a Siemens star centre's projection) and each backend's measured − exact offset \
             Δu, Δv and its length, px.\n\n| target | image | exact u, v |",
        );
        for b in &shown {
            s.push_str(&format!(" {} Δu, Δv (px) |", b.backend));
        }
        s.push_str("\n|---|---|---|");
        s.push_str(&"---|".repeat(shown.len()));
        s.push('\n');
        for ((id, image), truth) in &rows {
            s.push_str(&format!(
                "| {} | {} | {:.3}, {:.3} |",
                id.replace('|', "/"),
                image,
                truth[0],
                truth[1]
            ));
            for b in &by_backend {
                let cell = match b.get(&(*id, *image)) {
                    Some(Some(d)) => format!(
                        "{:+.4}, {:+.4} ({:.4})",
                        d[0],
                        d[1],
                        (d[0] * d[0] + d[1] * d[1]).sqrt()
                    ),
                    Some(None) => "not found".to_string(),
                    None => "–".to_string(),
                };
                s.push_str(&format!(" {cell} |"));
            }
            s.push('\n');
        }
        s
    }

    /// The chart (SVG): left, each backend's target position error (RMS, px); right, its
    /// radiometric error per channel (%), against the analytic radiance when the scene has one,
    /// otherwise against the first backend that rendered. Axes and backends are labelled; a
    /// failed backend is written "failed" where its bars would be.
    pub fn plot_svg(&self) -> Result<String, String> {
        use plotters::prelude::*;
        crate::plan::plot::register_font()?;
        let n = self.backends.len().max(1);
        let base = self
            .backends
            .iter()
            .find(|b| b.error.is_none())
            .map(|b| (b.backend.clone(), b.mean_rgb));
        let analytic = self.analytic.as_ref().is_some_and(|a| a.is_ok());
        let rel = |b: &BackendResult| relative_error(b, base.as_ref(), analytic);
        let rms_max = self
            .backends
            .iter()
            .filter_map(|b| b.target_rms_px)
            .fold(0.05f64, f64::max)
            * 1.25;
        let pct_max = self
            .backends
            .iter()
            .filter_map(rel)
            .flat_map(|r| r.map(|x| 100.0 * x.abs()))
            .fold(1.0f64, f64::max)
            * 1.25;
        let right_title = if analytic {
            "radiance vs analytic".to_string()
        } else {
            match &base {
                Some((name, _)) => format!("mean radiance vs {name}"),
                None => "mean radiance".into(),
            }
        };
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (420 + 160 * n as u32, 380)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| e.to_string())?;
            let (left, right) = root.split_horizontally((210 + 80 * n) as u32);
            let x_range = -0.5..n as f64 - 0.5;
            self.position_panel(&left, x_range.clone(), rms_max)?;
            self.radiometry_panel(&right, x_range, pct_max, right_title, &rel)?;
            root.present().map_err(|e| e.to_string())?;
        }
        Ok(svg)
    }

    /// The left panel: each backend's target position error (RMS, px) as a bar, "failed" or
    /// "no targets" where there is none.
    fn position_panel(
        &self,
        left: &plotters::drawing::DrawingArea<
            plotters::prelude::SVGBackend<'_>,
            plotters::coord::Shift,
        >,
        x_range: std::ops::Range<f64>,
        rms_max: f64,
    ) -> Result<(), String> {
        use plotters::prelude::*;
        let mut chart = ChartBuilder::on(left)
            .caption("target position vs exact truth", ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(x_range, 0.0..rms_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .x_desc("backend")
            .y_desc("RMS error (px)")
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, b) in self.backends.iter().enumerate() {
            let x = i as f64;
            let label = if b.error.is_some() {
                format!("{} (failed)", b.backend)
            } else {
                b.backend.clone()
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    label,
                    (x - 0.4, rms_max * 0.04),
                    ("sans-serif", 13),
                )))
                .map_err(|e| e.to_string())?;
            match (&b.error, b.target_rms_px) {
                (Some(_), _) => chart
                    .draw_series(std::iter::once(Text::new(
                        "failed",
                        (x - 0.25, rms_max * 0.5),
                        ("sans-serif", 16).into_font().color(&RED),
                    )))
                    .map(|_| ()),
                (None, Some(v)) => chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x - 0.3, 0.0), (x + 0.3, v)],
                        RGBColor(90, 90, 90).filled(),
                    )))
                    .map(|_| ()),
                (None, None) => chart
                    .draw_series(std::iter::once(Text::new(
                        "no targets",
                        (x - 0.3, rms_max * 0.5),
                        ("sans-serif", 13),
                    )))
                    .map(|_| ()),
            }
            .map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// The right panel: each backend's radiometric error per channel (%, `rel`) as R, G, B
    /// bars, "failed" or "no value" where there is none.
    fn radiometry_panel(
        &self,
        right: &plotters::drawing::DrawingArea<
            plotters::prelude::SVGBackend<'_>,
            plotters::coord::Shift,
        >,
        x_range: std::ops::Range<f64>,
        pct_max: f64,
        right_title: String,
        rel: &dyn Fn(&BackendResult) -> Option<[f64; 3]>,
    ) -> Result<(), String> {
        use plotters::prelude::*;
        let n = self.backends.len().max(1);
        let colours = [
            RGBColor(200, 40, 40),
            RGBColor(40, 150, 40),
            RGBColor(30, 80, 200),
        ];
        let mut chart = ChartBuilder::on(right)
            .caption(right_title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(x_range, -pct_max..pct_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .x_desc("backend (bars: R, G, B)")
            .y_desc("relative error (%)")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(
                [(-0.5, 0.0), (n as f64 - 0.5, 0.0)],
                BLACK.mix(0.5),
            ))
            .map_err(|e| e.to_string())?;
        for (i, b) in self.backends.iter().enumerate() {
            let x = i as f64;
            chart
                .draw_series(std::iter::once(Text::new(
                    b.backend.clone(),
                    (x - 0.4, -pct_max * 0.92),
                    ("sans-serif", 13),
                )))
                .map_err(|e| e.to_string())?;
            match rel(b) {
                Some(r) => {
                    for (c, col) in colours.iter().enumerate() {
                        let x0 = x - 0.3 + 0.2 * c as f64;
                        chart
                            .draw_series(std::iter::once(Rectangle::new(
                                [(x0, 0.0), (x0 + 0.18, 100.0 * r[c])],
                                col.filled(),
                            )))
                            .map_err(|e| e.to_string())?;
                    }
                }
                None => {
                    let text = if b.error.is_some() {
                        "failed"
                    } else {
                        "no value"
                    };
                    chart
                        .draw_series(std::iter::once(Text::new(
                            text,
                            (x - 0.25, pct_max * 0.5),
                            ("sans-serif", 16).into_font().color(&RED),
                        )))
                        .map_err(|e| e.to_string())?;
                }
            }
        }
        Ok(())
    }
}

/// A backend's radiometric error per channel: against the analytic radiance when the scene
/// has one (`analytic`), else against `base` (the first backend that rendered); `None` for a
/// failed backend.
fn relative_error(
    b: &BackendResult,
    base: Option<&(String, [f64; 3])>,
    analytic: bool,
) -> Option<[f64; 3]> {
    if b.error.is_some() {
        return None;
    }
    if analytic {
        return b.analytic_rel;
    }
    let (_, m) = base?;
    Some([0, 1, 2].map(|c| {
        if m[c] > 0.0 {
            b.mean_rgb[c] / m[c] - 1.0
        } else {
            0.0
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rectangles of an empty chart (background fills), to count only the bars.
    fn blank_rects() -> usize {
        let r = Report {
            backends: vec![BackendResult {
                backend: "x".into(),
                error: Some("e".into()),
                ..Default::default()
            }],
            ..Default::default()
        };
        r.plot_svg().unwrap().matches("<rect").count()
    }

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
            analytic: None,
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
        let svg = r.plot_svg().unwrap();
        // Labelled axes and backends; the failed backend is marked, not drawn as a bar.
        for label in [
            "RMS error (px)",
            "relative error (%)",
            "native",
            "mitsuba (failed)",
        ] {
            assert!(svg.contains(label), "{label} missing");
        }
        let failed = svg.lines().filter(|l| l.trim() == "failed").count();
        assert_eq!(failed, 2, "{svg}");
        // Bars: one (target RMS) + three (R, G, B vs native itself) for native only.
        assert_eq!(svg.matches("<rect").count() - blank_rects(), 4, "{svg}");
    }
}
