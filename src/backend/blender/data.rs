//! The scene description handed to the Python builder (`poser-blender/1`): the resolved model
//! reduced to what Blender needs, as plain JSON data, plus the assets it refers to.
//!
//! | key | content |
//! |---|---|
//! | `format` | `"poser-blender/1"` |
//! | `name`, `description` | the scenario's (data only) |
//! | `render` | `samples`, `seed`, `max_bounces`, `exposure`, `outputs` |
//! | `reference_channel` | channel whose indices a single RGB pass uses (1 = G, 550 nm) |
//! | `per_channel_passes` | one pass per channel with that channel's indices (dispersion) |
//! | `cameras[]` | `name`, `width`, `height`, `lens`, `fx`, `fy`, `cx`, `cy`, `focus_distance`, `f_number`, `focal_length` (m; thin-lens aperture radius = focal_length / 2N), `distortion` (`k1`, `k2`, `k3`, `p1`, `p2`), `r2_max` (lens field, `null`: unbounded), `rig_from_camera` (4×4), `port` (camera frame, as in the model), `housing` (`shell`, `inner`: PLY asset paths, [`super::housing`]; `null` without a port) |
//! | `poses[]` | `name`, `world_from_rig` (4×4), `images` (one name per camera), `time`, `seeds` (one Cycles seed per camera, [`cycles_seed`]) |
//! | `water` | the model's water (indices, σa, σs per channel, phase, extent) or `null` |
//! | `surface` | the sea surface (`none`, `flat`, `waves`) |
//! | `wave_field` | with `waves`: the native backend's height field ([`crate::optics::waves::WaveField`], same seed): `period`, `significant_height`, `components[]` = `[kx, ky, amplitude, phase]`; `null` otherwise |
//! | `bounds` | world box holding everything, with a margin: the extent of scene-filling water |
//! | `sun` | `direction` (propagation), `irradiance` (W/m² normal to it), `in_water`, `angle`, `caustics` |
//! | `lights[]` | `name`, `mount`, `type` + the model's parameters; poses as 4×4 |
//! | `objects[]` | `name`, `shape` (primitive or `{type: ply, path}`; baked objects: `{type: ply, path, texture}`, the PLY with `s`, `t` and the PNG of linear albedo; glass spheres and cylinders: `{type: shaded_ply, path}`, the PLY of [`super::housing`]'s layout with the shape's normals), `scale`, `matrix` (world, scale included), `material` |
//! | `targets[]` | printed targets: `name`, `texture` (PNG path), `width`, `height`, `origin`, `matrix`; 3D test objects: `name`, `kind` = `"test_object"`, `steps[]` (`size`, `center`: boxes in the target frame), `disks[]` (`id`, `center`, `radius`), `white`, `black` (reflectances), `matrix` |
//!
//! Matrices are row-major 4×4 nested arrays.

use crate::model::{LightKind, Model, Pose, SeaSurface, Shape, TargetKind};
use glam::{DMat4, DVec3};
use serde_json::{Value, json};

/// Format tag checked by the Python builder.
pub const FORMAT: &str = "poser-blender/1";

/// Longitude segments of a glass sphere's or cylinder's mesh for Cycles (a sphere's latitude
/// rings: half of it): as fine as a dome port's glass ([`crate::optics::port::housing_shell`]).
const GLASS_SPHERE_SEGMENTS: u32 = 384;

/// Angular diameter of the sun, rad (used only when the sun shines through a wavy surface).
const SUN_ANGLE: f64 = 0.00935;

/// The Cycles seed of image (`pose`, `camera`): a SplitMix64 hash of the scene seed and the
/// image's indices, in Cycles' range [0, 2³¹). Every image gets its own noise pattern (one seed
/// for all poses would repeat the same pattern in every image, correlated noise that feature
/// matching can lock onto); the same scene gives the same seeds.
pub fn cycles_seed(scene_seed: u64, pose: usize, camera: usize) -> u32 {
    use crate::rng::SplitMix64;
    let mut h = SplitMix64(scene_seed ^ 0xC1C1_E5EE_D000_0000).next_u64();
    h = SplitMix64(h ^ pose as u64).next_u64();
    h = SplitMix64(h ^ ((camera as u64) << 32)).next_u64();
    (h >> 33) as u32
}

