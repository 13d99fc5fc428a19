//! Filled objects (`fill = { … }` on a box, sphere or cylinder, `poser::model::Material::fill`):
//! a tank, a jar, a sample of turbid water in the scene. The native renderer against Beer–
//! Lambert and Fresnel, the bounce limit they get, what the Mitsuba compiler writes, and the
//! located errors. The three renderers against each other are in the full tier
//! (`filled_backends`). docs/scenes.md, "Filled objects".

use crate::support::column::load_text;
use poser::backend::native::render_one;
use poser::model::Model;
use poser::optics::interface::fresnel_transmittance;

/// A camera in air looking down a 1 m deep box of water (2 × 2 m across, 1.5 m below it)
/// against a sky of radiance 1; `fill` is the box's water table.
fn tank(fill: &str, extra: &str) -> String {
    format!(
        "name = \"tank\"\n[camera]\nwidth = 40\nheight = 30\nsensor_width = \"36 mm\"\n\
         focal_length = \"50 mm\"\n[[lights]]\nname = \"sky\"\ntype = \"ambient\"\nradiance = 1.0\n\
         [[objects]]\nname = \"tank\"\nshape = \"box\"\nsize = [\"2 m\", \"2 m\", \"1 m\"]\n\
         position = [0.0, 0.0, -2.0]\nfill = {fill}\n{extra}\
         [network]\ntype = \"explicit\"\n[[network.poses]]\nposition = [0.0, 0.0, 0.0]\n\
         look_at = [0.0, 0.0, -2.0]\nup = [0.0, 1.0, 0.0]\n[render]\nsamples = 64\nseed = 1\n"
    )
}

/// Mean of the central 6 × 6 pixels (within 2° of the axis).
fn centre(m: &Model, spp: u32) -> [f64; 3] {
    let img = render_one(m, 0, 0, Some(spp)).unwrap();
    let (w, h) = (img.width as usize, img.height as usize);
    let mut s = [0.0; 3];
    for y in h / 2 - 3..h / 2 + 3 {
        for x in w / 2 - 3..w / 2 + 3 {
            for (c, v) in s.iter_mut().enumerate() {
                *v += img.rgb[y * w + x][c] as f64 / 36.0;
            }
        }
    }
    s
}

const SIGMA_A: [f64; 3] = [0.5, 1.0, 2.0];

#[test]
fn an_index_matched_tank_transmits_beer_lambert() {
    // Index 1 (no refraction, no reflection) and no scattering: the sky seen through 1 m of
    // water is e^(−σa·1 m) on the axis, with no noise.
    let m = load_text(
        &tank(
            "{ absorption = [0.5, 1.0, 2.0], scattering = 0, ior = 1.0 }",
            "",
        ),
        &[],
    );
    let got = centre(&m, 4);
    for c in 0..3 {
        let want = (-SIGMA_A[c]).exp();
        // The central pixels look up to 2° off the axis: paths up to 0.06 % longer.
        assert!(
            got[c] < want && got[c] / want > 1.0 - 2e-3 * SIGMA_A[c],
            "channel {c}: {} for {want}",
            got[c]
        );
    }
}

#[test]
fn a_water_tank_reflects_and_transmits_as_fresnel_says() {
    // Index 1.5: the sky seen through the slab, its internal reflections summed incoherently,
    // plus the sky the slab reflects: R_slab + T_slab at normal incidence.
    let m = load_text(
        &tank(
            "{ absorption = [0.5, 1.0, 2.0], scattering = 0, ior = 1.5 }",
            "",
        ),
        &[],
    );
    let r = 1.0 - fresnel_transmittance(1.0, 1.5, 1.0, 1.0);
    let got = centre(&m, 1024);
    for c in 0..3 {
        let t = (-SIGMA_A[c]).exp();
        let tt = (1.0 - r) * (1.0 - r) * t / (1.0 - r * r * t * t);
        let rr = r + (1.0 - r) * (1.0 - r) * r * t * t / (1.0 - r * r * t * t);
        let want = tt + rr;
        // One Fresnel draw per face: about 0.5 % noise (1σ) on 36 pixels × 1024 samples.
        assert!(
            (got[c] / want - 1.0).abs() < 0.01,
            "channel {c}: {:.5} for {want:.5} (T {tt:.5}, R {rr:.5})",
            got[c]
        );
    }
    // Without the water's absorption the same box would be far brighter: the fill is used.
    let clear = load_text(
        &tank("{ absorption = 0, scattering = 0, ior = 1.5 }", ""),
        &[],
    );
    assert!(centre(&clear, 64)[2] > 3.0 * got[2]);
}

