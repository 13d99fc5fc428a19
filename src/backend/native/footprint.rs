//! The pixel's footprint on the surface a camera ray first hits: where its centre is and how
//! wide a patch of that surface one pixel sees, for the texture lookup filtered by it
//! ([`crate::texture::mip`]).
//!
//! Per pixel, the rays one pixel over in u and in v ([`CameraRays::ray`], so through the lens,
//! the port and the water exactly as the samples' rays) give the ray's differentials: the change
//! of origin and direction per pixel. At a hit, each neighbour ray (the sample's ray plus a
//! differential) is intersected with the hit's tangent plane; the two offsets span the
//! footprint, projected onto the surface (a grazing view stretches it). Its width is the
//! shorter offset: the filter never blurs more than the pixel does in any direction, and the
//! pixel's samples average what a long, grazing footprint leaves.
//!
//! Every sample of a pixel reads the texture at the footprint's centre (its hit moved back by
//! its offset from the pixel's centre along the two offsets, on the tangent plane): the lookup
//! is then the same for all of them, the pixel's average of the texture, and the texture adds
//! no variance between the samples. Read at each sample's own hit, the filtered texture would
//! still vary across the pixel (on reef_strip 59 % of the texture's variance stayed).

use super::camera::CameraRays;
use glam::DVec3;

/// Largest footprint width, in pixel offsets stretched by a grazing view: `1 / cos` capped at
/// this (a ray almost along the surface would otherwise ask for an infinitely wide average).
const MAX_STRETCH: f64 = 8.0;

/// Differentials of the camera rays of one pixel: origin and direction change per pixel in u
/// and in v.
#[derive(Debug, Clone, Copy)]
pub struct PixelSpread {
    d_o: [DVec3; 2],
    d_d: [DVec3; 2],
    /// The sample's offset from the pixel's centre, pixels (u, v).
    shift: [f64; 2],
}

/// Where and how wide to read a texture for one sample: the footprint's centre on the
/// surface's tangent plane and its width, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    pub centre: DVec3,
    pub width: f64,
}

impl PixelSpread {
    /// [`PixelSpread::at`] when the scene has textures and `render.texture_filter` is
    /// `"footprint"`, else `None` (point lookups).
    pub fn of(
        model: &crate::model::Model,
        scene: &super::scene::Scene,
        rays: &CameraRays,
        i: u32,
        j: u32,
    ) -> Option<PixelSpread> {
        let textured =
            scene.textures.iter().any(Option::is_some) || scene.meshes.iter().any(Option::is_some);
        let on = model.render.texture_filter == crate::model::TextureFilter::Footprint;
        if textured && on {
            PixelSpread::at(rays, i, j)
        } else {
            None
        }
    }

    /// The differentials at pixel (i, j) (from its centre's ray and the rays one pixel over,
    /// or one pixel back where those leave no ray); `None` where the centre has no ray.
    pub fn at(rays: &CameraRays, i: u32, j: u32) -> Option<PixelSpread> {
        let (u, v) = (i as f64 + 0.5, j as f64 + 0.5);
        let (o, d, _) = rays.ray(u, v)?;
        let diff = |du: f64, dv: f64| {
            let (o2, d2, _) = rays.ray(u + du, v + dv).or_else(|| {
                rays.ray(u - du, v - dv)
                    .map(|(a, b, c)| (2.0 * o - a, 2.0 * d - b, c))
            })?;
            Some((o2 - o, d2 - d))
        };
        let (ox, dx) = diff(1.0, 0.0)?;
        let (oy, dy) = diff(0.0, 1.0)?;
        Some(PixelSpread {
            d_o: [ox, oy],
            d_d: [dx, dy],
            shift: [0.0; 2],
        })
    }

    /// The same differentials for the sample at pixel position (i + `du`, j + `dv`).
    pub fn shifted(self, du: f64, dv: f64) -> PixelSpread {
        PixelSpread {
            shift: [du - 0.5, dv - 0.5],
            ..self
        }
    }