/// A glass sphere or cylinder (object frame, scale not applied) as a [`TaggedMesh`] with the
/// exact normals: the sphere as [`GLASS_SPHERE_SEGMENTS`] × half as many facets, the cylinder
/// as as many side quads with radial normals and two flat caps (their own vertices, normals
/// along the axis). Other shapes: empty.
fn glass_solid_mesh(shape: &Shape) -> crate::optics::port::TaggedMesh {
    use crate::optics::port::{Face, TaggedMesh};
    let mut m = TaggedMesh {
        normals: Some(Vec::new()),
        ..TaggedMesh::default()
    };
    match *shape {
        Shape::Sphere { radius } => {
            let mesh = crate::geometry::mesh::sphere(radius, GLASS_SPHERE_SEGMENTS);
            m.normals = Some(mesh.positions.iter().map(|p| p.normalize()).collect());
            m.faces = mesh.triangles.iter().map(|t| t.to_vec()).collect();
            m.positions = mesh.positions;
        }
        Shape::Cylinder { radius, height } => {
            let (seg, hz) = (GLASS_SPHERE_SEGMENTS, 0.5 * height);
            let ring = |z: f64| {
                (0..seg).map(move |j| {
                    let phi = std::f64::consts::TAU * j as f64 / seg as f64;
                    DVec3::new(radius * phi.cos(), radius * phi.sin(), z)
                })
            };
            let mut normals = Vec::new();
            // The side: two rings, radial normals.
            for z in [-hz, hz] {
                for p in ring(z) {
                    m.positions.push(p);
                    normals.push(DVec3::new(p.x, p.y, 0.0) / radius);
                }
            }
            for j in 0..seg {
                let k = (j + 1) % seg;
                m.faces.push(vec![j, k, seg + k, seg + j]);
            }
            // The caps: their own rings and centres, normals along the axis.
            for (side, z) in [(-1.0, -hz), (1.0, hz)] {
                let base = m.positions.len() as u32;
                m.positions.push(DVec3::new(0.0, 0.0, z));
                m.positions.extend(ring(z));
                normals.extend(std::iter::repeat_n(
                    DVec3::new(0.0, 0.0, side),
                    seg as usize + 1,
                ));
                for j in 0..seg {
                    let (a, b) = (base + 1 + j, base + 1 + (j + 1) % seg);
                    // Counter-clockwise seen from outside.
                    m.faces.push(if side > 0.0 {
                        vec![base, a, b]
                    } else {
                        vec![base, b, a]
                    });
                }
            }
            m.normals = Some(normals);
        }
        _ => {}
    }
    m.tags = vec![Face::Outer; m.faces.len()];
    m
}

/// Row-major 4×4 of a pose.
pub fn pose_rows(p: &Pose) -> Value {
    let r = p.rotation;
    let t = p.translation;
    json!([
        [r.x_axis.x, r.y_axis.x, r.z_axis.x, t.x],
        [r.x_axis.y, r.y_axis.y, r.z_axis.y, t.y],
        [r.x_axis.z, r.y_axis.z, r.z_axis.z, t.z],
        [0.0, 0.0, 0.0, 1.0]
    ])
}

fn mat_rows(m: &DMat4) -> Value {
    let row = |i: usize| [0, 1, 2, 3].map(|j| m.col(j)[i]);
    json!([row(0), row(1), row(2), row(3)])
}

fn pose_mat(p: &Pose) -> DMat4 {
    DMat4::from_cols(
        p.rotation.x_axis.extend(0.0),
        p.rotation.y_axis.extend(0.0),
        p.rotation.z_axis.extend(0.0),
        p.translation.extend(1.0),
    )
}

/// An asset file the description refers to, to be written beside the script.
pub struct Asset {
    pub path: String,
    pub bytes: Vec<u8>,
}

