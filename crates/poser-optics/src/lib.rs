//! poser-optics: the pure optics of poser, as a crate of its own so that the compiler keeps it
//! pure. It owns refractive indices (water, glass), water IOPs and phase functions, lens
//! models, housing ports with exact forward and backward projection, the water column's light,
//! sun position and the sea surface, and poser's one random stream ([`rng`]). It depends on
//! glam, serde and rayon only: nothing of the scene, the model or the back ends (the `poser`
//! crate re-exports it as `poser::optics`, and `poser::rng`).
//!
//! | module | owns |
//! |---|---|
//! | [`water`], [`glass`] | refractive indices (Quan–Fry, Millard–Seaver, Sellmeier), Jerlov IOPs |
//! | [`phase`] | Henyey–Greenstein and Fournier–Forand, and [`phase::PhaseFn`] (closed form or table) |
//! | [`column`](mod@column) | the plane-parallel water column's light field, solved once per scene (1D Monte Carlo) |
//! | [`sun`] | NOAA solar position, refraction of sunlight into the sea |
//! | [`interface`] | vector Snell with explicit TIR, unpolarised Fresnel |
//! | [`lens`] | rectilinear + Brown, equidistant and equisolid fisheye |
//! | [`port`] | flat (multi-layer, tilted), dome (decentred), cylinder (on/off axis) |
//! | [`lanes`] | f64 SIMD lanes for the batch port solvers (AVX2 picked at run time) |
//! | [`project`] | [`project::Projector`]: camera + port + poses for one channel |
//! | [`types`] | the value types: [`types::Camera`], [`types::Port`], [`types::Pose`], … (re-exported by the model) |
//! | [`rng`] | SplitMix64, the one deterministic random stream (renders, waves, benchmark points) |
//! | [`cases`] | the hard-case table of the port solvers, shared by the tests and `poser bench projection` |
//! | [`waves`] | seeded periodic random sea surface (Pierson–Moskowitz, Mitsuyasu spread) for caustics |
//!
//! "No solution" is always an explicit [`NoSolution`], never NaN.

// `!(x > y)` is deliberate throughout: it rejects NaN as well as the failing comparison.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cases;
pub mod column;
pub mod glass;
pub mod interface;
pub mod lanes;
pub mod lens;
pub mod phase;
pub mod port;
pub mod project;
pub mod reference;
pub mod rng;
pub mod sun;
pub mod surface;
pub mod types;
pub mod water;
pub mod waves;

use serde::{Deserialize, Serialize};
use types::{Camera, Port, Rgb};

/// Why a point has no pixel (or a pixel has no ray).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoSolution {
    /// The point (or the solution ray) is behind the camera.
    BehindCamera,
    /// The point lies between the entrance pupil and the port's inner surface.
    InsideHousing,
    /// The point lies inside the port's glass.
    InsideGlass,
    /// The camera ray never reaches the port (parallel to a flat port, along a cylinder axis).
    MissesPort,
    /// No camera ray reaches the point: beyond the flat port's critical angle.
    BeyondCriticalAngle,
    /// The ray is totally internally reflected at an interface.
    TotalInternalReflection,
    /// Outside the lens model's field (fisheye beyond 180°, distortion not invertible).
    OutsideLensField,
    /// The pixel exists but lies outside the sensor.
    OffSensor,
    /// The solver did not converge (guard; not expected).
    NoConvergence,
}

impl NoSolution {
    pub const ALL: [NoSolution; 9] = [
        NoSolution::BehindCamera,
        NoSolution::InsideHousing,
        NoSolution::InsideGlass,
        NoSolution::MissesPort,
        NoSolution::BeyondCriticalAngle,
        NoSolution::TotalInternalReflection,
        NoSolution::OutsideLensField,
        NoSolution::OffSensor,
        NoSolution::NoConvergence,
    ];
    /// Short status string (`behind_camera`, …) as written in CSV files.
    pub fn as_str(&self) -> &'static str {
        match self {
            NoSolution::BehindCamera => "behind_camera",
            NoSolution::InsideHousing => "inside_housing",
            NoSolution::InsideGlass => "inside_glass",
            NoSolution::MissesPort => "misses_port",
            NoSolution::BeyondCriticalAngle => "beyond_critical_angle",
            NoSolution::TotalInternalReflection => "total_internal_reflection",
            NoSolution::OutsideLensField => "outside_lens_field",
            NoSolution::OffSensor => "off_sensor",
            NoSolution::NoConvergence => "no_convergence",
        }
    }
}

impl std::fmt::Display for NoSolution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::error::Error for NoSolution {}

/// Lateral colour at the image corners, in pixels: the largest distance between where the R
/// and B channels project the same water point (at 2 m along each corner pixel's G ray), over
/// the four corners. 0 when there is no port or no water.
pub fn lateral_color_px(camera: &Camera, water_ior: Rgb) -> f64 {
    if matches!(camera.port, Port::None) {
        return 0.0;
    }
    let build = |ch: usize| project::Projector::for_camera(camera, ch, water_ior[ch]).ok();
    let (Some(g), Some(r), Some(b)) = (build(1), build(0), build(2)) else {
        return 0.0;
    };
    let (w, h) = (camera.width as f64, camera.height as f64);
    let mut worst: f64 = 0.0;
    for (u, v) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
        let Ok(ray) = g.camera_ray(u, v) else {
            continue;
        };
        let p = ray.origin + ray.dir * 2.0;
        if let (Ok(pr), Ok(pb)) = (r.project_camera_unbounded(p), b.project_camera_unbounded(p)) {
            let d = (pr[0] - pb[0]).hypot(pr[1] - pb[1]);
            if d.is_finite() {
                worst = worst.max(d);
            }
        }
    }
    worst
}
