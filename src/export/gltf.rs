//! The model as one glTF 2.0 binary file (`.glb`), a preview a trainer can open in any glTF
//! viewer without rendering: `poser export SCENE -o scene.glb` (docs/export.md).
//!
//! | glTF item | from the model | notes |
//! |---|---|---|
//! | node `site` → one mesh per object | every object's triangles ([`crate::geometry::mesh::object_mesh`]: seabed, boulders, corals, primitives, imported meshes) | PBR material: base colour = the albedo (linear), metallic 0, roughness 1; patterns are not drawn |
//! | node `targets` → one mesh per target | the printed face as a quad with UVs and its pattern as an embedded PNG ([`crate::geometry::targets::texture`], sRGB-encoded); the test object as its white steps with black disks | |
//! | node `water surface` | a flat quad at z = 0 or the wave height field ([`crate::optics::waves`], the renderer's seed), covering the site with a margin | only with water and a sea surface; blue, `alphaMode` BLEND |
//! | node `ports` → one mesh per camera | the housing port in front of each camera at the representative pose (pose 0): flat = a disc of the radius the field of view needs and the glass's thickness; dome = a spherical cap shell; cylinder = a tube shell | glass-like, `alphaMode` BLEND; the exact port is in the cameras' `extras` |
//! | node `cameras` → one node per image | every rig pose × every camera: a perspective camera, `yfov` from fy and the height, `aspectRatio` = width/height | exact intrinsics, distortion, lens, port and the f64 pose in `extras` |
//! | node `swim path` | a `LINE_STRIP` through the rig positions in pose order (`POINTS` for a single pose) | |
//! | node `lights` → `KHR_lights_punctual` | point and spot lights (candela), the sun as a directional light (lux) in the direction the model lights the scene with | rig-mounted lights at the representative pose |
//! | approximated | area lights → emissive rectangles; ambient light → the scene's `extras.ambient` | listed in [`Summary::approximated`] |
//!
//! Axes: poser's world is z up (x east, y north); glTF is y up. Every coordinate is baked with
//! the one rotation `(x, y, z)_poser → (x, z, −y)_glTF` ([`to_gltf`]), the inverse of what
//! [`crate::geometry::mesh::load_gltf`] applies on import, so an exported mesh imports back in
//! place. Cameras: poser's camera frame is OpenCV's (x right, y down, z forward), glTF's looks
//! down −z with +y up, so a camera node's rotation is `C · R_world_from_camera · diag(1, −1, −1)`
//! with `C` the axis rotation. Light units: `683 lm/W × max(channel)` with the colour the
//! channels divided by their largest ([`photometric`]).
//!
//! Nothing in a name from the scene is used as a path: names are written as glTF names and
//! `extras` strings only. Every value is checked finite; a non-finite one is refused with an
//! error naming it.

use crate::geometry::mesh::{TriMesh, object_mesh};
use crate::geometry::targets;
use crate::model::{Camera, LensModel, LightKind, Model, Mount, Port, Pose, Rgb, TargetKind};
use crate::optics::port::{self, HousingMesh, revolve, z_to};
use glam::{DMat3, DQuat, DVec3};
use gltf::json;
use gltf::json::validation::{Checked, USize64};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// Luminous efficacy used to turn poser's radiometric light units into the photometric units
/// of `KHR_lights_punctual`, lm/W (the peak of the photopic curve, at 555 nm).
pub const LUMENS_PER_WATT: f64 = 683.0;
/// Near clipping distance of the exported cameras, m.
pub const ZNEAR: f64 = 0.01;
/// Texels per metre of the target textures, at most (the side is capped by [`TARGET_MAX_PX`]).
pub const TARGET_PX_PER_M: f64 = 2000.0;
/// Largest side of a target texture in the preview, px.
pub const TARGET_MAX_PX: f64 = 2048.0;
/// Segments around the axis of the port meshes (and the targets' disks).
pub const PORT_SEGMENTS: u32 = port::MESH_SEGMENTS;
/// The rig pose at which rig-mounted lights and the ports are placed.
pub const REPRESENTATIVE_POSE: usize = 0;
/// Largest number of cells along one side of the wave mesh.
pub const WAVE_MAX_CELLS: f64 = 256.0;

/// poser world (z up) → glTF (y up): `(x, y, z) ↦ (x, z, −y)`.
pub fn to_gltf(p: DVec3) -> DVec3 {
    DVec3::new(p.x, p.z, -p.y)
}

/// The rotation of [`to_gltf`] as a matrix (columns: the images of poser's x, y, z).
pub const GLTF_FROM_POSER: DMat3 = DMat3::from_cols(
    DVec3::new(1.0, 0.0, 0.0),
    DVec3::new(0.0, 0.0, -1.0),
    DVec3::new(0.0, 1.0, 0.0),
);

/// A glTF camera's axes in poser's (OpenCV) camera frame: x right stays, y up = −y down,
/// z back = −z forward.
pub const OPENCV_FROM_GLTF_CAMERA: DMat3 = DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));

/// The rotation of a camera node in the glTF world: `C · R_world_from_camera · diag(1, −1, −1)`.
pub fn camera_node_rotation(world_from_camera: &Pose) -> DMat3 {
    GLTF_FROM_POSER * world_from_camera.rotation * OPENCV_FROM_GLTF_CAMERA
}

/// A light colour and intensity for `KHR_lights_punctual` from a radiometric RGB quantity
/// (W/sr for point and spot lights → candela; W/m² for the sun → lux): the colour is the
/// channels over their largest, the intensity `683 lm/W × max(channel)`, so that
/// `intensity × colour` per channel is 683 × the model's value.
pub fn photometric(rgb: Rgb) -> ([f32; 3], f64) {
    let m = rgb.iter().cloned().fold(0.0, f64::max);
    if m > 0.0 {
        (
            rgb.map(|c| (c / m).clamp(0.0, 1.0) as f32),
            LUMENS_PER_WATT * m,
        )
    } else {
        ([1.0; 3], 0.0)
    }
}

