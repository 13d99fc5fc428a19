//! The shared `world.xml`: what every view of the scene sees, in the order it is written:
//!
//! | item | function | Mitsuba 3 |
//! |---|---|---|
//! | sun | `sun` | `directional` (refracted direction and irradiance in water) |
//! | world-mounted lights | `light` (also used by the views for rig-mounted lights) | `point`, `spot`, area `rectangle`, `constant` |
//! | objects | [`shapes`] → `object_shapes`, `textured_shape`, `diffuse` | analytic shapes or world-frame `ply`, two-sided `diffuse`; glass objects are in each view (`view::glass_objects`) |
//! | targets | [`shapes`] → `target_shapes`, `white_card`, `lambert` | textured `rectangle`, or exact black `disk`s/`rectangle`s on a white card |
//!
//! Object and target shapes are built first (they write their meshes and textures into the
//! compiled files and may warn), then [`world`] assembles the document around them.
//! `scene_bounds` is here because the world is what it bounds; the views size the sea with it.

use super::xml::{self, El};
use super::{CARD_OFFSET, TEXELS_PER_PIXEL, basis, slug};
use crate::model::*;
use glam::{DMat3, DVec3};
use std::collections::BTreeMap;
use std::path::Path;

/// The shapes of every object, then every target, writing their meshes and textures into
/// `files`; what Mitsuba cannot express exactly is pushed onto `warnings`.
pub fn shapes(
    model: &Model,
    files: &mut BTreeMap<String, Vec<u8>>,
    warnings: &mut Vec<String>,
) -> Result<Vec<El>, String> {
    let mut shapes = Vec::new();
    // Glass objects go into each view, whose water medium their faces name as exterior
    // (`view::glass_objects`).
    for (i, o) in model.objects.iter().enumerate() {
        if o.material.glass.is_none() {
            shapes.extend(object_shapes(model, o, files, i, warnings)?);
        }
    }
    for (i, t) in model.targets.iter().enumerate() {
        shapes.extend(target_shapes(model, t, files, i)?);
    }
    Ok(shapes)
}

/// World content shared by every view: sun, world-mounted lights, objects, targets.
/// `shapes` are the already-built object/target shapes (they need asset files). With any
/// content, the document opens with the placement parameters at metres and 0 (world
/// coordinates, unless a view that includes it sets them) and the intensities of world-mounted
/// point and spot lights ([`xml::intensity_param`]), and its placed elements end with their
/// scale and translation ([`xml::place_at_origin`]).
pub fn world(model: &Model, shapes: Vec<El>) -> El {
    let mut root = El::new("scene").attr("version", "3.0.0");
    root.push_comment(format!(
        "poser scene `{}`: world content shared by every view",
        model.name
    ));
    let mut content: Vec<El> = sun(model).into_iter().collect();
    for (i, l) in model.lights.iter().enumerate() {
        if l.mount == Mount::World {
            let param = xml::intensity_param(i);
            content.push(light(l, &Pose::IDENTITY, Intensity::Param(&param)));
        }
    }
    content.extend(shapes);
    if content.is_empty() {
        return root;
    }
    for d in xml::placement_defaults(DVec3::ZERO, 1.0) {
        root.push(d);
    }
    for d in intensity_defaults(model, 1.0) {
        root.push(d);
    }
    for c in content {
        root.push(c);
    }
    xml::place_at_origin(&mut root);
    root
}

/// What Mitsuba cannot render of the sun: sunlight through a wavy surface. Checked by
/// [`super::build`] before anything is baked or written (the sun's emitter, [`sun`], then
/// needs no check of its own).
pub(super) fn check_sun(model: &Model) -> Result<(), String> {
    if model.sun.is_some() && model.needs.caustics {
        return Err(
            "the wavy sea surface (caustics) cannot be rendered by the Mitsuba backend: \
                    sunlight refracted through a wavy dielectric surface is a caustic that \
                    Mitsuba's path tracer does not converge on\n  help: use `surface = \"flat\"` \
                    or render with the native backend"
                .into(),
        );
    }
    Ok(())
}

