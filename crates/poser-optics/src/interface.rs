//! One optical interface: vector Snell refraction (with explicit total internal reflection) and
//! unpolarised Fresnel transmittance. Shared by the ports and the sea surface.

use glam::DVec3;

/// Refract unit direction `i` at an interface with unit normal `n` pointing into the
/// transmission side (`n·i > 0`), `eta = n1/n2`. `None` on total internal reflection.
/// Returns the unit transmitted direction and `cos θt`.
#[inline(always)]
pub fn refract(i: DVec3, n: DVec3, eta: f64) -> Option<(DVec3, f64)> {
    let c = n.dot(i);
    let s2 = eta * eta * (1.0 - c * c).max(0.0);
    if s2 > 1.0 {
        return None;
    }
    let ct = (1.0 - s2).sqrt();
    Some((eta * i + (ct - eta * c) * n, ct))
}

/// Unpolarised Fresnel transmittance `1 − ½(Rs + Rp)` from n1 to n2, given both cosines.
#[inline(always)]
pub fn fresnel_transmittance(n1: f64, n2: f64, cos_i: f64, cos_t: f64) -> f64 {
    let a = n1 * cos_i;
    let b = n2 * cos_t;
    let c = n1 * cos_t;
    let d = n2 * cos_i;
    if a + b <= 0.0 || c + d <= 0.0 {
        return 0.0;
    }
    let rs = ((a - b) / (a + b)).powi(2);
    let rp = ((c - d) / (c + d)).powi(2);
    (1.0 - 0.5 * (rs + rp)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_air_to_water_table() {
        // docs/optics.md §4.2, nw = 1.34: R at θair and θwater, printed to 1e-4 / 0.01°.
        let nw = 1.34;
        for (ta, r, tw) in [
            (0.0, 0.0211, 0.0),
            (30.0, 0.0222, 21.91),
            (60.0, 0.0610, 40.26),
            (80.0, 0.3502, 47.30),
            (89.0, 0.8968, 48.26),
        ] {
            let th = f64::to_radians(ta);
            let i = DVec3::new(th.sin(), 0.0, th.cos());
            let (t, ct) = refract(i, DVec3::Z, 1.0 / nw).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-15);
            assert!((ct.acos().to_degrees() - tw).abs() < 0.01, "θw at {ta}");
            let got = 1.0 - fresnel_transmittance(1.0, nw, th.cos(), ct);
            assert!((got - r).abs() < 1e-4, "R at {ta}: {got}");
        }
    }

    #[test]
    fn total_internal_reflection_is_reported() {
        // Water → air beyond asin(1/1.34) = 48.27°.
        let th = 50f64.to_radians();
        let i = DVec3::new(th.sin(), 0.0, th.cos());
        assert!(refract(i, DVec3::Z, 1.34).is_none());
        let th = 48f64.to_radians();
        let i = DVec3::new(th.sin(), 0.0, th.cos());
        assert!(refract(i, DVec3::Z, 1.34).is_some());
    }
}
