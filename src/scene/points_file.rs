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
//! The file: one point per line, `id x y z` in metres, separated by spaces, tabs, commas or
//! semicolons; `#` starts a comment; a first line whose coordinates are not numbers is a
//! header and is skipped. Ids are kept: the point of line `GCP7 …` in target `gcp` has the id
//! `gcp/GCP7`. Every problem names the file, line and column.

use super::diag::{Diagnostic, Span};
use super::reader::Cx;
use crate::model::{Object, Pose, Target, TargetKind, TargetPoint};
use glam::{DMat3, DQuat, DVec3};
use std::path::Path;

/// Most points one file may hold (each becomes a printed disk in every backend).
pub const MAX_POINTS: usize = 10_000;

/// One parsed line.
#[derive(Debug, Clone, PartialEq)]
pub struct FilePoint {
    pub id: String,
    pub p: DVec3,
}

/// Parse a points file's text. Errors are `(line, column, message)`, 1-based.
pub fn parse(text: &str) -> Result<Vec<FilePoint>, (usize, usize, String)> {
    let mut out: Vec<FilePoint> = Vec::new();
    let mut seen_data = false;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        // Fields with their 1-based start columns (in characters).
        let mut fields: Vec<(usize, &str)> = Vec::new();
        let mut start: Option<(usize, usize)> = None; // (byte, column)
        let mut col = 0;
        for (b, ch) in line.char_indices() {
            col += 1;
            let sep = ch.is_whitespace() || ch == ',' || ch == ';';
            match (sep, start) {
                (true, Some((s, c))) => {
                    fields.push((c, &line[s..b]));
                    start = None;
                }
                (false, None) => start = Some((b, col)),
                _ => {}
            }
        }
        if let Some((s, c)) = start {
            fields.push((c, &line[s..]));
        }
        if fields.is_empty() {
            continue;
        }
        let nums: Vec<Option<f64>> = fields
            .iter()
            .skip(1)
            .map(|(_, f)| f.parse::<f64>().ok())
            .collect();
        if !seen_data && fields.len() >= 4 && nums.iter().take(3).all(Option::is_none) {
            seen_data = true; // a header line
            continue;
        }
        seen_data = true;
        if fields.len() != 4 {
            let c = fields.get(4).map(|f| f.0).unwrap_or(fields[0].0);
            return Err((
                k + 1,
                c,
                format!("expected 4 fields `id x y z`, found {}", fields.len()),
            ));
        }
        let mut xyz = [0.0; 3];
        for (i, v) in nums.iter().enumerate() {
            let (c, f) = fields[i + 1];
            match v {
                Some(v) if v.is_finite() => xyz[i] = *v,
                _ => {
                    return Err((
                        k + 1,
                        c,
                        format!("`{f}` is not a finite number (coordinates are in metres)"),
                    ));
                }
            }
        }
        let id = fields[0].1.to_string();
        if out.iter().any(|q| q.id == id) {
            return Err((k + 1, fields[0].0, format!("the id `{id}` appears twice")));
        }
        if out.len() == MAX_POINTS {
            return Err((
                k + 1,
                1,
                format!("more than {MAX_POINTS} points (each is a printed disk)"),
            ));
        }
        out.push(FilePoint {
            id,
            p: DVec3::from_array(xyz),
        });
    }
    if out.is_empty() {
        return Err((1, 1, "the file holds no points".into()));
    }
    Ok(out)
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
                    .help("one point per line: `id x y z` in metres (spaces or commas; `#` comments; one optional header line)"),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whitespace_csv_header_and_comments() {
        let t = "# test field\nid,x,y,z\nA1, 0.5, -1.25, -10\n\nB2\t1e-1 2 -9.5  # a note\n";
        let v = parse(t).unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].id, "A1");
        assert_eq!(v[0].p, DVec3::new(0.5, -1.25, -10.0));
        assert_eq!(v[1].p, DVec3::new(0.1, 2.0, -9.5));
        // No header at all.
        assert_eq!(parse("7 1 2 3").unwrap()[0].id, "7");
    }

    #[test]
    fn errors_name_line_and_column() {
        assert_eq!(
            parse("id x y z\nA 1 2 3\nB 1 zz 3\n").unwrap_err(),
            (
                3,
                5,
                "`zz` is not a finite number (coordinates are in metres)".into()
            )
        );
        assert_eq!(parse("A 1 2 3\nA 4 5 6").unwrap_err().0, 2);
        assert_eq!(parse("A 1 2 3 4").unwrap_err().1, 9);
        assert_eq!(parse("A 1 2").unwrap_err().0, 1);
        assert!(parse("# nothing\n\n").is_err());
        assert!(parse("A 1 2 inf").is_err());
        // A header is only the first data line: a later non-numeric line is an error.
        assert_eq!(parse("A 1 2 3\nid x y z").unwrap_err().0, 2);
    }
}
