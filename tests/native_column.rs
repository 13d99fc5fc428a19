//! The native renderer's daylight from the water column (`render.daylight = "column"`,
//! crates/poser-optics/src/column.rs), the quick checks: the column's image is far less noisy
//! than the traced one at equal samples, a scene where the column cannot apply is refused with a
//! located diagnostic, a bounce limit that drops light is a located warning with its share, and
//! `explain` names the views that look down past the seabed. Its agreement with the brute-force
//! transport (minutes of CPU) is the full tier's `native_column_convergence`.

use crate::support::column::*;

/// `daylight = "column"` where the column cannot apply is an error at the key.
#[test]
fn column_where_it_cannot_apply_is_a_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    let text = SCENE.replace("LIGHT", "") + "[render]\ndaylight = \"column\"\n";
    std::fs::write(&p, text).unwrap();
    let err = match poser::scene::load(&p, &[]) {
        Ok(_) => panic!("a sunless, skyless column was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("E0238"), "{err}");
    assert!(err.contains("no daylight"), "{err}");
    assert!(err.contains("scene.toml:"), "{err}");
}

/// A limit that cuts off more than 1 % of the seabed's daylight is a located warning with the
/// share and the bounces that would do; the column (every order) or enough bounces silence it.
#[test]
fn a_bounce_limit_that_drops_light_is_a_warning_with_its_share() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    let text = SCENE
        .replace("LIGHT", SUN)
        .replace("jerlov = \"IB\"", "jerlov = \"3C\"")
        + "[render]\nbounces = 4\ndaylight = \"traced\"\n";
    std::fs::write(&p, &text).unwrap();
    let l = poser::scene::load(&p, &[]).unwrap();
    let w = l.render_warnings();
    assert!(w.contains("W0239"), "{w}");
    assert!(w.contains("render.bounces = 4 cuts off"), "{w}");
    assert!(w.contains("scene.toml:"), "{w}");
    assert!(
        w.contains("bounces = 4"),
        "the label points at the key: {w}"
    );
    assert!(w.contains("raise `render.bounces` to"), "{w}");
    let quiet = |sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let l = poser::scene::load(&p, &sets).unwrap();
        l.warnings.iter().all(|d| d.code != "W0239")
    };
    assert!(quiet(&["render.daylight=\"column\""]));
    assert!(quiet(&["render.bounces=400"]));
}

