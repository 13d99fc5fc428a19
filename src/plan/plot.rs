//! Plot of a simulated dive, as SVG or PNG: depth and ceiling (m, down) and NDL (min, right
//! axis) over runtime, with the stops and the safety stop visible in the depth line. Also what
//! every plot of poser shares: the embedded font ([`register_font`]) and the legend box
//! ([`legend`]).
//!
//! | output | backend | text |
//! |---|---|---|
//! | SVG | plotters' SVG backend | `<text>` elements (the viewer's sans-serif) |
//! | PNG 960×540 | plotters' bitmap backend, encoded by `image` | DejaVu Sans, embedded (`assets/fonts`, its licence beside it) |

use super::deco::{NDL_CAP, Ndl};
use super::dive::DiveReport;
use plotters::prelude::*;

const SIZE: (u32, u32) = (960, 540);

/// Text is laid out (SVG and PNG) and drawn (PNG) with one embedded font, so a plot looks the
/// same on every machine. plotters needs the font registered before any chart with text is
/// drawn, on any backend: every plot of poser calls this first.
pub fn register_font() -> Result<(), String> {
    static ONCE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    ONCE.get_or_init(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| "the embedded plot font is unreadable".to_string())
    })
    .clone()
}

/// The series legend of every plot of poser: a white box at 80 % over the plot, a black
/// border, at `position` (plotters' own default is `MiddleRight`).
pub fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(|e| e.to_string())
}

/// Render the dive as an SVG document.
pub fn svg(report: &DiveReport, title: &str) -> Result<String, String> {
    register_font()?;
    let mut buf = String::new();
    draw(
        SVGBackend::with_string(&mut buf, SIZE).into_drawing_area(),
        report,
        title,
    )?;
    Ok(buf)
}

/// Render the dive as a PNG file's bytes.
pub fn png(report: &DiveReport, title: &str) -> Result<Vec<u8>, String> {
    register_font()?;
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area(),
        report,
        title,
    )?;
    let img = image::RgbImage::from_raw(SIZE.0, SIZE.1, rgb).ok_or("plot buffer size")?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    report: &DiveReport,
    title: &str,
) -> Result<(), String> {
    let dive = &report.dive;
    let tmax = (dive.runtime / 60.0).max(1.0);
    let dmax = (dive.max_depth * 1.15).max(5.0);
    let ndl_max = NDL_CAP / 60.0;
    {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .right_y_label_area_size(50)
            .build_cartesian_2d(0f64..tmax, dmax..0f64)
            .map_err(|e| e.to_string())?
            .set_secondary_coord(0f64..tmax, 0f64..ndl_max);
        chart
            .configure_mesh()
            .x_desc("runtime (min)")
            .y_desc("depth (m)")
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .configure_secondary_axes()
            .y_desc("NDL (min)")
            .draw()
            .map_err(|e| e.to_string())?;
        let blue = RGBColor(20, 80, 200);
        let red = RGBColor(210, 40, 40);
        let green = RGBColor(30, 150, 60);
        chart
            .draw_series(LineSeries::new(
                dive.profile.iter().map(|&(t, d)| (t / 60.0, d)),
                blue.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label("depth")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue));
        chart
            .draw_series(LineSeries::new(
                dive.samples.iter().map(|s| (s.time / 60.0, s.ceiling)),
                red.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label("ceiling")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red));
        let ndl: Vec<(f64, f64)> = dive
            .samples
            .iter()
            .filter(|s| s.depth >= 3.0)
            .map(|s| {
                let m = match s.ndl {
                    Some(Ndl::Limit(n)) => n / 60.0,
                    Some(Ndl::Unlimited) => ndl_max,
                    _ => 0.0,
                };
                (s.time / 60.0, m)
            })
            .collect();
        chart
            .draw_secondary_series(LineSeries::new(ndl, green.stroke_width(1)))
            .map_err(|e| e.to_string())?
            .label("NDL (right axis)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], green));
        legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(())
}
