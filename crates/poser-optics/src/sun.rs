//! The sun: NOAA solar position, and refraction of sunlight through a flat sea surface.
//!
//! | function | inputs | notes |
//! |---|---|---|
//! | [`position`] | latitude, longitude (deg, east +), ISO-8601 date-time with offset | NOAA GML Solar Calculator (after Meeus), elevation includes atmospheric refraction; ≈ 0.003° from NREL SPA |
//! | [`direction_from`] | elevation, azimuth (rad, azimuth clockwise from north) | world z up, x east, y north |
//! | [`refract_into_water`] | propagation direction in air, n_water | Snell + unpolarised Fresnel at z = 0 |

use super::interface::{fresnel_transmittance, refract};
use glam::DVec3;

/// A parsed ISO-8601 date-time, reduced to the Julian day (UT).
fn parse_iso8601_jd(s: &str) -> Result<f64, String> {
    let err = |why: &str| {
        format!(
            "invalid date-time `{s}`: {why} (expected ISO-8601 like `2024-06-21T10:30:00+02:00` or `…Z`)"
        )
    };
    let s = s.trim();
    let num = |t: &str, what: &str| -> Result<i64, String> {
        if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
            return Err(err(&format!("bad {what} `{t}`")));
        }
        t.parse::<i64>().map_err(|_| err(&format!("bad {what}")))
    };
    let (date, rest) = s.split_at(s.find(['T', 't', ' ']).ok_or_else(|| err("missing `T`"))?);
    let rest = &rest[1..];
    let dparts: Vec<&str> = date.split('-').collect();
    if dparts.len() != 3 || dparts[0].len() != 4 {
        return Err(err("date must be YYYY-MM-DD"));
    }
    let (y, mo, d) = (
        num(dparts[0], "year")?,
        num(dparts[1], "month")?,
        num(dparts[2], "day")?,
    );
    if !(1..=12).contains(&mo) {
        return Err(err("month out of range"));
    }
    let mdays = [
        31,
        if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 {
            29
        } else {
            28
        },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if d < 1 || d > mdays[(mo - 1) as usize] {
        return Err(err("day out of range"));
    }
    // Split time and offset.
    let (time, offset_min) = if let Some(t) = rest.strip_suffix(['Z', 'z']) {
        (t, 0i64)
    } else if let Some(p) = rest.rfind(['+', '-']) {
        let (t, o) = rest.split_at(p);
        let sign = if o.starts_with('-') { -1 } else { 1 };
        let o = &o[1..];
        let (oh, om) = if let Some((h, m)) = o.split_once(':') {
            (num(h, "offset hours")?, num(m, "offset minutes")?)
        } else if o.len() == 4 {
            (
                num(&o[..2], "offset hours")?,
                num(&o[2..], "offset minutes")?,
            )
        } else if o.len() == 2 {
            (num(o, "offset hours")?, 0)
        } else {
            return Err(err("bad UTC offset"));
        };
        if oh > 14 || om > 59 {
            return Err(err("UTC offset out of range"));
        }
        (t, sign * (oh * 60 + om))
    } else {
        return Err(err("missing UTC offset (`Z` or `±HH:MM`)"));
    };
    let tparts: Vec<&str> = time.split(':').collect();
    if tparts.len() < 2 || tparts.len() > 3 {
        return Err(err("time must be HH:MM[:SS[.fff]]"));
    }
    let h = num(tparts[0], "hour")?;
    let mi = num(tparts[1], "minute")?;
    let sec = if tparts.len() == 3 {
        let (whole, frac) = tparts[2].split_once('.').unwrap_or((tparts[2], ""));
        let w = num(whole, "second")? as f64;
        let f = if frac.is_empty() {
            0.0
        } else {
            num(frac, "second fraction")? as f64 / 10f64.powi(frac.len() as i32)
        };
        w + f
    } else {
        0.0
    };
    if h > 24 || mi > 59 || sec >= 61.0 {
        return Err(err("time out of range"));
    }
    // Meeus, Astronomical Algorithms ch. 7 (Gregorian calendar).
    let (mut yy, mut mm) = (y, mo);
    if mm <= 2 {
        yy -= 1;
        mm += 12;
    }
    let a = yy.div_euclid(100);
    let b = 2 - a + a.div_euclid(4);
    let jd0 = (365.25 * (yy + 4716) as f64).floor()
        + (30.6001 * (mm + 1) as f64).floor()
        + d as f64
        + b as f64
        - 1524.5;
    let minutes_ut = (h * 60 + mi - offset_min) as f64 + sec / 60.0;
    Ok(jd0 + minutes_ut / 1440.0)
}

