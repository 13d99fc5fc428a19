//! The water column as a report: what `poser column` writes and `poser explain` prints of a
//! solved [`crate::optics::column::Column`].
//!
//! | output | content |
//! |---|---|
//! | [`json`] | the inputs the column was solved with (so an independent solver can redo it) and, per channel, E_d (direct, diffuse), E_u, E_0, K_d at every plane with the standard errors |
//! | [`csv`] | one row per plane and channel: `z_m,channel,E_d_direct,E_d_diffuse,E_u,E_0,K_d` |
//! | [`svg`] | E_d and E_u per channel against depth (log irradiance, depth down) |
//! | [`summary`] | the lines `explain` prints: K_d, the diffuse share at the seabed, the solve time |

use crate::model::{Model, Phase};
use crate::optics::column::{Column, ColumnInput};
use plotters::prelude::*;
use serde_json::json;

const CH: [&str; 3] = ["R", "G", "B"];

/// The column's JSON document.
pub fn json(model: &Model, input: &ColumnInput, col: &Column) -> serde_json::Value {
    let phase = match model.water.as_ref().map(|w| w.phase) {
        Some(Phase::HenyeyGreenstein { g }) => json!({"kind": "henyey_greenstein", "g": g}),
        Some(Phase::FournierForand { n, mu, backscatter }) => {
            json!({"kind": "fournier_forand", "n": n, "mu": mu, "backscatter": backscatter})
        }
        None => json!(null),
    };
    let channels: Vec<_> = (0..3)
        .map(|c| {
            let p = &col.profiles[c];
            json!({
                "name": CH[c],
                "E_d_direct": p.e_d_direct,
                "E_d_diffuse": p.e_d_diffuse,
                "E_u": p.e_u,
                "E_0": p.e_0,
                "K_d": p.k_d,
                "E_d_stderr": p.e_d_stderr,
                "E_u_stderr": p.e_u_stderr,
            })
        })
        .collect();
    json!({
        "scene": model.name,
        "depth": col.depth,
        "top": "open",
        "mu0": input.sun.map(|s| s.dirs.map(|d| -d.z)),
        "sun_irradiance": input.sun.map_or([0.0; 3], |s| s.irradiance),
        "ambient": input.ambient,
        "bottom_albedo": input.bottom_albedo,
        "phase": phase,
        "sigma_a": input.sigma_a,
        "sigma_s": input.sigma_s,
        "photons": col.photons,
        "method": if col.is_exact() { "exact" } else { "walk" },
        "solve_seconds": col.seconds,
        "truncated_share": col.truncated,
        "table": {
            "layers": crate::optics::column::NZ,
            "cos_bins": crate::optics::column::NMU,
            "azimuth_bins": crate::optics::column::NPHI,
        },
        "z": col.planes(),
        "channels": channels,
    })
}

/// The profiles as CSV.
pub fn csv(col: &Column) -> String {
    let mut s = String::from("z_m,channel,E_d_direct,E_d_diffuse,E_u,E_0,K_d\n");
    for (j, z) in col.planes().iter().enumerate() {
        for (c, name) in CH.iter().enumerate() {
            let p = &col.profiles[c];
            s += &format!(
                "{z:.4},{name},{:.6e},{:.6e},{:.6e},{:.6e},{:.6}\n",
                p.e_d_direct[j], p.e_d_diffuse[j], p.e_u[j], p.e_0[j], p.k_d[j]
            );
        }
    }
    s
}

/// E_d (solid) and E_u (dashed) per channel against depth, as SVG.
pub fn svg(col: &Column, title: &str) -> Result<String, String> {
    crate::plan::plot::register_font()?;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (720, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let z = col.planes();
        let vals = (0..3).flat_map(|c| {
            let p = &col.profiles[c];
            (0..z.len()).flat_map(move |j| [p.e_d(j), p.e_u[j]])
        });
        let (mut lo, mut hi) = (f64::INFINITY, 0f64);
        for v in vals.filter(|v| *v > 0.0) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            lo = 1e-3;
            hi = 1.0;
        }
        let (lo, hi) = (
            lo.log10().floor(),
            hi.log10().ceil().max(lo.log10().floor() + 1.0),
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(lo..hi, col.depth..0f64)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("log10 irradiance (W/m²)")
            .y_desc("depth (m)")
            .draw()
            .map_err(|e| e.to_string())?;
        let colors = [RED, GREEN, BLUE];
        for c in 0..3 {
            let p = &col.profiles[c];
            let down: Vec<(f64, f64)> = (0..z.len())
                .filter(|&j| p.e_d(j) > 0.0)
                .map(|j| (p.e_d(j).log10(), z[j]))
                .collect();
            let up: Vec<(f64, f64)> = (0..z.len())
                .filter(|&j| p.e_u[j] > 0.0)
                .map(|j| (p.e_u[j].log10(), z[j]))
                .collect();
            chart
                .draw_series(LineSeries::new(down, colors[c].stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(format!("E_d {}", CH[c]))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colors[c]));
            chart
                .draw_series(DashedLineSeries::new(up, 4, 4, colors[c].stroke_width(1)))
                .map_err(|e| e.to_string())?
                .label(format!("E_u {}", CH[c]))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colors[c]));
        }
        crate::plan::plot::legend(&mut chart, SeriesLabelPosition::MiddleRight)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}

/// The lines `explain` prints about a solved column.
pub fn summary(col: &Column) -> Vec<String> {
    let k = col.mean_k_d();
    let share = col.diffuse_share_at_bottom();
    vec![
        format!(
            "  K_d (surface to seabed) [{:.4}, {:.4}, {:.4}] 1/m; diffuse share of E_d at the \
             seabed [{:.0}, {:.0}, {:.0}] % (R, G, B)",
            k[0],
            k[1],
            k[2],
            100.0 * share[0],
            100.0 * share[1],
            100.0 * share[2]
        ),
        format!(
            "  {}, {} layers × {} × {} directions{}",
            if col.is_exact() {
                format!(
                    "solved exactly in {:.2} s (the water does not scatter: quadrature, no \
                     photons)",
                    col.seconds
                )
            } else {
                format!(
                    "solved in {:.2} s: {} photons per channel",
                    col.seconds, col.photons
                )
            },
            crate::optics::column::NZ,
            crate::optics::column::NMU,
            crate::optics::column::NPHI,
            if col.is_exact() {
                String::new()
            } else {
                format!(
                    "; E_d at the seabed ± [{:.2}, {:.2}, {:.2}] % (1σ)",
                    rel_err(col, 0),
                    rel_err(col, 1),
                    rel_err(col, 2)
                )
            }
        ),
    ]
}

fn rel_err(col: &Column, c: usize) -> f64 {
    let p = &col.profiles[c];
    let n = p.e_d_stderr.len() - 1;
    let e = p.e_d(n);
    if e > 0.0 {
        100.0 * p.e_d_stderr[n] / e
    } else {
        0.0
    }
}
