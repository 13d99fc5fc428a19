//! Mitsuba backend: compiled XML snapshots, byte stability, escaping and path safety, and the
//! clear errors for what Mitsuba cannot express.
use crate::support;
use glam::DVec3;
use poser::backend::mitsuba;
use poser::model::*;
use support::mitsuba::*;

fn text(c: &mitsuba::Compiled, file: &str) -> String {
    String::from_utf8(
        c.files
            .get(file)
            .unwrap_or_else(|| panic!("no {file}: {:?}", c.files.keys()))
            .clone(),
    )
    .unwrap()
}

#[test]
fn showcase_snapshot() {
    let c = mitsuba::build(&showcase()).unwrap();
    let names: Vec<&String> = c.files.keys().collect();
    insta::assert_debug_snapshot!("showcase_files", names);
    insta::assert_snapshot!("showcase_world", text(&c, "world.xml"));
    insta::assert_snapshot!("showcase_left_0", text(&c, "left_img_0000.xml"));
    insta::assert_snapshot!("showcase_right_1", text(&c, "right_img_0001.xml"));
    insta::assert_snapshot!("showcase_manifest", text(&c, "manifest.json"));
}

/// Per-view coordinates (docs/backends.md): each view sets `$poser_unit` to millimetres and
/// `$poser_origin_*` to minus its camera's centre (in millimetres) before it includes the
/// world, and every placed element of every document (shapes, sensors, point and spot lights)
/// ends its `to_world` with the scale and the translation by them, so that the camera and its
/// port sit at Mitsuba's origin, where its ray offsets are smallest. A sensor, which may not
/// scale, also starts with the inverse scale.
#[test]
fn each_view_puts_its_camera_at_the_origin() {
    let model = showcase();
    let c = mitsuba::build(&model).unwrap();
    for job in &c.manifest.views {
        let cam = model
            .cameras
            .iter()
            .position(|k| k.name == job.camera)
            .unwrap();
        let centre = model.world_from_camera(job.pose, cam).translation;
        assert!(
            centre.length() > 0.1,
            "the showcase's cameras are off the origin"
        );
        let xml = text(&c, &job.passes[0].xml);
        let default = |name: &str| -> f64 {
            let key = format!(r#"<default name="{name}" value=""#);
            let at = xml
                .find(&key)
                .unwrap_or_else(|| panic!("{key} in {}", job.image));
            assert!(
                at < xml.find("<include").unwrap(),
                "the defaults precede the include"
            );
            let rest = &xml[at + key.len()..];
            rest[..rest.find('"').unwrap()].parse().unwrap()
        };
        let unit = default("poser_unit");
        assert_eq!(unit, 1000.0, "views are in millimetres");
        assert_eq!(default("poser_per_unit"), 1e-3);
        let origin = DVec3::new(
            default("poser_origin_x"),
            default("poser_origin_y"),
            default("poser_origin_z"),
        );
        assert!(
            (origin / unit + centre).length() < 1e-12,
            "{origin} vs {centre}"
        );
    }
    let shift = concat!(
        r#"<scale value="$poser_unit"/>"#,
        r#"<translate x="$poser_origin_x" y="$poser_origin_y" z="$poser_origin_z"/>"#
    );
    let inverse = r#"<scale value="$poser_per_unit"/>"#;
    let mut kinds = std::collections::BTreeSet::new();
    for (name, _) in c.files.iter().filter(|(n, _)| n.ends_with(".xml")) {
        let xml = text(&c, name);
        let blocks: Vec<&str> = xml
            .split(r#"<transform name="to_world">"#)
            .skip(1)
            .collect();
        for b in &blocks {
            let body: String = b[..b.find("</transform>").unwrap()]
                .lines()
                .map(str::trim)
                .collect();
            assert!(body.ends_with(shift), "{name}: {body}");
        }
        // Sensors: the inverse scale first (their to_world may not scale).
        for s in xml.split("<sensor type=\"").skip(1) {
            let tw = &s[s.find(r#"<transform name="to_world">"#).unwrap()..];
            let first = tw.lines().nth(1).unwrap().trim();
            assert_eq!(first, inverse, "{name}: a sensor's to_world");
        }
        let mut placed = 0;
        for kind in [
            "<shape type=\"",
            "<sensor type=\"",
            "<emitter type=\"point\"",
            "<emitter type=\"spot\"",
        ] {
            let n = xml.matches(kind).count();
            if n > 0 {
                kinds.insert(kind);
            }
            placed += n;
        }
        assert_eq!(
            placed,
            blocks.len(),
            "{name}: one to_world per placed element"
        );
    }
    assert_eq!(
        kinds.len(),
        4,
        "shapes, sensors, point and spot lights all seen: {kinds:?}"
    );
}

#[test]
fn cylinder_port_and_fournier_forand_snapshot() {
    let mut m = base(
        "cylinder",
        camera(
            "cam",
            Port::Cylinder {
                axis_point: DVec3::ZERO,
                axis: DVec3::Y,
                inner_radius: 0.06,
                thickness: 0.005,
                glass: glass(),
            },
        ),
        Some(water(
            [0.3, 0.08, 0.04],
            [0.1, 0.12, 0.15],
            Phase::FournierForand {
                n: 1.1,
                mu: 3.5,
                backscatter: 0.0183,
            },
        )),
        nadir(DVec3::new(0.0, 0.0, -3.0)),
    );
    m.water.as_mut().unwrap().extent = WaterExtent::BoxAroundCamera {
        half_size: DVec3::new(2.0, 2.0, 2.0),
    };
    m.needs.medium_box = true;
    let c = mitsuba::build(&m).unwrap();
    let view = text(&c, "img_0000.xml");
    // The FF table is long: snapshot everything but its values.
    let short: String = view
        .lines()
        .map(|l| {
            if l.contains("name=\"values\"") {
                "      <string name=\"values\" value=\"…\"/>"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    insta::assert_snapshot!("cylinder_ff_view", short);
}

#[test]
fn compile_is_byte_stable() {
    let a = mitsuba::build(&showcase()).unwrap();
    let b = mitsuba::build(&showcase()).unwrap();
    assert_eq!(a.files, b.files);
    // And through the file system.
    let d1 = tempfile::tempdir().unwrap();
    let d2 = tempfile::tempdir().unwrap();
    mitsuba::compile(&showcase(), d1.path()).unwrap();
    mitsuba::compile(&showcase(), d2.path()).unwrap();
    for f in a.files.keys() {
        assert_eq!(
            std::fs::read(d1.path().join(f)).unwrap(),
            std::fs::read(d2.path().join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn per_channel_passes_use_each_channels_indices() {
    let mut m = showcase();
    m.needs.per_channel_passes = true;
    let c = mitsuba::build(&m).unwrap();
    for (k, suffix) in ["r", "g", "b"].iter().enumerate() {
        let v = text(&c, &format!("left_img_0000.{suffix}.xml"));
        let ng = xml_num(glass().ior[k]);
        let nw = xml_num(m.water.as_ref().unwrap().ior[k]);
        assert!(
            v.contains(&format!("<float name=\"int_ior\" value=\"{ng}\"/>")),
            "{suffix}: {v}"
        );
        assert!(
            v.contains(&format!("<float name=\"ext_ior\" value=\"{nw}\"/>")),
            "{suffix}"
        );
    }
    assert!(!c.files.contains_key("left_img_0000.xml"));
    let manifest = text(&c, "manifest.json");
    assert!(manifest.contains("\"channel\": 2"), "{manifest}");
}

fn xml_num(x: f64) -> String {
    mitsuba::xml::num(x)
}

#[test]
fn names_cannot_inject_xml() {
    let mut m = showcase();
    let evil = "a\"/><shape type=\"ply\"><string name=\"filename\" value=\"/etc/passwd\"/></shape><!-- ]]> --> &x;";
    m.name = evil.into();
    m.cameras[0].name = evil.into();
    m.lights[0].name = evil.into();
    m.objects[0].name = evil.into();
    // Image names come from pose/camera names and must be safe file names.
    m.cameras[0].name = "left".into();
    let c = mitsuba::build(&m).unwrap();
    for (f, bytes) in &c.files {
        if !f.ends_with(".xml") {
            continue;
        }
        let s = String::from_utf8(bytes.clone()).unwrap();
        // Every comment is well formed: no `--` inside.
        for part in s.split("<!--").skip(1) {
            let body = part.split("-->").next().unwrap();
            assert!(!body.contains("--"), "{f}: bad comment {body}");
        }
        // It parses as XML.
        let mut r = quick_xml::Reader::from_str(&s);
        loop {
            match r.read_event() {
                Ok(quick_xml::events::Event::Eof) => break,
                Ok(quick_xml::events::Event::Start(e)) | Ok(quick_xml::events::Event::Empty(e)) => {
                    // No element or attribute carries the injected content.
                    for a in e.attributes() {
                        let a = a.unwrap();
                        let v = a.value.to_string();
                        assert!(
                            !v.contains("passwd") && v != "ply",
                            "{f}: injected attribute {v}"
                        );
                    }
                }
                Ok(_) => {}
                Err(e) => panic!("{f}: not well-formed XML: {e}\n{s}"),
            }
        }
    }
}

#[test]
fn unsafe_image_names_are_refused() {
    for bad in ["../escape", "a/b", "/abs", ".hidden", "x\\y", "a b", ""] {
        let mut m = base("one", camera("cam", Port::None), None, nadir(DVec3::ZERO));
        m.poses[0].name = bad.into();
        let Err(e) = mitsuba::build(&m) else {
            panic!("{bad:?} accepted")
        };
        assert!(e.contains("cannot be used as a file name"), "{bad}: {e}");
    }
}

#[test]
fn files_stay_inside_the_output_dir() {
    let c = mitsuba::build(&showcase()).unwrap();
    for f in c.files.keys() {
        let p = std::path::Path::new(f);
        assert!(
            p.is_relative()
                && p.components()
                    .all(|c| matches!(c, std::path::Component::Normal(_))),
            "{f}"
        );
    }
    // Every filename referenced by a document is one of the files written.
    for (f, bytes) in &c.files {
        let s = String::from_utf8_lossy(bytes);
        let mut refs = Vec::new();
        for part in s.split("filename=\"").skip(1) {
            refs.push(part.split('"').next().unwrap().to_string());
        }
        for part in s.split("<string name=\"filename\" value=\"").skip(1) {
            refs.push(part.split('"').next().unwrap().to_string());
        }
        for v in refs {
            assert!(
                c.files.contains_key(&v),
                "{f} references undeclared file {v}"
            );
        }
    }
}

#[test]
fn fisheye_distortion_and_nonsquare_pixels_are_clear_errors() {
    let mut m = showcase();
    m.cameras[1].lens = LensModel::FisheyeEquidistant;
    let e = mitsuba::build(&m).unwrap_err();
    assert!(e.contains("camera `right`") && e.contains("fisheye"), "{e}");

    let mut m = showcase();
    m.cameras[0].distortion.k1 = -0.1;
    let e = mitsuba::build(&m).unwrap_err();
    assert!(
        e.contains("camera `left`") && e.contains("distortion"),
        "{e}"
    );

    let mut m = showcase();
    m.cameras[0].fy = m.cameras[0].fx * 1.01;
    let e = mitsuba::build(&m).unwrap_err();
    assert!(
        e.contains("camera `left`") && e.contains("square pixels"),
        "{e}"
    );

    let mut m = showcase();
    m.cameras[0].focus_distance = Some(2.0);
    m.cameras[0].f_number = Some(8.0);
    let e = mitsuba::build(&m).unwrap_err();
    assert!(
        e.contains("camera `left`") && e.contains("principal point"),
        "{e}"
    );
    m.cameras[0].cx = 80.0;
    m.cameras[0].cy = 60.0;
    let c = mitsuba::build(&m).unwrap();
    let v = text(&c, "left_img_0000.xml");
    assert!(
        v.contains("<sensor type=\"thinlens\">") && v.contains("aperture_radius"),
        "{v}"
    );
    // The view is in millimetres; the importer gives the lens back in metres.
    assert!(
        v.contains(r#"<float name="focus_distance" value="2000"/>"#),
        "{v}"
    );
    let dir = tempfile::tempdir().unwrap();
    mitsuba::write(&c, dir.path()).unwrap();
    let back = poser::import::mitsuba::import(&[dir.path().join("left_img_0000.xml")], "assets")
        .unwrap()
        .toml;
    let cam: toml::Table = toml::from_str(&back).unwrap();
    let cam = cam["camera"].as_table().unwrap();
    assert_eq!(cam["focus_distance"].as_float(), Some(2.0), "{back}");
    // The aperture's radius: the importer derives the focal length from fx and the pitch.
    let radius =
        cam["focal_length"].as_float().unwrap() / (2.0 * cam["f_number"].as_float().unwrap());
    let expected = m.cameras[0].focal_length / 16.0;
    assert!(
        (radius / expected - 1.0).abs() < 1e-12,
        "{radius} vs {expected}"
    );
}

#[test]
fn wavy_surface_caustics_are_a_clear_error() {
    let mut m = showcase();
    m.needs.caustics = true;
    let e = mitsuba::build(&m).unwrap_err();
    assert!(e.contains("caustic"), "{e}");
}

#[test]
fn only_what_the_scene_needs() {
    // In air, no port: no medium, no dielectric, no medium reference.
    let m = base(
        "air",
        camera("cam", Port::None),
        None,
        nadir(DVec3::new(0.0, 0.0, 2.0)),
    );
    let c = mitsuba::build(&m).unwrap();
    let v = text(&c, "img_0000.xml");
    for absent in ["<medium", "dielectric", "name=\"medium\"", "include"] {
        assert!(!v.contains(absent), "{absent} in\n{v}");
    }
    // Camera in water without port: the sensor references the water.
    let m = base(
        "inwater",
        camera("cam", Port::None),
        Some(water(
            [0.4, 0.1, 0.05],
            [0.0; 3],
            Phase::HenyeyGreenstein { g: 0.0 },
        )),
        nadir(DVec3::new(0.0, 0.0, -2.0)),
    );
    let v = text(&mitsuba::build(&m).unwrap(), "img_0000.xml");
    assert!(v.contains("<ref name=\"medium\" id=\"water\"/>"), "{v}");
    assert!(!v.contains("dielectric"));
}

#[test]
fn fournier_forand_table_keeps_the_backscatter_fraction() {
    for (n, mu) in [(1.1, 3.5), (1.05, 3.2), (1.15, 4.0)] {
        let b_exact = 1.0 - poser::optics::phase::ff_cdf(n, mu, std::f64::consts::FRAC_PI_2);
        let table = mitsuba::view::ff_table(n, mu, mitsuba::TABPHASE_SAMPLES);
        let b_table = mitsuba::view::table_backscatter(&table);
        // Cell-mean densities preserve each cell's mass; the piecewise-linear interpolation
        // moves at most half a cell of mass across 90°: < 1 % of B.
        assert!(
            (b_table / b_exact - 1.0).abs() < 0.01,
            "n {n} mu {mu}: {b_table} vs {b_exact}"
        );
        assert!(table.iter().all(|v| v.is_finite() && *v >= 0.0));
        // CDF sanity: 0 at 0, 1 at π.
        assert!(poser::optics::phase::ff_cdf(n, mu, 0.0).abs() < 1e-12);
        assert!((poser::optics::phase::ff_cdf(n, mu, std::f64::consts::PI) - 1.0).abs() < 1e-12);
    }
}

/// Every scene shipped (scenarios/, tests/canonical/) compiles, or fails with a clear
/// "cannot be expressed" error naming what Mitsuba lacks. The scenes pinned by `tests/in/` are
/// compiled (twice) and snapshotted by `tests/compile_out.rs` and skipped here: their textures
/// take seconds each to bake.
#[test]
fn every_shipped_scene_compiles_or_says_why() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let pinned = support::pinned_scenes();
    for dir in ["scenarios", "tests/canonical"] {
        let Ok(rd) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut paths: Vec<_> = rd
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .filter(|p| !pinned.contains(&p.canonicalize().unwrap()))
            .collect();
        paths.sort();
        for path in paths {
            let Ok(loaded) = poser::scene::load(&path, &[]) else {
                continue;
            }; // fragments (includes)
            match mitsuba::build(&loaded.model) {
                Ok(c) => assert!(c.files.contains_key(mitsuba::MANIFEST_FILE)),
                Err(e) => assert!(
                    e.contains("cannot be expressed") || e.contains("cannot be rendered"),
                    "{}: unexpected error {e}",
                    path.display()
                ),
            }
        }
    }
}

/// The housing policy (docs/render-conventions.md §5: the housing casts no shadow) cannot be
/// expressed in Mitsuba 3 (no shadow-ray visibility), so a scene with a sun and a port housing
/// gets one warning line naming the camera; without a sun, or without a port, none.
#[test]
fn sun_and_port_housing_warn_about_the_housing_shadow() {
    let m = showcase();
    let w = mitsuba::housing_shadow_warning(&m).expect("sun + ports: a warning");
    assert!(
        !w.contains('\n') && w.contains("`left`") && w.contains("shadow"),
        "{w}"
    );
    let c = mitsuba::build(&m).unwrap();
    assert!(c.warnings.iter().any(|x| x == &w), "{:?}", c.warnings);
    let mut no_sun = showcase();
    no_sun.sun = None;
    assert_eq!(mitsuba::housing_shadow_warning(&no_sun), None);
    let mut no_port = base("np", camera("cam", Port::None), None, nadir(DVec3::ZERO));
    no_port.sun = showcase().sun;
    assert_eq!(mitsuba::housing_shadow_warning(&no_port), None);
}
