//! `poser export SCENE -o scene.glb` (plain tier: no Python, no node): every shipped scenario
//! and lesson is exported by the built binary into a temporary folder and read back with the
//! `gltf` crate, then checked against the model loaded with `poser::scene::load`:
//!
//! | check | what |
//! |---|---|
//! | cameras | one camera node per rig pose × camera; extras fx, fy, cx, cy, width, height and the f64 pose equal the model's exactly; `yfov` and `aspectRatio` from the intrinsics |
//! | centre ray | a world point on the camera's optical axis (and, for a centred port, the point poser projects to the principal point) lies on the node's −Z axis; image right is node +X, image down node −Y |
//! | geometry | one site mesh per object with the vertices of `object_mesh` (axis-converted), one mesh per target with its texture, one port mesh per housed camera, the water surface iff the model has one; every POSITION finite and inside its accessor's min/max |
//! | path | a `LINE_STRIP` with one vertex per rig pose, at the rig positions |
//! | lights | `KHR_lights_punctual` count = point + spot + sun; area lights as emissive meshes and ambient lights in the scene's extras, listed as approximated |
//! | writing | no temporary file left beside the output; a bad scene exits 1 with a located diagnostic and writes nothing; a non-finite model value is refused |

use glam::{DMat4, DVec3};
use poser::model::{LightKind, Model, Port};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn scenarios() -> Vec<PathBuf> {
    support::shipped_scenes()
}

fn export(scene: &Path, out: &Path) -> std::process::Output {
    export_with(scene, &[], out)
}

/// `poser export SCENE --set …` into `out`.
fn export_with(scene: &Path, sets: &[String], out: &Path) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_poser"));
    cmd.arg("export").arg(scene).arg("-o").arg(out);
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    cmd.current_dir(root()).output().expect("run poser")
}

fn extras(e: &gltf::json::Extras) -> serde_json::Value {
    serde_json::from_str(e.as_ref().expect("extras").get()).unwrap()
}

type Raw = Box<gltf::json::extras::RawValue>;

/// The members of a JSON object, unparsed.
fn members(text: &str) -> std::collections::BTreeMap<String, Raw> {
    serde_json::from_str(text).unwrap()
}

/// A JSON number parsed exactly from its text (serde_json's default float parsing may be one
/// ulp off; Rust's `str::parse` rounds correctly, as the writer's shortest form needs).
fn exact(raw: &Raw) -> f64 {
    raw.get().trim().parse().unwrap()
}

fn exact_array(raw: &Raw) -> Vec<f64> {
    let items: Vec<Raw> = serde_json::from_str(raw.get()).unwrap();
    items.iter().map(exact).collect()
}

fn to_gltf(p: DVec3) -> DVec3 {
    DVec3::new(p.x, p.z, -p.y)
}

/// Global transform of every node (f64 from the file's f32 values).
fn globals(doc: &gltf::Document) -> Vec<DMat4> {
    let mut out = vec![DMat4::IDENTITY; doc.nodes().count()];
    let mut stack: Vec<(gltf::Node, DMat4)> = doc
        .default_scene()
        .unwrap()
        .nodes()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    while let Some((n, parent)) = stack.pop() {
        let m = n.transform().matrix();
        let g = parent * DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)));
        out[n.index()] = g;
        for k in n.children() {
            stack.push((k, g));
        }
    }
    out
}

/// The node named `name` at the scene's top level, and its children.
fn group<'a>(doc: &'a gltf::Document, name: &str) -> Vec<gltf::Node<'a>> {
    doc.default_scene()
        .unwrap()
        .nodes()
        .find(|n| n.name() == Some(name))
        .map(|n| n.children().collect())
        .unwrap_or_default()
}

fn positions(prim: &gltf::Primitive, buffers: &[gltf::buffer::Data]) -> Vec<[f32; 3]> {
    prim.reader(|b| Some(&buffers[b.index()].0[..]))
        .read_positions()
        .expect("POSITION")
        .collect()
}

/// Returns how many principal-point rays were checked.
fn check_scenario(scene: &Path, glb: &Path) -> usize {
    check_scenario_with(scene, &[], glb)
}