/// The description and its assets.
pub struct Description {
    pub json: Value,
    pub assets: Vec<Asset>,
    pub warnings: Vec<String>,
}

/// Build the description of `model`.
pub fn describe(model: &Model) -> Result<Description, String> {
    let mut assets = Vec::new();
    // What Cycles cannot express, for `compile`'s report.
    let warnings: Vec<String> = model.open_underside_warning("Cycles").into_iter().collect();
    let base_dir = std::path::Path::new(&model.source)
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or_default();
    let mut cameras = cameras_json(model);
    for (c, h) in cameras
        .iter_mut()
        .zip(super::housing::housings_json(model, &mut assets))
    {
        c["housing"] = h;
    }
    let poses = poses_json(model);

    let caustics = model.needs.caustics && matches!(model.site.surface, SeaSurface::Waves { .. });
    if caustics && model.sun.is_some() {
        // CAUSTICS_REFUSED (docs/backends.md): the sun reaches the seabed only through the
        // wavy glass surface, i.e. only by Cycles' MNEE; with the native wave field as the
        // caster, the seabed as the receiver and the sun as the caustics light, MNEE found
        // almost no paths (caustics_shallow at 80×60, 16 spp: 98 % of the pixels black, image
        // mean 0.0 against the native 38).
        return Err(
            "the sun through a wavy sea surface (caustics) cannot be rendered by the Blender backend: Cycles reaches the seabed through the wavy glass only by its manifold next-event estimation, which finds almost none of these paths (the seabed renders black with fireflies)
  help: use `surface = \"flat\"` or render with the native backend"
                .into(),
        );
    }
    let sun = sun_json(model, caustics);

    let lights: Vec<Value> = model.lights.iter().map(light_json).collect();

    let mut objects = Vec::new();
    for i in 0..model.objects.len() {
        objects.push(object_json(model, i, &base_dir, &mut assets)?);
    }

    let wave_field = wave_field_json(model);

    let targets = targets_json(model, &mut assets)?;

    let mut json = json!({
        "format": FORMAT,
        "name": model.name,
        "description": model.description,
        "render": {
            "samples": model.render.samples,
            "seed": model.render.seed,
            "max_bounces": model.render.max_bounces,
            "port_interfaces": model.port_interfaces(),
            "exposure": model.render.exposure,
            "outputs": model.render.outputs,
        },
        "reference_channel": 1,
        "per_channel_passes": model.needs.per_channel_passes,
        "caustics": caustics,
        "cameras": cameras,
        "poses": poses,
        "water": model.water,
        "surface": model.site.surface,
        "wave_field": wave_field,
        "bounds": bounds(model),
        "sun": sun,
        "lights": lights,
        "objects": objects,
        "targets": targets,
    });
    if let Some(c) = model.render.crop {
        // `render.crop`, [x, y, width, height] in pixels from the top-left corner: Cycles'
        // border render, cropped to the border (`builder.prepare_image`).
        json["render"]["crop"] = json!([c.x, c.y, c.width, c.height]);
    }
    Ok(Description {
        json,
        assets,
        warnings,
    })
}

/// The cameras: intrinsics, lens, rig placement and port.
fn cameras_json(model: &Model) -> Vec<Value> {
    model
        .cameras
        .iter()
        .map(|c| {
            json!({
                "name": c.name,
                "width": c.width,
                "height": c.height,
                "lens": c.lens,
                "fx": c.fx,
                "fy": c.fy,
                "cx": c.cx,
                "cy": c.cy,
                "focus_distance": c.focus_distance,
                "f_number": c.f_number,
                "focal_length": c.focal_length,
                "distortion": c.distortion,
                // Largest undistorted r² inside the lens field (null: no fold).
                "r2_max": Some(crate::optics::lens::Lens::from_camera(c).r2_max)
                    .filter(|r| r.is_finite()),
                "rig_from_camera": pose_rows(&c.rig_from_camera),
                "port": c.port,
            })
        })
        .collect()
}