/// What an export wrote, for the command's report.
#[derive(Debug, Clone, Default)]
pub struct Summary {
    /// Meshes of the site (objects), of targets, of ports.
    pub objects: usize,
    pub targets: usize,
    pub ports: usize,
    /// `"flat"`, `"waves"` or `None`.
    pub water_surface: Option<&'static str>,
    pub triangles: usize,
    /// Camera nodes (rig poses × cameras).
    pub cameras: usize,
    /// `KHR_lights_punctual` lights (point, spot, sun).
    pub lights: usize,
    pub path_points: usize,
    /// Lights glTF cannot express and what they became, one line each.
    pub approximated: Vec<String>,
    /// Size of the file, bytes.
    pub bytes: usize,
}

/// Export `model` to `path` (written atomically).
pub fn write(model: &Model, path: &Path) -> Result<Summary, String> {
    let (bytes, summary) = export(model)?;
    crate::io::write_atomic(path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(summary)
}

/// The `.glb` bytes of `model`, and what they hold.
pub fn export(model: &Model) -> Result<(Vec<u8>, Summary), String> {
    if model.poses.is_empty() {
        return Err("the model has no camera pose to export".into());
    }
    let mut b = Builder::new();
    let mut s = Summary::default();
    let base = Path::new(&model.source)
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();

    // Site geometry.
    let mut bounds = Bounds::default();
    site_group(&mut b, model, &base, &mut bounds, &mut s)?;

    // Targets.
    target_group(&mut b, model, &mut bounds, &mut s)?;

    for p in 0..model.poses.len() {
        bounds.add(model.poses[p].world_from_rig.translation);
        for c in 0..model.cameras.len() {
            bounds.add(model.world_from_camera(p, c).translation);
        }
    }

    // Water surface.
    if let Some(sea) = model.sea_interface(1) {
        water_surface(&mut b, model, &sea, &bounds, &mut s)?;
    }

    // Ports at the representative pose.
    port_group(&mut b, model, &mut s)?;

    // Cameras.
    let mut cnodes = Vec::new();
    for p in 0..model.poses.len() {
        for (c, cam) in model.cameras.iter().enumerate() {
            cnodes.push(camera_node(&mut b, model, p, c, cam)?);
            s.cameras += 1;
        }
    }
    b.group("cameras", cnodes);

    // Swim path.
    swim_path(&mut b, model, &mut s)?;

    // Lights.
    let (lnodes, ambient) = lights(&mut b, model, &bounds, &mut s)?;
    b.group("lights", lnodes);

    // Scene extras.
    let extras = json!({
        "generator": format!("poser {} export", env!("CARGO_PKG_VERSION")),
        "scenario": model.name,
        "description": model.description,
        "units": "metres",
        "axes": "glTF y up; poser's world (x east, y north, z up) maps as (x, y, z) -> (x, z, -y)",
        "camera_frame": "poser cameras are OpenCV (x right, y down, z forward); glTF cameras look down -z with +y up: node rotation = C * R_world_from_camera * diag(1, -1, -1)",
        "pixel_convention": "pixel centres at +0.5 (COLMAP's): the image centre is (width/2, height/2); OpenCV's principal point is (cx - 0.5, cy - 0.5)",
        "light_units": "point/spot intensity (cd) = 683 lm/W * max channel of I (W/sr); sun (lux) = 683 lm/W * max channel of E (W/m2); colour = channels / max",
        "representative_pose": REPRESENTATIVE_POSE,
        "ambient": ambient,
        "approximated": s.approximated,
    });
    b.finish(&model.name, extras_of("the scene", extras)?, &mut s)
}

/// The site: one mesh node per object with geometry, in the `site` group (their extent into
/// `bounds`).
fn site_group(
    b: &mut Builder,
    model: &Model,
    base: &Path,
    bounds: &mut Bounds,
    s: &mut Summary,
) -> Result<(), String> {
    let mut site = Vec::new();
    for o in &model.objects {
        let mesh = object_mesh(o, base)?;
        if mesh.triangles.is_empty() {
            continue;
        }
        bounds.add_mesh(&mesh);
        let a = o.material.albedo;
        // A glass object looks like the port's glass.
        let (colour, look) = match &o.material.glass {
            Some(_) => ([0.75, 0.88, 1.0, 0.3], Look::Glass),
            None => ([a[0], a[1], a[2], 1.0], Look::Opaque),
        };
        let mat = b.material(&o.name, colour, look, None, &format!("object `{}`", o.name))?;
        let prim = b.triangles(&mesh, None, mat, &format!("object `{}`", o.name))?;
        s.triangles += mesh.triangles.len();
        site.push(b.mesh_node(&o.name, vec![prim], None));
        s.objects += 1;
    }
    b.group("site", site);
    Ok(())
}

/// The targets: one node per target with its kind and point count, in the `targets` group
/// (their points and origins into `bounds`).
fn target_group(
    b: &mut Builder,
    model: &Model,
    bounds: &mut Bounds,
    s: &mut Summary,
) -> Result<(), String> {
    let mut tnodes = Vec::new();
    for (i, t) in model.targets.iter().enumerate() {
        let what = format!("target `{}`", t.name);
        let prims = target_primitives(b, t, i, &what, &mut s.triangles)?;
        for p in &t.points {
            bounds.add(p.world);
        }
        bounds.add(t.pose.translation);
        let extras = json!({
            "kind": serde_json::to_value(&t.kind).map_err(|e| e.to_string())?,
            "points": t.points.len(),
        });
        tnodes.push(b.mesh_node(&t.name, prims, extras_of(&what, extras)?));
        s.targets += 1;
    }
    b.group("targets", tnodes);
    Ok(())
}

/// The water surface over `bounds` with a margin: a flat plane, or the wave field's heights
/// on a grid.
fn water_surface(
    b: &mut Builder,
    model: &Model,
    sea: &crate::optics::surface::SeaInterface,
    bounds: &Bounds,
    s: &mut Summary,
) -> Result<(), String> {
    let (lo, hi) = bounds
        .get()
        .unwrap_or((DVec3::splat(-5.0), DVec3::splat(5.0)));
    let centre = 0.5 * (lo + hi);
    let half = 0.75 * (hi - lo).truncate().max_element() + 5.0;
    let (mesh, kind) = if sea.field.components.is_empty() {
        let mut m = crate::geometry::mesh::plane(2.0 * half, 2.0 * half);
        for p in &mut m.positions {
            p.x += centre.x;
            p.y += centre.y;
        }
        (m, "flat")
    } else {
        let step = (sea.field.peak_wavelength / 12.0).max(2.0 * half / WAVE_MAX_CELLS);
        let n = ((2.0 * half / step).ceil() as u32).clamp(1, WAVE_MAX_CELLS as u32);
        (
            grid(centre.x - half, centre.y - half, 2.0 * half, n, |x, y| {
                sea.field.height(x, y)
            }),
            "waves",
        )
    };
    let mat = b.material(
        "water surface",
        [0.05, 0.3, 0.55, 0.35],
        Look::Transparent,
        None,
        "the water surface",
    )?;
    let prim = b.triangles(&mesh, None, mat, "the water surface")?;
    s.triangles += mesh.triangles.len();
    let extras = json!({ "surface": kind, "n_water": model.ambient_ior() });
    let node = b.mesh_node(
        "water surface",
        vec![prim],
        extras_of("the water surface", extras)?,
    );
    b.scene_nodes.push(node);
    s.water_surface = Some(kind);
    Ok(())
}

/// The ports at the representative pose: one glass node per camera with a port, in the
/// `ports` group.
fn port_group(b: &mut Builder, model: &Model, s: &mut Summary) -> Result<(), String> {
    let mut pnodes = Vec::new();
    let mut glass = None;
    for (c, cam) in model.cameras.iter().enumerate() {
        let what = format!("the port of camera `{}`", cam.name);
        let Some(local) = port_mesh(cam, model.ambient_ior()[1], &what)? else {
            continue;
        };
        let wfc = model.world_from_camera(REPRESENTATIVE_POSE, c);
        let world = local.transformed(&wfc, DVec3::ONE);
        let glass = match glass {
            Some(g) => g,
            None => *glass.insert(b.material(
                "port glass",
                [0.75, 0.88, 1.0, 0.3],
                Look::Glass,
                None,
                "the port glass",
            )?),
        };
        let prim = b.triangles(&world, None, glass, &what)?;
        s.triangles += world.triangles.len();
        let extras = json!({
            "camera": cam.name,
            "pose_index": REPRESENTATIVE_POSE,
            "port": port_json(&cam.port, &what)?,
        });
        pnodes.push(b.mesh_node(
            &format!("port of {} ({})", cam.name, cam.port.kind_name()),
            vec![prim],
            extras_of(&what, extras)?,
        ));
        s.ports += 1;
    }
    b.group("ports", pnodes);
    Ok(())
}

/// The swim path: the rig positions in pose order as a line strip.
fn swim_path(b: &mut Builder, model: &Model, s: &mut Summary) -> Result<(), String> {
    let path: Vec<DVec3> = model
        .poses
        .iter()
        .map(|p| p.world_from_rig.translation)
        .collect();
    let mat = b.material(
        "swim path",
        [1.0, 0.8, 0.1, 1.0],
        Look::Line,
        None,
        "the swim path",
    )?;
    let prim = b.line_strip(&path, mat, "the swim path")?;
    let extras = json!({
        "points": "the rig positions (world_from_rig translations) in pose order",
        "network": model.network.kind,
        "path_length_m": model.network.path_length,
    });
    let node = b.mesh_node("swim path", vec![prim], extras_of("the swim path", extras)?);
    b.scene_nodes.push(node);
    s.path_points = path.len();
    Ok(())
}

// ------------------------------------------------------------------------------------------
// The builder: root, binary chunk, helpers
// ------------------------------------------------------------------------------------------

#[derive(Clone, Copy, PartialEq)]
enum Look {
    /// Rough dielectric, base colour only.
    Opaque,
    /// Double-sided, alpha-blended.
    Transparent,
    /// Smooth, double-sided, alpha-blended.
    Glass,
    /// An opaque, double-sided card (a target's printed face).
    Card,
    /// A line: the colour is also emitted so it reads under any lighting.
    Line,
    /// An emitter (an approximated area light): black base, emissive colour.
    Emissive([f32; 3]),
}

struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    scene_nodes: Vec<json::Index<json::Node>>,
}