fn sun(model: &Model) -> Option<El> {
    let sun = model.sun.as_ref()?;
    let (dir, e, note) = if model.water.is_some() {
        (
            sun.direction_water,
            sun.irradiance_water,
            "refracted into the water, irradiance just below the surface",
        )
    } else {
        (sun.direction_air, sun.irradiance, "in air")
    };
    Some(
        El::typed("emitter", "directional")
            .comment(format!(
                "sun at elevation {:.3}°, azimuth {:.3}°: {note}",
                sun.elevation.to_degrees(),
                sun.azimuth.to_degrees()
            ))
            .child(
                El::new("vector")
                    .attr("name", "direction")
                    .attr("value", super::xml::triple(dir.normalize().to_array())),
            )
            .rgb("irradiance", e),
    )
}

/// How a point or spot light's intensity is written.
pub(super) enum Intensity<'a> {
    /// The value in a document of this many length units per metre (× unit²).
    In(f64),
    /// `$name`: a parameter that each document sets in its own unit (world-mounted lights).
    Param(&'a str),
}

impl Intensity<'_> {
    fn write(&self, e: El, v: [f64; 3]) -> El {
        match self {
            Intensity::In(unit) => e.rgb("intensity", v.map(|c| c * unit * unit)),
            Intensity::Param(name) => e.child(
                El::new("rgb")
                    .attr("name", "intensity")
                    .attr("value", format!("${name}")),
            ),
        }
    }
}

/// `<default name="poser_intensity_N" …/>` for every world-mounted point or spot light, in a
/// document of `unit` length units per metre (W/sr × unit²): `world.xml` sets them in metres,
/// each view overrides them in its own unit ([`xml::intensity_param`]).
pub(super) fn intensity_defaults(model: &Model, unit: f64) -> Vec<El> {
    let mut out = Vec::new();
    for (i, l) in model.lights.iter().enumerate() {
        let intensity = match &l.kind {
            LightKind::Point { intensity, .. } | LightKind::Spot { intensity, .. } => intensity,
            LightKind::Area { .. } | LightKind::Ambient { .. } => continue,
        };
        if l.mount == Mount::World {
            out.push(
                El::new("default")
                    .attr("name", xml::intensity_param(i))
                    .attr("value", xml::triple(intensity.map(|c| c * unit * unit))),
            );
        }
    }
    out
}

/// One light in the world frame: `world_from_mount` is the identity for a world-mounted light
/// and the rig's pose for a rig-mounted one (emitted by each view).
pub(super) fn light(l: &Light, world_from_mount: &Pose, intensity_as: Intensity) -> El {
    let comment = format!("light `{}`", l.name);
    match &l.kind {
        LightKind::Point {
            position,
            intensity,
        } => intensity_as.write(
            El::typed("emitter", "point")
                .comment(comment)
                .to_world(DMat3::IDENTITY, world_from_mount.transform_point(*position)),
            *intensity,
        ),
        LightKind::Spot {
            position,
            direction,
            half_angle,
            intensity,
        } => {
            let p = world_from_mount.transform_point(*position);
            let z = world_from_mount.transform_vector(*direction).normalize();
            let (x, y) = basis(z);
            let cutoff = half_angle.to_degrees();
            intensity_as.write(
                El::typed("emitter", "spot")
                    .comment(format!(
                        "{comment}: sharp cone (beam_width = cutoff_angle - 0.001°)"
                    ))
                    .to_world(DMat3::from_cols(x, y, z), p)
                    .float("cutoff_angle", cutoff)
                    .float("beam_width", (cutoff - 1e-3).max(0.999 * cutoff)),
                *intensity,
            )
        }
        LightKind::Area {
            frame,
            width,
            height,
            radiance,
        } => {
            let f = world_from_mount.compose(frame);
            El::typed("shape", "rectangle")
                .comment(format!("{comment}: one-sided, emits along its +z"))
                .to_world(
                    DMat3::from_cols(
                        f.rotation.x_axis * (0.5 * width),
                        f.rotation.y_axis * (0.5 * height),
                        f.rotation.z_axis,
                    ),
                    f.translation,
                )
                .comment(
                    "null BSDF: the panel neither reflects nor blocks light (no shadow), like \
                     native and Blender lights; volpath passes through null surfaces on shadow \
                     rays too",
                )
                .child(El::typed("bsdf", "null"))
                .child(El::typed("emitter", "area").rgb("radiance", *radiance))
        }
        LightKind::Ambient { radiance } => El::typed("emitter", "constant")
            .comment(comment)
            .rgb("radiance", *radiance),
    }
}

