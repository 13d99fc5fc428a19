//! Exact ground truth: where every target lands in every image, intrinsics, poses, COLMAP export.
//!
//! [`write`] produces, in one directory:
//!
//! | file | contents |
//! |---|---|
//! | `truth.json` | everything below in one document: cameras (intrinsics, lens, distortion, port with per-channel indices), images (pose, `world_from_camera` and `camera_from_world`), and per image the target points in view |
//! | `points.csv` | `image,camera,pose,target,id,u,v,u_r,v_r,u_b,v_b,x,y,z,x_cam,y_cam,z_cam` — one row per visible target point; (u, v) is the G channel, pixel centres at +0.5 (COLMAP's convention; OpenCV's is this − 0.5, see `opencv/`) |
//! | `cameras.csv` | one row per camera: intrinsics, lens, distortion, port |
//! | `images.csv` | one row per image: `world_from_camera` as quaternion (w, x, y, z) + translation |
//! | `colmap/…`, `colmap_refractive/…` | COLMAP models (text and binary) of the true poses and the visible target points, without and with the port ([`colmap`]) |
//! | `opencv/…` | `cv::FileStorage` calibration files and the observations in OpenCV's pixel convention ([`opencv`]) |
//! | `markers/…` | the observations as marker files (`marker,image,x,y`) and the target points as a GCP reference (`label,x,y,z`) for outside photogrammetry software ([`markers`]) |
//!
//! Pixel convention: poser's, which is COLMAP's — the top-left pixel's centre is at (0.5,
//! 0.5). OpenCV's pixel centres are at integers; only the files under `opencv/` use it.
//!
//! A point is *in view* when its exact refractive projection (G channel) lands on the sensor,
//! the camera is on the printed side of its target, and nothing in the scene (objects,
//! targets; [`crate::geometry::Bvh::occluded`]) blocks the water path from the point to
//! where its ray leaves the port.

pub mod colmap;
pub mod markers;
pub mod opencv;

use crate::geometry::Bvh;
use crate::io::write_atomic;
use crate::model::{Camera, LensModel, Model, Port, Pose};
use crate::optics::NoSolution;
use crate::optics::project::Projector;
use crate::optics::surface::SeaInterface;
use glam::{DMat3, DQuat, DVec3};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// One target point seen in one image.
#[derive(Debug, Clone, Serialize)]
pub struct Observation {
    pub target: String,
    pub id: String,
    /// Pixel (G channel).
    pub u: f64,
    pub v: f64,
    /// Pixel per channel `[R, G, B]` (`null` where that channel has no pixel on the sensor).
    pub uv_rgb: [Option<[f64; 2]>; 3],
    pub world: DVec3,
    pub camera: DVec3,
}

