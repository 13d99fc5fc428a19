//! Sea water: refractive index (Quan–Fry with Millard–Seaver pressure term), absorption and
//! scattering per Jerlov type.
// PLACEHOLDER API (lead): signatures are the contract; the optics work replaces the bodies.

use crate::model::Rgb;

/// Phase refractive index of sea water at `temperature` °C, `salinity` PSU, `depth` m and
/// `wavelength` nm.
pub fn seawater_ior(temperature: f64, salinity: f64, depth: f64, wavelength: f64) -> f64 {
    let _ = (temperature, salinity, depth, wavelength);
    1.34
}

/// The Jerlov type names poser knows, in order.
pub const JERLOV_TYPES: &[&str] = &["I", "IA", "IB", "II", "III", "1C", "3C", "5C", "7C", "9C"];

/// Absorption and scattering coefficients (1/m) of a Jerlov type at the R, G, B channel
/// wavelengths; `None` for an unknown name.
pub fn jerlov(name: &str) -> Option<(Rgb, Rgb)> {
    JERLOV_TYPES
        .contains(&name)
        .then_some(([0.334, 0.062, 0.0235], [0.045, 0.0536, 0.068]))
}