/// Axis-aligned bounds of everything placed in the world (camera poses, objects, targets,
/// lights).
pub(super) fn scene_bounds(model: &Model) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut add = |p: DVec3| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    for p in &model.poses {
        add(p.world_from_rig.translation);
    }
    for o in &model.objects {
        add(o.pose.translation);
    }
    for t in &model.targets {
        add(t.pose.translation);
    }
    for l in &model.lights {
        if l.mount == Mount::World {
            match &l.kind {
                LightKind::Point { position, .. } | LightKind::Spot { position, .. } => {
                    add(*position)
                }
                LightKind::Area { frame, .. } => add(frame.translation),
                LightKind::Ambient { .. } => {}
            }
        }
    }
    if !lo.is_finite() {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    (lo, hi)
}

/// The object's BSDF: two-sided Lambertian; a checker on a plane becomes a `checkerboard`
/// texture with the native renderer's parity (`pattern_factor` in `crate::texture`). Patterns
/// Mitsuba cannot express on a shape are reported and the plain albedo is used.
fn diffuse(o: &Object, plane: Option<(f64, f64)>, warnings: &mut Vec<String>) -> El {
    let a = o.material.albedo;
    let reflectance = match (&o.material.pattern, plane) {
        (None, _) => El::typed("bsdf", "diffuse").rgb("reflectance", a),
        (Some(Pattern::Checker { size, contrast }), Some((w, h))) if *size > 0.0 => {
            // Object-frame x = (2u - 1)·w/2; the checkerboard's cell parity is that of
            // ⌊2u'⌋ + ⌊2v'⌋, so u' = x/(2·size).
            let (sx, sy) = (w * o.scale.x.abs(), h * o.scale.y.abs());
            let (ax, ay) = (sx / (2.0 * size), sy / (2.0 * size));
            El::typed("bsdf", "diffuse").child(
                El::typed("texture", "checkerboard")
                    .attr("name", "reflectance")
                    .comment(format!("checker of {size} m, contrast {contrast}"))
                    .rgb("color0", a)
                    .rgb("color1", a.map(|x| x * contrast))
                    .child(
                        El::new("transform")
                            .attr("name", "to_uv")
                            .child(
                                El::new("scale")
                                    .attr("x", xml::num(ax))
                                    .attr("y", xml::num(ay)),
                            )
                            .child(
                                El::new("translate")
                                    .attr("x", xml::num(-0.5 * ax))
                                    .attr("y", xml::num(-0.5 * ay)),
                            ),
                    ),
            )
        }
        (Some(p), _) => {
            // Every other pattern is baked (`textured_shape`) and never reaches here.
            let kind = match p {
                Pattern::Checker { .. } => "checker (on a non-plane shape)",
                _ => "baked",
            };
            warnings.push(format!(
                "object `{}`: the {kind} pattern cannot be expressed by the Mitsuba backend; \
                 its plain albedo is used",
                o.name
            ));
            El::typed("bsdf", "diffuse").rgb("reflectance", a)
        }
    };
    El::typed("bsdf", "twosided").child(reflectance)
}

