//! The `[[targets]]` of a scene: printed photogrammetry targets (checkerboard, circle grid,
//! coded targets, scale bar, Siemens star, stepped test object) and `points_file` lists of
//! disks, each with its name-unique ground-truth points (through [`crate::geometry::targets`]).

use super::{Spans, placement};
use crate::model::*;
use crate::scene::check;
use crate::scene::diag::Diagnostic;
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::Sources;
use crate::units::Dim;
use glam::DVec3;
use std::path::Path;

/// Every `[[targets]]` entry (a points file gives one target per point); names are unique.
pub(super) fn targets(
    cx: &mut Cx,
    t: &mut Tab,
    spans: &mut Spans,
    objects: &[Object],
    site: &Site,
    sources: &Sources,
    scene: &Path,
) -> Vec<Target> {
    let mut out: Vec<Target> = Vec::new();
    for (i, n) in t.tables(cx, F::Scene::targets).into_iter().enumerate() {
        let path = format!("targets[{i}]");
        let mut g = Tab::open(cx, Some(n), &path, n.span);
        let name = g
            .opt_str(cx, F::Target::name)
            .unwrap_or_else(|| format!("target{i}"));
        let ty = g
            .choice(
                cx,
                F::Target::kind,
                &[
                    "checkerboard",
                    "circle_grid",
                    "coded",
                    "scale_bar",
                    "siemens_star",
                    "test_object",
                    "points_file",
                ],
            )
            .unwrap_or("checkerboard");
        if ty == "points_file" {
            let disks = points_file(cx, &mut g, &name, objects, site, sources, scene);
            for d in &disks {
                if out.iter().any(|o| o.name == d.name) {
                    cx.push(
                        Diagnostic::error("E0291", format!("two targets are named `{}`", d.name))
                            .label(g.span_of(F::Target::name), "a point of this file has a taken name")
                            .help("a points file's disks are named `name/id`; give this target another `name`"),
                    );
                    break;
                }
            }
            spans.targets.extend(disks.iter().map(|_| g.span));
            g.finish_as(cx, Some(&format!("a points_file target (`{path}`)")));
            out.extend(disks);
            continue;
        }
        let kind = kind(cx, &mut g, ty);
        let pose = placement(cx, &mut g, DVec3::ZERO);
        if out.iter().any(|o| o.name == name) {
            let sp = g.span_of(F::Target::name);
            cx.push(
                Diagnostic::error("E0291", format!("two targets are named `{name}`"))
                    .label(sp, "duplicate name")
                    .help("target point ids are `name/index`, so names must be unique"),
            );
        }
        spans.targets.push(g.span);
        g.finish_as(cx, Some(&format!("a {ty} target (`{path}`)")));
        let points = crate::geometry::targets::points(&name, &kind, &pose);
        out.push(Target {
            name,
            kind,
            pose,
            points,
        });
    }
    out
}

/// The printed pattern of a target of type `ty` (not `points_file`), from its keys.
fn kind(cx: &mut Cx, g: &mut Tab, ty: &str) -> TargetKind {
    match ty {
        "checkerboard" => {
            let cols = g.u32(cx, F::Target::cols, 9);
            let rows = g.u32(cx, F::Target::rows, 6);
            let square = g.f64(cx, F::Target::square, Dim::Length, 0.04);
            check::at_least(cx, g, F::Target::cols, cols, 2);
            check::at_least(cx, g, F::Target::rows, rows, 2);
            check::positive(cx, g, F::Target::square, square, "m");
            let (cols, rows) = limit_grid(cx, g, cols, rows);
            TargetKind::Checkerboard { cols, rows, square }
        }
        "circle_grid" => {
            let cols = g.u32(cx, F::Target::cols, 7);
            let rows = g.u32(cx, F::Target::rows, 5);
            let spacing = g.f64(cx, F::Target::spacing, Dim::Length, 0.05);
            let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.02);
            check::at_least(cx, g, F::Target::cols, cols, 1);
            check::at_least(cx, g, F::Target::rows, rows, 1);
            check::positive(cx, g, F::Target::spacing, spacing, "m");
            check::positive(cx, g, F::Target::diameter, diameter, "m");
            check::fits(cx, g, F::Target::diameter, diameter, spacing, "the spacing");
            let (cols, rows) = limit_grid(cx, g, cols, rows);
            TargetKind::CircleGrid {
                cols,
                rows,
                spacing,
                diameter,
            }
        }
        "coded" => {
            let count = g.u32(cx, F::Target::count, 12);
            let spacing = g.f64(cx, F::Target::spacing, Dim::Length, 0.1);
            let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.02);
            let first_code = g.u32(cx, F::Target::first_code, 1);
            check::at_least(cx, g, F::Target::count, count, 1);
            let count = check::capped(cx, g, F::Target::count, count, 10_000, "coded targets", 1);
            check::positive(cx, g, F::Target::spacing, spacing, "m");
            check::positive(cx, g, F::Target::diameter, diameter, "m");
            check::fits(
                cx,
                g,
                F::Target::diameter,
                diameter * 2.5,
                spacing,
                "the spacing (the code ring is 2.5 × the diameter)",
            );
            TargetKind::Coded {
                count,
                spacing,
                diameter,
                first_code,
            }
        }
        "scale_bar" => {
            let length = g.f64(cx, F::Target::length, Dim::Length, 1.0);
            let width = g.f64(cx, F::Target::width, Dim::Length, 0.04);
            let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.02);
            check::positive(cx, g, F::Target::length, length, "m");
            check::positive(cx, g, F::Target::width, width, "m");
            check::positive(cx, g, F::Target::diameter, diameter, "m");
            check::fits(cx, g, F::Target::diameter, diameter, width, "the bar width");
            TargetKind::ScaleBar {
                length,
                width,
                diameter,
            }
        }
        "siemens_star" => {
            let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.2);
            let spokes = g.u32(cx, F::Target::spokes, 16);
            check::positive(cx, g, F::Target::diameter, diameter, "m");
            check::at_least(cx, g, F::Target::spokes, spokes, 2);
            let spokes = check::capped(cx, g, F::Target::spokes, spokes, 10_000, "spokes", 16);
            TargetKind::SiemensStar { diameter, spokes }
        }
        _ => {
            let size = g.f64(cx, F::Target::size, Dim::Length, 0.5);
            let levels = g.u32(cx, F::Target::levels, 3);
            let step = g.f64(cx, F::Target::step, Dim::Length, 0.05);
            let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.02);
            check::positive(cx, g, F::Target::size, size, "m");
            check::at_least(cx, g, F::Target::levels, levels, 1);
            let levels = check::capped(cx, g, F::Target::levels, levels, 1000, "levels", 1);
            check::positive(cx, g, F::Target::step, step, "m");
            check::positive(cx, g, F::Target::diameter, diameter, "m");
            TargetKind::TestObject {
                size,
                levels: levels.max(1),
                step,
                diameter,
            }
        }
    }
}

