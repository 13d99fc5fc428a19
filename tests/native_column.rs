//! The native renderer's daylight from the water column (`render.daylight = "column"`,
//! crates/poser-optics/src/column.rs) against its own brute-force transport (`"traced"`,
//! bounces raised so that nothing is cut off), on a flat untextured seabed where the column is
//! exact: the sun
//! case and the sky-only case. Also: the column's image is far less noisy at equal samples,
//! a scene where the column cannot apply is refused with a located diagnostic, and `explain`
//! names the views that look down past the seabed (where column and traced differ).

use poser::backend::native::render_one;
use poser::model::Model;

const SCENE: &str = r#"
name = "column_flat"
[site]
depth = "12 m"
surface = "flat"
[water]
jerlov = "IB"
phase = "hg"
g = 0.92
LIGHT
[[objects]]
name = "seabed"
shape = "plane"
width = "400 m"
height = "400 m"
position = [0.0, 0.0, -12.0]
albedo = 0.5
[camera]
width = 24
height = 16
focal_length = "16 mm"
[camera.port]
type = "none"
[network]
type = "explicit"
[[network.poses]]
position = [0.0, 0.0, -10.0]
"#;

/// Column against traced, relative, per channel (measured: within 0.7 % over seeds 1–3).
const AGREE: f64 = 0.01;

const SUN: &str = "[sun]\nelevation = \"60 deg\"\nazimuth = \"180 deg\"\nirradiance = 1000.0";
const SKY: &str = "[[lights]]\ntype = \"ambient\"\nradiance = 30.0";

fn model(light: &str, daylight: &str) -> Model {
    model_under(light, daylight, "fresnel")
}

/// The scene under `light`, with `render.daylight = daylight` and
/// `render.surface_from_below = underside`.
fn model_under(light: &str, daylight: &str, underside: &str) -> Model {
    let sets = [
        format!("render.daylight=\"{daylight}\""),
        format!("render.surface_from_below=\"{underside}\""),
        "render.bounces=200".to_string(),
    ];
    load_text(&SCENE.replace("LIGHT", light), &sets)
}

/// The model of scene `text` with the `--set` overrides `sets`.
fn load_text(text: &str, sets: &[String]) -> Model {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, text).unwrap();
    poser::scene::load(&p, sets).map(|l| l.model).unwrap()
}

/// Mean radiance per channel and the image.
fn render(m: &Model, spp: u32) -> ([f64; 3], Vec<[f32; 3]>) {
    let img = render_one(m, 0, 0, Some(spp)).unwrap();
    let n = img.rgb.len() as f64;
    let mean = [0, 1, 2].map(|c| img.rgb.iter().map(|p| p[c] as f64).sum::<f64>() / n);
    (mean, img.rgb)
}

fn rel_rmse(a: &[[f32; 3]], r: &[[f32; 3]], mean: [f64; 3]) -> f64 {
    let mut worst: f64 = 0.0;
    for c in 0..3 {
        let se = a
            .iter()
            .zip(r)
            .map(|(x, y)| (x[c] as f64 - y[c] as f64).powi(2))
            .sum::<f64>()
            / a.len() as f64;
        worst = worst.max(se.sqrt() / mean[c]);
    }
    worst
}

/// Column against traced under `light` and the surface `underside`; the traced means.
fn agree(light: &str, underside: &str, what: &str) -> [f64; 3] {
    let col = model_under(light, "column", underside);
    let traced = model_under(light, "traced", underside);
    let (mc, _) = render(&col, 512);
    let (mt, _) = render(&traced, 1024);
    for c in 0..3 {
        let rel = (mc[c] - mt[c]) / mt[c];
        eprintln!(
            "{what} channel {c}: column {:.5} traced {:.5} ({:+.2} %)",
            mc[c],
            mt[c],
            100.0 * rel
        );
        assert!(
            rel.abs() < AGREE,
            "{what}, channel {c}: column {} vs traced {} ({:+.2} %)",
            mc[c],
            mt[c],
            100.0 * rel
        );
    }
    mt
}