/// Axis-aligned bounds of what the export shows (poser world).
#[derive(Default)]
struct Bounds(Option<(DVec3, DVec3)>);

impl Bounds {
    fn add(&mut self, p: DVec3) {
        if !p.is_finite() {
            return;
        }
        self.0 = Some(match self.0 {
            None => (p, p),
            Some((lo, hi)) => (lo.min(p), hi.max(p)),
        });
    }
    fn add_mesh(&mut self, m: &TriMesh) {
        if let Some((lo, hi)) = m.bounds() {
            self.add(lo);
            self.add(hi);
        }
    }
    fn get(&self) -> Option<(DVec3, DVec3)> {
        self.0
    }
}

/// `extras` from a JSON value. A `null` anywhere means a non-finite number came in (serde_json
/// writes NaN and infinities as `null`; the export writes no other `null`): refused.
fn extras_of(what: &str, v: Value) -> Result<json::Extras, String> {
    fn find_null(v: &Value, path: &mut Vec<String>) -> bool {
        match v {
            Value::Null => true,
            Value::Array(a) => a.iter().enumerate().any(|(i, x)| {
                path.push(i.to_string());
                let hit = find_null(x, path);
                if !hit {
                    path.pop();
                }
                hit
            }),
            Value::Object(o) => o.iter().any(|(k, x)| {
                path.push(k.clone());
                let hit = find_null(x, path);
                if !hit {
                    path.pop();
                }
                hit
            }),
            _ => false,
        }
    }
    let mut path = Vec::new();
    if find_null(&v, &mut path) {
        return Err(format!(
            "{what}: `{}` is not a finite number; nothing was written",
            path.join(".")
        ));
    }
    let text = serde_json::to_string(&v).map_err(|e| format!("{what}: {e}"))?;
    json::extras::RawValue::from_string(text)
        .map(Some)
        .map_err(|e| format!("{what}: {e}"))
}

fn finite3(what: &str, field: &str, v: [f32; 3]) -> Result<[f32; 3], String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(format!(
            "{what}: its {field} is not finite ({v:?}); nothing was written"
        ))
    }
}

