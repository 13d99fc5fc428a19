//! A mesh object's georeference (issue 36): the keys that bring a photogrammetric model's
//! coordinates (UTM, a local shift, Y or Z up) into the object frame: `offset` or
//! `offset_file` (a sidecar of three numbers), `up_axis`; and the warning for a mesh whose
//! coordinates are far from its origin and that has no offset.

use crate::model::UpAxis;
use crate::scene::diag::{Diagnostic, Span};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::Sources;
use crate::units::Dim;
use glam::DVec3;
use std::path::Path;

/// Farthest a vertex may be from the object's origin (after `offset`, up axis and scale, in
/// metres) before the scene is warned: single precision (Mitsuba's and Cycles' vertices) spaces
/// numbers 8 mm apart at 100 km.
pub const FAR: f64 = 1e5;

/// `offset = [x, y, z]` or `offset_file = "…"` (not both) and `up_axis = "z" | "y"` of a mesh
/// object; the offset is zero when neither is given.
pub(super) fn keys(
    cx: &mut Cx,
    o: &mut Tab,
    sources: &Sources,
    scene: &Path,
) -> (DVec3, Option<UpAxis>) {
    let up = o
        .choice(cx, F::Object::up_axis, &["z", "y"])
        .map(|u| match u {
            "y" => UpAxis::Y,
            _ => UpAxis::Z,
        });
    let given = o.opt_vec3(cx, F::Object::offset, Dim::Number);
    let fspan = o.span_of(F::Object::offset_file);
    let file = o.opt_str(cx, F::Object::offset_file);
    if given.is_some() && file.is_some() {
        cx.push(
            Diagnostic::error("E0298", "give either `offset` or `offset_file`, not both")
                .label(
                    o.key_span(F::Object::offset_file),
                    "remove this or `offset`",
                )
                .help("`offset_file` names a file holding the three numbers `offset` would give"),
        );
    }
    let from_file = file.and_then(|rel| read_file(cx, &rel, fspan, sources, scene));
    (given.or(from_file).unwrap_or(DVec3::ZERO), up)
}

/// The offset in the sidecar `rel` (relative to the scene file that names it), or `None` after
/// a diagnostic.
fn read_file(cx: &mut Cx, rel: &str, span: Span, sources: &Sources, scene: &Path) -> Option<DVec3> {
    use crate::scene::source::{MAX_SCENE_BYTES, display, outside_diag, outside_root, read_capped};
    let dir = sources
        .dir_of(span.file)
        .unwrap_or_else(|| scene.parent().map(Path::to_path_buf).unwrap_or_default());
    let path = dir.join(rel);
    if let Some(why) = outside_root(sources, rel, &path) {
        cx.push(outside_diag(rel, &why, span));
        return None;
    }
    let shown = display(&path);
    let bytes = match read_capped(&path, MAX_SCENE_BYTES) {
        Ok(b) => b,
        Err(r) => {
            cx.push(
                Diagnostic::error("E0297", format!("cannot read the offset file `{shown}`"))
                    .label(span, r.reason())
                    .help("give the file relative to this scene file, e.g. `offset_file = \"model_offset.xyz\"`"),
            );
            return None;
        }
    };
    let text = String::from_utf8_lossy(&bytes);
    match parse(&text) {
        Ok(v) => {
            cx.files.push(path);
            Some(v)
        }
        Err((line, col, msg)) => {
            cx.push(
                Diagnostic::error("E0297", format!("{shown}:{line}:{col}: {msg}"))
                    .label(span, "in this offset file")
                    .help(HELP),
            );
            None
        }
    }
}

/// What an offset file holds.
const HELP: &str = "an offset file holds three numbers `x y z` (spaces, commas or semicolons between them; `#` starts a comment; one word before them on their line, such as a CRS name `EPSG:32633`, is skipped), in the mesh file's units and axes";

/// The three numbers of an offset file; errors are `(line, column, message)`, 1-based.
pub fn parse(text: &str) -> Result<DVec3, (usize, usize, String)> {
    let mut out: Vec<f64> = Vec::new();
    let mut last = (1, 1);
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let mut words: Vec<(usize, &str)> = Vec::new();
        let mut start = None;
        for (k, c) in line
            .char_indices()
            .chain(std::iter::once((line.len(), ' ')))
        {
            let sep = c.is_whitespace() || c == ',' || c == ';';
            match (sep, start) {
                (false, None) => start = Some(k),
                (true, Some(s)) => {
                    words.push((s, &line[s..k]));
                    start = None;
                }
                _ => {}
            }
        }
        // A label before the numbers (a CRS name) is skipped.
        if words.len() > 1 && words[0].1.parse::<f64>().is_err() {
            words.remove(0);
        }
        for (col, w) in words {
            last = (i + 1, col + 1);
            match w.parse::<f64>() {
                Ok(v) if v.is_finite() && out.len() < 3 => out.push(v),
                Ok(v) if v.is_finite() => {
                    return Err((
                        i + 1,
                        col + 1,
                        format!("a fourth number `{w}`: an offset is three numbers"),
                    ));
                }
                _ => return Err((i + 1, col + 1, format!("`{w}` is not a finite number"))),
            }
        }
    }
    match out.as_slice() {
        [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
        v => Err((
            last.0,
            last.1,
            format!("{} number(s) where an offset needs three", v.len()),
        )),
    }
}

/// Warn when the mesh file at `path` (accepted by the front end) has vertices farther than
/// [`FAR`] from the object's origin once its up axis and `scale` are applied, and no offset is
/// given: suggest its bounding box's centre, in the file's units and axes, as `offset`.
pub(super) fn warn_far(cx: &mut Cx, path: &Path, up: Option<UpAxis>, scale: DVec3, span: Span) {
    use crate::geometry::mesh::{file_axes, up_of, up_turned};
    let format = crate::geometry::meshfile::Format::of(path);
    let Ok(Some((lo, hi))) = crate::geometry::meshfile::vertex_bounds(path) else {
        return;
    };
    let (a, b) = (file_axes(lo, format), file_axes(hi, format));
    let (lo, hi) = (a.min(b), a.max(b));
    let up = up_of(up, format);
    let far = (0..8)
        .map(|k| {
            let c = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            (up_turned(c, up) * scale).length()
        })
        .fold(0.0, f64::max);
    if far <= FAR {
        return;
    }
    let c = 0.5 * (lo + hi);
    // Single precision's spacing at that distance.
    let spacing = 2f64.powi(far.log2().floor() as i32 - 23);
    cx.push(
        Diagnostic::warning(
            "W0296",
            format!(
                "the mesh's vertices are up to {:.0} km from its origin and no `offset` is given",
                far / 1e3
            ),
        )
        .label(span, format!("its bounding box's centre is [{:.0}, {:.0}, {:.0}]", c.x, c.y, c.z))
        .note(format!(
            "single precision (Mitsuba's and Cycles' vertices) spaces numbers {:.0} mm apart there",
            spacing * 1e3
        ))
        .help(format!(
            "add `offset = [{:.0}, {:.0}, {:.0}]` (the bounding box's centre, in the file's units and axes) to bring the mesh near its origin, and place it with `position`",
            c.x, c.y, c.z
        )),
    );
}
