//! The water as the renderer sees it: a homogeneous medium per channel inside a convex region
//! (below the sea surface, and inside the box around the camera when the scene asks for it),
//! with its phase function (Henyey–Greenstein, or Fournier–Forand tabulated from its closed-form
//! CDF; both from [`crate::optics::phase`]).
//!
//! | item | meaning |
//! |---|---|
//! | `sigma_a`, `sigma_s`, `sigma_t` | per channel, 1/m |
//! | region | `z ≤ 0` when the site has a sea surface or daylight (sun, ambient); ∩ the box `camera ± half_size` for `BoxAroundCamera` |
//! | phase | `cos θ` between propagation directions; FF as a piecewise-constant table in cos θ ([`FF_BINS`] bins, log-spaced in θ) — evaluation and sampling use the same table, so sample weights are exact |

use crate::model::{Model, SeaSurface, WaterExtent};
use glam::DVec3;

pub use crate::optics::phase::{FF_BINS, PhaseFn};

/// The water of one image: coefficients, phase and region.
#[derive(Debug, Clone)]
pub struct Medium {
    pub sigma_a: DVec3,
    pub sigma_s: DVec3,
    pub sigma_t: DVec3,
    pub phase: PhaseFn,
    /// Region bounds (may be infinite).
    lo: DVec3,
    hi: DVec3,
}

impl Medium {
    /// The medium around a camera at `camera_pos`, or `None` when the model has no water or the
    /// water neither absorbs nor scatters.
    pub fn new(model: &Model, camera_pos: DVec3) -> Option<Medium> {
        let w = model.water.as_ref()?;
        let sa = DVec3::from_array(w.absorption);
        let ss = DVec3::from_array(w.scattering);
        let st = sa + ss;
        if st.max_element() <= 0.0 {
            return None;
        }
        let mut lo = DVec3::NEG_INFINITY;
        let mut hi = DVec3::INFINITY;
        // The sea ends at z = 0 when there is a surface, and also when daylight (sun, ambient
        // sky) must come from above (the Mitsuba backend bounds its water the same way).
        let daylight = model.sun.is_some()
            || model
                .lights
                .iter()
                .any(|l| matches!(l.kind, crate::model::LightKind::Ambient { .. }));
        if !matches!(model.site.surface, SeaSurface::None) || daylight {
            hi.z = 0.0;
        }
        if let WaterExtent::BoxAroundCamera { half_size } = w.extent {
            lo = lo.max(camera_pos - half_size);
            hi = hi.min(camera_pos + half_size);
        }
        Some(Medium {
            sigma_a: sa,
            sigma_s: ss,
            sigma_t: st,
            phase: w.phase.phase_fn(),
            lo,
            hi,
        })
    }

    /// A medium filling all space (tests).
    pub fn everywhere(sigma_a: DVec3, sigma_s: DVec3, phase: PhaseFn) -> Medium {
        Medium {
            sigma_a,
            sigma_s,
            sigma_t: sigma_a + sigma_s,
            phase,
            lo: DVec3::NEG_INFINITY,
            hi: DVec3::INFINITY,
        }
    }

    pub fn scatters(&self) -> bool {
        self.sigma_s.max_element() > 0.0
    }