fn f32x3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn quat(what: &str, m: DMat3) -> Result<json::scene::UnitQuaternion, String> {
    let q = DQuat::from_mat3(&m).normalize();
    let v = [q.x as f32, q.y as f32, q.z as f32, q.w as f32];
    let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
    if !(n.is_finite() && n > 0.5) {
        return Err(format!(
            "{what}: its rotation is not finite; nothing was written"
        ));
    }
    Ok(json::scene::UnitQuaternion(v.map(|x| x / n)))
}

impl Builder {
    fn new() -> Builder {
        Builder {
            root: json::Root {
                asset: json::Asset {
                    copyright: None,
                    extensions: None,
                    extras: None,
                    generator: Some(format!("poser {} export", env!("CARGO_PKG_VERSION"))),
                    min_version: None,
                    version: "2.0".into(),
                },
                ..Default::default()
            },
            bin: Vec::new(),
            scene_nodes: Vec::new(),
        }
    }

    /// Append bytes as a buffer view (4-byte aligned).
    fn view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: None,
        })
    }

    fn accessor(
        &mut self,
        view: json::Index<json::buffer::View>,
        count: usize,
        component: json::accessor::ComponentType,
        ty: json::accessor::Type,
        min_max: Option<(Value, Value)>,
    ) -> json::Index<json::Accessor> {
        let (min, max) = match min_max {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A POSITION accessor (glTF frame, f32) with its exact min and max.
    fn positions(
        &mut self,
        pts: &[DVec3],
        what: &str,
    ) -> Result<json::Index<json::Accessor>, String> {
        let mut bytes = Vec::with_capacity(pts.len() * 12);
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for (i, &p) in pts.iter().enumerate() {
            let v = f32x3(to_gltf(p));
            if !v.iter().all(|x| x.is_finite()) {
                return Err(format!(
                    "{what}: vertex {i} is not finite ({p}); nothing was written"
                ));
            }
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
                bytes.extend_from_slice(&v[k].to_le_bytes());
            }
        }
        if pts.is_empty() {
            return Err(format!("{what}: no vertex"));
        }
        let view = self.view(&bytes, Some(json::buffer::Target::ArrayBuffer));
        let mm = |a: [f32; 3]| json!(a.map(f64::from));
        Ok(self.accessor(
            view,
            pts.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            Some((mm(lo), mm(hi))),
        ))
    }

    fn uvs(&mut self, uv: &[[f32; 2]]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = uv
            .iter()
            .flat_map(|t| t.iter().flat_map(|x| x.to_le_bytes()))
            .collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ArrayBuffer));
        self.accessor(
            view,
            uv.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec2,
            None,
        )
    }

    fn indices(&mut self, idx: &[u32]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ElementArrayBuffer));
        self.accessor(
            view,
            idx.len(),
            json::accessor::ComponentType::U32,
            json::accessor::Type::Scalar,
            None,
        )
    }

    /// A triangle primitive of a world-frame (poser) mesh, optionally with UVs.
    fn triangles(
        &mut self,
        mesh: &TriMesh,
        uv: Option<&[[f32; 2]]>,
        material: json::Index<json::Material>,
        what: &str,
    ) -> Result<json::mesh::Primitive, String> {
        let pos = self.positions(&mesh.positions, what)?;
        let mut attributes = BTreeMap::new();
        attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
        if let Some(uv) = uv {
            let t = self.uvs(uv);
            attributes.insert(Checked::Valid(json::mesh::Semantic::TexCoords(0)), t);
        }
        let flat: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let indices = self.indices(&flat);
        Ok(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(material),
            mode: Checked::Valid(json::mesh::Mode::Triangles),
            targets: None,
        })
    }

    /// A line through `pts` (poser world) in order; a single point for one pose.
    fn line_strip(
        &mut self,
        pts: &[DVec3],
        material: json::Index<json::Material>,
        what: &str,
    ) -> Result<json::mesh::Primitive, String> {
        let pos = self.positions(pts, what)?;
        let mut attributes = BTreeMap::new();
        attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
        let mode = if pts.len() >= 2 {
            json::mesh::Mode::LineStrip
        } else {
            json::mesh::Mode::Points
        };
        Ok(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: None,
            material: Some(material),
            mode: Checked::Valid(mode),
            targets: None,
        })
    }

    fn material(
        &mut self,
        name: &str,
        base: [f64; 4],
        look: Look,
        texture: Option<json::Index<json::Texture>>,
        what: &str,
    ) -> Result<json::Index<json::Material>, String> {
        let c = base.map(|x| x as f32);
        if !c.iter().all(|x| x.is_finite()) {
            return Err(format!(
                "{what}: its colour is not finite ({base:?}); nothing was written"
            ));
        }
        let c = c.map(|x| x.clamp(0.0, 1.0));
        let (metal, rough) = match look {
            Look::Glass => (0.0, 0.05),
            _ => (0.0, 1.0),
        };
        let blend = matches!(look, Look::Transparent | Look::Glass);
        let emissive = match look {
            Look::Line => [c[0], c[1], c[2]],
            Look::Emissive(e) => e,
            _ => [0.0; 3],
        };
        Ok(self.root.push(json::Material {
            alpha_mode: Checked::Valid(if blend {
                json::material::AlphaMode::Blend
            } else {
                json::material::AlphaMode::Opaque
            }),
            alpha_cutoff: None,
            double_sided: !matches!(look, Look::Opaque | Look::Emissive(_)),
            name: Some(name.to_string()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(if blend {
                    c
                } else {
                    [c[0], c[1], c[2], 1.0]
                }),
                base_color_texture: texture.map(|index| json::texture::Info {
                    index,
                    tex_coord: 0,
                    extensions: None,
                    extras: None,
                }),
                metallic_factor: json::material::StrengthFactor(metal),
                roughness_factor: json::material::StrengthFactor(rough),
                metallic_roughness_texture: None,
                extensions: None,
                extras: None,
            },
            emissive_factor: json::material::EmissiveFactor(emissive),
            ..Default::default()
        }))
    }

    /// An embedded PNG as a texture (linear filtering, clamped).
    fn png_texture(&mut self, name: &str, png: &[u8]) -> json::Index<json::Texture> {
        let view = self.view(png, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(name.to_string()),
            uri: None,
            extensions: None,
            extras: None,
        });
        let sampler = self.root.push(json::texture::Sampler {
            mag_filter: Some(Checked::Valid(json::texture::MagFilter::Linear)),
            min_filter: Some(Checked::Valid(json::texture::MinFilter::LinearMipmapLinear)),
            wrap_s: Checked::Valid(json::texture::WrappingMode::ClampToEdge),
            wrap_t: Checked::Valid(json::texture::WrappingMode::ClampToEdge),
            ..Default::default()
        });
        self.root.push(json::Texture {
            name: Some(name.to_string()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        })
    }

    fn mesh_node(
        &mut self,
        name: &str,
        primitives: Vec<json::mesh::Primitive>,
        extras: json::Extras,
    ) -> json::Index<json::Node> {
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.to_string()),
            primitives,
            weights: None,
        });
        self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(name.to_string()),
            extras,
            ..Default::default()
        })
    }

    /// A parent node of `children` at the scene's root (nothing when there are none).
    fn group(&mut self, name: &str, children: Vec<json::Index<json::Node>>) {
        if children.is_empty() {
            return;
        }
        let n = self.root.push(json::Node {
            children: Some(children),
            name: Some(name.to_string()),
            ..Default::default()
        });
        self.scene_nodes.push(n);
    }

    fn finish(
        mut self,
        name: &str,
        extras: json::Extras,
        s: &mut Summary,
    ) -> Result<(Vec<u8>, Summary), String> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        if self.bin.len() > u32::MAX as usize - (1 << 20) {
            return Err(format!(
                "the scene's geometry is {} bytes, beyond what one .glb can hold (4 GiB)",
                self.bin.len()
            ));
        }
        self.root.buffers.push(json::Buffer {
            byte_length: USize64(self.bin.len() as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: None,
        });
        let nodes = std::mem::take(&mut self.scene_nodes);
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras,
            name: Some(name.to_string()),
            nodes,
        });
        self.root.scene = Some(scene);
        let lights: &[json::extensions::scene::khr_lights_punctual::Light] = self.root.as_ref();
        if !lights.is_empty() {
            self.root.extensions_used.push("KHR_lights_punctual".into());
        }
        let text = json::serialize::to_vec(&self.root).map_err(|e| e.to_string())?;
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0,
            },
            json: std::borrow::Cow::Owned(text),
            bin: Some(std::borrow::Cow::Owned(self.bin)),
        };
        let bytes = glb.to_vec().map_err(|e| e.to_string())?;
        s.bytes = bytes.len();
        Ok((bytes, std::mem::take(s)))
    }
}

