//! Linear images: the one linear RGB image type of the media stages and the one EXR reader,
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
