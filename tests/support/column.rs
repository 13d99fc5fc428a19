//! The native column tests' scene (`native_column`, fast tier; `native_column_convergence`,
//! full tier): a flat untextured seabed 12 m down, lit by the sun or the sky, where the water
//! column is exact, and the same in turbid coastal water, with the means and images of one
//! native render.

use poser::backend::native::render_one;
use poser::model::Model;

pub const SCENE: &str = r#"
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

pub const SUN: &str = "[sun]\nelevation = \"60 deg\"\nazimuth = \"180 deg\"\nirradiance = 1000.0";
pub const SKY: &str = "[[lights]]\ntype = \"ambient\"\nradiance = 30.0";

pub fn model(light: &str, daylight: &str) -> Model {
    model_under(light, daylight, "fresnel")
}

/// The scene under `light`, with `render.daylight = daylight` and
/// `render.surface_from_below = underside`.
pub fn model_under(light: &str, daylight: &str, underside: &str) -> Model {
    let sets = [
        format!("render.daylight=\"{daylight}\""),
        format!("render.surface_from_below=\"{underside}\""),
        "render.bounces=200".to_string(),
    ];
    load_text(&SCENE.replace("LIGHT", light), &sets)
}

/// The model of scene `text` with the `--set` overrides `sets`.
pub fn load_text(text: &str, sets: &[String]) -> Model {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("scene.toml");
    std::fs::write(&p, text).unwrap();
    poser::scene::load(&p, sets).map(|l| l.model).unwrap()
}

/// Mean radiance per channel and the image.
pub fn render(m: &Model, spp: u32) -> ([f64; 3], Vec<[f32; 3]>) {
    let img = render_one(m, 0, 0, Some(spp)).unwrap();
    let n = img.rgb.len() as f64;
    let mean = [0, 1, 2].map(|c| img.rgb.iter().map(|p| p[c] as f64).sum::<f64>() / n);
    (mean, img.rgb)
}

pub fn rel_rmse(a: &[[f32; 3]], r: &[[f32; 3]], mean: [f64; 3]) -> f64 {
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

/// Coastal water (Jerlov 3C, σs ≈ 1 /m), the camera `height` above a flat seabed 5 m down.
pub fn turbid(bounces: u32, daylight: &str, height: f64) -> Model {
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