fn check_scenario_with(scene: &Path, sets: &[String], glb: &Path) -> usize {
    let name = scene.file_name().unwrap().to_string_lossy().to_string();
    let model: Model = poser::scene::load(scene, sets)
        .unwrap_or_else(|f| panic!("{name}: {}", f.render()))
        .model;
    let bytes = std::fs::read(glb).unwrap();
    let (doc, buffers, images) =
        gltf::import_slice(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
    let g = globals(&doc);
    let mut centre_rays = 0;

    // Every POSITION finite and inside its accessor's bounds.
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let acc = prim.get(&gltf::Semantic::Positions).unwrap();
            let lo: Vec<f64> = serde_json::from_value(acc.min().expect("min")).unwrap();
            let hi: Vec<f64> = serde_json::from_value(acc.max().expect("max")).unwrap();
            let mut seen = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for p in positions(&prim, &buffers) {
                assert!(p.iter().all(|x| x.is_finite()), "{name}: {p:?}");
                for (k, v) in p.into_iter().enumerate() {
                    seen.0[k] = seen.0[k].min(v);
                    seen.1[k] = seen.1[k].max(v);
                }
            }
            // The bounds are f32 values written as their shortest f64 text.
            for k in 0..3 {
                assert_eq!(
                    seen.0[k],
                    lo[k] as f32,
                    "{name}: mesh {:?} min",
                    mesh.name()
                );
                assert_eq!(
                    seen.1[k],
                    hi[k] as f32,
                    "{name}: mesh {:?} max",
                    mesh.name()
                );
            }
        }
    }

    // Site: one mesh per object, with the vertices the geometry service makes.
    let base = Path::new(&model.source).parent().unwrap().to_path_buf();
    let site = group(&doc, "site");
    let meshes: Vec<_> = model
        .objects
        .iter()
        .map(|o| poser::geometry::mesh::object_mesh(o, &base).unwrap())
        .filter(|m| !m.triangles.is_empty())
        .collect();
    assert_eq!(site.len(), meshes.len(), "{name}: site meshes");
    for (node, m) in site.iter().zip(&meshes) {
        let prim = node.mesh().unwrap().primitives().next().unwrap();
        let pos = positions(&prim, &buffers);
        assert_eq!(pos.len(), m.positions.len(), "{name}: {:?}", node.name());
        let k = pos.len() / 2;
        let want = to_gltf(m.positions[k]).as_vec3().to_array();
        assert_eq!(pos[k], want, "{name}: vertex {k} of {:?}", node.name());
        let base_colour = prim.material().pbr_metallic_roughness().base_color_factor();
        let o = model
            .objects
            .iter()
            .find(|o| Some(o.name.as_str()) == node.name())
            .unwrap();
        assert_eq!(base_colour[0], o.material.albedo[0] as f32, "{name}");
        assert_eq!(
            prim.material().pbr_metallic_roughness().metallic_factor(),
            0.0
        );
        assert_eq!(
            prim.material().pbr_metallic_roughness().roughness_factor(),
            1.0
        );
    }

    // Targets: one mesh each; printed faces carry their pattern as a decodable texture.
    let tnodes = group(&doc, "targets");
    assert_eq!(tnodes.len(), model.targets.len(), "{name}: targets");
    for (node, t) in tnodes.iter().zip(&model.targets) {
        assert_eq!(node.name(), Some(t.name.as_str()));
        let prim = node.mesh().unwrap().primitives().next().unwrap();
        if matches!(t.kind, poser::model::TargetKind::TestObject { .. }) {
            continue;
        }
        let info = prim
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap_or_else(|| panic!("{name}: target `{}` has no texture", t.name));
        let img = &images[info.texture().source().index()];
        assert!(img.width >= 2 && img.height >= 2);
        // Ink and paper (reflectance 0.05 and 0.9), sRGB-encoded as glTF base colours are:
        // 64 and 243 of 255.
        let srgb = |x: f64| 255.0 * (1.055 * x.powf(1.0 / 2.4) - 0.055);
        let px: Vec<u8> = img.pixels.chunks(3).map(|c| c[0]).collect();
        let (lo, hi) = (*px.iter().min().unwrap(), *px.iter().max().unwrap());
        assert!(
            (lo as f64 - srgb(0.05)).abs() <= 1.5 && (hi as f64 - srgb(0.9)).abs() <= 1.5,
            "{name}: target `{}`: texture levels {lo}..{hi}",
            t.name
        );
        assert!(prim.get(&gltf::Semantic::TexCoords(0)).is_some());
    }

    // Water surface iff the model has one; a port mesh per housed camera.
    let water = doc
        .default_scene()
        .unwrap()
        .nodes()
        .any(|n| n.name() == Some("water surface"));
    assert_eq!(
        water,
        model.sea_interface(1).is_some(),
        "{name}: water surface"
    );
    if water {
        let m = doc
            .materials()
            .find(|m| m.name() == Some("water surface"))
            .unwrap();
        assert_eq!(m.alpha_mode(), gltf::material::AlphaMode::Blend);
    }
    let housed = model
        .cameras
        .iter()
        .filter(|c| !matches!(c.port, Port::None))
        .count();
    assert_eq!(group(&doc, "ports").len(), housed, "{name}: ports");

    // Cameras: one node per image.
    let cams = group(&doc, "cameras");
    let n = model.poses.len() * model.cameras.len();
    assert_eq!(cams.len(), n, "{name}: camera nodes");
    assert_eq!(doc.cameras().count(), n, "{name}: cameras");
    let picks: Vec<usize> = [0, n / 2, n - 1].into_iter().collect();
    for (i, node) in cams.iter().enumerate() {
        let (p, c) = (i / model.cameras.len(), i % model.cameras.len());
        assert_eq!(node.name(), Some(model.image_name(p, c).as_str()));
        let cam = &model.cameras[c];
        let camera = node.camera().unwrap();
        let gltf::camera::Projection::Perspective(persp) = camera.projection() else {
            panic!("{name}: not a perspective camera");
        };
        assert_eq!(
            persp.aspect_ratio(),
            Some((cam.width as f64 / cam.height as f64) as f32)
        );
        if cam.lens == poser::model::LensModel::Rectilinear {
            let want = 2.0 * (0.5 * cam.height as f64 / cam.fy).atan();
            assert_eq!(persp.yfov(), want as f32, "{name}: yfov");
        }
        assert!(persp.znear() > 0.0 && persp.znear() <= 0.05);
        if !picks.contains(&i) {
            continue;
        }
        // Exact intrinsics and pose in the extras.
        let e = extras(camera.extras());
        let raw = members(camera.extras().as_ref().unwrap().get());
        for (k, v) in [
            ("fx", cam.fx),
            ("fy", cam.fy),
            ("cx", cam.cx),
            ("cy", cam.cy),
        ] {
            assert_eq!(exact(&raw[k]), v, "{name}: {k}");
        }
        assert_eq!(e["width"].as_u64(), Some(cam.width as u64));
        assert_eq!(e["height"].as_u64(), Some(cam.height as u64));
        assert_eq!(e["pose_index"].as_u64(), Some(p as u64));
        assert_eq!(e["camera"].as_str(), Some(cam.name.as_str()));
        assert_eq!(e["port"]["kind"].as_str(), Some(cam.port.kind_name()));
        assert!(e["pixel_convention"].as_str().unwrap().contains("+0.5"));
        let wfc = model.world_from_camera(p, c);
        let ne = members(node.extras().as_ref().unwrap().get());
        assert_eq!(exact(&ne["pose_index"]), p as f64);
        let pose = members(ne["world_from_camera"].get());
        let t = exact_array(&pose["translation"]);
        assert_eq!(
            t,
            wfc.translation.to_array().to_vec(),
            "{name}: translation"
        );
        let rows: Vec<Raw> = serde_json::from_str(pose["rotation_rows"].get()).unwrap();
        assert_eq!(rows.len(), 3);
        for (k, row) in rows.iter().enumerate() {
            assert_eq!(
                exact_array(row),
                wfc.rotation.row(k).to_array().to_vec(),
                "{name}: rotation row {k}"
            );
        }

        // The optical axis, image right and image down, through the node's frame.
        let local_of = |p_cam: DVec3| {
            let w = wfc.transform_point(p_cam);
            g[node.index()].inverse().transform_point3(to_gltf(w))
        };
        let scale = 1.0 + wfc.translation.length();
        let tol = 1e-5 * scale;
        let d = 2.0;
        let a = local_of(DVec3::new(0.0, 0.0, d));
        assert!(
            a.x.abs() < tol && a.y.abs() < tol && (a.z + d).abs() < tol,
            "{name}: image {i}: the optical axis point is at {a} in the glTF camera frame"
        );
        let r = local_of(DVec3::new(0.1, 0.0, d));
        assert!(
            (r.x - 0.1).abs() < tol && r.y.abs() < tol,
            "{name}: right → {r}"
        );
        let dn = local_of(DVec3::new(0.0, 0.1, d));
        assert!(
            (dn.y + 0.1).abs() < tol && dn.x.abs() < tol,
            "{name}: down → {dn}"
        );
        // With a centred port, the point poser images at the principal point is on −Z too.
        let centred = match &cam.port {
            Port::None => true,
            Port::Flat { normal, .. } => (*normal - DVec3::Z).length() < 1e-12,
            Port::Dome { center, .. } => center.x == 0.0 && center.y == 0.0,
            Port::Cylinder { .. } => false,
        };
        if centred
            && model
                .sea_interface(1)
                .is_none_or(|_| !model.above_surface(p, c))
        {
            let pr = model.projector(c, 1).unwrap();
            let (o, dir, _) = pr.pixel_ray_world(p, cam.cx, cam.cy).unwrap();
            let w = o + dir * d;
            let px = pr.project_world(p, w).unwrap();
            assert!(
                (px[0] - cam.cx).abs() < 1e-6 && (px[1] - cam.cy).abs() < 1e-6,
                "{name}: {px:?}"
            );
            centre_rays += 1;
            let q = g[node.index()].inverse().transform_point3(to_gltf(w));
            let off = q.x.hypot(q.y);
            assert!(
                q.z < 0.0 && off < tol + 1e-9 * q.z.abs(),
                "{name}: image {i}: the principal point's world point is {off} m off the node's −Z axis ({q})"
            );
        }
    }

    // Swim path: one vertex per rig pose, in order.
    let path = doc
        .meshes()
        .find(|m| m.name() == Some("swim path"))
        .unwrap();
    let prim = path.primitives().next().unwrap();
    let want_mode = if model.poses.len() >= 2 {
        gltf::mesh::Mode::LineStrip
    } else {
        gltf::mesh::Mode::Points
    };
    assert_eq!(prim.mode(), want_mode, "{name}");
    let pts = positions(&prim, &buffers);
    assert_eq!(pts.len(), model.poses.len(), "{name}: path vertices");
    for (k, pose) in model.poses.iter().enumerate().step_by(7) {
        let want = to_gltf(pose.world_from_rig.translation)
            .as_vec3()
            .to_array();
        assert_eq!(pts[k], want, "{name}: path vertex {k}");
    }

    // Lights.
    let punctual = model
        .lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Point { .. } | LightKind::Spot { .. }))
        .count()
        + model.sun.as_ref().map_or(0, |s| {
            let d = if model.water.is_some() {
                s.direction_water
            } else {
                s.direction_air
            };
            usize::from(d.z < 0.0)
        });
    let lights = doc.lights().map_or(0, |l| l.count());
    assert_eq!(lights, punctual, "{name}: lights");
    for node in group(&doc, "lights") {
        let Some(light) = node.light() else { continue };
        assert!(light.intensity().is_finite() && light.intensity() >= 0.0);
        if let gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = light.kind()
        {
            assert!(0.0 <= inner_cone_angle && inner_cone_angle < outer_cone_angle);
            assert!(outer_cone_angle <= std::f32::consts::FRAC_PI_2);
        }
    }
    let se = extras(doc.default_scene().unwrap().extras());
    let ambient = model
        .lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Ambient { .. }))
        .count();
    let area = model
        .lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Area { .. }))
        .count();
    assert_eq!(se["ambient"].as_array().unwrap().len(), ambient, "{name}");
    assert_eq!(
        se["approximated"].as_array().unwrap().len(),
        ambient + area,
        "{name}"
    );
    let emissive = doc
        .meshes()
        .filter(|m| m.name().is_some_and(|n| n.starts_with("area light ")))
        .count();
    assert_eq!(emissive, area, "{name}: emissive area lights");
    centre_rays
}