#[test]
fn a_scattering_fill_raises_the_default_bounce_limit_and_a_low_one_warns() {
    let scattering = "{ absorption = 0.1, scattering = 1.5, g = 0.8 }";
    let m = load_text(&tank(scattering, ""), &[]);
    assert_eq!(m.render.max_bounces, 64);
    // `poser explain` says where the water is.
    let reasons = m.needs.reasons.join("\n");
    assert!(
        reasons.contains("water only inside the 1 filled object(s)")
            && reasons.contains("filled object `tank`: water inside, σa = [0.1000"),
        "{reasons}"
    );
    // A clear fill keeps the default.
    let clear = load_text(&tank("{ absorption = 0.1, scattering = 0 }", ""), &[]);
    assert_eq!(clear.render.max_bounces, 8);
    // Written below it: W0241 names the object and the bounces.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    std::fs::write(
        &p,
        tank(scattering, "").replace("samples = 64", "samples = 64\nbounces = 8"),
    )
    .unwrap();
    let loaded = poser::scene::load(&p, &[]).unwrap();
    let text: String = loaded.warnings.iter().map(|d| format!("{d:?}")).collect();
    assert!(text.contains("W0241") && text.contains("`tank`"), "{text}");
}

fn errors(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, text).unwrap();
    match poser::scene::load(&p, &[]) {
        Ok(_) => panic!("loaded:\n{text}"),
        Err(f) => f.render(),
    }
}

#[test]
fn filled_objects_refuse_what_they_cannot_be() {
    let water = "{ jerlov = \"3C\" }";
    // Glass and fill on one object.
    let e = errors(&tank(water, "glass = \"N-BK7\"\n"));
    assert!(e.contains("E0303") && e.contains("help:"), "{e}");
    // A plane holds nothing.
    let e = errors(&tank(water, "").replace("shape = \"box\"", "shape = \"plane\""));
    assert!(e.contains("E0296") && e.contains("filled object"), "{e}");
    // A filled object has no colour.
    let e = errors(&tank(water, "albedo = 0.5\n"));
    assert!(
        e.contains("E0292") && e.contains("a filled object has no `albedo`"),
        "{e}"
    );
    // The object is the water's extent.
    let e = errors(&tank("{ jerlov = \"3C\", extent = \"box\" }", ""));
    assert!(e.contains("E0100") && e.contains("extent"), "{e}");
    // A camera inside it.
    let e = errors(&tank(water, "").replace(
        "position = [0.0, 0.0, -2.0]\nfill",
        "position = [0.0, 0.0, -0.2]\nfill",
    ));
    assert!(
        e.contains("E0304") && e.contains("inside filled object `tank`"),
        "{e}"
    );
    // A lamp inside it.
    let lamp = "[[lights]]\nname = \"lamp\"\ntype = \"point\"\nmount = \"world\"\n\
                position = [0.0, 0.0, -2.0]\nintensity = 10\n";
    let e = errors(&tank(water, lamp));
    assert!(
        e.contains("E0305") && e.contains("light `lamp` is inside"),
        "{e}"
    );
}

#[test]
fn mitsuba_gets_the_water_as_the_objects_interior() {
    let m = load_text(
        &tank("{ absorption = [0.5, 1.0, 2.0], scattering = 0.3 }", ""),
        &[],
    );
    let dir = tempfile::tempdir().unwrap();
    poser::backend::mitsuba::compile(&m, dir.path()).unwrap();
    let xml =
        std::fs::read_to_string(dir.path().join(format!("{}.xml", m.image_name(0, 0)))).unwrap();
    let medium = xml
        .find("<medium type=\"homogeneous\" id=\"fill_0\">")
        .expect(&xml);
    let interior = xml
        .find("<ref name=\"interior\" id=\"fill_0\"/>")
        .expect(&xml);
    assert!(medium < interior, "the medium is declared before its use");
    assert!(xml.contains("int_ior"), "its faces are a dielectric");
    // In air: `volpath` (see the full tier for why not `volpathmis`).
    assert!(xml.contains("<integrator type=\"volpath\">"), "{xml}");
}

