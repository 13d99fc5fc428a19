//! Targets from a points file (`[[targets]] type = "points_file"`): a laboratory's test field
//! or a GCP layout, as published (`id x y z` per line), printed as one disk per point.
//!
//! | key | meaning |
//! |---|---|
//! | `file` | the list, relative to the scene file, inside the scene's folder |
//! | `diameter` | disk diameter (each disk is printed black on a white plate twice as wide) |
//! | `surface` | `"given"`: at the file's coordinates, facing the target's +z; `"seabed"`: dropped straight down onto the scene's objects, facing the surface it lands on |
//! | `position`, `rotation`, `look_at` | the file's frame in the world |
//!
//! The file: one point per line, `id x y z` in metres, read by the one point-list parser
//! ([`crate::points`], the same as `poser project --points`): separated by commas, semicolons,
//! spaces or tabs; `#` starts a comment; an optional header line. Ids are kept and unique:
//! the point of line `GCP7 …` in target `gcp` has the id `gcp/GCP7`. Every problem names the
//! file, line and column.

use super::diag::{Diagnostic, Span};
use super::reader::Cx;
use crate::model::{Object, Pose, Target, TargetKind, TargetPoint};
use glam::{DMat3, DQuat, DVec3};
use std::path::Path;

/// Most points one file may hold (each becomes a printed disk in every backend).
pub const MAX_POINTS: usize = 10_000;

/// One point of the file (the shared point-list parser's [`crate::points::Point`]).
pub type FilePoint = crate::points::Point;

/// Parse a points file's text ([`crate::points::parse`]), refusing what a target list may not
/// hold: no point, the same id twice, more than [`MAX_POINTS`]. Errors are `(line, column,
/// message)`, 1-based.
pub fn parse(text: &str) -> Result<Vec<FilePoint>, (usize, usize, String)> {
    let out = crate::points::parse(text).map_err(|e| (e.line, e.col, e.message))?;
    for (i, q) in out.iter().enumerate() {
        if i == MAX_POINTS {
            return Err((
                q.line,
                1,
                format!("more than {MAX_POINTS} points (each is a printed disk)"),
            ));
        }
        if out[..i].iter().any(|o| o.id == q.id) {
            return Err((q.line, q.col, format!("the id `{}` appears twice", q.id)));
        }
    }
    if out.is_empty() {
        return Err((1, 1, "the file holds no points".into()));
    }
    Ok(out)
}

/// Read the points file `rel` that a scene key names (`span`: the key's value): relative to
/// the file holding the key, refused outside the scene's folder, read and parsed ([`read`]),
/// and recorded among the files the scene was read from. Empty on any problem (diagnosed).
pub fn read_named(
    cx: &mut Cx,
    sources: &super::source::Sources,
    scene: &Path,
    rel: &str,
    span: Span,
) -> Vec<FilePoint> {
    let dir = sources
        .dir_of(span.file)
        .unwrap_or_else(|| scene.parent().map(Path::to_path_buf).unwrap_or_default());
    let file = dir.join(rel);
    if let Some(why) = super::source::outside_root(sources, rel, &file) {
        cx.push(super::source::outside_diag(rel, &why, span));
        return vec![];
    }
    let pts = read(cx, &file, span);
    if !pts.is_empty() {
        cx.files.push(file);
    }
    pts
}

