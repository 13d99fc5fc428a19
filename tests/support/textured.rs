//! The textured-mesh test site (`tests/textures/mesh.toml`, issue 36): loading it, and where the
//! disk printed in its texture is in a render against where the truth projects it.

use poser::model::Model;
use std::path::Path;

/// Load a scene (panics with the diagnostics).
pub fn load(path: &Path) -> Model {
    match poser::scene::load(path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}

/// The disk printed in the texture (radius 16 texels at texel-edge (160, 128) of 512 × 384 on
/// the 1 m × 0.75 m quad, on a white square of half-size 3 radii: `tests/textures/mesh/make.py`),
/// as a target the compare module measures.
pub fn texture_disk(model: &Model) -> poser::compare::Disk {
    let o = &model.objects[0];
    let local = glam::DVec3::new(-0.5 + 160.0 / 512.0, 0.375 - 0.75 * 128.0 / 384.0, 0.0);
    poser::compare::Disk {
        id: "texture disk".into(),
        center: o.pose.transform_point(local),
        normal: o.pose.rotation.z_axis,
        radius: 16.0 / 512.0,
        clear_radius: 3.0 * 16.0 / 512.0,
        x_axis: Some(o.pose.rotation.x_axis),
    }
}

/// Measured − expected position of the texture's disk in the render in `dir`, px.
pub fn disk_error(model: &Model, dir: &Path) -> [f64; 2] {
    let proj = model.projector(0, 1).unwrap();
    let (c, half) = poser::compare::expected_disk(&proj, None, 0, &texture_disk(model))
        .expect("the disk is measurable");
    let img =
        poser::compare::LinearImage::read(&dir.join(format!("{}.exr", model.image_name(0, 0))))
            .unwrap();
    let g = img.channel(1);
    let gray = poser::compare::detect::Gray {
        width: img.width,
        height: img.height,
        data: &g,
    };
    let m = poser::compare::detect::disk_centroid(&gray, c, half, 0.03 / 0.8).unwrap();
    [m[0] - c[0], m[1] - c[1]]
}

/// Run the `poser` binary in `dir`; returns (success, stdout + stderr).
pub fn poser_in(args: &[&str], dir: &std::path::Path) -> (bool, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        o.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    )
}
