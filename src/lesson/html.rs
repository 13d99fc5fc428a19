//! The lesson page: `OUT/index.html`, one self-contained file that works offline (CSS
//! inline, images as `data:` URIs, plots as inline SVG, no script), and `OUT/lesson.json` with
//! the same numbers. Both are written atomically.
//!
//! | section | contents |
//! |---|---|
//! | header | title, the question, the set-up, the form (quick or full) and the command |
//! | numbers | one table row per variant; every number measured by this run |
//! | figures | per variant: deformation map and height profile, a rendered view and the residual vectors, the dive profile, or the seen/unseen surface maps (kinds `contrast`, `gsd`, `completeness`, `metrology` and `surface` write their own sections: [`super::contrast::html`], [`super::gsd::html`], [`super::completeness::section`], [`super::metrology::html`], [`super::surface::html`]) |
//! | try next | each suggestion with the `poser lesson … --set` that changes one thing |
//!
//! Every number cell carries `data-key="<variant slug>.<quantity>"` so tools (and the tests)
//! can find it; [`case_row`] writes the usual row of a kind's table: the case, then such cells.

use super::{Report, Results, slug};
use crate::io::write_atomic;
use std::fmt::Write as _;
use std::path::Path;

/// Text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// Standard base64 (RFC 4648) with padding, for `data:` URIs.
pub fn base64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

pub(crate) fn png(bytes: &[u8], alt: &str) -> String {
    format!(
        "<img alt=\"{}\" src=\"data:image/png;base64,{}\">",
        escape(alt),
        base64(bytes)
    )
}

/// An SVG from plotters, inline (its XML declaration, if any, dropped).
pub(crate) fn svg(s: &str) -> String {
    match s.find("<svg") {
        Some(i) => s[i..].to_string(),
        None => String::new(),
    }
}

pub(crate) fn num(key: &str, text: String) -> String {
    format!("<td class=\"num\" data-key=\"{}\">{text}</td>", escape(key))
}