/// Solar (zenith, azimuth) in degrees from the NOAA algorithm, refraction included.
fn noaa(latitude: f64, longitude: f64, jd: f64) -> (f64, f64) {
    let rad = f64::to_radians;
    let deg = f64::to_degrees;
    let t = (jd - 2451545.0) / 36525.0;
    let l0 = (280.46646 + t * (36000.76983 + 0.0003032 * t)).rem_euclid(360.0);
    let m = 357.52911 + t * (35999.05029 - 0.0001537 * t);
    let e = 0.016708634 - t * (0.000042037 + 0.0000001267 * t);
    let mr = rad(m);
    let c = mr.sin() * (1.914602 - t * (0.004817 + 0.000014 * t))
        + (2.0 * mr).sin() * (0.019993 - 0.000101 * t)
        + 0.000289 * (3.0 * mr).sin();
    let omega = 125.04 - 1934.136 * t;
    let lambda = l0 + c - 0.00569 - 0.00478 * rad(omega).sin();
    let eps0 = 23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - 0.001813 * t))) / 60.0) / 60.0;
    let eps = eps0 + 0.00256 * rad(omega).cos();
    let decl = (rad(eps).sin() * rad(lambda).sin()).asin();
    let y = (rad(eps) / 2.0).tan().powi(2);
    let l0r = rad(l0);
    let eot = 4.0
        * deg(y * (2.0 * l0r).sin() - 2.0 * e * mr.sin()
            + 4.0 * e * y * mr.sin() * (2.0 * l0r).cos()
            - 0.5 * y * y * (4.0 * l0r).sin()
            - 1.25 * e * e * (2.0 * mr).sin());
    let ut_min = (jd + 0.5).fract() * 1440.0;
    let tst = (ut_min + eot + 4.0 * longitude).rem_euclid(1440.0);
    let h = rad(tst / 4.0 - 180.0);
    let phi = rad(latitude);
    let cosz = (phi.sin() * decl.sin() + phi.cos() * decl.cos() * h.cos()).clamp(-1.0, 1.0);
    let zen = cosz.acos();
    // Azimuth clockwise from north (atan2 form; no quadrant ambiguity).
    let az = (h.sin()).atan2(h.cos() * phi.sin() - decl.tan() * phi.cos()) + std::f64::consts::PI;
    let el = 90.0 - deg(zen);
    let refr_arcsec = if el > 85.0 {
        0.0
    } else if el > 5.0 {
        let te = rad(el).tan();
        58.1 / te - 0.07 / te.powi(3) + 0.000086 / te.powi(5)
    } else if el > -0.575 {
        1735.0 + el * (-518.2 + el * (103.4 + el * (-12.79 + el * 0.711)))
    } else {
        -20.772 / rad(el).tan()
    };
    (deg(zen) - refr_arcsec / 3600.0, deg(az).rem_euclid(360.0))
}

/// Solar elevation and azimuth (rad; azimuth clockwise from north) at `latitude`,
/// `longitude` (degrees, east positive) and an ISO-8601 date-time with offset
/// (`"2024-06-21T10:30:00+02:00"`). The elevation is apparent (atmospheric refraction added).
pub fn position(latitude: f64, longitude: f64, datetime: &str) -> Result<(f64, f64), String> {
    if !(-90.0..=90.0).contains(&latitude) || !latitude.is_finite() {
        return Err(format!("latitude {latitude} is outside [-90, 90] degrees"));
    }
    if !(-180.0..=360.0).contains(&longitude) || !longitude.is_finite() {
        return Err(format!(
            "longitude {longitude} is outside [-180, 360] degrees"
        ));
    }
    let jd = parse_iso8601_jd(datetime)?;
    let (zen, az) = noaa(latitude, longitude, jd);
    Ok(((90.0 - zen).to_radians(), az.to_radians()))
}

