//! SVG plot of a simulated dive: depth and ceiling (m, down) and NDL (min, right axis) over
//! runtime, with the stops and the safety stop visible in the depth line.

use super::deco::{NDL_CAP, Ndl};
use super::dive::DiveReport;
use plotters::prelude::*;

/// Render the dive as an SVG document.
pub fn svg(report: &DiveReport, title: &str) -> Result<String, String> {
    let dive = &report.dive;
    let tmax = (dive.runtime / 60.0).max(1.0);
    let dmax = (dive.max_depth * 1.15).max(5.0);
    let ndl_max = NDL_CAP / 60.0;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (960, 540)).into_drawing_area();
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
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}