/// Mitsuba's medium inside a shape comes back as a filled object: poser's own jar compiled and
/// imported (a `dielectric` sphere of the water's index with its `interior` medium), and a
/// hand-written fog box (a `null` cube holding a medium given by σt, albedo and scale).
#[test]
fn a_medium_inside_a_mitsuba_shape_imports_as_a_filled_object() {
    let src = tank(
        "{ absorption = [0.5, 1.0, 2.0], scattering = [0.3, 0.2, 0.1], g = 0.7 }",
        "",
    );
    let m = load_text(&src, &[]);
    let dir = tempfile::tempdir().unwrap();
    poser::backend::mitsuba::compile(&m, &dir.path().join("mi")).unwrap();
    let xml = dir.path().join(format!("mi/{}.xml", m.image_name(0, 0)));
    let out = dir.path().join("back/scene.toml");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["import", xml.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let back = poser::scene::load(&out, &[]).unwrap().model;
    assert!(
        back.water.is_none(),
        "the fill's medium is not the scene's water"
    );
    let o = back
        .objects
        .iter()
        .find(|o| o.material.fill.is_some())
        .expect("a filled object");
    let (a, b) = (
        m.objects[0].material.fill.as_ref().unwrap(),
        o.material.fill.as_ref().unwrap(),
    );
    for c in 0..3 {
        assert!(
            (a.absorption[c] - b.absorption[c]).abs() < 1e-9,
            "{a:?} {b:?}"
        );
        assert!(
            (a.scattering[c] - b.scattering[c]).abs() < 1e-9,
            "{a:?} {b:?}"
        );
    }
    assert!(
        matches!(b.phase, poser::model::Phase::HenyeyGreenstein { g } if (g - 0.7).abs() < 1e-12)
    );
    assert!(
        matches!(o.shape, poser::model::Shape::Box { size } if (size - glam::DVec3::new(2.0, 2.0, 1.0)).length() < 1e-9)
    );
    // Its faces keep the water's index (green's: Mitsuba's dielectric takes one).
    assert!((b.ior[1] - a.ior[1]).abs() < 1e-9);

    // A fog box: a `null` cube holding a medium, in front of a camera looking down -z.
    let fog = r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
  <medium type="homogeneous" id="fog">
    <rgb name="sigma_t" value="2, 1, 0.5"/><rgb name="albedo" value="0.5, 0.5, 0.5"/>
    <float name="scale" value="0.5"/><phase type="isotropic"/>
  </medium>
  <shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/>
    <transform name="to_world"><scale value="0.5"/><translate z="-3"/></transform>
  </shape>
</scene>"#;
    std::fs::write(dir.path().join("fog.xml"), fog).unwrap();
    let out = dir.path().join("fog/scene.toml");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args([
            "import",
            dir.path().join("fog.xml").to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let fog = poser::scene::load(&out, &[]).unwrap().model;
    assert!(fog.water.is_none());
    let w = fog.objects[0]
        .material
        .fill
        .as_ref()
        .expect("a filled object");
    assert_eq!(w.absorption, [0.5, 0.25, 0.125]);
    assert_eq!(w.scattering, [0.5, 0.25, 0.125]);
    assert_eq!(w.ior, [1.0; 3], "a null boundary");
    assert!(matches!(w.phase, poser::model::Phase::HenyeyGreenstein { g } if g == 0.0));
}

#[test]
fn a_camera_in_a_filled_box_is_one_error_and_a_target_behind_one_is_warned() {
    let water = "{ jerlov = \"3C\" }";
    let e = errors(&tank(water, "").replace(
        "position = [0.0, 0.0, -2.0]\nfill",
        "position = [0.0, 0.0, -0.2]\nfill",
    ));
    assert!(
        e.contains("E0304") && !e.contains("E0405"),
        "one error, not a glass one too: {e}"
    );
    // A target behind the tank: the truth counts the tank opaque, and says so.
    let target = "[[targets]]\nname = \"board\"\ntype = \"checkerboard\"\ncols = 4\nrows = 3\n\
                  square = \"5 cm\"\nposition = [0.0, 0.0, -3.0]\n";
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, tank(water, target)).unwrap();
    let loaded = poser::scene::load(&p, &[]).unwrap();
    let text: String = loaded.warnings.iter().map(|d| format!("{d:?}")).collect();
    assert!(
        text.contains("W0406") && text.contains("seen through filled object `tank`"),
        "{text}"
    );
}
