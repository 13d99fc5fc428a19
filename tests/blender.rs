//! Blender backend: generated scripts are data-only, and Cycles renders agree with analytic
//! truth (projection and radiometry). Renders are 160×120 with the real `bpy`.

use crate::support;

use glam::DVec3;
use poser::backend::RenderOptions;
use poser::compare::LinearImage;
use poser::model::*;
use std::path::Path;
use support::blender::*;

fn render(model: &Model, out: &Path, samples: u32) -> LinearImage {
    require_bpy();
    let opts = RenderOptions {
        samples: Some(samples),
        poses: None,
        progress: false,
        resume: false,
    };
    let report = poser::backend::blender::render(model, out, &opts).expect("Cycles render");
    assert_eq!(report.images.len(), 1);
    assert!(out.join("img_0001.png").exists(), "PNG preview written");
    LinearImage::read(&report.images[0]).expect("EXR readable")
}

/// Pixel centre (u, v) → ray in the camera frame.
fn pixel_ray(cam: &Camera, u: f64, v: f64) -> DVec3 {
    DVec3::new((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0).normalize()
}

#[test]
fn pinhole_centroid_matches_projection() {
    // A black square (albedo 0) on a white sky (ambient radiance 1) in air, fronto-parallel,
    // off-centre, with an off-centre principal point: the projection of a fronto-parallel
    // square is a similarity, so its intensity centroid is the projection of its centre.
    let centre = DVec3::new(0.31, -0.17, 0.0);
    let mut patch = plane("patch", 0.0, 0.4, [0.0; 3]);
    patch.pose.translation = centre;
    let cam = camera("cam", Port::None);
    let position = DVec3::new(0.05, 0.02, 3.0);
    let m = model(
        "pinhole",
        cam.clone(),
        position,
        None,
        vec![ambient(1.0)],
        vec![patch],
    );
    let dir = tempfile::tempdir().unwrap();
    let img = render(&m, dir.path(), 256);
    let (mut sw, mut su, mut sv) = (0.0, 0.0, 0.0);
    for j in 0..img.height {
        for i in 0..img.width {
            let w = 1.0 - img.rgb[j * img.width + i][1] as f64;
            assert!(w > -1e-4, "pixel ({i},{j}) brighter than the sky: {w}");
            sw += w;
            su += w * (i as f64 + 0.5);
            sv += w * (j as f64 + 0.5);
        }
    }
    let pc = m.world_from_camera(0, 0).inverse().transform_point(centre);
    let (u, v) = (cam.fx * pc.x / pc.z + cam.cx, cam.fy * pc.y / pc.z + cam.cy);
    let area = (0.4 * cam.fx / pc.z).powi(2);
    let (eu, ev) = (su / sw - u, sv / sw - v);
    eprintln!("pinhole centroid error: ({eu:.4}, {ev:.4}) px; area {sw:.2} vs {area:.2} px²");
    // 256 spp: edge-coverage noise gives ≈0.007 px (σ); 0.03 px is > 4σ.
    assert!(
        eu.abs() < 0.03 && ev.abs() < 0.03,
        "centroid off by ({eu}, {ev}) px"
    );
    // The flux equals the square's area in px² (emission 1 ↔ pixel value 1), to 0.5 %.
    assert!((sw / area - 1.0).abs() < 5e-3, "area {sw} vs {area}");
}

/// Unpolarised Fresnel transmittance from index n1 into n2 at incidence cosine `ci`.
fn fresnel_t(n1: f64, n2: f64, ci: f64) -> f64 {
    let s2 = (n1 / n2).powi(2) * (1.0 - ci * ci);
    let ct = (1.0 - s2).sqrt();
    let rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
    let rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
    1.0 - 0.5 * (rs * rs + rp * rp)
}

/// Snell refraction of unit `d` at a plane with unit normal `n` (pointing against `d`).
fn refract(d: DVec3, n: DVec3, eta: f64) -> DVec3 {
    let ci = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - ci * ci);
    (eta * d + (eta * ci - k.sqrt()) * n).normalize()
}

struct Patch {
    /// World point seen by the pixel centre, and the camera-side water path length.
    point: DVec3,
    water_path: f64,
    /// Product of the Fresnel transmittances along the camera ray and the n² factor.
    factor: f64,
}