// ------------------------------------------------------------------------------------------
// Targets
// ------------------------------------------------------------------------------------------

fn target_primitives(
    b: &mut Builder,
    t: &crate::model::Target,
    index: usize,
    what: &str,
    triangles: &mut usize,
) -> Result<Vec<json::mesh::Primitive>, String> {
    if let TargetKind::TestObject { diameter, .. } = t.kind {
        // The staircase (white) and a black disk on every corner point, just above its step.
        let steps = crate::geometry::bvh::target_mesh(t);
        let w = targets::WHITE;
        let white = b.material(
            &format!("{} steps", t.name),
            [w, w, w, 1.0],
            Look::Opaque,
            None,
            what,
        )?;
        let k = targets::BLACK;
        let black = b.material(
            &format!("{} disks", t.name),
            [k, k, k, 1.0],
            Look::Opaque,
            None,
            what,
        )?;
        let mut disks = TriMesh::default();
        for (_, p) in targets::local_points(&t.kind) {
            let mut d = tri_mesh(revolve(
                &[(0.0, 0.0), (0.5 * diameter, 0.0)],
                false,
                PORT_SEGMENTS,
            ));
            for q in &mut d.positions {
                *q += p + DVec3::new(0.0, 0.0, 1e-4);
            }
            disks.append(&d);
        }
        let disks = disks.transformed(&t.pose, DVec3::ONE);
        *triangles += steps.triangles.len() + disks.triangles.len();
        return Ok(vec![
            b.triangles(&steps, None, white, what)?,
            b.triangles(&disks, None, black, what)?,
        ]);
    }
    let (w, h) = targets::extent(&t.kind);
    let ppm = TARGET_PX_PER_M.min(TARGET_MAX_PX / w.max(h));
    // The renderers' own pattern (linear reflectance × 255), sRGB-encoded as glTF wants.
    let img = targets::texture(&t.kind, ppm);
    // Power-of-two sides (what mipmaps want everywhere, WebGL 1 included): nearest-neighbour
    // upsampling of the same texels; the UVs span the whole image either way.
    let (pw, ph) = (
        img.width().next_power_of_two(),
        img.height().next_power_of_two(),
    );
    let mut img = if (pw, ph) == img.dimensions() {
        img
    } else {
        upsample_nearest(&img, pw, ph)
    };
    let lut: Vec<u8> = (0..=255u32)
        .map(|v| {
            (crate::sensor::tone(crate::model::ToneCurve::Srgb, v as f64 / 255.0) * 255.0).round()
                as u8
        })
        .collect();
    for px in img.pixels_mut() {
        px.0 = px.0.map(|v| lut[v as usize]);
    }
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| format!("{what}: cannot encode its texture: {e}"))?;
    let tex = b.png_texture(&format!("target {index}: {}", t.name), &png);
    let mat = b.material(&t.name, [1.0; 4], Look::Card, Some(tex), what)?;
    let quad = crate::geometry::mesh::plane(w, h).transformed(&t.pose, DVec3::ONE);
    // `plane` corners: (-x,-y), (+x,-y), (+x,+y), (-x,+y). The texture's row 0 is +y and
    // glTF's v runs down the image: v = 0 at +y.
    let uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    *triangles += quad.triangles.len();
    Ok(vec![b.triangles(&quad, Some(&uv), mat, what)?])
}

// ------------------------------------------------------------------------------------------
// Meshes built here: height fields (surfaces of revolution: `optics::port::revolve`)
// ------------------------------------------------------------------------------------------