#[test]
fn every_scenario_exports_and_reads_back_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let list = scenarios();
    let mut names = Vec::new();
    let mut centre_rays = 0;
    for scene in &list {
        let stem = scene.file_stem().unwrap().to_string_lossy().to_string();
        let glb = tmp.path().join(format!("{stem}.glb"));
        let o = export(scene, &glb);
        assert!(
            o.status.success(),
            "poser export {} failed:\n{}",
            scene.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("wrote ") && err.contains("camera(s)"), "{err}");
        let model = poser::scene::load(scene, &[]).ok().unwrap().model;
        if model
            .lights
            .iter()
            .any(|l| matches!(l.kind, LightKind::Ambient { .. } | LightKind::Area { .. }))
        {
            assert!(err.contains("approximated:"), "{}: {err}", scene.display());
        }
        names.push(format!("{stem}.glb"));
        centre_rays += check_scenario(scene, &glb);
    }
    assert!(
        centre_rays >= 10,
        "only {centre_rays} principal-point rays checked"
    );
    // Written atomically: nothing but the outputs in the folder (no temporary file left).
    let mut found: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    found.sort();
    names.sort();
    assert_eq!(found, names);
}

#[test]
fn rewriting_replaces_the_file_atomically() {
    let tmp = tempfile::tempdir().unwrap();
    let glb = tmp.path().join("sub/scene.glb");
    let scene = root().join("scenarios/calibration_flat.toml");
    assert!(export(&scene, &glb).status.success());
    let first = std::fs::read(&glb).unwrap();
    std::fs::write(&glb, b"old").unwrap();
    assert!(export(&scene, &glb).status.success());
    assert_eq!(std::fs::read(&glb).unwrap(), first, "deterministic bytes");
    let names: Vec<_> = std::fs::read_dir(glb.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("scene.glb")]);
}