#[test]
fn column_lit_flat_seabed_matches_brute_force_under_the_sun() {
    agree(SUN, "fresnel", "sun");
}

/// The sky under the reflecting surface (Snell's window) and under the open one, column
/// against traced in each; and the traced transport's two surfaces differ by what the column
/// says the reflecting surface changes at the seabed (E_d there, `Model::surface_reflection_gain`),
/// so the reflection is really there, in the traced transport as in the column.
#[test]
fn column_lit_flat_seabed_matches_brute_force_under_the_sky() {
    let fresnel = agree(SKY, "fresnel", "sky, reflecting surface");
    let open = agree(SKY, "open", "sky, open surface");
    let gain = model(SKY, "traced").surface_reflection_gain().unwrap();
    for c in 0..3 {
        let got = fresnel[c] / open[c] - 1.0;
        let want = gain[c].unwrap();
        eprintln!("channel {c}: reflecting/open − 1: traced {got:+.4}, column's E_d {want:+.4}");
        assert!(
            (got / want - 1.0).abs() < REFLECTION_AGREE,
            "channel {c}: the traced surface changes the image by {got:+.4}, the column's E_d by {want:+.4}"
        );
    }
}

/// The reflecting surface's change of the image mean against the column's change of E_d at the
/// seabed, relative. They are not the same quantity: the image also holds the light the 2 m of
/// water below the camera scatters into it, whose share differs between the surfaces.
const REFLECTION_AGREE: f64 = 0.1;

/// At equal samples the column's image is at least twice as close to its converged self as
/// the traced one is (16 times less variance); measured 5.8 % against 32.6 % at 4 spp (9.7 %
/// before the surfaces' column estimate read the table's bins, which this bound would fail).
#[test]
fn column_is_far_less_noisy_at_equal_samples() {
    let col = model(SUN, "column");
    let traced = model(SUN, "traced");
    let (mc, refc) = render(&col, 1024);
    let (mt, reft) = render(&traced, 1024);
    let (_, c4) = render(&col, 4);
    let (_, t4) = render(&traced, 4);
    let (ec, et) = (rel_rmse(&c4, &refc, mc), rel_rmse(&t4, &reft, mt));
    eprintln!("relative RMSE at 4 spp: column {ec:.3}, traced {et:.3}");
    assert!(ec * 4.0 < et, "column {ec} vs traced {et}");
}

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

/// Coastal water (Jerlov 3C, σs ≈ 1 /m), the camera `height` above a flat seabed 5 m down.
fn turbid(bounces: u32, daylight: &str, height: f64) -> Model {
    let text = SCENE
        .replace("LIGHT", SUN)
        .replace("jerlov = \"IB\"", "jerlov = \"3C\"")
        .replace("depth = \"12 m\"", "depth = \"5 m\"")
        .replace("[0.0, 0.0, -12.0]", "[0.0, 0.0, -5.0]")
        .replace(
            "[0.0, 0.0, -10.0]",
            &format!("[0.0, 0.0, {}]", height - 5.0),
        );
    // The open surface, on which the share's tolerances below were measured; under the
    // reflecting surface the quick solve's share at 8 bounces reads 5.4 points of G high
    // (38.6 % against 33.1 % lost), not yet understood.
    let sets = [
        format!("render.daylight=\"{daylight}\""),
        format!("render.bounces={bounces}"),
        "render.surface_from_below=\"open\"".to_string(),
    ];
    load_text(&text, &sets)
}