/// A `n × n` cell height field over the square `[x0, x0 + size] × [y0, y0 + size]`.
fn grid(x0: f64, y0: f64, size: f64, n: u32, h: impl Fn(f64, f64) -> f64) -> TriMesh {
    let mut m = TriMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let x = x0 + size * i as f64 / n as f64;
            let y = y0 + size * j as f64 / n as f64;
            m.positions.push(DVec3::new(x, y, h(x, y)));
        }
    }
    m.triangulate_grid(n, n);
    m
}

/// A camera's housing port in its camera frame (`None` without a port): the glass shell of
/// [`crate::optics::port::housing_mesh`].
fn port_mesh(cam: &Camera, n_water: f64, what: &str) -> Result<Option<TriMesh>, String> {
    let Some(mesh) = port::housing_mesh(cam, n_water) else {
        return Ok(None);
    };
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err(format!(
            "{what}: its geometry is not finite; nothing was written"
        ));
    }
    Ok(Some(tri_mesh(mesh)))
}

/// The optics' mesh as the geometry's.
fn tri_mesh(m: HousingMesh) -> TriMesh {
    TriMesh {
        positions: m.positions,
        triangles: m.triangles,
    }
}

fn port_json(port: &Port, what: &str) -> Result<Value, String> {
    serde_json::to_value(port).map_err(|e| format!("{what}: {e}"))
}

// ------------------------------------------------------------------------------------------
// Cameras
// ------------------------------------------------------------------------------------------

/// Vertical field of view of a camera from its intrinsics (fy, height) and lens mapping, rad
/// (below π, as glTF requires).
pub fn yfov(cam: &Camera) -> f64 {
    let y = 0.5 * cam.height as f64 / cam.fy;
    let half = match cam.lens {
        LensModel::Rectilinear => y.atan(),
        LensModel::FisheyeEquidistant => y,
        LensModel::FisheyeEquisolid => 2.0 * (0.5 * y).min(1.0).asin(),
    };
    (2.0 * half).min(std::f64::consts::PI * 0.999)
}

fn camera_node(
    b: &mut Builder,
    model: &Model,
    p: usize,
    c: usize,
    cam: &Camera,
) -> Result<json::Index<json::Node>, String> {
    let image = model.image_name(p, c);
    let what = format!("camera `{}` at pose {p} (`{image}`)", cam.name);
    let wfc = model.world_from_camera(p, c);
    let fov = yfov(cam);
    let aspect = cam.width as f64 / cam.height as f64;
    if !(fov.is_finite() && fov > 0.0 && aspect.is_finite() && aspect > 0.0) {
        return Err(format!(
            "{what}: its field of view is not finite (fy {}, height {}); nothing was written",
            cam.fy, cam.height
        ));
    }
    // The vertical field of view in the water: the rays of the top and bottom edge centres
    // through the port.
    let fov_water = crate::optics::project::Projector::for_camera(cam, 1, model.ambient_ior()[1])
        .ok()
        .and_then(|pr| {
            let top = pr.camera_ray(cam.cx, 0.0).ok()?.dir;
            let bottom = pr.camera_ray(cam.cx, cam.height as f64).ok()?.dir;
            let a = top.angle_between(bottom);
            a.is_finite().then_some(a)
        });
    let d = cam.distortion;
    let mut cam_extras = json!({
        "image": image,
        "pose_index": p,
        "camera_index": c,
        "camera": cam.name,
        "width": cam.width,
        "height": cam.height,
        "fx": cam.fx,
        "fy": cam.fy,
        "cx": cam.cx,
        "cy": cam.cy,
        "pixel_convention": "pixel centres at +0.5 (COLMAP's): pixel (i, j) covers [i, i+1] x [j, j+1]; OpenCV's principal point is (cx - 0.5, cy - 0.5)",
        "lens": serde_json::to_value(cam.lens).map_err(|e| e.to_string())?,
        "distortion": {"model": "Brown-Conrady (OpenCV), normalised coordinates", "k1": d.k1, "k2": d.k2, "k3": d.k3, "p1": d.p1, "p2": d.p2},
        "focal_length_m": cam.focal_length,
        "pixel_pitch_m": cam.pixel_pitch,
        "port": port_json(&cam.port, &what)?,
        "yfov_rad": fov,
        "yfov_note": "glTF's yfov is the lens's in air, from fy and the height; it has no principal-point offset, distortion or port",
    });
    if let Some(obj) = cam_extras.as_object_mut() {
        if let Some(f) = cam.focus_distance {
            obj.insert("focus_distance_m".into(), json!(f));
        }
        if let Some(n) = cam.f_number {
            obj.insert("f_number".into(), json!(n));
        }
        if let Some(a) = fov_water {
            obj.insert("yfov_in_water_rad".into(), json!(a));
        }
    }
    let camera = b.root.push(json::Camera {
        name: Some(image.clone()),
        orthographic: None,
        perspective: Some(json::camera::Perspective {
            aspect_ratio: Some(aspect as f32),
            yfov: fov as f32,
            zfar: None,
            znear: ZNEAR as f32,
            extensions: None,
            extras: None,
        }),
        type_: Checked::Valid(json::camera::Type::Perspective),
        extensions: None,
        extras: extras_of(&what, cam_extras)?,
    });
    let r = wfc.rotation;
    let pose = &model.poses[p];
    let node_extras = json!({
        "image": image,
        "pose_index": p,
        "camera_index": c,
        "camera": cam.name,
        "pose_name": pose.name,
        "time_s": pose.time,
        "strip": pose.strip,
        "world_from_camera": {
            "frame": "poser world (x east, y north, z up; metres) from poser camera (OpenCV: x right, y down, z forward): p_world = R p_camera + t",
            "rotation_rows": [r.row(0).to_array(), r.row(1).to_array(), r.row(2).to_array()],
            "translation": wfc.translation.to_array(),
        },
    });
    let translation = finite3(&what, "position", f32x3(to_gltf(wfc.translation)))?;
    let rotation = quat(&what, camera_node_rotation(&wfc))?;
    Ok(b.root.push(json::Node {
        camera: Some(camera),
        name: Some(image),
        translation: Some(translation),
        rotation: Some(rotation),
        extras: extras_of(&what, node_extras)?,
        ..Default::default()
    }))
}

