//! `poser project`: project CSV points through the camera and port.
//!
//! Reads `id,x,y,z` (header required, metres; camera or world frame), writes `id,u,v,status`
//! with status `ok` or the reason there is no pixel (`behind_camera`, `inside_glass`, …; for
//! `off_sensor` the pixel is still written). Pixel centres at +0.5 (COLMAP's
//! convention; OpenCV's = this − 0.5).
use super::{CliError, FrameArg, SceneArgs, load_model};
use crate::optics::project::Projector;
use crate::truth::csv_field;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Split one CSV line into fields (RFC 4180 quotes).
fn split_csv(line: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut was_quoted = false;
    while let Some(c) = chars.next() {
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    cur.push('"');
                    chars.next();
                } else {
                    quoted = false;
                }
            } else {
                cur.push(c);
            }
        } else if c == '"' && cur.trim().is_empty() {
            quoted = true;
            was_quoted = true;
            cur.clear();
        } else if c == ',' {
            out.push(if was_quoted {
                std::mem::take(&mut cur)
            } else {
                cur.trim().to_string()
            });
            cur.clear();
            was_quoted = false;
        } else {
            cur.push(c);
        }
    }
    if quoted {
        return Err("unterminated quoted field".into());
    }
    out.push(if was_quoted {
        cur
    } else {
        cur.trim().to_string()
    });
    Ok(out)
}

/// Parse the points file: `(id, point)` per data row.
pub fn parse_points(text: &str, file: &str) -> Result<Vec<(String, DVec3)>, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((hl, header)) = lines.next() else {
        return Err(format!(
            "{file}: empty file\nhelp: the first line must be the header `id,x,y,z`"
        ));
    };
    let cols: Vec<String> = split_csv(header.trim_start_matches('\u{feff}'))
        .map_err(|e| format!("{file}:{}: {e}", hl + 1))?
        .iter()
        .map(|c| c.to_ascii_lowercase())
        .collect();
    let find = |name: &str| cols.iter().position(|c| c == name);
    let (Some(ci), Some(cx), Some(cy), Some(cz)) = (find("id"), find("x"), find("y"), find("z"))
    else {
        return Err(format!(
            "{file}:{}: header `{}` lacks one of the columns id, x, y, z\nhelp: the first line must be `id,x,y,z` (metres)",
            hl + 1,
            header.trim()
        ));
    };
    let mut out = Vec::new();
    for (i, line) in lines {
        let f = split_csv(line).map_err(|e| format!("{file}:{}: {e}", i + 1))?;
        let get = |k: usize, what: &str| -> Result<f64, String> {
            let s = f
                .get(k)
                .ok_or_else(|| format!("{file}:{}: missing column `{what}`", i + 1))?;
            let v: f64 = s.parse().map_err(|_| {
                format!("{file}:{}: `{s}` is not a number (column `{what}`)", i + 1)
            })?;
            if !v.is_finite() {
                return Err(format!(
                    "{file}:{}: `{s}` is not a finite number (column `{what}`)",
                    i + 1
                ));
            }
            Ok(v)
        };
        let id = f
            .get(ci)
            .cloned()
            .ok_or_else(|| format!("{file}:{}: missing column `id`", i + 1))?;
        out.push((id, DVec3::new(get(cx, "x")?, get(cy, "y")?, get(cz, "z")?)));
    }
    Ok(out)
}

/// Parse a channel name (`r`, `g`, `b`, or `0`, `1`, `2`).
pub fn parse_channel(s: &str) -> Result<usize, String> {
    match s.to_ascii_lowercase().as_str() {
        "r" | "red" | "0" => Ok(0),
        "g" | "green" | "1" => Ok(1),
        "b" | "blue" | "2" => Ok(2),
        _ => Err(format!("--channel `{s}`: expected r, g or b")),
    }
}