/// The poses: rig placement, image names, time and one Cycles seed per camera.
fn poses_json(model: &Model) -> Vec<Value> {
    model
        .poses
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let images: Vec<String> = (0..model.cameras.len())
                .map(|c| model.image_name(i, c))
                .collect();
            let seeds: Vec<u32> = (0..model.cameras.len())
                .map(|c| cycles_seed(model.render.seed, i, c))
                .collect();
            json!({
                "name": p.name,
                "world_from_rig": pose_rows(&p.world_from_rig),
                "images": images,
                "time": p.time,
                "seeds": seeds,
            })
        })
        .collect()
}

/// The sun: in the air above caustics (through the wave field), else in the water when there
/// is water, else in the air.
fn sun_json(model: &Model, caustics: bool) -> Option<Value> {
    model.sun.as_ref().map(|s| {
        if caustics {
            json!({"direction": s.direction_air, "irradiance": s.irradiance, "in_water": false,
                   "angle": SUN_ANGLE, "caustics": true})
        } else if model.water.is_some() {
            json!({"direction": s.direction_water, "irradiance": s.irradiance_water,
                   "in_water": true, "angle": 0.0, "caustics": false})
        } else {
            json!({"direction": s.direction_air, "irradiance": s.irradiance, "in_water": false,
                   "angle": 0.0, "caustics": false})
        }
    })
}

/// One light: its kind's parameters, name and mount.
fn light_json(l: &crate::model::Light) -> Value {
    let mut v = match &l.kind {
        LightKind::Point {
            position,
            intensity,
        } => {
            json!({"type": "point", "position": position, "intensity": intensity})
        }
        LightKind::Spot {
            position,
            direction,
            half_angle,
            intensity,
        } => json!({
            "type": "spot", "position": position, "direction": direction,
            "half_angle": half_angle, "intensity": intensity
        }),
        LightKind::Area {
            frame,
            width,
            height,
            radiance,
        } => json!({
            "type": "area", "frame": pose_rows(frame), "width": width,
            "height": height, "radiance": radiance
        }),
        LightKind::Ambient { radiance } => json!({"type": "ambient", "radiance": radiance}),
    };
    v["name"] = json!(l.name);
    v["mount"] = json!(l.mount);
    v
}