/// Expected linear radiance in each channel for a Lambertian plane z = `z_plane` (albedo ρ,
/// normal +z) lit by a point light of intensity I at `light` in absorbing water.
fn expected(m: &Model, light: DVec3, intensity: f64, rho: f64, p: &Patch) -> [f64; 3] {
    let w = m.water.as_ref().unwrap();
    let to_light = light - p.point;
    let r = to_light.length();
    let cos = to_light.z / r;
    [0, 1, 2].map(|c| {
        let e = intensity * cos / (r * r) * (-w.absorption[c] * r).exp();
        rho / std::f64::consts::PI * e * (-w.absorption[c] * p.water_path).exp() * p.factor
    })
}

fn patch_through(m: &Model, u: f64, v: f64, z_plane: f64) -> Patch {
    let cam = &m.cameras[0];
    let wfc = m.world_from_camera(0, 0);
    let d = pixel_ray(cam, u, v);
    match &cam.port {
        Port::None => {
            let o = wfc.translation;
            let dw = wfc.transform_vector(d);
            let t = (z_plane - o.z) / dw.z;
            Patch {
                point: o + t * dw,
                water_path: t,
                factor: 1.0,
            }
        }
        Port::Flat {
            normal,
            distance,
            thickness,
            glass,
            ..
        } => {
            // The scene is rendered with the reference (G) channel's indices.
            let (ng, nw) = (glass.ior[1], m.water.as_ref().unwrap().ior[1]);
            let n = *normal;
            let t1 = distance / d.dot(n);
            let p1 = d * t1;
            let d1 = refract(d, -n, 1.0 / ng);
            let t2 = thickness / d1.dot(n);
            let p2 = p1 + d1 * t2;
            let d2 = refract(d1, -n, ng / nw);
            let tr = fresnel_t(1.0, ng, d.dot(n)) * fresnel_t(ng, nw, d1.dot(n));
            let o = wfc.transform_point(p2);
            let dw = wfc.transform_vector(d2);
            let t = (z_plane - o.z) / dw.z;
            // Radiance entering the air from water is divided by n_w² (Mitsuba's physical
            // convention; Cycles gets it from the emitter scaling).
            Patch {
                point: o + t * dw,
                water_path: t,
                factor: tr / (nw * nw),
            }
        }
        _ => unreachable!(),
    }
}

fn radiometry(port: Port, tag: &str) {
    let rho = 0.5;
    let intensity = 2.0;
    let z_plane = -4.0;
    let position = DVec3::new(0.0, 0.0, -2.0);
    let light_rig = DVec3::new(0.1, 0.0, 0.0);
    let strobe = Light {
        name: "strobe".into(),
        mount: Mount::Rig,
        kind: LightKind::Point {
            position: light_rig,
            intensity: [intensity; 3],
        },
    };
    let mut m = model(
        tag,
        camera("cam", port),
        position,
        Some(water([0.40, 0.10, 0.05], [0.0; 3])),
        vec![strobe],
        vec![plane("patch", z_plane, 3.0, [rho; 3])],
    );
    m.needs.medium = true;
    let light = m.poses[0].world_from_rig.transform_point(light_rig);
    let dir = tempfile::tempdir().unwrap();
    let img = render(&m, dir.path(), 16);
    // Every pixel (the plane fills the view): sums of rendered and analytic values.
    let mut got = [0.0; 3];
    let mut want = [0.0; 3];
    for j in 0..img.height {
        for i in 0..img.width {
            let p = patch_through(&m, i as f64 + 0.5, j as f64 + 0.5, z_plane);
            let e = expected(&m, light, intensity, rho, &p);
            let px = img.rgb[j * img.width + i];
            for c in 0..3 {
                got[c] += px[c] as f64;
                want[c] += e[c];
            }
        }
    }
    for c in 0..3 {
        let ratio = got[c] / want[c];
        eprintln!("{tag}: channel {c}: Cycles/analytic = {ratio:.5}");
        // Direct lighting from a point light through absorbing water is noise-free in Cycles;
        // the ≈2e-4 left is the glass slab's inter-reflections, which the reference ignores.
        // 0.5 % also covers float32 image storage and the pixel-area average.
        assert!(
            (ratio - 1.0).abs() < 5e-3,
            "{tag} channel {c}: ratio {ratio}"
        );
    }
}

