//! Sea water: refractive index (Quan–Fry with Millard–Seaver pressure term), absorption and
//! scattering per Jerlov type.
//!
//! | function | inputs (units) | source |
//! |---|---|---|
//! | [`quan_fry`] | T °C, S PSU, λ nm | Quan & Fry, Appl. Opt. 34(18):3477 (1995); valid 400–700 nm, 0–30 °C, 0–35 PSU, 1 atm |
//! | [`millard_seaver`] | T °C, S PSU, P dbar (sea pressure), λ nm | Millard & Seaver, Deep-Sea Res. 37(12):1909 (1990); 500–700 nm, 0–11 000 dbar |
//! | [`seawater_ior`] | T, S, depth m, λ | Quan–Fry + (M&S(P) − M&S(0)) pressure increment |
//! | [`jerlov`] | type name | Solonenko & Mobley, Appl. Opt. 54(17):5392 (2015), Tables 4–8, a and b at 650/550/450 nm |
//!
//! All indices are relative to air (as are the Schott glass indices), so Snell's law at the
//! port only needs ratios and the camera-side medium is n = 1.

use super::types::Rgb;

/// Quan–Fry (1995) index of sea water relative to air at atmospheric pressure.
pub fn quan_fry(temperature: f64, salinity: f64, wavelength: f64) -> f64 {
    const N0: f64 = 1.31405;
    const N1: f64 = 1.779e-4;
    const N2: f64 = -1.05e-6;
    const N3: f64 = 1.6e-8;
    const N4: f64 = -2.02e-6;
    const N5: f64 = 15.868;
    const N6: f64 = 0.01155;
    const N7: f64 = -0.00423;
    const N8: f64 = -4382.0;
    const N9: f64 = 1.1455e6;
    let (t, s, l) = (temperature, salinity, wavelength);
    N0 + (N1 + N2 * t + N3 * t * t) * s
        + N4 * t * t
        + (N5 + N6 * s + N7 * t) / l
        + N8 / (l * l)
        + N9 / (l * l * l)
}

/// Millard–Seaver (1990) 27-term index of sea water relative to air; `pressure` is the sea
/// pressure in dbar (0 at the surface), wavelength in nm.
pub fn millard_seaver(temperature: f64, salinity: f64, pressure: f64, wavelength: f64) -> f64 {
    let (t, s, p) = (temperature, salinity, pressure);
    let l = wavelength * 1e-3; // µm
    let l2 = l * l;
    let (t2, t3) = (t * t, t * t * t);
    // Pure water, 1 atm.
    let nw = 1.3280657 - 0.0045536802 * l2
        + 0.0025471707 / l2
        + 7.501966e-6 / (l2 * l2)
        + 2.802632e-6 / (l2 * l2 * l2)
        - 5.2883907e-6 * t
        - 3.0738272e-6 * t2
        + 3.0124687e-8 * t3
        - 2.0883178e-10 * t2 * t2
        + 1.0508621e-5 * t * l
        + 2.1282248e-7 * t2 * l
        - 1.705881e-9 * t3 * l;
    // Salinity terms.
    let ns = 1.9029121e-4 * s + 2.4239607e-6 * s / l2 - 7.3960297e-7 * s * t
        + 8.9818478e-9 * s * t2
        + 1.2078804e-10 * s * t3
        - 3.589495e-7 * s * t * l;
    // Pressure terms.
    let np = 1.5868383e-6 * p - 1.574074e-11 * p * p + 1.0712063e-8 * p / l2 - 9.4834486e-9 * p * t
        + 1.0100326e-10 * p * t2
        + 5.8085198e-15 * p * p * t2
        - 1.1177517e-9 * p * s
        + 5.7311268e-11 * p * s * t
        - 1.5460458e-12 * p * t2 * s;
    nw + ns + np
}

/// Sea pressure (dbar) at `depth` m below the surface, hydrostatic with ρ = 1025 kg/m³.
pub fn sea_pressure_dbar(depth: f64) -> f64 {
    depth.max(0.0) * 1025.0 * 9.80665 / 1e4
}

/// Phase refractive index of sea water at `temperature` °C, `salinity` PSU, `depth` m and
/// `wavelength` nm: Quan–Fry at the surface plus the Millard–Seaver pressure increment
/// (≈ +1.5e-6 per metre).
pub fn seawater_ior(temperature: f64, salinity: f64, depth: f64, wavelength: f64) -> f64 {
    let base = quan_fry(temperature, salinity, wavelength);
    if depth > 0.0 {
        let p = sea_pressure_dbar(depth);
        base + millard_seaver(temperature, salinity, p, wavelength)
            - millard_seaver(temperature, salinity, 0.0, wavelength)
    } else {
        base
    }
}