#[test]
fn a_bad_scene_exits_1_with_a_located_diagnostic_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("bad.toml");
    let base = root().join("tests/invalid/shared/base.toml");
    std::fs::write(
        &scene,
        format!(
            "include = [{:?}]\n[[objects]]\nshape = \"plane\"\nposition = [0, 0, -5]\nalbedo = 1.5\n",
            base.to_string_lossy()
        ),
    )
    .unwrap();
    let glb = tmp.path().join("bad.glb");
    let o = export(&scene, &glb);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("bad.toml:5:10"),
        "no file:line:column in:\n{err}"
    );
    assert!(err.contains("help:"), "{err}");
    assert!(!glb.exists());
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "{left:?}");
}

#[test]
fn a_non_finite_value_is_refused_by_name() {
    let scene = root().join("scenarios/calibration_flat.toml");
    let model = poser::scene::load(&scene, &[]).ok().unwrap().model;
    assert!(poser::export::gltf::export(&model).is_ok());
    let mut bad = model.clone();
    bad.cameras[0].fx = f64::NAN;
    let e = poser::export::gltf::export(&bad).unwrap_err();
    assert!(e.contains("`fx`") && e.contains("not a finite"), "{e}");
    let mut bad = model.clone();
    bad.poses[1].world_from_rig.translation.y = f64::INFINITY;
    let e = poser::export::gltf::export(&bad).unwrap_err();
    assert!(e.contains("not") && e.contains("finite"), "{e}");
    let mut bad = model;
    bad.objects[0].pose.translation.x = f64::NAN;
    let e = poser::export::gltf::export(&bad).unwrap_err();
    assert!(e.contains("finite"), "{e}");
}