#[test]
fn lambertian_patch_in_water_matches_beer_lambert_inverse_square() {
    radiometry(Port::None, "camera_in_water");
}

#[test]
fn lambertian_patch_through_flat_port_has_n2_and_fresnel() {
    radiometry(flat_port(), "flat_port");
}

#[test]
fn hostile_names_are_only_data() {
    require_bpy();
    let dir = tempfile::tempdir().unwrap();
    let sentinel = dir.path().join("PWNED");
    let s = sentinel.display().to_string();
    let evil = [
        format!("a\"b'c\n\"\"\"__import__('os').system('touch {s}')"),
        format!("''' + __import__('os').system('touch {s}') + '''"),
        format!("\\\"); import os; os.system('touch {s}'); (\""),
        "é😀\u{2028}\r\t\0end".to_string(),
    ];
    let mut objects = Vec::new();
    for (i, e) in evil.iter().enumerate() {
        objects.push(plane(&format!("{i}{e}"), -1.0 - i as f64, 0.5, [0.5; 3]));
    }
    let mut m = model(
        &evil[0],
        camera(&evil[1], Port::None),
        DVec3::new(0.0, 0.0, 1.0),
        None,
        vec![ambient(1.0)],
        objects.clone(),
    );
    m.description = evil[2].clone();
    m.poses[0].name = evil[3].clone();
    poser::backend::blender::compile(&m, dir.path()).unwrap();
    let script = std::fs::read_to_string(dir.path().join("scene.py")).unwrap();
    assert!(script.is_ascii(), "the script is pure ASCII");
    // Build only and save a .blend, then list the object names from it.
    let blend = dir.path().join("hostile.blend");
    let out = poser::backend::python::command(&dir.path().join("scene.py"))
        .arg("--no-render")
        .arg("--save-blend")
        .arg(&blend)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!sentinel.exists(), "a scene name ran code");
    let list = dir.path().join("list.py");
    std::fs::write(
        &list,
        "import bpy, json, sys\nbpy.ops.wm.open_mainfile(filepath=sys.argv[1])\n\
         print('NAMES=' + json.dumps(sorted(o.name for o in bpy.data.objects)))\n",
    )
    .unwrap();
    let out = poser::backend::python::command(&list)
        .arg(&blend)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("NAMES="))
        .expect("names printed");
    let names: Vec<String> = serde_json::from_str(line).unwrap();
    for o in &objects {
        // Blender names are C strings: NUL becomes U+FFFD; everything else round-trips.
        let want = format!("object:{}", o.name).replace('\0', "\u{fffd}");
        assert!(names.contains(&want), "{want:?} not among {names:?}");
    }
    assert!(names.contains(&format!("camera:{}", evil[1])), "{names:?}");
    assert!(!sentinel.exists());
}

#[test]
fn ports_project_like_the_optics_truth() {
    // The canonical scenes (tests/canonical): a 5×4 circle grid seen through each port kind.
    // Disk centroids are measured with `compare::detect` and compared with the exact
    // refractive projection (`optics`).
    require_bpy();
    for scene in [
        "pinhole_air",
        "flat_tilted",
        "dome_decentred",
        "cylinder_off_axis",
    ] {
        let path = format!("tests/canonical/{scene}.toml");
        let model = poser::scene::load(Path::new(&path), &[])
            .map_err(|f| f.render())
            .unwrap()
            .model;
        let dir = tempfile::tempdir().unwrap();
        let opts = RenderOptions {
            samples: Some(64),
            poses: None,
            progress: false,
            resume: false,
        };
        poser::backend::blender::render(&model, dir.path(), &opts).unwrap();
        let (found, expected) = poser::compare::measure_targets(&model, dir.path()).unwrap();
        assert_eq!(
            found.len(),
            expected,
            "{scene}: every visible disk is found"
        );
        // The cylinder stretches the grid across its axis, so only its disks whose window
        // stays on the card are measured (9 of 20); every other scene shows all 20.
        let min = if scene == "cylinder_off_axis" { 8 } else { 20 };
        assert!(found.len() >= min, "{scene}: {} disks", found.len());
        let checked = &found;
        let rms = (checked
            .iter()
            .map(|(_, _, d)| d[0] * d[0] + d[1] * d[1])
            .sum::<f64>()
            / checked.len() as f64)
            .sqrt();
        let max = checked
            .iter()
            .map(|(_, _, d)| d[0].hypot(d[1]))
            .fold(0.0, f64::max);
        eprintln!(
            "{scene}: {} disks vs truth: rms {rms:.4} px, max {max:.4} px",
            checked.len()
        );
        // Measured max 0.045–0.083 px at 64 spp (the small disks' edge coverage noise is
        // ≈0.03 px σ): 0.15 px bounds it at ~5σ.
        assert!(max < 0.15, "{scene}: max {max} px");
    }
}

