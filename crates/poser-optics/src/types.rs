//! The value types the optics core works on, free of the scene and the model (which re-exports
//! them: `poser::model`). Conventions are the model's: camera frame OpenCV (x right, y down,
//! z forward, origin at the entrance pupil), SI units, channels `[R, G, B]`.
//!
//! | type | what |
//! |---|---|
//! | [`Rgb`] | a per-channel quantity |
//! | [`Pose`] | a rigid transform `parent_from_child` |
//! | [`Camera`] | sensor, intrinsics, lens model, distortion, port and mount of one camera |
//! | [`LensModel`], [`Distortion`] | the lens mapping and Brown–Conrady distortion |
//! | [`Glass`], [`Port`] | a port material and the housing port geometry |

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// Per-channel quantity, `[R, G, B]`.
pub type Rgb = [f64; 3];

/// A rigid transform `parent_from_child`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Columns are the child frame's axes expressed in the parent frame.
    pub rotation: DMat3,
    /// Origin of the child frame in the parent frame, metres.
    pub translation: DVec3,
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// Map a point from the child frame to the parent frame.
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }
    /// Map a direction from the child frame to the parent frame.
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }
    /// The inverse transform (`child_from_parent`).
    pub fn inverse(&self) -> Pose {
        let rt = self.rotation.transpose();
        Pose {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }
    /// Composition `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Pose) -> Pose {
        Pose {
            rotation: self.rotation * other.rotation,
            translation: self.rotation * other.translation + self.translation,
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Camera {
    /// Unique name within the rig (`"left"`, `"cam0"`, …).
    pub name: String,
    /// Image size in pixels.
    pub width: u32,
    pub height: u32,
    /// Pixel pitch, m.
    pub pixel_pitch: f64,
    /// Focal length, m (= fx · pixel_pitch).
    pub focal_length: f64,
    /// Focal lengths in pixels.
    pub fx: f64,
    pub fy: f64,
    /// Principal point in pixels, pixel centres at +0.5 (COLMAP's convention; the image centre
    /// is (w/2, h/2)). OpenCV's principal point is this − 0.5.
    pub cx: f64,
    pub cy: f64,
    pub lens: LensModel,
    pub distortion: Distortion,
    /// Focus distance, m (`None`: pinhole, everything sharp).
    pub focus_distance: Option<f64>,
    /// Aperture f-number (`None`: pinhole).
    pub f_number: Option<f64>,
    /// The housing port in front of this camera.
    pub port: Port,
    /// Pose of this camera in the rig frame (`rig_from_camera`).
    pub rig_from_camera: Pose,
}

impl Camera {
    /// The same camera with its pixel grid resampled by `scale` (a preview at a fraction of the
    /// resolution): same sensor, field of view, lens, distortion and port; sizes rounded to
    /// whole pixels (at least 1) and the intrinsics scaled by the exact ratio of the new to the
    /// old width, so that every ray keeps its place on the sensor. Square pixels stay square
    /// (Mitsuba's perspective sensor has no other kind): both axes take the width's ratio, and
    /// the rounded height crops or extends the bottom edge by under half a pixel. Non-square
    /// pixels are scaled per axis.
    pub fn with_resolution_scale(&self, scale: f64) -> Camera {
        let w = ((self.width as f64 * scale).round() as u32).max(1);
        let h = ((self.height as f64 * scale).round() as u32).max(1);
        let sx = w as f64 / self.width as f64;
        let sy = if self.fx == self.fy {
            sx
        } else {
            h as f64 / self.height as f64
        };
        Camera {
            width: w,
            height: h,
            pixel_pitch: self.pixel_pitch / sx,
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: self.cx * sx,
            cy: self.cy * sy,
            ..self.clone()
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LensModel {
    /// r = f·tan θ.
    Rectilinear,
    /// r = f·θ.
    FisheyeEquidistant,
    /// r = 2f·sin(θ/2).
    FisheyeEquisolid,
}

/// Brown–Conrady distortion, OpenCV convention, on normalised coordinates.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Distortion {
    pub k1: f64,
    pub k2: f64,
    pub k3: f64,
    pub p1: f64,
    pub p2: f64,
}

impl Distortion {
    pub fn is_zero(&self) -> bool {
        self.k1 == 0.0 && self.k2 == 0.0 && self.k3 == 0.0 && self.p1 == 0.0 && self.p2 == 0.0
    }
}

/// A port material with its index per channel.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Glass {
    /// Catalogue name (`"N-BK7"`, `"fused_silica"`, `"PMMA"`, `"sapphire"`) or `"custom"`.
    pub name: String,
    /// Index per channel.
    pub ior: Rgb,
}

/// A further glass layer of a flat port, outward of the first (a laminate, a protective
/// window): its thickness, m, and its glass.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GlassLayer {
    pub thickness: f64,
    pub glass: Glass,
}

/// A housing port, in the **camera frame** (OpenCV axes, origin at the entrance pupil).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Port {
    /// No housing: the camera sits directly in the medium (air survey, or an idealised camera).
    None,
    /// Flat port. Inner face `{x : normal·x = distance}`; the first glass layer (`thickness`,
    /// `glass`) ends at `distance + thickness`, and each of `outer_layers` follows it outwards
    /// (empty for the usual single slab). `normal` is a unit vector pointing from the camera
    /// into the water (untilted: +z).
    Flat {
        normal: DVec3,
        distance: f64,
        thickness: f64,
        glass: Glass,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        outer_layers: Vec<GlassLayer>,
    },
    /// Dome port: spheres about `center` with radii `inner_radius` and
    /// `inner_radius + thickness`. `center` = 0 is a perfectly centred dome.
    Dome {
        center: DVec3,
        inner_radius: f64,
        thickness: f64,
        glass: Glass,
    },
    /// Cylindrical port: coaxial cylinders of radii `inner_radius` and `inner_radius +
    /// thickness` about the line through `axis_point` with unit direction `axis`.
    Cylinder {
        axis_point: DVec3,
        axis: DVec3,
        inner_radius: f64,
        thickness: f64,
        glass: Glass,
    },
}

impl Port {
    pub fn glass(&self) -> Option<&Glass> {
        match self {
            Port::None => None,
            Port::Flat { glass, .. } | Port::Dome { glass, .. } | Port::Cylinder { glass, .. } => {
                Some(glass)
            }
        }
    }
    /// Total glass thickness, m (0 without a port): a flat port's layers summed.
    pub fn total_thickness(&self) -> f64 {
        match self {
            Port::None => 0.0,
            Port::Flat {
                thickness,
                outer_layers,
                ..
            } => thickness + outer_layers.iter().map(|l| l.thickness).sum::<f64>(),
            Port::Dome { thickness, .. } | Port::Cylinder { thickness, .. } => *thickness,
        }
    }
    /// A flat port's glass layers from the camera outwards: (thickness m, index in `channel`).
    /// Empty for other ports.
    pub fn flat_layers(&self, channel: usize) -> Vec<(f64, f64)> {
        match self {
            Port::Flat {
                thickness,
                glass,
                outer_layers,
                ..
            } => std::iter::once((*thickness, glass.ior[channel.min(2)]))
                .chain(
                    outer_layers
                        .iter()
                        .map(|l| (l.thickness, l.glass.ior[channel.min(2)])),
                )
                .collect(),
            _ => vec![],
        }
    }
    /// Refractive surfaces a camera ray crosses on its way out (inner and outer glass faces).
    /// Mitsuba and Cycles count each as a path vertex, so their bounce budgets add these to
    /// the model's `max_bounces` (which, like the native tracer, counts scattering only).
    pub fn interfaces(&self) -> u32 {
        match self {
            Port::None => 0,
            Port::Flat { outer_layers, .. } => 2 + outer_layers.len() as u32,
            Port::Dome { .. } | Port::Cylinder { .. } => 2,
        }
    }
    pub fn kind_name(&self) -> &'static str {
        match self {
            Port::None => "none",
            Port::Flat { .. } => "flat",
            Port::Dome { .. } => "dome",
            Port::Cylinder { .. } => "cylinder",
        }
    }
}