/// What `render.bounces` cuts off, as the column measures it (W0239, `explain`:
/// [`Model::bounce_cut`]), is what the traced render loses against an unlimited one, per
/// channel, for a camera close to the seabed and one 0.6 m above it (whose image holds more of
/// the water's own light, which has met more events).
#[test]
fn bounce_limit_share_from_the_column_is_what_the_render_loses() {
    for height in [0.1, 0.6] {
        let (m_full, _) = render(&turbid(200, "traced", height), 1024);
        for b in [2u32, 4, 8] {
            let cut = turbid(b, "traced", height);
            let (m_cut, _) = render(&cut, 1024);
            let share = cut.bounce_cut().expect("a column").share;
            for c in 0..3 {
                let lost = 1.0 - m_cut[c] / m_full[c];
                eprintln!(
                    "{height} m, bounces {b}, channel {c}: lost {:.2} %, column says {:.2} %",
                    100.0 * lost,
                    100.0 * share[c]
                );
                assert!(share[c] > 0.01, "channel {c}: the case should cut light");
                // The quick solve's share moves ±1 point over seeds and reads about 1 point
                // high (a 30° cone about the nadir; this camera sees less); the unlimited
                // traced reference is heavy-tailed: over seeds 0–3 its mean moves ±1.5 points
                // of G's and ±3 of B's loss at 8 bounces.
                let tol = if b < 8 { 0.025 } else { 0.045 };
                assert!(
                    (lost - share[c]).abs() < tol,
                    "{height} m, bounces {b}, channel {c}: lost {lost}, column {}",
                    share[c]
                );
            }
        }
    }
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

/// A textured seabed under coastal water (Jerlov II, sky only, 18 m), the camera 1.5 m above
/// it: a good part of the seabed's light reaches the camera scattered forward on the way,
/// with its texture blurred, not lost. The column's gather traces its directions to the
/// seabed for that light (`GATHER_LEVELS`); reading the column's uniform bottom instead gave
/// the image about half the texture's contrast (regression slope of the traced image on the
/// column's 1.8 / 2.1, G / B), and a mean that took the bottom's albedo for the footprint's
/// (−1.9 % here, +3.6 / +4.3 % on paper_survey's first pose). Measured now: slope 1.01–1.03.
#[test]
fn column_keeps_the_texture_of_the_seabed_seen_through_the_water() {
    const TEXTURED: &str = r#"
name = "column_textured"
[site]
depth = "18 m"
[water]
jerlov = "II"
phase = "hg"
g = 0.9
[[lights]]
type = "ambient"
radiance = 0.05
[[objects]]
name = "seabed"
shape = "plane"
width = "400 m"
height = "400 m"
position = [0.0, 0.0, -18.0]
albedo = [0.3, 0.3, 0.25]
pattern = { type = "fbm", size = "2 m", gain = 0.75, contrast = 0.3, seed = 1 }
[camera]
width = 24
height = 16
pixel_pitch = "1.5 mm"
focal_length = "14 mm"
[camera.port]
type = "none"
[network]
type = "explicit"
[[network.poses]]
position = [0.0, 0.0, -16.5]
"#;
    let load = |daylight: &str| {
        let sets = [
            format!("render.daylight=\"{daylight}\""),
            "render.bounces=64".to_string(),
        ];
        load_text(TEXTURED, &sets)
    };
    let (mc, col) = render(&load("column"), 256);
    let (mt, traced) = render(&load("traced"), 1024);
    for c in 1..3 {
        // The slope of the traced image on the column's, per pixel: the traced noise (20 %
        // per pixel) does not bias it, the column's (1 %) hardly.
        let n = col.len() as f64;
        let (xm, ym) = (mc[c], mt[c]);
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (x, y) in col.iter().zip(&traced) {
            let (x, y) = (x[c] as f64 - xm, y[c] as f64 - ym);
            sxy += x * y;
            sxx += x * x;
        }
        let slope = sxy / sxx;
        let contrast = (sxx / n).sqrt() / xm;
        let rel = mc[c] / mt[c] - 1.0;
        eprintln!(
            "channel {c}: column {xm:.6} traced {ym:.6} ({:+.2} %), texture contrast in the column {contrast:.3}, slope {slope:.3}",
            100.0 * rel
        );
        assert!(
            contrast > 0.1,
            "channel {c}: the seabed's texture must show: {contrast}"
        );
        assert!(
            (slope - 1.0).abs() < 0.15,
            "channel {c}: the column's image holds 1/{slope:.2} of the texture's contrast"
        );
        assert!(rel.abs() < 0.03, "channel {c}: {:+.2} %", 100.0 * rel);
    }
}