// ------------------------------------------------------------------------------------------
// Lights
// ------------------------------------------------------------------------------------------

fn push_light(
    b: &mut Builder,
    what: &str,
    name: &str,
    kind: json::extensions::scene::khr_lights_punctual::Type,
    rgb: Rgb,
    spot: Option<(f64, f64)>,
    extras: Value,
) -> Result<json::Index<json::extensions::scene::khr_lights_punctual::Light>, String> {
    use json::extensions::scene::khr_lights_punctual as khr;
    let (color, intensity) = photometric(rgb);
    if !(intensity.is_finite() && intensity >= 0.0 && intensity <= f32::MAX as f64) {
        return Err(format!(
            "{what}: its intensity is not finite ({rgb:?}); nothing was written"
        ));
    }
    let light = khr::Light {
        color,
        extensions: None,
        extras: extras_of(what, extras)?,
        intensity: intensity as f32,
        name: Some(name.to_string()),
        range: None,
        spot: spot.map(|(inner, outer)| khr::Spot {
            inner_cone_angle: inner as f32,
            outer_cone_angle: outer as f32,
        }),
        type_: Checked::Valid(kind),
    };
    Ok(b.root.push(light))
}

fn light_node(
    b: &mut Builder,
    what: &str,
    name: &str,
    light: json::Index<json::extensions::scene::khr_lights_punctual::Light>,
    position: DVec3,
    direction: Option<DVec3>,
) -> Result<json::Index<json::Node>, String> {
    let rotation = match direction {
        // A glTF light shines along its node's −z.
        Some(d) => Some(quat(what, z_to(-(GLTF_FROM_POSER * d)))?),
        None => None,
    };
    Ok(b.root.push(json::Node {
        name: Some(name.to_string()),
        translation: Some(finite3(what, "position", f32x3(to_gltf(position)))?),
        rotation,
        extensions: Some(json::extensions::scene::Node {
            khr_lights_punctual: Some(
                json::extensions::scene::khr_lights_punctual::KhrLightsPunctual { light },
            ),
        }),
        ..Default::default()
    }))
}

/// The light nodes, and the ambient lights for the scene's `extras`.
fn lights(
    b: &mut Builder,
    model: &Model,
    bounds: &Bounds,
    s: &mut Summary,
) -> Result<(Vec<json::Index<json::Node>>, Value), String> {
    use json::extensions::scene::khr_lights_punctual::Type;
    let rig = model.poses[REPRESENTATIVE_POSE].world_from_rig;
    let mut nodes = Vec::new();
    let mut ambient = Vec::new();
    for (i, l) in model.lights.iter().enumerate() {
        let what = format!("light `{}`", l.name);
        let mount = match l.mount {
            Mount::Rig => "rig",
            Mount::World => "world",
        };
        match l.in_world(&rig).kind {
            LightKind::Point {
                position,
                intensity,
            } => {
                let extras = json!({
                    "poser_kind": "point", "mount": mount, "pose_index": REPRESENTATIVE_POSE,
                    "intensity_w_per_sr": intensity,
                    "conversion": "candela = 683 lm/W * max channel (W/sr); color = channels / max",
                });
                let li = push_light(b, &what, &l.name, Type::Point, intensity, None, extras)?;
                nodes.push(light_node(b, &what, &l.name, li, position, None)?);
                s.lights += 1;
            }
            LightKind::Spot {
                position,
                direction,
                half_angle,
                intensity,
            } => {
                let outer = half_angle.min(std::f64::consts::FRAC_PI_2);
                if half_angle > outer {
                    s.approximated.push(format!(
                        "spot light `{}`: its {:.1}° half-angle is cut to 90° (KHR_lights_punctual's widest cone)",
                        l.name,
                        half_angle.to_degrees()
                    ));
                }
                // poser's spot has a sharp edge: the falloff is kept to the last 1 % of the cone.
                let inner = 0.99 * outer;
                let extras = json!({
                    "poser_kind": "spot", "mount": mount, "pose_index": REPRESENTATIVE_POSE,
                    "intensity_w_per_sr": intensity, "half_angle_rad": half_angle,
                    "conversion": "candela = 683 lm/W * max channel (W/sr); color = channels / max; poser's cone is sharp: inner = 0.99 outer",
                });
                let li = push_light(
                    b,
                    &what,
                    &l.name,
                    Type::Spot,
                    intensity,
                    Some((inner, outer)),
                    extras,
                )?;
                let d = direction;
                if !(d.is_finite() && d.length() > 0.0) {
                    return Err(format!(
                        "{what}: its direction is not finite; nothing was written"
                    ));
                }
                nodes.push(light_node(b, &what, &l.name, li, position, Some(d))?);
                s.lights += 1;
            }
            LightKind::Area {
                frame,
                width,
                height,
                radiance,
            } => {
                let mesh =
                    crate::geometry::mesh::plane(width, height).transformed(&frame, DVec3::ONE);
                let (color, _) = photometric(radiance);
                let name = format!("area light {} (emissive)", l.name);
                let mat = b.material(
                    &name,
                    [0.0, 0.0, 0.0, 1.0],
                    Look::Emissive(color),
                    None,
                    &what,
                )?;
                let prim = b.triangles(&mesh, None, mat, &what)?;
                s.triangles += mesh.triangles.len();
                let extras = json!({
                    "poser_kind": "area", "mount": mount, "pose_index": REPRESENTATIVE_POSE,
                    "radiance_w_per_m2_sr": radiance, "width_m": width, "height_m": height,
                    "emits_along": "the rectangle's normal (one-sided)",
                    "approximated": "glTF has no area light: an emissive rectangle (it lights nothing in a viewer)",
                });
                nodes.push(b.mesh_node(&name, vec![prim], extras_of(&what, extras)?));
                s.approximated.push(format!(
                    "area light `{}`: an emissive rectangle `{name}` (glTF has no area light)",
                    l.name
                ));
            }
            LightKind::Ambient { radiance } => {
                ambient.push(json!({
                    "name": l.name, "index": i, "radiance_w_per_m2_sr": radiance,
                }));
                s.approximated.push(format!(
                    "ambient light `{}`: the scene's extras.ambient (glTF has no ambient light)",
                    l.name
                ));
            }
        }
    }
    if let Some(sun) = &model.sun {
        // The direction and irradiance the model lights the scene with (the native renderer's
        // rule): refracted into the water when there is water, else as in air.
        let (dir, e, refracted) = if model.water.is_some() {
            (sun.direction_water, sun.irradiance_water, true)
        } else {
            (sun.direction_air, sun.irradiance, false)
        };
        let what = "the sun".to_string();
        if !(dir.is_finite() && e.iter().all(|x| x.is_finite())) {
            return Err(format!(
                "{what}: its direction or irradiance is not finite; nothing was written"
            ));
        }
        if dir.z < 0.0 {
            let extras = json!({
                "poser_kind": "sun",
                "refracted": refracted,
                "elevation_rad": sun.elevation, "azimuth_rad": sun.azimuth,
                "direction_air": sun.direction_air.to_array(),
                "direction_water": sun.direction_water.to_array(),
                "irradiance_air_w_per_m2": sun.irradiance,
                "irradiance_water_w_per_m2": sun.irradiance_water,
                "conversion": "lux = 683 lm/W * max channel (W/m2) of the irradiance used; color = channels / max",
            });
            let li = push_light(b, &what, "sun", Type::Directional, e, None, extras)?;
            let top = bounds.get().map_or(DVec3::ZERO, |(lo, hi)| {
                DVec3::new(
                    0.5 * (lo.x + hi.x),
                    0.5 * (lo.y + hi.y),
                    hi.z.max(0.0) + 1.0,
                )
            });
            nodes.push(light_node(b, &what, "sun", li, top, Some(dir))?);
            s.lights += 1;
        }
    }
    Ok((nodes, Value::Array(ambient)))
}