/// One image of the network.
#[derive(Debug, Clone, Serialize)]
pub struct ImageTruth {
    pub name: String,
    pub camera: String,
    pub camera_index: usize,
    pub pose_index: usize,
    /// `world_from_camera` rotation, row-major, and translation (camera centre).
    pub world_from_camera: PoseJson,
    pub camera_from_world: PoseJson,
    pub points: Vec<Observation>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PoseJson {
    pub rotation: [[f64; 3]; 3],
    pub translation: [f64; 3],
    /// Quaternion (w, x, y, z), w ≥ 0.
    pub quaternion: [f64; 4],
}

#[derive(Debug, Clone, Serialize)]
pub struct CameraTruth {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub lens: LensModel,
    pub distortion: crate::model::Distortion,
    pub port: Port,
    /// Indices `[R, G, B]` of the camera-side medium, port glass and water.
    pub ior_air: [f64; 3],
    pub ior_glass: Option<[f64; 3]>,
    pub ior_water: [f64; 3],
    pub rig_from_camera: PoseJson,
}

#[derive(Debug, Clone, Serialize)]
pub struct Truth {
    pub scene: String,
    pub conventions: &'static str,
    pub cameras: Vec<CameraTruth>,
    pub images: Vec<ImageTruth>,
}

fn quat_wxyz(r: DMat3) -> [f64; 4] {
    let q = DQuat::from_mat3(&r).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    // `+ 0.0` turns −0 into 0 so files do not show "-0".
    [q.w + 0.0, q.x + 0.0, q.y + 0.0, q.z + 0.0]
}

fn pose_json(p: &Pose) -> PoseJson {
    let r = p.rotation;
    PoseJson {
        rotation: [0, 1, 2].map(|i| [r.x_axis[i], r.y_axis[i], r.z_axis[i]]),
        translation: (p.translation + DVec3::ZERO).to_array(),
        quaternion: quat_wxyz(r),
    }
}

/// Whether a target point at `world` (its printed face's normal `normal`), projected to `uv`
/// in image `pose` of `proj`, is seen: the camera on its printed side, and nothing in
/// `occluded(point, end)` blocking the water path from it to where its ray leaves the port
/// (or, from the air, enters the water through `through`).
pub fn unobstructed(
    proj: &Projector,
    through: Option<&SeaInterface>,
    pose: usize,
    world: DVec3,
    normal: DVec3,
    uv: [f64; 2],
    occluded: impl Fn(DVec3, DVec3) -> bool,
) -> bool {
    let Ok((exit, d, _)) = proj.pixel_ray_world(pose, uv[0], uv[1]) else {
        return false;
    };
    let exit = match through {
        Some(iface) => match iface.refract_down(exit, d) {
            Ok((s, _, _)) => s,
            Err(_) => return false,
        },
        None => exit,
    };
    (exit - world).dot(normal) > 0.0 && !occluded(world, exit)
}

/// Compute the ground truth of every image (occlusion against the model's scene geometry).
pub fn compute(model: &Model) -> Result<Truth, String> {
    compute_in(model, &Bvh::of_model(model)?)
}

/// [`compute`] with the model's scene geometry already built.
pub fn compute_in(model: &Model, scene: &Bvh) -> Result<Truth, String> {
    compute_with(model, |a, b| scene.occluded(a, b))
}

/// Compute with a caller-supplied occlusion test `occluded(point, port_exit)` (world frame).
pub fn compute_with(
    model: &Model,
    occluded: impl Fn(DVec3, DVec3) -> bool,
) -> Result<Truth, String> {
    let mut cameras = Vec::new();
    let mut projectors = Vec::new();
    for (ci, cam) in model.cameras.iter().enumerate() {
        let pr: Vec<Projector> = (0..3)
            .map(|ch| model.projector(ci, ch))
            .collect::<Result<_, _>>()?;
        projectors.push(pr);
        cameras.push(camera_truth(cam, model.ambient_ior()));
    }
    let mut images = Vec::new();
    for pi in 0..model.poses.len() {
        for (ci, cam) in model.cameras.iter().enumerate() {
            let pr = &projectors[ci];
            let wfc = model.world_from_camera(pi, ci);
            let cfw = wfc.inverse();
            // Every target point through each channel's batch solver (the same pixels as
            // `project_world` point by point).
            let in_camera: Vec<DVec3> = model
                .targets
                .iter()
                .flat_map(|t| {
                    t.points
                        .iter()
                        .map(|tp| pr[1].world_to_camera(pi, tp.world))
                })
                .collect();
            // A camera above the water sees each point through the sea surface.
            let through: Option<Vec<SeaInterface>> = model
                .above_surface(pi, ci)
                .then(|| (0..3).filter_map(|ch| model.sea_interface(ch)).collect());
            let uv_all: Vec<Vec<Result<[f64; 2], NoSolution>>> = match &through {
                None => pr
                    .iter()
                    .map(|p| {
                        let mut out = vec![Err(NoSolution::NoConvergence); in_camera.len()];
                        p.project_camera_many(&in_camera, &mut out);
                        out
                    })
                    .collect(),
                Some(ifaces) => pr
                    .iter()
                    .zip(ifaces)
                    .map(|(p, iface)| {
                        let world = model
                            .targets
                            .iter()
                            .flat_map(|t| t.points.iter().map(|tp| tp.world));
                        world
                            .map(|w| crate::optics::surface::project_through(p, iface, pi, w))
                            .collect()
                    })
                    .collect(),
            };
            let mut k = 0;
            let mut points = Vec::new();
            for target in &model.targets {
                let normal = target.pose.rotation.z_axis;
                for tp in &target.points {
                    let i = k;
                    k += 1;
                    let Ok(uv) = uv_all[1][i] else {
                        continue;
                    };
                    let through = through.as_ref().map(|i| &i[1]);
                    if !unobstructed(&pr[1], through, pi, tp.world, normal, uv, &occluded) {
                        continue;
                    }
                    let uv_rgb = [0, 1, 2].map(|ch| uv_all[ch][i].ok());
                    points.push(Observation {
                        target: target.name.clone(),
                        id: tp.id.clone(),
                        u: uv[0],
                        v: uv[1],
                        uv_rgb,
                        world: tp.world,
                        camera: cfw.transform_point(tp.world),
                    });
                }
            }
            images.push(ImageTruth {
                name: model.image_name(pi, ci),
                camera: cam.name.clone(),
                camera_index: ci,
                pose_index: pi,
                world_from_camera: pose_json(&wfc),
                camera_from_world: pose_json(&cfw),
                points,
            });
        }
    }
    Ok(Truth {
        scene: model.name.clone(),
        conventions: "world z up, metres; camera frame x right, y down, z forward (OpenCV's and COLMAP's), origin at the entrance pupil; pixel centres at +0.5 (COLMAP's convention; OpenCV's = this - 0.5); (u, v) = G channel (550 nm)",
        cameras,
        images,
    })
}

/// One camera's exact intrinsics, lens, port and indices as the truth files give them
/// (`water`: the ambient indices per channel).
pub fn camera_truth(cam: &Camera, water: [f64; 3]) -> CameraTruth {
    CameraTruth {
        name: cam.name.clone(),
        width: cam.width,
        height: cam.height,
        fx: cam.fx,
        fy: cam.fy,
        cx: cam.cx,
        cy: cam.cy,
        lens: cam.lens,
        distortion: cam.distortion,
        port: cam.port.clone(),
        ior_air: [1.0; 3],
        ior_glass: cam.port.glass().map(|g| g.ior),
        ior_water: water,
        rig_from_camera: pose_json(&cam.rig_from_camera),
    }
}

/// Quote a CSV field when needed (RFC 4180).
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt(x: Option<[f64; 2]>, i: usize) -> String {
    x.map(|p| p[i].to_string()).unwrap_or_default()
}

/// Render the truth files as (relative path, bytes), in a fixed order.
pub fn files(model: &Model, truth: &Truth) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut out = Vec::new();
    let json = serde_json::to_string_pretty(truth).map_err(|e| e.to_string())?;
    out.push(("truth.json".to_string(), json.into_bytes()));