/// `type = "points_file"` (see [`crate::scene::points_file`]): one disk target per line of `file`.
fn points_file(
    cx: &mut Cx,
    g: &mut Tab,
    name: &str,
    objects: &[Object],
    site: &Site,
    sources: &Sources,
    scene: &Path,
) -> Vec<Target> {
    let diameter = g.f64(cx, F::Target::diameter, Dim::Length, 0.1);
    check::positive(cx, g, F::Target::diameter, diameter, "m");
    let surface = g
        .choice(cx, F::Target::surface, &["given", "seabed"])
        .unwrap_or("given");
    let frame = placement(cx, g, DVec3::ZERO);
    let fspan = g.span_of(F::Target::file);
    let Some(rel) = g.opt_str(cx, F::Target::file) else {
        cx.push(
            Diagnostic::error("E0293", format!("`{}` needs a `file`", g.path))
                .label(g.span, "no `file`")
                .help("give the list of `id x y z` relative to this scene file: `file = \"gcps.txt\"`"),
        );
        return vec![];
    };
    let pts = crate::scene::points_file::read_named(cx, sources, scene, &rel, fspan);
    if pts.is_empty() || !(diameter > 0.0) {
        return vec![];
    }
    if surface == "given" {
        return crate::scene::points_file::given(name, diameter, &frame, &pts);
    }
    match crate::scene::points_file::dropped(name, diameter, &frame, &pts, objects, -site.depth) {
        Ok((disks, missed)) => {
            if !missed.is_empty() {
                cx.push(
                    Diagnostic::warning(
                        "W0292",
                        format!(
                            "{} of {} points are above no object and lie on the nominal seabed",
                            missed.len(),
                            pts.len()
                        ),
                    )
                    .label(
                        g.span_of(F::Target::surface),
                        format!("e.g. `{}`", missed[0]),
                    )
                    .help(
                        "add a seabed object under them, or use `surface = \"given\"` with their z",
                    ),
                );
            }
            disks
        }
        Err(e) => {
            cx.push(
                Diagnostic::error("E0294", "cannot drop the points onto the scene's objects")
                    .label(g.span_of(F::Target::surface), e)
                    .help("fix the objects' meshes, or use `surface = \"given\"`"),
            );
            vec![]
        }
    }
}

/// Grids of more than a million points are refused (and replaced by a small one so that
/// checking continues without allocating them).
fn limit_grid(cx: &mut Cx, g: &Tab, cols: u32, rows: u32) -> (u32, u32) {
    if cols as u64 * rows as u64 > 1_000_000 {
        cx.push(
            Diagnostic::error("E0050", format!("`{}` has too many points", g.path))
                .label(
                    g.span_of(F::Target::cols),
                    format!("{cols} × {rows} exceeds one million"),
                )
                .help("real targets have at most a few thousand points"),
        );
        return (2, 2);
    }
    (cols, rows)
}