    /// The footprint on the surface through `p` with normal `n` of the pixel whose sample ray
    /// `o + t d` hits it at `p`. Width 0 when it cannot be told (the lookup is then a point
    /// lookup at `p`); the centre stays `p` along an offset that cannot be told.
    pub fn at_hit(&self, o: DVec3, d: DVec3, p: DVec3, n: DVec3) -> Footprint {
        let dist = (p - o).length();
        let cos = n.dot(d).abs();
        let mut w = f64::INFINITY;
        let mut centre = p;
        for k in 0..2 {
            let (o2, d2) = (o + self.d_o[k], d + self.d_d[k]);
            let den = n.dot(d2);
            let t = n.dot(p - o2) / den;
            let off = if den.abs() > 1e-12 && t.is_finite() && t > 0.0 {
                o2 + t * d2 - p
            } else {
                DVec3::INFINITY
            };
            // Capped: at most the offset at the hit's distance, stretched by MAX_STRETCH.
            let flat = (self.d_o[k] + dist * self.d_d[k]).length();
            let cap = flat * MAX_STRETCH.min(1.0 / cos.max(1e-9));
            let len = off.length();
            if len <= cap {
                centre -= self.shift[k] * off;
            }
            w = w.min(len.min(cap));
        }
        Footprint {
            centre,
            width: if w.is_finite() { w } else { 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pinhole_footprint_grows_with_distance_and_obliquity() {
        // Rays from the origin, 1 mrad apart per pixel in x and y.
        let s = PixelSpread {
            d_o: [DVec3::ZERO; 2],
            d_d: [DVec3::new(1e-3, 0.0, 0.0), DVec3::new(0.0, 1e-3, 0.0)],
            shift: [0.0; 2],
        };
        let width = |o, d, p, n| s.at_hit(o, d, p, n).width;
        let d = DVec3::new(0.0, 0.0, -1.0);
        let up = DVec3::Z;
        let w2 = width(DVec3::ZERO, d, DVec3::new(0.0, 0.0, -2.0), up);
        assert!((w2 - 2e-3).abs() < 1e-9, "{w2}");
        let w4 = width(DVec3::ZERO, d, DVec3::new(0.0, 0.0, -4.0), up);
        assert!((w4 - 4e-3).abs() < 1e-9, "{w4}");
        // A surface tilted 60° about y: the x offset stretches by 1/cos 60° = 2, the y offset
        // not, and the width is the shorter one.
        let n = DVec3::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let wt = width(DVec3::ZERO, d, DVec3::new(0.0, 0.0, -2.0), n);
        assert!((wt - 2e-3).abs() < 1e-6, "{wt}");
        // Grazing in both: capped.
        let g = width(DVec3::ZERO, d, DVec3::new(0.0, 0.0, -2.0), DVec3::X);
        assert!(g.is_finite() && g <= 2e-3 * MAX_STRETCH * 1.0001, "{g}");
    }

    #[test]
    fn every_sample_of_a_pixel_finds_the_same_centre() {
        // Pinhole at the origin looking down at the plane z = -2; pixel (0, 0)'s centre ray
        // is straight down, 1 mrad per pixel.
        let s = PixelSpread {
            d_o: [DVec3::ZERO; 2],
            d_d: [DVec3::new(1e-3, 0.0, 0.0), DVec3::new(0.0, 1e-3, 0.0)],
            shift: [0.0; 2],
        };
        for (du, dv) in [(0.5, 0.5), (0.1, 0.9), (0.97, 0.02)] {
            let d = DVec3::new((du - 0.5) * 1e-3, (dv - 0.5) * 1e-3, -1.0);
            let p = d * (2.0 / -d.z);
            let f = s.shifted(du, dv).at_hit(DVec3::ZERO, d, p, DVec3::Z);
            assert!(
                f.centre.distance(DVec3::new(0.0, 0.0, -2.0)) < 1e-8,
                "{f:?}"
            );
        }
    }
}
