//! Glass objects (`glass = "N-BK7"` on a box, `poser::model::Material::glass`): the native
//! renderer against Fresnel and Snell, the daylight choice they force, and what the Mitsuba and
//! Blender compilers write for them. The three renderers against each other are in the full
//! tier (`glass_backends`).

use crate::support::column::load_text;
use crate::support::glass_lens;
use glam::DVec3;
use poser::backend::native::render_one;
use poser::model::Model;
use poser::optics::interface::{fresnel_transmittance, refract};

/// A camera in air 2 m above a 6 m emitting panel (radiance 1) facing it, and a 50 mm N-BK7
/// slab 1 m down, turned by `tilt_deg` about x; `width` px wide; the panel `panel` m on a side.
fn slab(tilt_deg: f64, width: u32, panel: f64, with_slab: bool) -> Model {
    let slab = if with_slab {
        format!(
            "[[objects]]\nname = \"window\"\nshape = \"box\"\nsize = [\"2 m\", \"2 m\", \"50 mm\"]\n\
             position = [0.0, 0.0, -1.0]\nrotation = [{}, 0.0, 0.0]\nglass = \"N-BK7\"\n",
            tilt_deg.to_radians()
        )
    } else {
        String::new()
    };
    load_text(
        &format!(
            "name = \"slab\"\n[camera]\nwidth = {width}\nheight = {h}\nsensor_width = \"36 mm\"\n\
             focal_length = \"50 mm\"\n\
             [[lights]]\nname = \"panel\"\ntype = \"area\"\nmount = \"world\"\n\
             position = [0.0, 0.0, -2.0]\naim = [0.0, 0.0, 1.0]\nwidth = {panel}\n\
             height = {panel}\nradiance = 1.0\n{slab}\
             [network]\ntype = \"explicit\"\n[[network.poses]]\nposition = [0.0, 0.0, 0.0]\n\
             look_at = [0.0, 0.0, -2.0]\nup = [0.0, 1.0, 0.0]\n[render]\nsamples = 64\nseed = 1\n",
            h = width * 3 / 4
        ),
        &[],
    )
}

/// Normal incidence through a clear slab of index `n` in air, its multiple reflections
/// summed incoherently: (1 − R)² Σ R²ᵏ = (1 − R) / (1 + R).
fn slab_transmittance(n: f64) -> f64 {
    let r = 1.0 - fresnel_transmittance(1.0, n, 1.0, 1.0);
    (1.0 - r) / (1.0 + r)
}

#[test]
fn a_glass_slab_in_air_transmits_what_fresnel_says() {
    let m = slab(0.0, 40, 6.0, true);
    let n = m.objects[0].material.glass.as_ref().unwrap().ior[1];
    let img = render_one(&m, 0, 0, Some(256)).unwrap();
    // The central 10 × 10 pixels: within 5° of the normal.
    let (w, h) = (img.width as usize, img.height as usize);
    let mut sum = 0.0;
    for y in h / 2 - 5..h / 2 + 5 {
        for x in w / 2 - 5..w / 2 + 5 {
            sum += img.rgb[y * w + x][1] as f64;
        }
    }
    let mean = sum / 100.0;
    let want = slab_transmittance(n);
    assert!((want - 0.919).abs() < 0.002, "{want}");
    // Noise: one Fresnel draw per face, about 0.2 % on this mean (1σ).
    assert!(
        (mean / want - 1.0).abs() < 0.006,
        "through the slab {mean:.5}, Fresnel {want:.5}"
    );
}

/// The radiance-weighted centroid of the G channel, px (pixel centres at +0.5).
fn centroid(m: &Model) -> [f64; 2] {
    let img = render_one(m, 0, 0, Some(64)).unwrap();
    let w = img.width as usize;
    let (mut s, mut su, mut sv) = (0.0, 0.0, 0.0);
    for (i, p) in img.rgb.iter().enumerate() {
        let g = p[1] as f64;
        s += g;
        su += g * ((i % w) as f64 + 0.5);
        sv += g * ((i / w) as f64 + 0.5);
    }
    [su / s, sv / s]
}

/// Where a ray from the pupil (the origin) along `(0, s, −1)` meets the plane z = −2 after
/// crossing the slab (normal `nrm`, faces ±t/2 about `c`, index `n` in air), by Snell at both
/// faces.
fn through_slab(s: f64, nrm: DVec3, c: DVec3, t: f64, n: f64) -> f64 {
    let mut o = DVec3::ZERO;
    let mut d = DVec3::new(0.0, s, -1.0).normalize();
    let nrm = if nrm.dot(d) > 0.0 { nrm } else { -nrm };
    for (k, eta) in [(-0.5, 1.0 / n), (0.5, n)] {
        let p0 = c + nrm * (k * t);
        let tt = nrm.dot(p0 - o) / nrm.dot(d);
        o += d * tt;
        d = refract(d, nrm, eta).unwrap().0.normalize();
    }
    (o + d * ((-2.0 - o.z) / d.z)).y
}