/// Project every point; returns the CSV text.
pub fn project_csv(p: &Projector, pts: &[(String, DVec3)], world_pose: Option<usize>) -> String {
    let mut out = String::from("id,u,v,status\n");
    let xs: Vec<DVec3> = pts.iter().map(|(_, x)| *x).collect();
    let px = p.project_points(&xs, world_pose);
    for ((id, _), r) in pts.iter().zip(px) {
        let _ = match r {
            Ok(px) if p.on_sensor(px) => writeln!(out, "{},{},{},ok", csv_field(id), px[0], px[1]),
            Ok(px) => writeln!(out, "{},{},{},off_sensor", csv_field(id), px[0], px[1]),
            Err(e) => writeln!(out, "{},,,{}", csv_field(id), e),
        };
    }
    out
}

/// The arguments of `poser project`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// CSV file with header `id,x,y,z` (metres).
    #[arg(long)]
    pub points: PathBuf,
    /// Camera of the rig (default: the first).
    #[arg(long)]
    pub camera: Option<String>,
    /// Frame of the input points.
    #[arg(long, value_enum, default_value = "camera")]
    pub frame: FrameArg,
    /// Rig pose index for `--frame world` (default 0).
    #[arg(long, default_value_t = 0)]
    pub pose: usize,
    /// Colour channel: r, g or b (default g).
    #[arg(long, default_value = "g")]
    pub channel: String,
    /// Output CSV (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let (scene, points, camera, frame, pose, channel, output) = (
        &args.scene,
        &args.points,
        args.camera.as_deref(),
        args.frame,
        args.pose,
        &args.channel,
        args.output.as_deref(),
    );
    let ch = parse_channel(channel).map_err(CliError::Usage)?;
    let text = std::fs::read_to_string(points)
        .map_err(|e| CliError::Failed(format!("{}: {e}", points.display())))?;
    let pts = parse_points(&text, &points.display().to_string()).map_err(CliError::Failed)?;
    let model = load_model(scene)?;
    let cam = match camera {
        None => 0,
        Some(name) => model
            .camera_index(name)
            .map_err(|e| CliError::Usage(format!("--{e}")))?,
    };
    let world_pose = match frame {
        FrameArg::Camera => None,
        FrameArg::World => {
            if pose >= model.poses.len() {
                return Err(CliError::Usage(format!(
                    "--pose {pose} is out of range (the network has {} poses)",
                    model.poses.len()
                )));
            }
            Some(pose)
        }
    };
    if world_pose.is_some_and(|pi| model.above_surface(pi, cam)) {
        return Err(CliError::Failed(format!(
            "camera `{}` is above the sea surface at pose {pose}: `poser project` projects \
             through the port only\n  help: `poser truth` projects the scene's targets through \
             the surface",
            model.cameras[cam].name
        )));
    }
    let p = Projector::new(&model, cam, ch).map_err(CliError::Failed)?;
    let csv = project_csv(&p, &pts, world_pose);
    match output {
        Some(path) => crate::io::write_atomic(path, csv.as_bytes())
            .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?,
        None => print!("{csv}"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_parsing_reports_line_numbers() {
        let pts = parse_points("id,x,y,z\n\"a,1\",1,2,3\nb, 4 ,5,6\n", "f.csv").unwrap();
        assert_eq!(pts[0].0, "a,1");
        assert_eq!(pts[1].1, DVec3::new(4.0, 5.0, 6.0));
        let e = parse_points("id,x,y,z\na,1,2\n", "f.csv").unwrap_err();
        assert!(e.starts_with("f.csv:2:"), "{e}");
        let e = parse_points("id,x,y,z\na,1,zz,3\n", "f.csv").unwrap_err();
        assert!(e.contains("`zz` is not a number"), "{e}");
        assert!(
            parse_points("name,x,y\n", "f.csv")
                .unwrap_err()
                .contains("help:")
        );
        assert!(parse_points("id,x,y,z\na,NaN,1,1\n", "f.csv").is_err());
        // Column order is taken from the header.
        let p = parse_points("z,y,x,id\n3,2,1,p\n", "f.csv").unwrap();
        assert_eq!(p[0], ("p".into(), DVec3::new(1.0, 2.0, 3.0)));
    }

    #[test]
    fn channels() {
        assert_eq!(parse_channel("R"), Ok(0));
        assert_eq!(parse_channel("b"), Ok(2));
        assert!(parse_channel("x").is_err());
    }
}