/// Render `scene` (a canonical scene with `--set` overrides) and measure its disks against the
/// exact projection: (disks found, rms, max) in px.
fn measure_canonical(scene: &str, sets: &[&str], samples: u32) -> (usize, f64, f64) {
    let path = format!("tests/canonical/{scene}.toml");
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let model = poser::scene::load(Path::new(&path), &sets)
        .map_err(|f| f.render())
        .unwrap()
        .model;
    let dir = tempfile::tempdir().unwrap();
    let opts = RenderOptions {
        samples: Some(samples),
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::blender::render(&model, dir.path(), &opts).unwrap();
    let script = std::fs::read_to_string(dir.path().join("scene.py")).unwrap();
    assert!(
        script.contains("shader poser_camera("),
        "camera shader embedded"
    );
    let (found, expected) = poser::compare::measure_targets(&model, dir.path()).unwrap();
    assert_eq!(
        found.len(),
        expected,
        "{scene}: every visible disk is found"
    );
    let n = found.len().max(1) as f64;
    let rms = (found
        .iter()
        .map(|(_, _, d)| d[0] * d[0] + d[1] * d[1])
        .sum::<f64>()
        / n)
        .sqrt();
    let max = found
        .iter()
        .map(|(_, _, d)| d[0].hypot(d[1]))
        .fold(0.0, f64::max);
    (found.len(), rms, max)
}

#[test]
fn brown_conrady_distortion_projects_like_the_optics_truth() {
    // poser's OSL custom camera inverts the distortion per film sample: the circle grid seen
    // through strong barrel distortion (several px at the corners), in air and
    // through the tilted flat port, must land where `optics` puts it.
    require_bpy();
    let distortion = [
        "camera.distortion.k1=-0.22",
        "camera.distortion.k2=0.06",
        "camera.distortion.p1=0.0015",
        "camera.distortion.p2=-0.001",
    ];
    for scene in ["pinhole_air", "flat_tilted"] {
        let (n, rms, max) = measure_canonical(scene, &distortion, 64);
        eprintln!("{scene} + Brown–Conrady: {n} disks vs truth: rms {rms:.4} px, max {max:.4} px");
        assert!(n >= 20, "{scene}: {n} disks");
        // Same noise floor as the undistorted scenes (max 0.045–0.083 px at 64 spp, σ ≈ 0.03 px
        // per disk): 0.15 px is ~5σ, far below the ≈1–4 px the distortion moves the disks.
        assert!(max < 0.15, "{scene}: max {max} px");
    }
}

#[test]
fn fisheyes_project_like_the_optics_truth() {
    // Undistorted fisheyes use Cycles' panoramic camera; with distortion they go through the
    // OSL camera. Both against the exact projection of the same grid.
    require_bpy();
    let cases: [(&str, &[&str]); 3] = [
        (
            "equisolid (panoramic)",
            &["camera.lens=\"fisheye_equisolid\""],
        ),
        (
            "equidistant (panoramic)",
            &["camera.lens=\"fisheye_equidistant\""],
        ),
        (
            "equidistant + distortion (OSL)",
            &[
                "camera.lens=\"fisheye_equidistant\"",
                "camera.distortion.k1=0.03",
                "camera.distortion.k2=-0.01",
            ],
        ),
    ];
    for (tag, sets) in cases {
        let (n, rms, max) = measure_canonical("pinhole_air", sets, 64);
        eprintln!("fisheye {tag}: {n} disks vs truth: rms {rms:.4} px, max {max:.4} px");
        assert!(n >= 20, "{tag}: {n} disks");
        // As above: 64-spp edge-coverage noise ≈0.03 px σ per disk.
        assert!(max < 0.15, "{tag}: max {max} px");
    }
}

/// A canonical scene with `outputs = ["rgb", "depth"]`, a scratch directory and render options.
fn depth_scene(name: &str, samples: u32) -> (Model, tempfile::TempDir, RenderOptions) {
    let model = poser::scene::load(
        Path::new(&format!("tests/canonical/{name}.toml")),
        &["render.outputs=[\"rgb\", \"depth\"]".to_string()],
    )
    .map_err(|f| f.render())
    .unwrap()
    .model;
    let opts = RenderOptions {
        samples: Some(samples),
        poses: None,
        progress: false,
        resume: false,
    };
    (model, tempfile::tempdir().unwrap(), opts)
}

#[test]
fn depth_pass_is_camera_z_of_the_first_surface_through_the_port() {
    // The tilted flat port scene with `outputs = ["rgb", "depth"]`: `<image>.depth.exr` holds
    // the camera-frame z of the surface seen through each pixel centre (the native backend's
    // definition). Expected: the exact refracted pixel ray (`optics`) meets the card's plane.
    require_bpy();
    let (model, dir, opts) = depth_scene("flat_tilted", 4);
    poser::backend::blender::render(&model, dir.path(), &opts).unwrap();
    let depth = LinearImage::read(&dir.path().join("img_0001.depth.exr")).expect("depth EXR");
    assert_eq!((depth.width, depth.height), (160, 120));
    let proj = model.projector(0, 1).unwrap();
    let card = &model.targets[0];
    let (w, h) = poser::geometry::targets::extent(&card.kind);
    let normal = card.pose.rotation.z_axis;
    let camera_from_world = proj.world_from_camera(0).inverse();
    let (mut on, mut off, mut outliers, mut worst) = (0, 0, 0, 0.0f64);
    for j in 0..depth.height {
        for i in 0..depth.width {
            let (u, v) = (i as f64 + 0.5, j as f64 + 0.5);
            let (o, d, _) = proj.pixel_ray_world(0, u, v).unwrap();
            let t = (card.pose.translation - o).dot(normal) / d.dot(normal);
            let hit = o + t * d;
            let local = card.pose.inverse().transform_point(hit);
            let got = depth.rgb[j * depth.width + i];
            // Pixels whose centre ray is within 2 mm (≈0.4 px) of the card's edge are skipped.
            let margin = 0.002;
            if local.x.abs() < w / 2.0 - margin && local.y.abs() < h / 2.0 - margin {
                let want = camera_from_world.transform_point(hit).z;
                let err = (got[1] as f64 - want).abs();
                worst = worst.max(err);
                on += 1;
                // Float32 storage and single-precision intersections at ≈1 m: ~1e-6 m; the
                // sample lands within ±0.005 px of the centre (|dz/du| < 1e-3 m/px here);
                // the port's glass is exact in Cycles (flat faces). Measured: every pixel but
                // one < 1e-5 m; one pixel (118, 28) at 2.8e-4 m, the same for every seed: its
                // centre ray meets the port's outer glass 0.5 µm from the diagonal shared by
                // the face's two triangles, where Cycles' ray is deflected (a ray-on-edge
                // artefact of triangle meshes; a measure-zero set for jittered samples). So: at most
                // 0.1 % of the pixels above 2e-5 m, none above 1e-3 m (0.1 % of the depth).
                if err > 2e-5 {
                    eprintln!("pixel ({i},{j}): depth {} vs {want}", got[1]);
                    outliers += 1;
                }
                assert!(err < 1e-3, "pixel ({i},{j}): depth {} vs {want}", got[1]);
                assert!(
                    got[0] == got[1] && got[2] == got[1],
                    "same value in R, G, B"
                );
            } else if local.x.abs() > w / 2.0 + margin || local.y.abs() > h / 2.0 + margin {
                // No surface behind the card: 0, as the native backend writes.
                assert_eq!(got[1], 0.0, "pixel ({i},{j}) sees nothing");
                off += 1;
            }
        }
    }
    eprintln!(
        "depth: {on} pixels on the card, max error {worst:.2e} m, {outliers} above 2e-5 m; \
         {off} pixels off it"
    );
    assert!(on > 2000 && off > 2000, "{on} on, {off} off");
    assert!(
        outliers * 1000 <= on,
        "{outliers} of {on} pixels above 2e-5 m"
    );
}

#[test]
fn test_object_disks_project_like_the_optics_truth() {
    // A 2-level staircase test object (3D: its disks lie on two heights, 60 mm apart) seen
    // from 1 m in air, image axes along the object's (the detector's square windows must stay
    // on each step); each corner disk's centroid is measured with `compare::detect` and
    // compared with the exact projection, as the printed targets are.
    require_bpy();
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("test_object.toml");
    std::fs::write(
        &scene,
        r#"name = "test_object"
[site]
depth = "10 m"
surface = "none"
[camera]
width = 160
height = 120
sensor_width = "36 mm"
focal_length = "34 mm"
principal_point = [83.7, 57.2]
[[lights]]
type = "ambient"
radiance = 1.0
[[targets]]
name = "pyramid"
type = "test_object"
size = "0.5 m"
levels = 2
step = "60 mm"
diameter = "60 mm"
position = [0.0, 0.0, -5.0]
[network]
type = "explicit"
speed = "0.2 m/s"
[[network.poses]]
position = [0.03, -0.02, -3.94]
look_at = [0.0, 0.0, -5.0]
up = [0.0, 1.0, 0.0]
[render]
samples = 64
seed = 3
bounces = 8
"#,
    )
    .unwrap();
    let model = poser::scene::load(&scene, &[])
        .map_err(|f| f.render())
        .unwrap()
        .model;
    let out = dir.path().join("out");
    let opts = RenderOptions {
        samples: Some(64),
        poses: None,
        progress: false,
        resume: false,
    };
    poser::backend::blender::render(&model, &out, &opts).unwrap();
    let img = LinearImage::read(&out.join("img_0001.exr")).unwrap();
    let g = img.channel(1);
    let gray = poser::compare::detect::Gray {
        width: img.width,
        height: img.height,
        data: &g,
    };
    let proj = model.projector(0, 1).unwrap();
    let t = &model.targets[0];
    let dark = poser::geometry::targets::BLACK / poser::geometry::targets::WHITE;
    let mut errs = Vec::new();
    for p in &t.points {
        // Each disk sits `diameter` from its step's two outer edges: a square white cell of
        // that half-size around it, along the target's axes.
        let d = poser::compare::Disk {
            id: p.id.clone(),
            center: p.world,
            normal: t.pose.rotation.z_axis,
            radius: 0.03,
            clear_radius: 0.06,
            x_axis: Some(t.pose.rotation.x_axis),
        };
        let Some((c, half)) = poser::compare::expected_disk(&proj, None, 0, &d) else {
            continue;
        };
        let m = poser::compare::detect::disk_centroid(&gray, c, half, dark)
            .unwrap_or_else(|e| panic!("disk {} not found: {e:?}", p.id));
        errs.push((p.id.clone(), m[0] - c[0], m[1] - c[1]));
    }
    let rms = (errs.iter().map(|(_, x, y)| x * x + y * y).sum::<f64>() / errs.len() as f64).sqrt();
    let max = errs.iter().map(|(_, x, y)| x.hypot(*y)).fold(0.0, f64::max);
    eprintln!(
        "test object: {} disks vs truth: rms {rms:.4} px, max {max:.4} px",
        errs.len()
    );
    assert_eq!(errs.len(), 8, "all 8 corner disks measured: {errs:?}");
    // 64 spp edge-coverage noise ≈0.03 px σ per disk (as for the grids); the disks are
    // 64-gons (centroid exact). A missing test object would fail to find the disks at all.
    assert!(max < 0.15, "max {max} px: {errs:?}");
}

#[test]
fn depth_pass_matches_the_native_backend() {
    // Same file name, format and definition as `src/backend/native`: both backends render the
    // decentred dome scene's depth; per pixel they must agree.
    require_bpy();
    let (model, dir, opts) = depth_scene("dome_decentred", 1);
    let read = |b: &str| {
        let out = dir.path().join(b);
        poser::backend::Backend::parse(b)
            .unwrap()
            .render(&model, &out, &opts)
            .unwrap();
        LinearImage::read(&out.join("img_0001.depth.exr")).unwrap()
    };
    let (native, cycles) = (read("native"), read("blender"));
    assert_eq!((native.width, native.height), (cycles.width, cycles.height));
    let (mut both, mut differ, mut worst) = (0, 0, 0.0f64);
    for (a, b) in native.rgb.iter().zip(&cycles.rgb) {
        let (a, b) = (a[1] as f64, b[1] as f64);
        if a > 0.0 && b > 0.0 {
            both += 1;
            worst = worst.max((a - b).abs());
        } else if (a > 0.0) != (b > 0.0) {
            differ += 1;
        }
    }
    eprintln!(
        "depth native vs Cycles: {both} pixels on a surface, max |Δz| {worst:.2e} m; \
         {differ} pixels on a surface in one only"
    );
    assert!(both > 2000, "{both} pixels");
    // Measured max 1.6e-4 m (median 2e-7 m) at ≈1 m: the dome is a tessellated sphere in
    // Cycles (smooth normals, 384×96 facets) and exact in the native backend. 1e-3 m = 0.1 %.
    assert!(worst < 1e-3, "max |Δz| {worst} m");
    // Pixels whose centre ray grazes the card's edge may fall either side (measured: 1).
    assert!(differ <= 10, "{differ} pixels differ in coverage");
}

#[test]
fn sunlit_seabed_through_flat_port_matches_analytic_radiance() {
    // tests/canonical/sun_seabed.toml: the sun refracted into absorbing water (a directional
    // light in the water, E_w normal to its refracted direction) lights a white seabed at 5 m,
    // seen through a flat port from 2 m above. Radiance = ρ/π · E_w cosθw · exp(-σa 5/cosθw)
    // · exp(-σa path) · Fresnel(port) / n_w².
    require_bpy();
    let m = poser::scene::load(Path::new("tests/canonical/sun_seabed.toml"), &[])
        .map_err(|f| f.render())
        .unwrap()
        .model;
    let sun = m.sun.clone().unwrap();
    let w = m.water.clone().unwrap();
    let z_plane = m.objects[0].pose.translation.z;
    let rho = m.objects[0].material.albedo[1];
    let dir = tempfile::tempdir().unwrap();
    let img = render(&m, dir.path(), 16);
    let mut got = [0.0; 3];
    let mut want = [0.0; 3];
    for j in 0..img.height {
        for i in 0..img.width {
            let p = patch_through(&m, i as f64 + 0.5, j as f64 + 0.5, z_plane);
            let cos_w = -sun.direction_water.z;
            let px = img.rgb[j * img.width + i];
            for c in 0..3 {
                let e =
                    sun.irradiance_water[c] * cos_w * (-w.absorption[c] * -p.point.z / cos_w).exp();
                want[c] += rho / std::f64::consts::PI
                    * e
                    * (-w.absorption[c] * p.water_path).exp()
                    * p.factor;
                got[c] += px[c] as f64;
            }
        }
    }
    for c in 0..3 {
        let ratio = got[c] / want[c];
        eprintln!("sun_seabed: channel {c}: Cycles/analytic = {ratio:.5}");
        // Direct sunlight on a Lambertian plane: the only noise is the reflect-or-refract
        // choice at the two glass faces (σ ≈ 0.04 % over the whole image at 16 spp), plus the
        // slab's inter-reflections (≈2e-4). The housing casts no shadow (as in the native
        // backend and the analytic model; builder.py HOUSING_SHADOW): with its shadow, 85
        // pixels in a corner were dark and the ratio was 0.9968, which 0.2 % rejects.
        assert!((ratio - 1.0).abs() < 2e-3, "channel {c}: ratio {ratio}");
    }
}

/// Python run in a fresh process: open a saved .blend and render its scene as saved (camera,
/// lights, world, seed, samples) to an EXR.
const RENDER_SAVED_BLEND: &str = r#"
import sys
import bpy
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
scene = bpy.context.scene
scene.render.filepath = sys.argv[2]
scene.render.use_file_extension = False
scene.render.image_settings.file_format = "OPEN_EXR"
bpy.ops.render.render(write_still=True, scene=scene.name)
"#;

#[test]
fn saved_blend_renders_what_poser_renders() {
    // calibration_flat (three strobes and an ambient world in water, flat port) at 64×48,
    // 16 spp, pose 0: poser's own Cycles render against the .blend `--save-blend` writes,
    // reopened in a fresh bpy process and rendered as saved. Before the strengths were set at
    // build time the saved file had Blender's default 10 W strobes and grey world
    // (R −56 %, B +15 % at full size).
    require_bpy();
    let sets = ["camera.width=64", "camera.height=48", "render.samples=16"].map(String::from);
    let m = poser::scene::load(Path::new("scenarios/calibration_flat.toml"), &sets)
        .map_err(|f| f.render())
        .unwrap()
        .model;
    let dir = tempfile::tempdir().unwrap();
    let opts = RenderOptions {
        samples: None,
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    let ours = poser::backend::blender::render(&m, &dir.path().join("poser"), &opts)
        .expect("Cycles render");
    let a = LinearImage::read(&ours.images[0]).unwrap();
    let script = dir.path().join("poser/scene.py");
    let blend = dir.path().join("saved.blend");
    let st = poser::backend::python::command(&script)
        .arg("--save-blend")
        .arg(&blend)
        .arg("--no-render")
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let exr = dir.path().join("saved.exr");
    let st = std::process::Command::new(poser::backend::python::interpreter())
        .arg("-c")
        .arg(RENDER_SAVED_BLEND)
        .arg(&blend)
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let b = LinearImage::read(&exr).unwrap();
    assert_eq!((a.width, a.height), (b.width, b.height));
    let n = a.rgb.len() as f64;
    for c in 0..3 {
        let d: Vec<f64> = a
            .rgb
            .iter()
            .zip(&b.rgb)
            .map(|(x, y)| y[c] as f64 - x[c] as f64)
            .collect();
        let mean_d = d.iter().sum::<f64>() / n;
        // Noise allowance from the images: 4 standard errors of the mean per-pixel difference
        // (0 when both renders use the same seed and agree exactly), plus float rounding.
        let sd = (d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let mean_a = a.rgb.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let allowed = 4.0 * sd / n.sqrt() + 1e-5 * mean_a;
        eprintln!(
            "saved .blend channel {c}: mean {mean_a:.5}, saved − poser {mean_d:+.3e} \
             (allowed {allowed:.3e}; per-pixel sd {sd:.3e})"
        );
        assert!(
            mean_d.abs() <= allowed,
            "channel {c}: the saved .blend renders {:+.2} % off poser's render",
            100.0 * mean_d / mean_a
        );
    }
}

#[test]
fn wavy_sea_surface_has_the_requested_significant_height() {
    // caustics_shallow asks for Hs = 0.25 m (λp 4 m, wind 6 m/s). The sea surface Blender
    // builds is the native backend's wave field; Hs measured here as 4·std of the built mesh's
    // heights over one period (before: an ocean modifier on the wind alone, Hs 1.60 m). The
    // sun is removed: its caustics are refused (data.rs CAUSTICS_REFUSED).
    require_bpy();
    let mut m = poser::scene::load(Path::new("scenarios/caustics_shallow.toml"), &[])
        .map_err(|f| f.render())
        .unwrap()
        .model;
    m.sun = None;
    let dir = tempfile::tempdir().unwrap();
    poser::backend::blender::compile(&m, dir.path()).unwrap();
    let code = r#"
import json, sys
sys.path.insert(0, sys.argv[1])
import bpy
from poser_blender import builder
desc = json.load(open(sys.argv[2] + "/scene.json"))
bpy.ops.wm.read_factory_settings(use_empty=True)
built = builder.build(desc, sys.argv[2], bpy.context.scene)
me = built.wave_mesh
z = [v.co.z for v in me.vertices]
print("POSER_HS", builder.significant_height([(0.0, 0.0, h) for h in z]), len(built.wave_tiles))
"#;
    let out = std::process::Command::new(poser::backend::python::interpreter())
        .arg("-c")
        .arg(code)
        .arg(poser::backend::python::backends_dir().join("blender"))
        .arg(dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = text.lines().find(|l| l.starts_with("POSER_HS")).unwrap();
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().unwrap())
        .collect();
    eprintln!(
        "Blender sea surface: Hs {:.4} m (asked 0.25), {} tiles",
        v[0], v[1]
    );
    // The grid includes each period's closing row and column (repeated heights): ±1 %.
    assert!((v[0] / 0.25 - 1.0).abs() < 0.01, "Hs {} m", v[0]);
    assert!(v[1] >= 1.0);
}
