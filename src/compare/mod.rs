//! Cross-backend agreement: locate targets in rendered images, compare them with the exact
//! ground truth and with each other, and write the `poser compare` report.

pub mod detect;
pub mod report;

use std::path::Path;

/// A linear RGB float image as read from an EXR.
pub struct LinearImage {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB triples, row 0 at the top.
    pub rgb: Vec<[f32; 3]>,
}

impl LinearImage {
    pub fn read(path: &Path) -> Result<Self, String> {
        let img = image::open(path)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .into_rgb32f();
        let (w, h) = img.dimensions();
        let rgb = img.pixels().map(|p| p.0).collect();
        Ok(LinearImage {
            width: w as usize,
            height: h as usize,
            rgb,
        })
    }
    /// One channel as a flat vector.
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.rgb.iter().map(|p| p[c]).collect()
    }
    /// Mean per channel.
    pub fn mean(&self) -> [f64; 3] {
        let mut m = [0.0; 3];
        for p in &self.rgb {
            for c in 0..3 {
                m[c] += p[c] as f64;
            }
        }
        m.map(|v| v / self.rgb.len().max(1) as f64)
    }
}