/// One table row of a case: its label, then a number cell per `(key, text)`, each keyed
/// `SLUG.KEY` (the case's [`slug`]) for whoever reads the page's numbers.
pub(crate) fn case_row(s: &mut String, label: &str, cells: &[(&str, String)]) {
    let k = slug(label);
    s.push_str("<tr><th>");
    s.push_str(&escape(label));
    s.push_str("</th>");
    for (key, text) in cells {
        s.push_str(&num(&format!("{k}.{key}"), text.clone()));
    }
    s.push_str("</tr>\n");
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;\
color:#1b2a33;background:#fbfdfe}h1{color:#0b4f6c}.q{font-size:1.3em;font-style:italic}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #b9c9d3;padding:.3em .6em}\
th{background:#dcebf3}td.num{text-align:right;font-variant-numeric:tabular-nums}\
code{background:#eef3f6;padding:.1em .3em}figure{display:inline-block;margin:.5em;vertical-align:top}\
figure img,figure svg{max-width:520px;height:auto;border:1px solid #ccd}.small{color:#567;font-size:.9em}\
.shows{background:#e6f3ea;border-left:4px solid #2e8b57;padding:.1em 1em;margin:1em 0}\
.warn{background:#fff4d6;border-left:4px solid #d08a00;padding:.4em .8em;margin:.5em 0}";

/// The page as a string.
pub fn page(r: &Report) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\
         <style>{STYLE}</style></head><body>\n<h1>{t}</h1>\n<p class=\"q\">{q}</p>\n\
         {shows}<h2>Set-up</h2><p>{setup}</p>\n{view}<p class=\"small\">Form: <b>{form}</b>. Scene \
         <code>{scene}</code>; run with <code>{cmd}</code> ({secs:.0} s).</p>\n",
        t = escape(&r.title),
        q = escape(&r.question),
        view = if r.view_png.is_empty() {
            String::new()
        } else {
            format!(
                "<figure class=\"view\">{}<figcaption>What the camera sees: the first image of \
                 “{}”, a quick native preview.</figcaption></figure>\n",
                png(&r.view_png, &format!("camera view, {}", r.view_label)),
                escape(&r.view_label)
            )
        },
        shows = if r.shows.is_empty() {
            String::new()
        } else {
            format!(
                "<div class=\"shows\"><h2>What this shows</h2><p>{}</p></div>\n",
                escape(&r.shows)
            )
        },
        setup = escape(&r.setup),
        form = r.form,
        scene = escape(&r.scene),
        cmd = escape(&r.command),
        secs = r.seconds,
    );
    if let Some(full) = &r.full_command {
        let sets = if r.form_sets.is_empty() {
            "the scene as written".to_string()
        } else {
            r.form_sets
                .iter()
                .map(|s| format!("<code>{}</code>", escape(s)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            s,
            "<div class=\"warn\"><b>Quick form.</b> This page ran the lesson with {sets}: \
             smaller and faster than the set-up above describes, so its numbers are not the \
             full lesson's. The full form: <code>{}</code>.</div>",
            escape(full)
        );
    }
    match &r.results {
        Results::Deformation { rows } => deformation_section(&mut s, rows),
        Results::Contrast { rows } => s.push_str(&super::contrast::html(rows)),
        Results::Gsd { rows } => s.push_str(&super::gsd::html(rows)),
        Results::Calibration { rows } => calibration_section(&mut s, rows),
        Results::Dive(res) => s.push_str(&super::dive::html(res, false)),
        Results::Survey(res) => s.push_str(&super::dive::html(res, true)),
        Results::Completeness { rows } => s.push_str(&super::completeness::section(rows)),
        Results::Metrology { rows } => s.push_str(&super::metrology::html(rows)),
        Results::Surface { rows } => s.push_str(&super::surface::html(rows)),
    }
    if !r.try_next.is_empty() {
        s.push_str("<h2>Try next</h2>\n<ul>\n");
        for t in &r.try_next {
            let _ = writeln!(
                s,
                "<li>{}: <code>{}</code></li>",
                escape(&t.text),
                escape(&t.command)
            );
        }
        s.push_str("</ul>\n");
    }
    s.push_str(
        "<p class=\"small\">Made by poser; every number on this page was measured by this \
         run.</p>\n</body></html>\n",
    );
    s
}

/// The deformation lesson's numbers: per case, COLMAP's reprojection error, focal error and
/// height errors (RMS, NMAD, the bowl), the warnings, then the error maps.
fn deformation_section(s: &mut String, rows: &[super::deformation::Row]) {
    s.push_str(
        "<h2>The numbers</h2>\n<p>Each case is processed by COLMAP (self-calibrating \
         bundle adjustment of exact refractive observations with 0.3 px noise, an \
         OpenCV camera model that ignores the port) and compared with the truth.</p>\n\
         <table><tr><th>case</th><th>images</th><th>reprojection, px</th>\
         <th>focal error, %</th><th>RMS Z, mm</th><th>NMAD Z, mm</th><th>bowl peak-to-peak, mm</th>\
         <th>bowl share, %</th></tr>\n",
    );
    for row in rows {
        case_row(
            s,
            &row.label,
            &[
                ("images", row.images.to_string()),
                ("reprojection_px", format!("{:.2}", row.reprojection_px)),
                (
                    "focal_error_percent",
                    format!("{:+.2}", row.focal_error_percent),
                ),
                ("rms_z_mm", format!("{:.1}", row.rms_z_mm)),
                ("nmad_z_mm", format!("{:.1}", row.nmad_z_mm)),
                ("bowl_mm", format!("{:.1}", row.bowl_mm)),
                ("bowl_share", format!("{:.0}", 100.0 * row.bowl_share)),
            ],
        );
    }
    s.push_str(
        "</table>\n<p class=\"small\">Bowl: a quadratic surface fitted to the height \
         errors; its share is the part of their variance it explains. NMAD: the robust \
         spread of the height errors (what RMS would be without outliers).</p>\n",
    );
    for row in rows.iter().filter(|r| !r.warnings.is_empty()) {
        let _ = writeln!(
            s,
            "<div class=\"warn\"><b>⚠ {}:</b> {}</div>",
            escape(&row.label),
            row.warnings
                .iter()
                .map(|w| escape(w))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    deformation_maps(s, rows);
}

/// The calibration lesson's numbers: per port, OpenCV's calibration (focal ratios, principal
/// point, distortion, lateral colour), then each port's view and residuals.
fn calibration_section(s: &mut String, rows: &[super::calibration::Row]) {
    s.push_str(
        "<h2>The numbers</h2>\n<p>OpenCV detects the board's inner corners in the \
         rendered images and calibrates a pinhole camera with k1, k2, p1, p2, k3; the \
         colour channels are also calibrated one by one. Pixel convention: OpenCV's, \
         pixel centres at integers (poser's and COLMAP's are at +0.5, so cx<sub>poser\
         </sub> = cx<sub>OpenCV</sub> + 0.5).</p>\n<table><tr><th>port</th>\
         <th>views</th><th>RMS, px</th><th>f<sub>x</sub>/f<sub>air</sub></th>\
         <th>f<sub>y</sub>/f<sub>air</sub></th><th>c<sub>x</sub>, c<sub>y</sub> \
         (OpenCV), px</th><th>k1</th><th>k2</th><th>p1</th><th>p2</th><th>k3</th>\
         <th>lateral colour R−B at the corners, px (calibrated; detected)</th></tr>\n",
    );
    for row in rows {
        let c = &row.calibration;
        let d = &c.grey.dist;
        case_row(
            s,
            &row.label,
            &[
                ("views", c.views.len().to_string()),
                ("rms", format!("{:.3}", c.grey.rms)),
                ("fx_ratio", format!("{:.3}", row.fx_ratio)),
                ("fy_ratio", format!("{:.3}", row.fy_ratio)),
                (
                    "principal_point",
                    format!("{:.1}, {:.1}", c.grey.cx, c.grey.cy),
                ),
                ("k1", format!("{:.3}", d.k1)),
                ("k2", format!("{:.3}", d.k2)),
                ("p1", format!("{:.4}", d.p1)),
                ("p2", format!("{:.4}", d.p2)),
                ("k3", format!("{:.3}", d.k3)),
                (
                    "lateral_colour",
                    c.lateral_colour.as_ref().map_or("–".into(), |l| {
                        format!("{:.2}; {:.2}", l.r_minus_b_px, l.detected_r_minus_b_px)
                    }),
                ),
            ],
        );
    }
    let f_air = rows.first().map_or(f64::NAN, |r| r.f_air);
    let _ = write!(
        s,
        "</table>\n<p class=\"small\">f<sub>air</sub> = {f_air:.1} px: the lens's focal \
         length over the pixel pitch. A flat port multiplies the focal length by about \
         the water's index; a centred dome leaves it nearly unchanged. Lateral colour: \
         the distance between the red and the blue image of the same point, at the \
         board corners seen nearest to the image corners, through the per-channel \
         calibrations and directly between the corners detected in each channel.</p>\n\
         <h2>Views and residuals</h2>\n"
    );
    for row in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{img}<figcaption>View 1 as rendered.</figcaption>\
             </figure>\n<figure>{svg}<figcaption>Corners (dots) and their residual \
             vectors after calibration.</figcaption></figure>\n<p class=\"small\">\
             Render alone: <code>{cmd}</code></p>\n",
            l = escape(&row.label),
            img = png(&row.view_png, &format!("rendered view, {}", row.label)),
            svg = svg(&row.residuals_svg),
            cmd = escape(&row.command),
        );
    }
}

/// Write `index.html` and `lesson.json` into `dir`.
pub fn write(r: &Report, dir: &Path) -> Result<(), String> {
    let mut json = serde_json::to_vec_pretty(r).map_err(|e| e.to_string())?;
    json.push(b'\n');
    for (name, bytes) in [("lesson.json", json), ("index.html", page(r).into_bytes())] {
        let p = dir.join(name);
        write_atomic(&p, &bytes).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(())
}

/// The deformation lesson's maps, each with its colour bar's range beside it: one scale for the
/// whole page, so that a bowl of millimetres and one of decimetres do not look alike.
fn deformation_maps(s: &mut String, rows: &[super::deformation::Row]) {
    let scale = rows.first().map_or(f64::NAN, |r| r.map_scale_mm);
    let _ = writeln!(
        s,
        "<h2>Where the error is</h2>\n<p>Every map below uses one colour scale: \
         <span style=\"color:#3366ff\">blue</span> <span data-key=\"map_scale_mm\">\
         {scale:.1}</span> mm low, white on the truth, <span style=\"color:#e0302f\">red\
         </span> {scale:.1} mm high. Black dots are the cameras; ringed dots are the \
         targets. One scale, so that cases of millimetres and of decimetres do not look \
         alike; each caption gives the case's own range too.</p>"
    );
    for row in rows {
        let _ = write!(
            s,
            "<h3>{l}</h3>\n<figure>{img}<figcaption>Height error per tie point. Colour \
             bar <span data-key=\"{k}.map_range_mm\">−{scale:.1} … +{scale:.1}</span> \
             mm, the page's one scale (this case alone spans ±{own:.1} mm).</figcaption>\
             </figure>\n\
             <figure>{svg}\
             <figcaption>Mean height error along and across the plot.</figcaption>\
             </figure>\n<p class=\"small\">Alone: <code>{cmd}</code></p>\n",
            l = escape(&row.label),
            img = png(&row.map_png, &format!("deformation map, {}", row.label)),
            svg = svg(&row.profile_svg),
            cmd = escape(&row.command),
            own = row.own_scale_mm,
            scale = row.map_scale_mm,
            k = slug(&row.label),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(
            escape("<a href='x'>&\""),
            "&lt;a href=&#39;x&#39;&gt;&amp;&quot;"
        );
    }
}

#[cfg(test)]
mod page_tests {
    use super::super::{Next, Report, Results, deformation::Row};
    use super::page;

    #[test]
    fn the_page_is_self_contained_and_shows_every_number_in_its_cell() {
        let r = Report {
            scene: "s.toml".into(),
            title: "T <1>".into(),
            question: "Q?".into(),
            setup: "S".into(),
            shows: "A & B.".into(),
            view_label: "flat".into(),
            view_png: vec![0x89, b'P', b'N', b'G'],
            form: "quick",
            form_sets: vec!["network.length=10".into()],
            command: "poser lesson s.toml -o o".into(),
            full_command: Some("poser lesson s.toml -o o --full".into()),
            results: Results::Deformation {
                rows: vec![Row {
                    label: "flat, pupil 3 cm".into(),
                    command: "poser evaluate s.toml -o out/flat".into(),
                    images: 336,
                    registered: 336,
                    points: 1432,
                    reprojection_px: 0.5,
                    focal_error_percent: 1.12,
                    rms_z_mm: 30.46,
                    nmad_z_mm: 21.0,
                    bowl_mm: 115.9,
                    bowl_share: 0.998,
                    seconds: 6.0,
                    warnings: vec!["only 25 of 330 images registered <x>".into()],
                    map_scale_mm: 65.0,
                    own_scale_mm: 65.0,
                    map_png: vec![0x89, b'P', b'N', b'G'],
                    profile_svg: "<?xml version=\"1.0\"?><svg></svg>".into(),
                }],
            },
            try_next: vec![Next {
                text: "Fly higher".into(),
                command: "poser lesson s.toml -o o_next --set 'network.altitude=\"2 m\"'".into(),
            }],
            seconds: 7.0,
        };
        let p = page(&r);
        assert!(p.contains("<h1>T &lt;1&gt;</h1>"));
        assert!(p.contains("<h2>What this shows</h2><p>A &amp; B.</p>"));
        assert!(p.contains("What the camera sees: the first image of “flat”"));
        assert!(p.contains(
            "<b>Quick form.</b> This page ran the lesson with <code>network.length=10</code>"
        ));
        assert!(p.contains("The full form: <code>poser lesson s.toml -o o --full</code>"));
        assert!(p.contains("data-key=\"flat_pupil_3_cm.rms_z_mm\">30.5<"));
        assert!(p.contains("data-key=\"flat_pupil_3_cm.nmad_z_mm\">21.0<"));
        assert!(p.contains("<span data-key=\"map_scale_mm\">65.0</span> mm low"));
        assert!(p.contains("this case alone spans ±65.0 mm"));
        assert!(p.contains(
            "Colour bar <span data-key=\"flat_pupil_3_cm.map_range_mm\">−65.0 … +65.0</span> mm"
        ));
        assert!(p.contains(
            "class=\"warn\"><b>⚠ flat, pupil 3 cm:</b> only 25 of 330 images registered &lt;x&gt;"
        ));
        assert!(p.contains("data-key=\"flat_pupil_3_cm.focal_error_percent\">+1.12<"));
        assert!(p.contains("data-key=\"flat_pupil_3_cm.bowl_share\">100<"));
        assert!(p.contains("src=\"data:image/png;base64,iVBORw==\""));
        assert!(p.contains("<svg></svg>") && !p.contains("<?xml"));
        assert!(p.contains("--set &#39;network.altitude=&quot;2 m&quot;&#39;"));
        assert!(!p.contains("<script") && !p.contains("src=\"http"));
    }
}