/// A scene with every light kind (rig-mounted point and spot, a world area light, an ambient
/// light, the sun through a flat surface), exported with each port kind.
#[test]
fn every_light_and_port_kind() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("lights.toml");
    let base = root().join("tests/invalid/shared/base.toml");
    std::fs::write(
        &scene,
        format!(
            "include = [{:?}]\n\
             [sun]\nelevation = \"50 deg\"\nazimuth = \"120 deg\"\n\
             [[lights]]\ntype = \"point\"\nname = \"torch\"\nposition = [0.1, 0, 0]\nintensity = [2, 1, 0.5]\n\
             [[lights]]\ntype = \"spot\"\nname = \"strobe\"\nposition = [0.2, 0, 0]\naim = [0, 1, 1]\nbeam_angle = \"100 deg\"\n\
             [[lights]]\ntype = \"area\"\nname = \"panel\"\nposition = [0, 0, -1]\nwidth = 1\nheight = 0.5\n\
             [[lights]]\ntype = \"ambient\"\nname = \"sky\"\nradiance = 0.05\n\
             [[objects]]\nname = \"floor\"\nshape = \"plane\"\nwidth = 4\nheight = 4\nposition = [0, 0, -5]\n",
            base.to_string_lossy()
        ),
    )
    .unwrap();
    let cases: [&[&str]; 4] = [
        &[],
        &["camera.port.type=dome", "camera.port.inner_radius=0.05"],
        &["camera.port.type=cylinder", "camera.port.inner_radius=0.06"],
        &["camera.port.type=flat", "camera.port.tilt=5 deg"],
    ];
    for (k, sets) in cases.iter().enumerate() {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let glb = tmp.path().join(format!("lights-{k}.glb"));
        let o = export_with(&scene, &sets, &glb);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{sets:?}: {err}");
        assert!(
            err.contains("approximated:")
                && err.contains("area light `panel`")
                && err.contains("ambient light `sky`"),
            "{err}"
        );
        check_scenario_with(&scene, &sets, &glb);

        let model = poser::scene::load(&scene, &sets).ok().unwrap().model;
        let bytes = std::fs::read(&glb).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let g = globals(&doc);
        let lights = group(&doc, "lights");
        let by_name = |n: &str| lights.iter().find(|x| x.name() == Some(n)).unwrap();
        let down = |node: &gltf::Node| g[node.index()].transform_vector3(DVec3::NEG_Z).normalize();
        // The point light: candela = 683 lm/W × the largest channel, colour = the ratios.
        let torch = by_name("torch").light().unwrap();
        assert_eq!(torch.intensity(), (683.0 * 2.0) as f32);
        assert_eq!(torch.color(), [1.0, 0.5, 0.25]);
        let rig = model.poses[0].world_from_rig;
        let at = g[by_name("torch").index()].transform_point3(DVec3::ZERO);
        let want = to_gltf(rig.transform_point(DVec3::new(0.1, 0.0, 0.0)));
        assert!((at - want).length() < 1e-5, "{at} {want}");
        // The spot: its cone and its direction (the rig's aim, in the world, then glTF).
        let strobe = by_name("strobe");
        let gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = strobe.light().unwrap().kind()
        else {
            panic!("not a spot")
        };
        assert_eq!(outer_cone_angle, 50f64.to_radians() as f32);
        assert!(inner_cone_angle < outer_cone_angle && inner_cone_angle > 0.9 * outer_cone_angle);
        let aim = to_gltf(rig.transform_vector(DVec3::new(0.0, 1.0, 1.0).normalize()));
        assert!(
            (down(strobe) - aim).length() < 1e-6,
            "{} {aim}",
            down(strobe)
        );
        // The sun: directional, along the refracted direction the model lights the water with.
        let sun = by_name("sun");
        assert!(matches!(
            sun.light().unwrap().kind(),
            gltf::khr_lights_punctual::Kind::Directional
        ));
        let s = model.sun.as_ref().unwrap();
        let want = to_gltf(s.direction_water);
        assert!((down(sun) - want).length() < 1e-6, "{} {want}", down(sun));
        assert!(
            (s.direction_water - s.direction_air).length() > 1e-3,
            "refracted"
        );
        let lux = 683.0 * s.irradiance_water.iter().cloned().fold(0.0, f64::max);
        assert_eq!(sun.light().unwrap().intensity(), lux as f32);
        // The area light: an emissive rectangle of its size where the model puts it.
        let panel = doc
            .meshes()
            .find(|m| m.name() == Some("area light panel (emissive)"))
            .unwrap();
        let prim = panel.primitives().next().unwrap();
        assert_eq!(prim.material().emissive_factor(), [1.0; 3]);
        let pts = positions(&prim, &buffers);
        assert_eq!(pts.len(), 4);
        let y: Vec<f32> = pts.iter().map(|p| p[1]).collect();
        assert!(y.iter().all(|v| (*v - -1.0).abs() < 1e-6), "{y:?}");
        // The port mesh: in front of the camera (pose 0), within a few port radii.
        let port = group(&doc, "ports");
        assert_eq!(port.len(), 1);
        let prim = port[0].mesh().unwrap().primitives().next().unwrap();
        let cam = model.world_from_camera(0, 0);
        let kind = model.cameras[0].port.kind_name();
        for p in positions(&prim, &buffers) {
            let w = DVec3::new(p[0] as f64, -(p[2] as f64), p[1] as f64);
            let local = cam.inverse().transform_point(w);
            assert!(local.length() < 0.5, "{kind}: port vertex {local}");
            if kind == "flat" || kind == "dome" {
                assert!(
                    local.z > -1e-6,
                    "{kind}: port vertex behind the pupil {local}"
                );
            }
        }
        let e = extras(port[0].extras());
        assert_eq!(e["port"]["kind"].as_str(), Some(kind));
        assert_eq!(kind, ["flat", "dome", "cylinder", "flat"][k]);
    }
}
