//! `poser project`: project CSV points through the camera and port.
//!
//! Reads a point list, `id x y z` in metres (camera or world frame; [`crate::points`], the
//! same parser as a `points_file` target: CSV with a header naming the columns, or a published
//! GCP list separated by blanks, commas or semicolons), writes `id,u,v,status`
//! with status `ok` or the reason there is no pixel (`behind_camera`, `inside_glass`, …; for
//! `off_sensor` the pixel is still written). Pixel centres at +0.5 (COLMAP's
//! convention; OpenCV's = this − 0.5).
use super::{CliError, FrameArg, SceneArgs, load_model};
use crate::optics::project::Projector;
use crate::optics::project::parse_channel;
use crate::points::parse_points;
use crate::truth::csv_field;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::PathBuf;

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
    /// Point list: `id x y z` in metres per line (CSV with a header `id,x,y,z` in any order,
    /// or blanks, commas or semicolons; `#` comments).
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
    let p = model.projector(cam, ch).map_err(CliError::Failed)?;
    let csv = project_csv(&p, &pts, world_pose);
    match output {
        Some(path) => crate::io::write_atomic(path, csv.as_bytes())
            .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?,
        None => print!("{csv}"),
    }
    Ok(())
}