#[test]
fn a_tilted_slab_shifts_the_image_as_snell_says() {
    // A 4 cm panel on the axis, seen through the slab turned by 30°: the slab moves the rays
    // sideways by t·sin(θ − θ′)/cos θ′ ≈ 9.9 mm, 1.4 px here.
    let (w, panel) = (200, 0.04);
    let bare = slab(30.0, w, panel, false);
    let tilted = slab(30.0, w, panel, true);
    let pr = bare.projector(0, 1).unwrap();
    let at = |m: &Model| centroid(m);
    let c0 = at(&bare);
    let p0 = pr.project_world(0, DVec3::new(0.0, 0.0, -2.0)).unwrap();
    assert!(
        (c0[0] - p0[0]).abs() < 0.02 && (c0[1] - p0[1]).abs() < 0.02,
        "{c0:?} {p0:?}"
    );
    // The pinhole ray whose path through the slab ends on the panel's centre (bisection).
    let o = &tilted.objects[0];
    let n = o.material.glass.as_ref().unwrap().ior[1];
    let nrm = o.pose.rotation * DVec3::Z;
    let f = |s: f64| through_slab(s, nrm, o.pose.translation, 0.05, n);
    let (mut lo, mut hi) = (-0.1, 0.1);
    assert!(f(lo) * f(hi) < 0.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if f(lo) * f(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let s = 0.5 * (lo + hi);
    let want = pr.project_world(0, DVec3::new(0.0, 2.0 * s, -2.0)).unwrap();
    let got = at(&tilted);
    let shift = ((want[0] - p0[0]).powi(2) + (want[1] - p0[1]).powi(2)).sqrt();
    assert!(
        shift > 1.0,
        "the slab should move the panel's image: {shift} px"
    );
    assert!(
        (got[0] - want[0]).abs() < 0.03 && (got[1] - want[1]).abs() < 0.03,
        "rendered {got:?}, Snell {want:?} (bare {c0:?})"
    );
}

/// The exact and the native image of a glass-lens scene: (flux px, centroid px) of each.
fn lens_images(lens: glass_lens::Lens) -> ((f64, [f64; 2]), (f64, [f64; 2])) {
    let m = glass_lens::scene(lens);
    let img = render_one(&m, 0, 0, None).unwrap();
    let want = glass_lens::exact_image(lens, &m);
    let got: Vec<f64> = img.rgb.iter().map(|p| p[1] as f64).collect();
    let w = img.width as usize;
    let (exact, native) = (
        glass_lens::flux_centroid(&want, w),
        glass_lens::flux_centroid(&got, w),
    );
    eprintln!("{lens:?}: exact {exact:?}, native {native:?}");
    (exact, native)
}

#[test]
fn a_glass_ball_images_the_panel_where_exact_refraction_puts_it() {
    // The square's image through the ball lens: its flux and centroid by 16 × 16 rays per
    // pixel, traced exactly with every Fresnel branch, against the native render at 256 spp.
    // Measured: flux 26.946 px against 26.951, centroid within 0.022 px. The 64-segment mesh
    // of an opaque sphere in its place moved the centroid by 0.42 px: facets refract.
    let ((fw, cw), (fg, cg)) = lens_images(glass_lens::Lens::Ball);
    // Inverted: the square lies at +x, +y (right of and above the image centre when seen
    // directly); its image through the ball lies left of and below the ball's centre.
    assert!(cw[0] < 100.0 && cw[1] > 75.0, "{cw:?}");
    assert!((fg / fw - 1.0).abs() < 0.02, "flux {fg} vs {fw}");
    assert!(
        (cg[0] - cw[0]).abs() < 0.05 && (cg[1] - cw[1]).abs() < 0.05,
        "native {cg:?}, exact {cw:?}"
    );
}

#[test]
fn a_glass_rod_images_the_panel_where_exact_refraction_puts_it() {
    // The same with a 30 cm rod along x: a cylindrical lens, inverting across its axis only
    // (the image below the centre, still right of it), exact through its side and caps.
    let ((fw, cw), (fg, cg)) = lens_images(glass_lens::Lens::Rod);
    assert!(cw[0] > 100.0 && cw[1] > 75.0, "{cw:?}");
    assert!((fg / fw - 1.0).abs() < 0.02, "flux {fg} vs {fw}");
    assert!(
        (cg[0] - cw[0]).abs() < 0.05 && (cg[1] - cw[1]).abs() < 0.05,
        "native {cg:?}, exact {cw:?}"
    );
}

const SUN_SEABED: &str = include_str!("canonical/sun_seabed.toml");
const BLOCK: &str = "\n[[objects]]\nname = \"block\"\nshape = \"box\"\nsize = [0.4, 0.3, 0.2]\n\
                     position = [0.3, 0.2, -4.5]\nrotation = [10.0, 20.0, 30.0]\nglass = \"PMMA\"\n";

#[test]
fn glass_objects_keep_daylight_traced() {
    // Scattering water, where the column applies.
    let sets = ["water.scattering=0.1".to_string()];
    let plain = load_text(SUN_SEABED, &sets);
    assert!(
        plain.daylight_choice(None).0.is_some(),
        "{}",
        plain.daylight_choice(None).1
    );
    let m = load_text(&format!("{SUN_SEABED}{BLOCK}"), &sets);
    let (input, why) = m.daylight_choice(None);
    assert!(
        input.is_none() && why.contains("glass object `block`"),
        "{why}"
    );
}

/// A number as the Mitsuba XML writes it.
fn xml_num(x: f64) -> String {
    poser::backend::mitsuba::xml::num(x)
}

#[test]
fn mitsuba_puts_glass_in_each_view_with_the_water_outside() {
    let m = load_text(&format!("{SUN_SEABED}{BLOCK}"), &[]);
    let c = poser::backend::mitsuba::build(&m).unwrap();
    let world = String::from_utf8(c.files["world.xml"].clone()).unwrap();
    assert!(!world.contains("dielectric"), "glass is not in world.xml");
    let view = String::from_utf8(c.files["img_0001.xml"].clone()).unwrap();
    let at = view.find("object `block`: PMMA glass").expect(&view);
    let shape = &view[at..view[at..].find("</shape>").unwrap() + at];
    let n = m.objects[1].material.glass.as_ref().unwrap().ior[1];
    let n_w = m.ambient_ior()[1];
    for want in [
        "type=\"dielectric\"".to_string(),
        format!("name=\"int_ior\" value=\"{}\"", xml_num(n)),
        format!("name=\"ext_ior\" value=\"{}\"", xml_num(n_w)),
        "name=\"exterior\"".to_string(),
    ] {
        assert!(shape.contains(&want), "{want} in {shape}");
    }
}

#[test]
fn blender_describes_the_glass_and_its_indices() {
    let m = load_text(&format!("{SUN_SEABED}{BLOCK}"), &[]);
    let d = poser::backend::blender::data::describe(&m).unwrap();
    let g = &d.json["objects"][1]["material"]["glass"];
    assert_eq!(g["name"], "PMMA");
    let ior = m.objects[1].material.glass.as_ref().unwrap().ior;
    for c in 0..3 {
        assert_eq!(g["ior"][c].as_f64().unwrap(), ior[c]);
    }
    assert!(d.json["objects"][0]["material"].get("glass").is_none());
}

const BALL: &str = "\n[[objects]]\nname = \"ball\"\nshape = \"sphere\"\nradius = 0.15\n\
                    position = [-0.5, 0.35, -4.7]\nscale = 1.5\nglass = \"N-BK7\"\n";

/// Compiled to Mitsuba and imported back (`poser import` of a view), the block and the ball
/// are the same glass objects: their glass, size, place and orientation.
#[test]
fn a_glass_object_survives_the_round_trip_through_mitsuba() {
    let m = load_text(&format!("{SUN_SEABED}{BLOCK}{BALL}"), &[]);
    let dir = tempfile::tempdir().unwrap();
    poser::backend::mitsuba::compile(&m, &dir.path().join("m")).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .current_dir(dir.path())
        .args(["import", "m/img_0001.xml", "-o", "back/scene.toml"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let back = poser::scene::load(&dir.path().join("back/scene.toml"), &[])
        .map_err(|f| f.render())
        .unwrap()
        .model;
    let (a, b) = (
        &m.objects[1],
        back.objects.iter().find(|o| o.name == "block").unwrap(),
    );
    assert_eq!(
        b.material.glass.as_ref().map(|g| g.name.as_str()),
        Some("PMMA")
    );
    let (poser::model::Shape::Box { size: sa }, poser::model::Shape::Box { size: sb }) =
        (&a.shape, &b.shape)
    else {
        panic!("{:?}", b.shape)
    };
    assert!((*sa * a.scale - *sb * b.scale).abs().max_element() < 1e-9);
    assert!((a.pose.translation - b.pose.translation).length() < 1e-9);
    let r = a.pose.rotation.transpose() * b.pose.rotation;
    assert!(
        (r - glam::DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|x| x.abs() < 1e-9)
    );
    let ball = back.objects.iter().find(|o| o.name == "ball").unwrap();
    assert_eq!(
        ball.material.glass.as_ref().map(|g| g.name.as_str()),
        Some("N-BK7")
    );
    let poser::model::Shape::Sphere { radius } = ball.shape else {
        panic!("{:?}", ball.shape)
    };
    assert!(
        (radius * ball.scale.x - 0.225).abs() < 1e-9,
        "{radius} × {}",
        ball.scale
    );
    assert!((ball.pose.translation - m.objects[2].pose.translation).length() < 1e-9);
}

/// The ground truth does not refract through glass: it counts a glass object as opaque, so a
/// target behind a window is left out of the truth of the images that see it through the glass
/// (W0406 says so when the scene is loaded), and is in it without the window.
#[test]
fn the_truth_leaves_out_what_glass_hides() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/invalid/warn_target_behind_glass.toml");
    let loaded = poser::scene::load(&path, &[])
        .map_err(|f| f.render())
        .unwrap();
    assert!(loaded.warnings.iter().any(|w| w.code == "W0406"));
    let with = poser::truth::compute(&loaded.model).unwrap();
    let mut bare = loaded.model.clone();
    bare.objects.retain(|o| o.material.glass.is_none());
    let without = poser::truth::compute(&bare).unwrap();
    let count = |t: &poser::truth::Truth| {
        t.images
            .iter()
            .flat_map(|i| &i.points)
            .filter(|p| p.target == "grid")
            .count()
    };
    assert_eq!(count(&without), 6);
    assert_eq!(count(&with), 0);
}

/// A camera inside a glass sphere or cylinder is refused (E0405), and a target seen through one
/// is warned of (W0406), as for a box: the checks take every glass shape. The scene is the
/// invalid corpus's base (camera at z = −3 looking down at z = −5) with its objects replaced.
#[test]
fn a_glass_sphere_or_cylinder_around_the_camera_or_before_a_target_is_caught() {
    let base = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/invalid/warn_target_behind_glass.toml");
    let codes = |object: &str| -> Vec<String> {
        let sets = vec![format!("objects=[{object}]")];
        match poser::scene::load(&base, &sets) {
            Ok(l) => l.warnings.iter().map(|w| w.code.to_string()).collect(),
            Err(f) => f.diagnostics.iter().map(|d| d.code.to_string()).collect(),
        }
    };
    for shape in [
        "shape=\"sphere\", radius=\"0.6 m\"",
        "shape=\"cylinder\", radius=\"0.6 m\", height=\"1 m\"",
    ] {
        let around = codes(&format!(
            "{{name=\"glass\", {shape}, position=[0, 0, -3.1], glass=\"PMMA\"}}"
        ));
        assert!(around.contains(&"E0405".to_string()), "{shape}: {around:?}");
        let between = codes(&format!(
            "{{name=\"glass\", {shape}, position=[0, 0, -4.2], glass=\"PMMA\"}}"
        ));
        assert!(
            between.contains(&"W0406".to_string()),
            "{shape}: {between:?}"
        );
        // Beside the line of sight: neither.
        let beside = codes(&format!(
            "{{name=\"glass\", {shape}, position=[3, 0, -4.2], glass=\"PMMA\"}}"
        ));
        assert!(
            !beside.contains(&"W0406".to_string()) && !beside.contains(&"E0405".to_string()),
            "{shape}: {beside:?}"
        );
    }
}

/// Glass and filled objects may touch but not overlap (E0407): a tank's window sunk 5 cm into
/// its water is refused; the same window standing on the water's top face loads.
#[test]
fn a_window_against_a_tanks_water_loads_and_one_inside_it_is_refused() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/invalid/glass_overlaps_filled_object.toml");
    let failure = poser::scene::load(&path, &[]).err().expect("E0407");
    assert!(
        failure.diagnostics.iter().any(|d| d.code == "E0407"),
        "{}",
        failure.render()
    );
    let against = vec!["objects.1.position=[0, 0, -4.19]".to_string()];
    if let Err(f) = poser::scene::load(&path, &against) {
        panic!("{}", f.render());
    }
}