/// The Jerlov type names poser knows, in order.
pub const JERLOV_TYPES: &[&str] = &["I", "IA", "IB", "II", "III", "1C", "3C", "5C", "7C", "9C"];

/// Solonenko & Mobley (2015) IOPs at [650, 550, 450] nm: (type, a, b), 1/m.
/// Transcribed from `jerlov_iop_solonenko_mobley_2015.csv` (shared reference); the 5C 650 nm
/// row is the Williamson & Hollins (2022) replacement for a corrupt printed value.
const JERLOV_TABLE: &[(&str, Rgb, Rgb)] = &[
    ("I", [0.334, 0.062, 0.018], [0.000899, 0.0017, 0.00381]),
    ("IA", [0.334, 0.0622, 0.0221], [0.00234, 0.00354, 0.00631]),
    ("IB", [0.334, 0.0623, 0.0235], [0.045, 0.0536, 0.068]),
    ("II", [0.334, 0.0622, 0.0241], [0.27, 0.358, 0.504]),
    ("III", [0.336, 0.0646, 0.0388], [0.737, 0.98, 1.38]),
    ("1C", [0.344, 0.076, 0.105], [0.274, 0.365, 0.514]),
    ("3C", [0.346, 0.082, 0.154], [0.8, 1.06, 1.5]),
    ("5C", [0.367, 0.117, 0.297], [1.002, 1.33, 1.87]),
    ("7C", [0.403, 0.195, 0.542], [1.77, 2.35, 3.3]),
    ("9C", [0.456, 0.348, 0.943], [2.35, 3.12, 4.39]),
];

/// Absorption and scattering coefficients (1/m) of a Jerlov type at the R, G, B channel
/// wavelengths; `None` for an unknown name.
pub fn jerlov(name: &str) -> Option<(Rgb, Rgb)> {
    JERLOV_TABLE
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|&(_, a, b)| (a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quan_fry_matches_reference_values() {
        // docs/optics.md §2.2: 550 nm, S = 35; printed to 1e-6.
        for (t, want) in [
            (0.0, 1.342262),
            (10.0, 1.341671),
            (20.0, 1.340789),
            (25.0, 1.340238),
        ] {
            assert!((quan_fry(t, 35.0, 550.0) - want).abs() < 1e-6, "T={t}");
        }
        // Pure water and sea water at 20 °C, 450/550/650 nm.
        for (s, l, want) in [
            (0.0, 450.0, 1.339247),
            (0.0, 550.0, 1.334338),
            (0.0, 650.0, 1.331324),
            (35.0, 450.0, 1.345861),
            (35.0, 650.0, 1.337661),
        ] {
            assert!((quan_fry(20.0, s, l) - want).abs() < 1e-6, "S={s} λ={l}");
        }
    }

    #[test]
    fn millard_seaver_matches_reference_values() {
        // docs/optics.md §2.2 table, 550 nm, S = 35; printed to 1e-6.
        for (t, p, want) in [
            (0.0, 0.0, 1.342232),
            (0.0, 1000.0, 1.343800),
            (0.0, 4000.0, 1.348313),
            (20.0, 0.0, 1.340763),
            (20.0, 1000.0, 1.342202),
            (25.0, 4000.0, 1.345722),
        ] {
            assert!(
                (millard_seaver(t, 35.0, p, 550.0) - want).abs() < 1.5e-6,
                "T={t} P={p}"
            );
        }
    }

    #[test]
    fn pressure_adds_about_1_5e6_per_metre() {
        let d = seawater_ior(15.0, 35.0, 100.0, 550.0) - seawater_ior(15.0, 35.0, 0.0, 550.0);
        // ≈ +1.46e-3 per 1000 dbar (docs/optics.md §2.2); 100 m ≈ 100.5 dbar.
        assert!((d - 1.47e-4).abs() < 1e-5, "{d}");
    }

    #[test]
    fn jerlov_types_all_present_and_match_csv() {
        for t in JERLOV_TYPES {
            let (a, b) = jerlov(t).unwrap();
            assert!(a.iter().chain(b.iter()).all(|v| *v > 0.0));
        }
        assert!(jerlov("X").is_none());
        let (a, b) = jerlov("IB").unwrap();
        assert_eq!(a, [0.334, 0.0623, 0.0235]);
        assert_eq!(b, [0.045, 0.0536, 0.068]);
    }
}