    let mut pts =
        String::from("image,camera,pose,target,id,u,v,u_r,v_r,u_b,v_b,x,y,z,x_cam,y_cam,z_cam\n");
    for im in &truth.images {
        for o in &im.points {
            let _ = writeln!(
                pts,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&im.name),
                csv_field(&im.camera),
                im.pose_index,
                csv_field(&o.target),
                csv_field(&o.id),
                o.u,
                o.v,
                opt(o.uv_rgb[0], 0),
                opt(o.uv_rgb[0], 1),
                opt(o.uv_rgb[2], 0),
                opt(o.uv_rgb[2], 1),
                o.world.x,
                o.world.y,
                o.world.z,
                o.camera.x,
                o.camera.y,
                o.camera.z
            );
        }
    }
    out.push(("points.csv".into(), pts.into_bytes()));

    let mut cams = String::from(
        "camera,width,height,fx,fy,cx,cy,lens,k1,k2,k3,p1,p2,port,port_params,glass,n_glass_r,n_glass_g,n_glass_b,n_water_r,n_water_g,n_water_b\n",
    );
    for c in &truth.cameras {
        let d = c.distortion;
        let g = c.ior_glass.unwrap_or([f64::NAN; 3]);
        let gs = |i: usize| {
            if c.ior_glass.is_some() {
                g[i].to_string()
            } else {
                String::new()
            }
        };
        let _ = writeln!(
            cams,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            csv_field(&c.name),
            c.width,
            c.height,
            c.fx,
            c.fy,
            c.cx,
            c.cy,
            lens_name(c.lens),
            d.k1,
            d.k2,
            d.k3,
            d.p1,
            d.p2,
            c.port.kind_name(),
            port_params(&c.port)
                .iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(" "),
            csv_field(c.port.glass().map(|g| g.name.as_str()).unwrap_or("")),
            gs(0),
            gs(1),
            gs(2),
            c.ior_water[0],
            c.ior_water[1],
            c.ior_water[2]
        );
    }
    out.push(("cameras.csv".into(), cams.into_bytes()));

    let mut ims = String::from("image,camera,pose,qw,qx,qy,qz,tx,ty,tz,points\n");
    for im in &truth.images {
        let p = &im.world_from_camera;
        let _ = writeln!(
            ims,
            "{},{},{},{},{},{},{},{},{},{},{}",
            csv_field(&im.name),
            csv_field(&im.camera),
            im.pose_index,
            p.quaternion[0],
            p.quaternion[1],
            p.quaternion[2],
            p.quaternion[3],
            p.translation[0],
            p.translation[1],
            p.translation[2],
            im.points.len()
        );
    }
    out.push(("images.csv".into(), ims.into_bytes()));

    out.extend(colmap::files(model, truth));
    out.extend(opencv::files(truth));
    out.extend(markers::files(model, truth));
    Ok(out)
}

fn lens_name(l: LensModel) -> &'static str {
    match l {
        LensModel::Rectilinear => "rectilinear",
        LensModel::FisheyeEquidistant => "fisheye_equidistant",
        LensModel::FisheyeEquisolid => "fisheye_equisolid",
    }
}

/// Port geometry in Refractive COLMAP's order (without the indices).
fn port_params(p: &Port) -> Vec<f64> {
    match p {
        Port::None => vec![],
        Port::Flat {
            normal,
            distance,
            thickness,
            ..
        } => {
            vec![normal.x, normal.y, normal.z, *distance, *thickness]
        }
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => {
            vec![center.x, center.y, center.z, *inner_radius, *thickness]
        }
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => vec![
            axis_point.x,
            axis_point.y,
            axis_point.z,
            axis.x,
            axis.y,
            axis.z,
            *inner_radius,
            *thickness,
        ],
    }
}

/// Compute the ground truth of `model` and write it into `dir` (see the module table). Every
/// file is written atomically; nothing is written if the computation fails.
pub fn write(model: &Model, dir: &Path) -> Result<(), String> {
    write_truth(model, &compute(model)?, dir)
}

/// [`write`] with the model's geometry ([`Bvh::of_model`]) already built by the caller.
pub fn write_in(model: &Model, scene: &Bvh, dir: &Path) -> Result<(), String> {
    write_truth(model, &compute_in(model, scene)?, dir)
}

fn write_truth(model: &Model, truth: &Truth, dir: &Path) -> Result<(), String> {
    let files = files(model, truth)?;
    for (rel, bytes) in files {
        let path = dir.join(&rel);
        write_atomic(&path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}