/// A seabed patch smaller than the view: the camera looks down past it into water without a
/// bottom, which the column lights as if the seabed went on and traced daylight leaves
/// bottomless. `explain` says how much of the view does (measured on the shipped archaeology
/// scene before its backdrop plane, whose first pose saw 1 m past its 16 m seabed: column +14 %
/// (G) against traced;
/// with a 200 m seabed +0.5 %, docs/column.md).
#[test]
fn explain_names_views_past_the_seabed() {
    let line = |width: &str| {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("scene.toml");
        let scene = SCENE.replace("LIGHT", SUN).replace(
            "width = \"400 m\"\nheight = \"400 m\"",
            &format!("width = \"{width}\"\nheight = \"{width}\""),
        );
        std::fs::write(&p, scene).unwrap();
        let m = poser::scene::load(&p, &[]).map(|l| l.model).unwrap();
        let text = poser::explain::explain(&m);
        let daylight = text
            .lines()
            .find(|l| l.starts_with("daylight (native):"))
            .map(str::to_string)
            .unwrap();
        let past = text
            .lines()
            .find(|l| l.contains("looks past the seabed") || l.contains("looks down past every"))
            .map(str::to_string);
        (daylight, past)
    };
    // 2 m above the seabed, a 16 mm lens on 24 × 16 px of 3.76 µm: a footprint of 11 × 8 mm.
    // Under "auto" (the default) such views keep daylight traced, and the line says why.
    let (daylight, small) = line("2 mm");
    let small = small.expect("a 2 mm seabed seen from 2 m must be named");
    assert!(
        daylight.contains("daylight (native): traced:"),
        "{daylight}"
    );
    let share: f64 = small
        .split(" % of the cameras' view")
        .next()
        .and_then(|h| h.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no share in {small}"));
    assert!(share > 20.0 && share < 100.0, "{small}");
    let (daylight, wide) = line("400 m");
    assert_eq!(wide, None, "a seabed wider than the view is not named");
    assert!(daylight.contains("daylight (native): column"), "{daylight}");
}

/// An unshaded surface takes the column's light without its noise, however it is tilted: the
/// renderer adds the irradiance an open plane of its normal receives, exactly, and estimates
/// by next-event estimation only what the local geometry changes (`Integrator::column_nee`,
/// crates/poser-optics/src/column/open.rs). A plane tilted about two axes over open water,
/// one bounce (the camera ray's gather and the surface's estimate), 4 spp. Measured, median
/// and largest relative noise of a pixel (G, B): sun 0.10 / 0.06 % and 1.6 / 1.6 %; sky 0.11
/// / 0.09 % and 1.9 / 1.7 % (0.33 / 0.36 % and 0.33 / 0.35 % median before the camera ray's
/// gather took its own control variate, below). The one-direction estimate alone (before
/// both): sun 4.1 / 1.9 % and 13 / 18 %; sky 6.4 / 3.5 % and 33 / 20 %.
#[test]
fn an_unshaded_tilted_surface_takes_the_columns_light_without_its_noise() {
    for light in [SUN, SKY] {
        let text = SCENE.replace("LIGHT", light).replace(
            "width = \"400 m\"\nheight = \"400 m\"\nposition = [0.0, 0.0, -12.0]",
            "width = \"6 m\"\nheight = \"6 m\"\nposition = [0.0, 0.0, -11.5]\nrotation = \"35, 20, 0 deg\"",
        );
        assert!(text.contains("35, 20, 0 deg"));
        let sets = [
            "render.daylight=\"column\"".to_string(),
            "render.bounces=1".to_string(),
        ];
        let m = load_text(&text, &sets);
        assert_quiet(&m, 0.01, 0.06);
    }
}

/// The water in front of the camera takes the open column's in-scattered light without its
/// noise: the camera ray's gather adds the light the open column's water along the ray
/// scatters towards the camera, exactly (`Column::scattered_along`,
/// crates/poser-optics/src/column/scatter.rs), and estimates by one traced point and
/// direction only what the local geometry changes. A camera 6 m above a uniform seabed in
/// turbid coastal water (Jerlov 3C, where the water's own light is most of the image), one
/// bounce, 4 spp. Measured, median and largest relative noise of a pixel (G, B): sun 1.6 /
/// 1.3 % and 5.1 / 7.2 %; sky 0.9 / 1.5 % and 6.2 / 6.0 %. The gather without the control
/// variate: sun 14.8 % and 41.8 % (G), about 80× the variance.
#[test]
fn the_water_in_view_takes_the_columns_scattered_light_without_its_noise() {
    for light in [SUN, SKY] {
        let text = SCENE
            .replace("LIGHT", light)
            .replace("jerlov = \"IB\"", "jerlov = \"3C\"")
            .replace(
                "position = [0.0, 0.0, -10.0]",
                "position = [0.0, 0.0, -6.0]",
            );
        assert!(text.contains("-6.0]"));
        let sets = [
            "render.daylight=\"column\"".to_string(),
            "render.bounces=1".to_string(),
        ];
        let m = load_text(&text, &sets);
        assert_quiet(&m, 0.03, 0.1);
    }
}

/// In green and blue, the median and largest relative noise of a pixel (its standard error
/// over its mean) of the first image at 4 spp are under `median` and `worst`.
fn assert_quiet(m: &poser::model::Model, median: f64, worst: f64) {
    let img = poser::backend::native::render_one(m, 0, 0, Some(4)).unwrap();
    for c in 1..3 {
        let mut rel: Vec<f64> = img
            .rgb
            .iter()
            .zip(&img.variance)
            .map(|(p, v)| (v[c] as f64).sqrt() / p[c] as f64)
            .collect();
        assert!(
            rel.iter().all(|r| r.is_finite()),
            "channel {c}: a black pixel"
        );
        rel.sort_by(f64::total_cmp);
        let (med, max) = (rel[rel.len() / 2], rel[rel.len() - 1]);
        let what = format!(
            "channel {c}: relative noise of a pixel, median {:.3} %, largest {:.3} %",
            100.0 * med,
            100.0 * max
        );
        eprintln!("{what}");
        assert!(med < median && max < worst, "{what}");
    }
}

/// Clear water (no scattering) takes the column as well: its surfaces get the sky's light
/// through Snell's window by the column's estimate (the open irradiance exact, one shadow ray
/// for what the surroundings change), not by a cosine direction half of which leave the window.
/// The flat seabed 2 m below the camera, one bounce, under the sun and under the sky: the
/// column's means agree with traced daylight at 200 bounces within 1 % (measured: −0.04 to
/// +0.04 % in G and B), and its pixels are quiet at 4 spp where the traced sky's are not
/// (measured: at most 0.022 % per pixel with the column; traced under the sky, median 58 % in G).
#[test]
fn clear_water_takes_the_column_and_its_sky_without_noise() {
    for light in [SUN, SKY] {
        let text = SCENE
            .replace("LIGHT", light)
            .replace("jerlov = \"IB\"", "jerlov = \"IB\"\nscattering = 0");
        assert!(text.contains("scattering = 0"));
        let load = |daylight: &str, bounces: u32| {
            let sets = [
                format!("render.daylight=\"{daylight}\""),
                format!("render.bounces={bounces}"),
            ];
            load_text(&text, &sets)
        };
        let auto = load("auto", 1);
        assert!(auto.column_input().is_ok(), "{:?}", auto.column_input());
        let column = load("column", 1);
        assert_quiet(&column, 0.005, 0.02);
        let (mc, _) = render(&column, 256);
        let (mt, _) = render(&load("traced", 200), 1024);
        for c in 1..3 {
            let d = mc[c] / mt[c] - 1.0;
            let what = format!(
                "clear water, channel {c}: column {:.5} traced {:.5} ({:+.2} %)",
                mc[c],
                mt[c],
                100.0 * d
            );
            eprintln!("{what}");
            assert!(d.abs() < 0.01, "{what}");
        }
    }
}
