//! Linear images: the one linear RGB image type of the media stages, the one EXR reader, the
//! sRGB transfer ([`srgb8`]) and an auto-exposed PNG preview ([`preview_png`]);
//! for the sensor stage (`poser sensor`, `poser render`'s camera files) and for `poser
//! compare` ([`crate::compare::LinearImage`] is read through [`read_exr`]).
//!
//! Still elsewhere (issue 39): the native renderer's [`crate::backend::native::Image`] (with
//! depth, variance and albedo) and `compare::LinearImage` (sizes as `usize`).
use std::path::Path;

/// A linear RGB image (row-major, row 0 at the top), radiance in W/(m²·sr) per channel.
#[derive(Debug, Clone)]
pub struct Linear {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[f32; 3]>,
}

/// Read a linear RGB EXR (any channel layout the `image` crate reads, as RGB `f32`).
pub fn read_exr(path: &Path) -> Result<Linear, String> {
    let img = ::image::open(path)
        .map_err(|e| format!("{}: {e}", path.display()))?
        .into_rgb32f();
    Ok(Linear {
        width: img.width(),
        height: img.height(),
        rgb: img.pixels().map(|p| p.0).collect(),
    })
}

/// The sRGB transfer of a linear value in [0, 1] (clamped; not finite → 0), as an 8-bit code.
pub fn srgb8(x: f64) -> u8 {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (v * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// An auto-exposed sRGB PNG of `img` for a page: the 99th percentile of the pixels' brightest
/// channel maps to 0.9 (a black image stays black).
pub fn preview_png(img: &Linear) -> Result<Vec<u8>, String> {
    let mut peak: Vec<f32> = img
        .rgb
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]))
        .filter(|v| v.is_finite())
        .collect();
    peak.sort_by(f32::total_cmp);
    let p99 = peak
        .get(((peak.len().max(1) - 1) as f64 * 0.99) as usize)
        .copied()
        .unwrap_or(0.0) as f64;
    let exposure = if p99 > 0.0 { 0.9 / p99 } else { 1.0 };
    let bytes: Vec<u8> = img
        .rgb
        .iter()
        .flat_map(|p| p.map(|c| srgb8(exposure * c as f64)))
        .collect();
    let buf = ::image::RgbImage::from_raw(img.width, img.height, bytes)
        .ok_or("image buffer has the wrong size")?;
    let mut out = std::io::Cursor::new(Vec::new());
    buf.write_to(&mut out, ::image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}