/// Direction sunlight propagates in air (world, z up) for elevation/azimuth (rad).
pub fn direction_from(elevation: f64, azimuth: f64) -> DVec3 {
    let c = elevation.cos();
    -DVec3::new(c * azimuth.sin(), c * azimuth.cos(), elevation.sin())
}

/// Refract sunlight propagating along `dir_air` through a flat surface into water of index
/// `n_water`: returns (direction in water, factor on normal irradiance
/// `T_Fresnel · cos θa / cos θw`). A sun at or below the horizon gives the grazing limit
/// direction and factor 0.
pub fn refract_into_water(dir_air: DVec3, n_water: f64) -> (DVec3, f64) {
    let i = dir_air.normalize_or(-DVec3::Z);
    let down = -DVec3::Z;
    let ci = i.dot(down);
    if ci <= 0.0 {
        // Sun at/below horizon: grazing limit, no light enters.
        let h = DVec3::new(i.x, i.y, 0.0).normalize_or(DVec3::X);
        let st = 1.0 / n_water;
        let d = h * st + down * (1.0 - st * st).max(0.0).sqrt();
        return (d, 0.0);
    }
    match refract(i, down, 1.0 / n_water) {
        Some((t, ct)) => (t, fresnel_transmittance(1.0, n_water, ci, ct) * ci / ct),
        None => (i, 0.0), // n_water < 1 and beyond critical: nothing transmitted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spa_worked_example() {
        // Reda & Andreas 2004 example, 2003-10-17 19:30:30 UT (12:30:30 at −7 h),
        // 39.742476 N, 105.1786 W. NOAA reference: z = 50.10864°, A = 194.34258° (docs/optics.md
        // §4.1); tolerance 1e-3° for transcription of constants.
        let (el, az) = position(39.742476, -105.1786, "2003-10-17T12:30:30-07:00").unwrap();
        let z = 90.0 - el.to_degrees();
        assert!((z - 50.10864).abs() < 1e-3, "zenith {z}");
        assert!(
            (az.to_degrees() - 194.34258).abs() < 1e-3,
            "azimuth {}",
            az.to_degrees()
        );
        let jd = parse_iso8601_jd("2003-10-17T19:30:30Z").unwrap();
        assert!((jd - 2452930.312847).abs() < 1e-6);
        let (el2, _) = position(39.742476, -105.1786, "2003-10-17T19:30:30Z").unwrap();
        assert_eq!(el, el2);
    }

    #[test]
    fn bad_datetimes_are_errors() {
        for s in [
            "2024-06-21",
            "2024-13-01T10:00:00Z",
            "2024-02-30T10:00Z",
            "2024-06-21T10:00:00",
            "x",
        ] {
            assert!(position(0.0, 0.0, s).is_err(), "{s}");
        }
        assert!(position(0.0, 0.0, "2024-06-21T10:00+0200").is_ok());
        assert!(position(0.0, 0.0, "2024-06-21T10:00:00.5+02:00").is_ok());
        assert!(position(95.0, 0.0, "2024-06-21T10:00Z").is_err());
    }

    #[test]
    fn refraction_into_water() {
        // Sun at 30° elevation (θa = 60°) into nw = 1.34: θw = 40.26°, R = 0.0610 (docs/optics.md §4.2).
        let d = direction_from(30f64.to_radians(), 0.0);
        let (w, f) = refract_into_water(d, 1.34);
        let tw = (-w.z).acos().to_degrees();
        assert!((tw - 40.26).abs() < 0.01);
        assert!((w.length() - 1.0).abs() < 1e-14);
        let want = (1.0 - 0.0610) * 60f64.to_radians().cos() / 40.26f64.to_radians().cos();
        assert!((f - want).abs() < 2e-4, "{f} vs {want}");
        // Heading is kept (north).
        assert!(w.y < 0.0 && w.x.abs() < 1e-15);
        let (_, f0) = refract_into_water(direction_from(-0.1, 0.0), 1.34);
        assert_eq!(f0, 0.0);
    }
}