/// Object `i`: its shape (a textured mesh, a baked mesh with its PNG, a primitive, or a
/// tessellated PLY; the files go to `assets`), scale, world matrix and material.
fn object_json(
    model: &Model,
    i: usize,
    base_dir: &std::path::Path,
    assets: &mut Vec<Asset>,
) -> Result<Value, String> {
    let o = &model.objects[i];
    if let Some(p) = crate::texture::mapped::prepare_object(model, i)? {
        let m = pose_mat(&o.pose) * DMat4::from_scale(o.scale);
        return Ok(json!({
            "name": o.name,
            "shape": mapped_parts(&p, i, assets).map_err(|e| format!("object `{}`: {e}", o.name))?,
            "scale": o.scale,
            "matrix": mat_rows(&m),
            "material": o.material,
        }));
    }
    let baked = crate::texture::bake::bake_object(model, i)?;
    let shape = match (&o.shape, baked) {
        (_, Some(b)) => {
            // Baked texture (crate::texture::bake): the object-frame mesh with `s`, `t`
            // (t = 1 - v: Blender's image rows run bottom-up) and the linear 8-bit PNG.
            if b.coarsened() {
                eprintln!("warning: object `{}`: texture {}", o.name, b.summary());
            }
            let path = format!("assets/object_{i}.ply");
            let texture = format!("assets/object_{i}.png");
            assets.push(Asset {
                path: path.clone(),
                bytes: crate::texture::bake::ply_bytes(&b.mesh, &b.uv, true),
            });
            assets.push(Asset {
                path: texture.clone(),
                bytes: b
                    .texture
                    .png()
                    .map_err(|e| format!("object `{}`: {e}", o.name))?,
            });
            json!({"type": "ply", "path": path, "smooth": false, "texture": texture})
        }
        (Shape::Sphere { .. } | Shape::Cylinder { .. }, None) if o.material.glass.is_some() => {
            // GLASS_OBJECTS: glass refracts at its true normals: finely tessellated (as a dome
            // port's glass), with the shape's normals for smooth shading, in the housings' PLY
            // layout ([`super::housing::ply_bytes`]).
            let path = format!("assets/object_{i}.ply");
            assets.push(Asset {
                path: path.clone(),
                bytes: super::housing::ply_bytes(&glass_solid_mesh(&o.shape)),
            });
            json!({"type": "shaded_ply", "path": path})
        }
        (shape, None) => match shape {
            Shape::Plane { .. } | Shape::Box { .. } => {
                serde_json::to_value(&o.shape).map_err(|e| e.to_string())?
            }
            Shape::Sphere { .. }
            | Shape::Cylinder { .. }
            | Shape::Mesh { .. }
            | Shape::Seabed { .. }
            | Shape::Boulders { .. }
            | Shape::Coral { .. } => {
                // Tessellated by the shared mesh module (same triangles as the native
                // renderer), in the object frame; pose and scale stay in `matrix`.
                let path = format!("assets/object_{i}.ply");
                let mesh = crate::geometry::mesh::shape_mesh(&o.shape, base_dir)
                    .map_err(|e| format!("object `{}`: {e}", o.name))?;
                let bytes = crate::geometry::mesh::ply_bytes(
                    &mesh,
                    crate::geometry::mesh::PlyFormat::BinaryLittleEndian,
                );
                let smooth = matches!(o.shape, Shape::Sphere { .. });
                assets.push(Asset {
                    path: path.clone(),
                    bytes,
                });
                json!({"type": "ply", "path": path, "smooth": smooth})
            }
        },
    };
    let m = pose_mat(&o.pose) * DMat4::from_scale(o.scale);
    Ok(json!({
        "name": o.name,
        "shape": shape,
        "scale": o.scale,
        "matrix": mat_rows(&m),
        "material": o.material,
    }))
}

/// The native backend's wave field (same parameters and seed), so that Cycles refracts the
/// sun through the very surface the native caustics are computed from; `null` without waves.
fn wave_field_json(model: &Model) -> Value {
    match model.site.surface {
        SeaSurface::Waves {
            height,
            wavelength,
            wind_speed,
        } => {
            let f = crate::optics::waves::WaveField::new(
                height,
                wavelength,
                wind_speed,
                crate::optics::waves::WIND_DIRECTION,
                model.site.seed,
            );
            let comps: Vec<[f64; 4]> = f
                .components
                .iter()
                .map(|c| [c.kx, c.ky, c.amplitude, c.phase])
                .collect();
            json!({"period": f.period, "significant_height": f.significant_height,
                   "max_abs_height": f.max_abs_height(), "components": comps})
        }
        _ => Value::Null,
    }
}

/// The targets: printed targets with their texture PNG (to `assets`), 3D test objects as data.
fn targets_json(model: &Model, assets: &mut Vec<Asset>) -> Result<Vec<Value>, String> {
    let mut targets = Vec::new();
    for (i, t) in model.targets.iter().enumerate() {
        match super::target_texture(t)? {
            Some(tex) => {
                let path = format!("assets/target_{i}.png");
                assets.push(Asset {
                    path: path.clone(),
                    bytes: tex.png,
                });
                targets.push(json!({
                    "name": t.name,
                    "texture": path,
                    "width": tex.width,
                    "height": tex.height,
                    "origin": tex.origin,
                    "matrix": pose_rows(&t.pose),
                }));
            }
            None => targets.push(test_object(t)),
        }
    }
    Ok(targets)
}

