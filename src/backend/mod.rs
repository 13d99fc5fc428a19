//! The back ends that run outside Rust (Mitsuba 3, Blender/Cycles) and what all back ends
//! share: render options and reports, and the pinned Python environment.

pub mod blender;
pub mod mitsuba;
pub mod python;

use std::path::PathBuf;

/// Options common to every backend's `render`.
#[derive(Debug, Clone, Default)]
pub struct RenderOptions {
    /// Override of the scene's samples per pixel.
    pub samples: Option<u32>,
    /// Render only these rig-pose indices (all when `None`).
    pub poses: Option<Vec<usize>>,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

impl RenderOptions {
    /// The pose indices to render for a model with `n` poses.
    pub fn pose_indices(&self, n: usize) -> Vec<usize> {
        match &self.poses {
            Some(p) => p.iter().copied().filter(|&i| i < n).collect(),
            None => (0..n).collect(),
        }
    }
}

/// What a render produced.
#[derive(Debug, Clone, Default)]
pub struct RenderReport {
    /// Linear EXR images written, one per (pose, camera).
    pub images: Vec<PathBuf>,
    /// Wall-clock seconds of the whole render.
    pub seconds: f64,
}