/// A closed cylinder about the axis `m.z_axis` through `t`, of radius `r` and half-height `hz`:
/// Mitsuba's open `cylinder` and two `disk`s facing out, each with `bsdf` (also the glass
/// objects' form, `view::glass_objects`).
pub(super) fn capped_cylinder(
    m: DMat3,
    t: DVec3,
    r: f64,
    hz: f64,
    bsdf: &El,
    comment: String,
) -> Vec<El> {
    let axis = m.z_axis;
    let mut out = vec![
        El::typed("shape", "cylinder")
            .comment(comment)
            .point("p0", t - axis * hz)
            .point("p1", t + axis * hz)
            .float("radius", r)
            .child(bsdf.clone()),
    ];
    for sign in [-1.0, 1.0] {
        let n = axis * sign;
        out.push(
            El::typed("shape", "disk")
                .to_world(
                    DMat3::from_cols(m.x_axis * r, m.y_axis * r * sign, n),
                    t + n * hz,
                )
                .child(bsdf.clone()),
        );
    }
    out
}

/// The Mitsuba shape(s) of one object: analytic plugins for planes, boxes, spheres and
/// cylinders; PLY meshes (world frame, from `crate::geometry::mesh`) for the rest.
fn object_shapes(
    model: &Model,
    o: &Object,
    files: &mut BTreeMap<String, Vec<u8>>,
    index: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<El>, String> {
    if let Some(p) = crate::texture::mapped::prepare_object(model, index)? {
        return mapped_shapes(o, &p, files, index);
    }
    if let Some(b) = crate::texture::bake::bake_object(model, index)? {
        return Ok(vec![textured_shape(o, &b, files, index, warnings)?]);
    }
    let s = o.scale;
    let m = o.pose.rotation;
    let t = o.pose.translation;
    let comment = format!("object `{}`", o.name);
    let uniform_xy = (s.x - s.y).abs() <= 1e-12 * s.x.abs().max(1.0);
    let uniform = uniform_xy && (s.x - s.z).abs() <= 1e-12 * s.x.abs().max(1.0);
    let plane = match o.shape {
        Shape::Plane { width, height } => Some((width, height)),
        _ => None,
    };
    let bsdf = diffuse(o, plane, warnings);
    match &o.shape {
        Shape::Plane { width, height } => Ok(vec![
            El::typed("shape", "rectangle")
                .comment(comment)
                .to_world(
                    m * DMat3::from_diagonal(s * DVec3::new(0.5 * width, 0.5 * height, 1.0)),
                    t,
                )
                .child(bsdf),
        ]),
        Shape::Box { size } => Ok(vec![
            El::typed("shape", "cube")
                .comment(comment)
                .to_world(m * DMat3::from_diagonal(s * *size * 0.5), t)
                .child(bsdf),
        ]),
        Shape::Sphere { radius } if uniform => Ok(vec![
            El::typed("shape", "sphere")
                .comment(comment)
                .point("center", t)
                .float("radius", radius * s.x.abs())
                .child(bsdf),
        ]),
        Shape::Cylinder { radius, height } if uniform_xy => Ok(capped_cylinder(
            m,
            t,
            radius * s.x.abs(),
            0.5 * height * s.z,
            &bsdf,
            comment,
        )),
        _ => {
            let base = Path::new(&model.source).parent().unwrap_or(Path::new("."));
            let mesh = crate::geometry::mesh::object_mesh(o, base)?;
            if mesh.triangles.is_empty() {
                return Ok(vec![]);
            }
            let file = format!("meshes/{index:03}-{}.ply", slug(&o.name));
            files.insert(
                file.clone(),
                crate::geometry::mesh::ply_bytes(
                    &mesh,
                    crate::geometry::mesh::PlyFormat::BinaryLittleEndian,
                ),
            );
            Ok(vec![
                El::typed("shape", "ply")
                    .comment(format!(
                        "{comment}: {} triangles, world frame",
                        mesh.triangles.len()
                    ))
                    .string("filename", &file)
                    .boolean("face_normals", true)
                    .child(bsdf),
            ])
        }
    }
}

/// A baked object ([`crate::texture::bake`]): its world-frame PLY with per-vertex `s`, `t`
/// and its texture as a `bitmap` (linear 8-bit values, so `raw`; bilinear between texel
/// centres, clamped at the edges: the convention the native renderer and Cycles use too).
fn textured_shape(
    o: &Object,
    b: &crate::texture::bake::Baked,
    files: &mut BTreeMap<String, Vec<u8>>,
    index: usize,
    warnings: &mut Vec<String>,
) -> Result<El, String> {
    if b.coarsened() {
        warnings.push(format!("object `{}`: texture {}", o.name, b.summary()));
    }
    let world = b.mesh.transformed(&o.pose, o.scale);
    let mesh_file = format!("meshes/{index:03}-{}.ply", slug(&o.name));
    files.insert(
        mesh_file.clone(),
        crate::texture::bake::ply_bytes(&world, &b.uv, false),
    );
    let tex_file = format!("textures/object-{index:03}-{}.png", slug(&o.name));
    files.insert(
        tex_file.clone(),
        b.texture
            .png()
            .map_err(|e| format!("object `{}`: {e}", o.name))?,
    );
    Ok(El::typed("shape", "ply")
        .comment(format!(
            "object `{}`: {} triangles, world frame, baked texture {}",
            o.name,
            world.triangles.len(),
            b.summary()
        ))
        .string("filename", &mesh_file)
        .boolean("face_normals", true)
        .child(
            El::typed("bsdf", "twosided").child(
                El::typed("bsdf", "diffuse").child(
                    El::typed("texture", "bitmap")
                        .attr("name", "reflectance")
                        .string("filename", &tex_file)
                        .comment("values are linear albedo × 255, not sRGB")
                        .boolean("raw", true)
                        .string("filter_type", "bilinear")
                        .string("wrap_mode", "clamp"),
                ),
            ),
        ))
}

/// A textured mesh ([`crate::texture::mapped`]): one world-frame PLY per material (with `s`, `t`
/// and linear vertex colours where it has them) and its look: the chosen mipmap level as a
/// 16-bit linear PNG in a `bitmap` (`raw`, bilinear between texel centres, the material's wrap:
/// the native renderer's [`crate::texture::mapped::Image16::sample`]), the vertex colours
/// through a `mesh_attribute` texture, or one colour.
fn mapped_shapes(
    o: &Object,
    p: &crate::texture::mapped::Prepared,
    files: &mut BTreeMap<String, Vec<u8>>,
    index: usize,
) -> Result<Vec<El>, String> {
    use crate::geometry::meshfile::Wrap;
    use crate::texture::mapped::Look;
    let mut out = Vec::new();
    let mut written: Vec<(*const crate::texture::mapped::Image16, String)> = Vec::new();
    for part in p.parts() {
        let k = part.material as usize;
        let world = part.mesh.transformed(&o.pose, o.scale);
        let mesh_file = format!("meshes/{index:03}-{}-{k}.ply", slug(&o.name));
        let look = &p.looks[k];
        let colors = matches!(look, Look::VertexColors).then_some(&part.colors[..]);
        let uv = (!part.uv.is_empty()).then_some(&part.uv[..]);
        files.insert(
            mesh_file.clone(),
            crate::texture::bake::ply_bytes_with(&world, uv, colors, false),
        );
        let name = &p.plan.file.materials[k].name;
        let reflectance = match look {
            Look::Color(c) => El::typed("bsdf", "diffuse").rgb("reflectance", *c),
            Look::VertexColors => El::typed("bsdf", "diffuse").child(
                El::typed("texture", "mesh_attribute")
                    .attr("name", "reflectance")
                    .string("name", "vertex_color"),
            ),
            Look::Image(img) => {
                let key = std::sync::Arc::as_ptr(img);
                let tex_file = match written.iter().find(|(p, _)| *p == key) {
                    Some((_, f)) => f.clone(),
                    None => {
                        let f = format!("textures/object-{index:03}-{}-{k}.png", slug(&o.name));
                        files.insert(
                            f.clone(),
                            img.png().map_err(|e| format!("object `{}`: {e}", o.name))?,
                        );
                        written.push((key, f.clone()));
                        f
                    }
                };
                let plan = &p.plan.materials[k];
                El::typed("bsdf", "diffuse").child(
                    El::typed("texture", "bitmap")
                        .attr("name", "reflectance")
                        .string("filename", &tex_file)
                        .comment(format!(
                            "mipmap level {} of {}: linear 16-bit values, colour factor applied",
                            plan.level,
                            plan.image.as_deref().unwrap_or("")
                        ))
                        .boolean("raw", true)
                        .string("filter_type", "bilinear")
                        .string(
                            "wrap_mode",
                            match img.wrap {
                                Wrap::Repeat => "repeat",
                                Wrap::Clamp => "clamp",
                                Wrap::Mirror => "mirror",
                            },
                        ),
                )
            }
        };
        out.push(
            El::typed("shape", "ply")
                .comment(format!(
                    "object `{}`, material `{name}`: {} triangles, world frame",
                    o.name,
                    world.triangles.len()
                ))
                .string("filename", &mesh_file)
                .boolean("face_normals", true)
                .child(El::typed("bsdf", "twosided").child(reflectance)),
        );
    }
    Ok(out)
}

/// Texture resolution for a target: at least [`TEXELS_PER_PIXEL`] texels per image pixel at
/// the closest camera position (water magnifies by up to its index), clamped by
/// `targets::texture` to its maximum size.
fn target_px_per_m(model: &Model, t: &Target) -> f64 {
    let fx = model
        .cameras
        .iter()
        .map(|c| c.fx.max(c.fy))
        .fold(0.0, f64::max);
    let mut dmin = f64::INFINITY;
    for p in 0..model.poses.len() {
        for c in 0..model.cameras.len() {
            let d = (model.world_from_camera(p, c).translation - t.pose.translation).length();
            dmin = dmin.min(d);
        }
    }
    let n = model.ambient_ior().iter().cloned().fold(1.0, f64::max);
    let (w, h) = crate::geometry::targets::extent(&t.kind);
    let dmin = (dmin - 0.5 * w.hypot(h)).max(0.05);
    (TEXELS_PER_PIXEL * fx * n / dmin).clamp(500.0, 20_000.0)
}

/// The white card of a geometric target, `CARD_OFFSET` behind its printed face.
fn white_card(t: &Target) -> El {
    let (w, h) = crate::geometry::targets::extent(&t.kind);
    El::typed("shape", "rectangle")
        .comment(format!("target `{}`: white card {w} m × {h} m", t.name))
        .to_world(
            t.pose.rotation * DMat3::from_diagonal(DVec3::new(0.5 * w, 0.5 * h, 1.0)),
            t.pose.transform_point(DVec3::new(0.0, 0.0, -CARD_OFFSET)),
        )
        .child(lambert(crate::geometry::targets::WHITE))
}

fn lambert(albedo: f64) -> El {
    El::typed("bsdf", "twosided")
        .child(El::typed("bsdf", "diffuse").rgb("reflectance", [albedo; 3]))
}

/// A target: its printed face as a `rectangle` with a PNG texture from `targets::texture`
/// (linear reflectance, `raw`), or for the 3D test object its steps as `cube`s and its disks as
/// `disk`s.
fn target_shapes(
    model: &Model,
    t: &Target,
    files: &mut BTreeMap<String, Vec<u8>>,
    index: usize,
) -> Result<Vec<El>, String> {
    let m = t.pose.rotation;
    match t.kind {
        TargetKind::TestObject {
            size,
            levels,
            step,
            diameter,
        } => {
            let mut out = Vec::new();
            for k in 0..levels {
                let (side, top) = crate::geometry::targets::test_object_step(size, levels, step, k);
                out.push(
                    El::typed("shape", "cube")
                        .comment(format!("target `{}`: step {k}", t.name))
                        .to_world(
                            m * DMat3::from_diagonal(DVec3::new(
                                0.5 * side,
                                0.5 * side,
                                0.5 * step,
                            )),
                            t.pose
                                .transform_point(DVec3::new(0.0, 0.0, top - 0.5 * step)),
                        )
                        .child(lambert(crate::geometry::targets::WHITE)),
                );
            }
            for (id, p) in crate::geometry::targets::local_points(&t.kind) {
                let r = 0.5 * diameter;
                out.push(
                    El::typed("shape", "disk")
                        .comment(format!("target `{}`: disk {id}", t.name))
                        .to_world(
                            DMat3::from_cols(m.x_axis * r, m.y_axis * r, m.z_axis),
                            t.pose.transform_point(p + DVec3::new(0.0, 0.0, 1e-5)),
                        )
                        .child(lambert(crate::geometry::targets::BLACK)),
                );
            }
            Ok(out)
        }
        TargetKind::CircleGrid { diameter, .. } | TargetKind::ScaleBar { diameter, .. } => {
            // Exact geometry: black `disk`s on the printed face (z = 0), the white card just
            // behind it, so disk edges are analytic (a texture's texels would bias centroids).
            let mut out = vec![white_card(t)];
            let r = 0.5 * diameter;
            for (id, p) in crate::geometry::targets::local_points(&t.kind) {
                out.push(
                    El::typed("shape", "disk")
                        .comment(format!("target `{}`: disk {id}", t.name))
                        .to_world(
                            DMat3::from_cols(m.x_axis * r, m.y_axis * r, m.z_axis),
                            t.pose.transform_point(p),
                        )
                        .child(lambert(crate::geometry::targets::BLACK)),
                );
            }
            Ok(out)
        }
        TargetKind::Checkerboard { cols, rows, square } => {
            // Exact geometry: one black `rectangle` per dark square (parity as in
            // `targets::reflectance`: cell (0, 0) at (-x, -y) is black), white card behind.
            let mut out = vec![white_card(t)];
            let (w, h) = (cols as f64 * square, rows as f64 * square);
            for j in 0..rows {
                for i in 0..cols {
                    if (i + j) % 2 != 0 {
                        continue;
                    }
                    let c = DVec3::new(
                        -0.5 * w + (i as f64 + 0.5) * square,
                        -0.5 * h + (j as f64 + 0.5) * square,
                        0.0,
                    );
                    let mut sq = El::typed("shape", "rectangle");
                    if out.len() == 1 {
                        sq.push_comment(format!("target `{}`: black squares", t.name));
                    }
                    out.push(
                        sq.to_world(
                            m * DMat3::from_diagonal(DVec3::new(0.5 * square, 0.5 * square, 1.0)),
                            t.pose.transform_point(c),
                        )
                        .child(lambert(crate::geometry::targets::BLACK)),
                    );
                }
            }
            Ok(out)
        }
        _ => {
            let (w, h) = crate::geometry::targets::extent(&t.kind);
            let ppm = target_px_per_m(model, t);
            let img = crate::geometry::targets::texture(&t.kind, ppm);
            let mut png = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .map_err(|e| format!("target `{}`: cannot encode its texture: {e}", t.name))?;
            let file = format!("textures/{index:03}-{}.png", slug(&t.name));
            files.insert(file.clone(), png);
            Ok(vec![
                El::typed("shape", "rectangle")
                    .comment(format!(
                        "target `{}`: {w} m × {h} m, texture {}×{} px",
                        t.name,
                        img.width(),
                        img.height()
                    ))
                    .to_world(
                        m * DMat3::from_diagonal(DVec3::new(0.5 * w, 0.5 * h, 1.0)),
                        t.pose.translation,
                    )
                    .child(
                        El::typed("bsdf", "twosided").child(
                            El::typed("bsdf", "diffuse").child(
                                El::typed("texture", "bitmap")
                                    .attr("name", "reflectance")
                                    .string("filename", &file)
                                    .comment("values are linear reflectance × 255, not sRGB")
                                    .boolean("raw", true)
                                    .string("filter_type", "bilinear")
                                    .comment(
                                        "the PNG's row 0 is the target's +y edge; Mitsuba's v = 0 \
                                         is row 0, the rectangle's v = 0 is -y: flip v",
                                    )
                                    .child(
                                        El::new("transform")
                                            .attr("name", "to_uv")
                                            .child(El::new("scale").attr("y", "-1"))
                                            .child(El::new("translate").attr("y", "1")),
                                    ),
                            ),
                        ),
                    ),
            ])
        }
    }
}