/// The 3D test object (staircase pyramid) as data: its steps as boxes (target frame, the same
/// cuboids as the native renderer's `target_mesh` and Mitsuba's `cube`s) and its disks as
/// flat black disks 10 µm above each step's top face (as in the Mitsuba backend), with the
/// printed reflectances.
fn test_object(t: &crate::model::Target) -> Value {
    let TargetKind::TestObject {
        size,
        levels,
        step,
        diameter,
    } = t.kind
    else {
        unreachable!("only test objects have no texture")
    };
    let steps: Vec<Value> = (0..levels)
        .map(|k| {
            let (side, top) = crate::geometry::targets::test_object_step(size, levels, step, k);
            json!({"size": [side, side, step], "center": [0.0, 0.0, top - 0.5 * step]})
        })
        .collect();
    let disks: Vec<Value> = crate::geometry::targets::local_points(&t.kind)
        .into_iter()
        .map(
            |(id, p)| json!({"id": id, "center": [p.x, p.y, p.z + 1e-5], "radius": 0.5 * diameter}),
        )
        .collect();
    json!({
        "name": t.name,
        "kind": "test_object",
        "steps": steps,
        "disks": disks,
        "white": crate::geometry::targets::WHITE,
        "black": crate::geometry::targets::BLACK,
        "matrix": pose_rows(&t.pose),
    })
}

/// A world box holding every camera position, light, object and target point, with a margin
/// of five absorption lengths of the least absorbed channel (clamped to 5–400 m) so that
/// scene-filling water looks unbounded. Extinction lengths were too short: daylight scattered
/// tens of times wanders sideways until it is absorbed, and the sea box's black sides took
/// it (two_gas_dive at 73 bounces: −13 % G, −25 % B against native with 5 extinction lengths).
fn bounds(model: &Model) -> Value {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut add = |p: DVec3, r: f64| {
        lo = lo.min(p - DVec3::splat(r));
        hi = hi.max(p + DVec3::splat(r));
    };
    for i in 0..model.poses.len() {
        for c in 0..model.cameras.len() {
            add(model.world_from_camera(i, c).translation, 0.5);
        }
        for l in &model.lights {
            let p = match &l.kind {
                LightKind::Point { position, .. } | LightKind::Spot { position, .. } => *position,
                LightKind::Area { frame, .. } => frame.translation,
                LightKind::Ambient { .. } => continue,
            };
            let w = match l.mount {
                crate::model::Mount::Rig => model.poses[i].world_from_rig.transform_point(p),
                crate::model::Mount::World => p,
            };
            add(w, 0.5);
        }
    }
    for o in &model.objects {
        let r = match &o.shape {
            Shape::Plane { width, height } => 0.5 * width.hypot(*height),
            Shape::Box { size } => 0.5 * size.length(),
            Shape::Sphere { radius } => *radius,
            Shape::Cylinder { radius, height } => radius.hypot(0.5 * height),
            Shape::Seabed {
                width,
                length,
                roughness,
                relief,
                ..
            } => {
                let heights = relief.iter().map(|p| 2.0 * p.z.abs()).fold(0.0, f64::max);
                0.5 * width.hypot(*length) + 4.0 * roughness + heights
            }
            Shape::Boulders {
                width,
                length,
                radius,
                ..
            } => 0.5 * width.hypot(*length) + 2.0 * radius,
            Shape::Coral { radius, .. } => 1.5 * radius,
            Shape::Mesh { .. } => 10.0,
        };
        add(o.pose.translation, r * o.scale.max_element());
    }
    for t in &model.targets {
        for p in &t.points {
            add(p.world, 0.5);
        }
    }
    if !lo.is_finite() {
        lo = DVec3::splat(-1.0);
        hi = DVec3::splat(1.0);
    }
    let margin = model
        .water
        .as_ref()
        .map(|w| {
            let a = w.absorption.into_iter().fold(f64::INFINITY, f64::min);
            if a > 0.0 {
                (5.0 / a).clamp(5.0, 400.0)
            } else {
                400.0
            }
        })
        .unwrap_or(5.0);
    json!({"min": lo - DVec3::splat(margin), "max": hi + DVec3::splat(margin)})
}