/// `image::imageops::resize(img, width, height, FilterType::Nearest)`, pixel for pixel, without
/// its filtering passes (through `f32` RGBA, a weight per pixel: 59% of exporting
/// uav_through_waves): its Nearest reads the one source pixel under each output pixel's
/// centre, `⌊(o + ½)·ratio⌋` in `f32`, clamped, and its weight of 1 keeps the 8-bit values.
fn upsample_nearest(img: &image::RgbImage, width: u32, height: u32) -> image::RgbImage {
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 {
        return image::RgbImage::new(width, height);
    }
    let index = |n: u32, new: u32| -> Vec<u32> {
        let ratio = n as f32 / new as f32;
        (0..new)
            .map(|o| (((o as f32 + 0.5) * ratio).floor() as i64).clamp(0, n as i64 - 1) as u32)
            .collect()
    };
    let (xs, ys) = (index(w, width), index(h, height));
    image::RgbImage::from_fn(width, height, |x, y| {
        *img.get_pixel(xs[x as usize], ys[y as usize])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upsample_nearest_is_the_image_crates_nearest_resize() {
        for (w, h, pw, ph) in [
            (3, 5, 4, 8),
            (37, 23, 64, 32),
            (100, 1, 128, 1),
            (5, 5, 5, 8),
            (700, 300, 1024, 512),
        ] {
            let img = image::RgbImage::from_fn(w, h, |x, y| {
                image::Rgb([(x * 7 + y * 13) as u8, (x * y) as u8, (x ^ y) as u8])
            });
            let want = image::imageops::resize(&img, pw, ph, image::imageops::FilterType::Nearest);
            assert_eq!(upsample_nearest(&img, pw, ph), want, "{w}x{h} -> {pw}x{ph}");
        }
    }

    #[test]
    fn axes_round_trip_with_the_importer() {
        // load_gltf maps (x, y, z)_glTF → (x, −z, y)_poser; to_gltf is its inverse.
        let p = DVec3::new(1.0, 2.0, 3.0);
        let g = to_gltf(p);
        assert_eq!(DVec3::new(g.x, -g.z, g.y), p);
        assert_eq!(GLTF_FROM_POSER * p, g);
        assert!((GLTF_FROM_POSER.determinant() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn camera_axes_map_to_gltf_conventions() {
        // A camera looking straight down (poser −z) with image x east, image y south.
        let r = DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z);
        let pose = Pose {
            rotation: r,
            translation: DVec3::ZERO,
        };
        let m = camera_node_rotation(&pose);
        // glTF camera −z (its view direction) is down in glTF (−y); +y (up in the image) is
        // north in poser = −z in glTF.
        assert!((m * -DVec3::Z - -DVec3::Y).length() < 1e-12);
        assert!((m * DVec3::Y - -DVec3::Z).length() < 1e-12);
        assert!((m * DVec3::X - DVec3::X).length() < 1e-12);
    }

    #[test]
    fn photometric_keeps_the_channel_ratios() {
        let (c, i) = photometric([2.0, 1.0, 0.5]);
        assert_eq!(c, [1.0, 0.5, 0.25]);
        assert_eq!(i, 683.0 * 2.0);
        assert_eq!(photometric([0.0; 3]).1, 0.0);
    }

    #[test]
    fn revolve_closes_a_disc_and_a_tube() {
        let disc = tri_mesh(revolve(
            &[(0.0, 0.0), (1.0, 0.0), (1.0, 0.1), (0.0, 0.1)],
            false,
            16,
        ));
        assert_eq!(disc.positions.len(), 2 + 2 * 16);
        assert_eq!(disc.triangles.len(), 16 + 2 * 16 + 16);
        let tube = tri_mesh(revolve(
            &[(1.0, -1.0), (1.1, -1.0), (1.1, 1.0), (1.0, 1.0)],
            true,
            16,
        ));
        assert_eq!(tube.triangles.len(), 4 * 2 * 16);
        // Every triangle is proper.
        for m in [&disc, &tube] {
            for i in 0..m.triangles.len() {
                assert!(m.face_normal(i).length() > 0.5);
            }
        }
    }

    #[test]
    fn extras_refuse_non_finite_numbers() {
        let e = extras_of("camera `a`", json!({"fx": f64::NAN})).unwrap_err();
        assert!(e.contains("`fx`"), "{e}");
        assert!(extras_of("x", json!({"fx": 1.5})).unwrap().is_some());
    }
}