    /// Part `[a, b]` of the ray parameter range `[t0, t1]` inside the region (`dir` unit).
    pub fn interval(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let (mut a, mut b) = (t0, t1);
        for k in 0..3 {
            let (l, h) = (self.lo[k], self.hi[k]);
            if d[k] == 0.0 {
                if o[k] < l || o[k] > h {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d[k];
            let (mut x, mut y) = ((l - o[k]) * inv, (h - o[k]) * inv);
            if x > y {
                std::mem::swap(&mut x, &mut y);
            }
            // Infinite bounds give ±inf or NaN (0·inf never: d[k] != 0).
            if x > a {
                a = x;
            }
            if y < b {
                b = y;
            }
        }
        (a < b).then_some((a, b))
    }

    /// Transmittance along `o + t d`, t ∈ [t0, t1].
    pub fn transmittance(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> DVec3 {
        match self.interval(o, d, t0, t1) {
            Some((a, b)) => tr(self.sigma_t, b - a),
            None => DVec3::ONE,
        }
    }
}

/// exp(-σ·len) per channel, exact 0 for an infinite length with σ > 0 and 1 with σ = 0.
#[inline]
pub fn tr(sigma: DVec3, len: f64) -> DVec3 {
    DVec3::new(ex(sigma.x, len), ex(sigma.y, len), ex(sigma.z, len))
}

#[inline]
fn ex(s: f64, len: f64) -> f64 {
    if s == 0.0 { 1.0 } else { (-s * len).exp() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::phase::{self, ff_table};
    use std::f64::consts::PI;

    /// `u_of_cos` inverts `sample_cos` for Henyey–Greenstein (forward, backward, isotropic)
    /// and the Fournier–Forand table, and the mass between two cosines is the integral of
    /// the density.
    #[test]
    fn u_of_cos_inverts_the_cosine_sampler() {
        for ph in [
            PhaseFn::Hg { g: 0.92 },
            PhaseFn::Hg { g: -0.3 },
            PhaseFn::Hg { g: 0.0 },
            ff_table(1.10, 3.5835),
        ] {
            for i in 0..=200 {
                let u = i as f64 / 200.0;
                let c = ph.sample_cos(u);
                let back = ph.sample_cos(ph.u_of_cos(c));
                assert!((back - c).abs() < 1e-9, "{ph:?}: u {u}, cos {c} -> {back}");
            }
            let (c0, c1) = (0.2, 0.9);
            let n = 20_000;
            let mass: f64 = (0..n)
                .map(|i| {
                    ph.eval(c0 + (c1 - c0) * (i as f64 + 0.5) / n as f64) * 2.0 * PI * (c1 - c0)
                        / n as f64
                })
                .sum();
            let du = (ph.u_of_cos(c1) - ph.u_of_cos(c0)).abs();
            assert!((du - mass).abs() < 1e-4 * mass.max(1.0), "{du} vs {mass}");
        }
    }

    #[test]
    fn phase_tables_integrate_to_one_and_sample_consistently() {
        let hg = PhaseFn::Hg { g: 0.8 };
        // ∫ p dΩ for HG by a midpoint rule in μ (smooth enough at g = 0.8: error < 1e-3).
        let n = 200_000;
        let s: f64 = (0..n)
            .map(|i| hg.eval(-1.0 + 2.0 * (i as f64 + 0.5) / n as f64) * 4.0 * PI / n as f64)
            .sum();
        assert!((s - 1.0).abs() < 1e-3, "{s}");
        let ff = ff_table(1.10, 3.5835);
        let PhaseFn::Tab { mu, dens, .. } = &ff else {
            unreachable!()
        };
        // The table holds exactly the mass of the closed-form CDF per bin.
        let total: f64 = (0..FF_BINS)
            .map(|k| dens[k] * 2.0 * PI * (mu[k] - mu[k + 1]))
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        // Bin averages agree with the analytic density away from the peak (bins are ≤ 0.4 %
        // wide in θ there, so the bin average is within 1 % of the point value).
        for deg in [5.0f64, 30.0, 90.0, 150.0] {
            let th = deg.to_radians();
            let a = phase::ff_eval(1.10, 3.5835, th);
            let t = ff.eval(th.cos());
            assert!((t / a - 1.0).abs() < 1e-2, "{deg}°: table {t} vs {a}");
        }
        for p in [hg, ff] {
            // Stratified samples: the backscattered fraction is exact to 1/m plus the bin width.
            let m = 100_000;
            let back = (0..m)
                .filter(|&i| p.sample_cos((i as f64 + 0.5) / m as f64) < 0.0)
                .count();
            let bf = back as f64 / m as f64;
            let expect = match &p {
                PhaseFn::Hg { g } => phase::hg_backscatter(*g),
                _ => 0.018313,
            };
            assert!((bf - expect).abs() < 5e-4, "{bf} vs {expect}");
        }
    }

    #[test]
    fn region_box_and_surface() {
        let m = Medium {
            sigma_a: DVec3::splat(0.1),
            sigma_s: DVec3::ZERO,
            sigma_t: DVec3::splat(0.1),
            phase: PhaseFn::Hg { g: 0.0 },
            lo: DVec3::new(-1.0, -1.0, f64::NEG_INFINITY),
            hi: DVec3::new(1.0, 1.0, 0.0),
        };
        let (a, b) = m
            .interval(DVec3::new(-5.0, 0.0, -1.0), DVec3::X, 0.0, 100.0)
            .unwrap();
        assert_eq!((a, b), (4.0, 6.0));
        assert!(
            m.interval(DVec3::new(0.0, 0.0, 1.0), DVec3::X, 0.0, 100.0)
                .is_none()
        );
        let (a, b) = m
            .interval(DVec3::new(0.0, 0.0, -3.0), DVec3::Z, 0.0, 100.0)
            .unwrap();
        assert_eq!((a, b), (0.0, 3.0));
    }
}