/// A textured mesh ([`crate::texture::mapped`]) for Cycles: one object-frame PLY per material
/// (`s`, `t` with t = 1 − v, linear vertex colours where it has them) and its look: the chosen
/// mipmap level as a 16-bit linear PNG (Image Texture, `Non-Color`, `Linear`, the material's
/// wrap), the vertex colours (`Col`), or one colour.
fn mapped_parts(
    p: &crate::texture::mapped::Prepared,
    index: usize,
    assets: &mut Vec<Asset>,
) -> Result<Value, String> {
    use crate::geometry::meshfile::Wrap;
    use crate::texture::mapped::Look;
    let mut parts = Vec::new();
    let mut written: Vec<(*const crate::texture::mapped::Image16, String)> = Vec::new();
    for part in p.parts() {
        let k = part.material as usize;
        let look = &p.looks[k];
        let path = format!("assets/object_{index}_{k}.ply");
        let colors = matches!(look, Look::VertexColors).then_some(&part.colors[..]);
        let uv = (!part.uv.is_empty()).then_some(&part.uv[..]);
        assets.push(Asset {
            path: path.clone(),
            bytes: crate::texture::bake::ply_bytes_with(&part.mesh, uv, colors, true),
        });
        let v = match look {
            Look::Color(c) => json!({"path": path, "color": c}),
            Look::VertexColors => json!({"path": path, "vertex_colors": true}),
            Look::Image(img) => {
                let key = std::sync::Arc::as_ptr(img);
                let texture = match written.iter().find(|(p, _)| *p == key) {
                    Some((_, f)) => f.clone(),
                    None => {
                        let f = format!("assets/object_{index}_{k}.png");
                        assets.push(Asset {
                            path: f.clone(),
                            bytes: img.png()?,
                        });
                        written.push((key, f.clone()));
                        f
                    }
                };
                let extension = match img.wrap {
                    Wrap::Repeat => "REPEAT",
                    Wrap::Clamp => "EXTEND",
                    Wrap::Mirror => "MIRROR",
                };
                json!({"path": path, "texture": texture, "extension": extension})
            }
        };
        parts.push(v);
    }
    Ok(json!({"type": "ply_parts", "parts": parts}))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(path: &str) -> Model {
        crate::scene::load(std::path::Path::new(path), &[])
            .unwrap_or_else(|f| panic!("{}", f.render()))
            .model
    }

    #[test]
    fn every_image_gets_its_own_deterministic_cycles_seed() {
        let m = load("scenarios/calibration_flat.toml");
        assert!(m.poses.len() >= 2);
        let seeds = |m: &Model| -> Vec<u64> {
            let d = describe(m).unwrap().json;
            d["poses"]
                .as_array()
                .unwrap()
                .iter()
                .flat_map(|p| p["seeds"].as_array().unwrap().clone())
                .map(|s| s.as_u64().unwrap())
                .collect()
        };
        let a = seeds(&m);
        assert_eq!(a.len(), m.poses.len() * m.cameras.len());
        // Two poses get different seeds; all are distinct here; all in Cycles' range.
        assert_ne!(a[0], a[1]);
        let mut u = a.clone();
        u.sort();
        u.dedup();
        assert_eq!(u.len(), a.len(), "repeated seeds: {a:?}");
        assert!(a.iter().all(|&s| s < 1 << 31));
        // The same scene gives the same seeds; another scene seed gives others.
        assert_eq!(seeds(&load("scenarios/calibration_flat.toml")), a);
        let mut other = m.clone();
        other.render.seed += 1;
        assert_ne!(seeds(&other)[0], a[0]);
    }

    #[test]
    fn sun_caustics_are_refused_with_a_hint() {
        let m = load("scenarios/caustics_shallow.toml");
        let e = describe(&m).err().expect("refused");
        assert!(e.contains("caustics") && e.contains("help:"), "{e}");
        // Without the sun the wavy surface is described with the native wave field (the
        // objects, whose textures the description would bake, play no part in it).
        let mut m = m;
        m.sun = None;
        m.objects.clear();
        let d = describe(&m).unwrap().json;
        let f = &d["wave_field"];
        assert_eq!(f["significant_height"].as_f64(), Some(0.25));
        assert!(f["components"].as_array().unwrap().len() > 10);
    }
}