/// Read and parse `path`; problems become one diagnostic on the `file` key (`span`), naming
/// the file, line and column.
pub fn read(cx: &mut Cx, path: &Path, span: Span) -> Vec<FilePoint> {
    let shown = super::source::display(path);
    // Read the front end's one way: a regular file, at most 16 MiB (10 000 points are far
    // less), never a device or a named pipe.
    let text = match super::source::read_capped(path, super::source::MAX_SCENE_BYTES) {
        Ok(b) => match super::source::not_text(&b) {
            None => String::from_utf8(b).expect("checked by not_text"),
            Some((at, _)) => {
                let line = 1 + b[..at].iter().filter(|&&c| c == b'\n').count();
                let col = 1 + at
                    - b[..at]
                        .iter()
                        .rposition(|&c| c == b'\n')
                        .map_or(0, |i| i + 1);
                cx.push(
                    Diagnostic::error("E0293", format!("`{shown}` is not a text file"))
                        .label(span, format!("a NUL or non-UTF-8 byte at {shown}:{line}:{col}"))
                        .help("a points file is UTF-8 text, one `id x y z` per line: check that `file` names it and not an image or other binary file"),
                );
                return vec![];
            }
        },
        Err(r) => {
            let help = match r {
                super::source::Refusal::Unreadable(_) => {
                    "give the file relative to this scene file, e.g. `file = \"gcps.txt\"`"
                }
                _ => {
                    "a points file is a regular text file of at most 16 MiB; folders, devices and named pipes are never read"
                }
            };
            cx.push(
                Diagnostic::error("E0293", format!("cannot read the points file `{shown}`"))
                    .label(span, r.reason())
                    .help(help),
            );
            return vec![];
        }
    };
    match parse(&text) {
        Ok(v) => v,
        Err((line, col, msg)) => {
            cx.push(
                Diagnostic::error("E0294", format!("{shown}:{line}:{col}: {msg}"))
                    .label(span, "in this points file")
                    .help(crate::points::HELP),
            );
            vec![]
        }
    }
}

/// The disks of a `given` points file: at `frame · p`, facing the frame's +z.
pub fn given(name: &str, diameter: f64, frame: &Pose, pts: &[FilePoint]) -> Vec<Target> {
    pts.iter()
        .map(|q| {
            disk(
                name,
                &q.id,
                diameter,
                Pose {
                    rotation: frame.rotation,
                    translation: frame.transform_point(q.p),
                },
            )
        })
        .collect()
}

/// Height above the surface at which a dropped disk is printed (it would otherwise share its
/// plane with the surface and flicker between the two in every renderer).
pub const LIFT: f64 = 1e-3;

/// The disks of a `seabed` points file: each point `frame · p` dropped straight down (along
/// −z) onto the highest object below it, facing that surface (its normal turned upwards),
/// [`LIFT`] above it. Points above no object land on the nominal seabed `z = seabed_z`,
/// facing up; their ids are returned second.
pub fn dropped(
    name: &str,
    diameter: f64,
    frame: &Pose,
    pts: &[FilePoint],
    objects: &[Object],
    seabed_z: f64,
) -> Result<(Vec<Target>, Vec<String>), String> {
    use crate::geometry::{Bvh, Ray, SurfaceId};
    let meshes = objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            crate::geometry::mesh::object_mesh(o, Path::new("."))
                .map(|m| (SurfaceId::Object(i as u32), m))
        })
        .collect::<Result<Vec<_>, String>>()?;
    let bvh = Bvh::from_meshes(meshes);
    let top = bvh
        .bounds()
        .map(|(_, hi)| hi.z)
        .unwrap_or(seabed_z)
        .max(seabed_z)
        + 1.0;
    let mut missed = Vec::new();
    let mut out = Vec::new();
    for q in pts {
        let w = frame.transform_point(q.p);
        let ray = Ray {
            origin: DVec3::new(w.x, w.y, top),
            dir: DVec3::NEG_Z,
        };
        let (point, normal) = match bvh.intersect(&ray, f64::INFINITY) {
            Some(h) => {
                let n = if h.normal.z < 0.0 {
                    -h.normal
                } else {
                    h.normal
                };
                (h.point, n)
            }
            None => {
                missed.push(q.id.clone());
                (DVec3::new(w.x, w.y, seabed_z), DVec3::Z)
            }
        };
        // Turn +z onto the normal, keeping the frame's heading as far as possible.
        let rotation = DMat3::from_quat(DQuat::from_rotation_arc(DVec3::Z, normal))
            * DMat3::from_rotation_z(heading(&frame.rotation));
        out.push(disk(
            name,
            &q.id,
            diameter,
            Pose {
                rotation,
                translation: point + normal * LIFT,
            },
        ));
    }
    Ok((out, missed))
}

/// Rotation of a frame's x axis about the world z axis, rad.
fn heading(r: &DMat3) -> f64 {
    r.x_axis.y.atan2(r.x_axis.x)
}

fn disk(name: &str, id: &str, diameter: f64, pose: Pose) -> Target {
    let kind = TargetKind::Disk { diameter };
    let tname = format!("{name}/{id}");
    Target {
        points: vec![TargetPoint {
            id: tname.clone(),
            world: pose.translation,
        }],
        name: tname,
        kind,
        pose,
    }
}
