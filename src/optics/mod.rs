//! The optics core: refractive indices (water, glass), water IOPs and phase functions, lens
//! models, housing ports with exact forward and backward projection, sun position.

pub mod glass;
pub mod phase;
pub mod sun;
pub mod water;

use crate::model::{Camera, Rgb};

/// Lateral colour at the image corners, in pixels: the largest distance between where the R
/// and B channels project the same water point (at 2 m along each corner pixel's ray), over the
/// four corners. 0 when there is no port or no water.
// PLACEHOLDER body (lead): the optics work implements it with the exact projection.
pub fn lateral_color_px(camera: &Camera, water_ior: Rgb) -> f64 {
    let _ = (camera, water_ior);
    0.0
}
