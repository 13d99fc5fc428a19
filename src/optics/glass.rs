//! Port materials: Sellmeier dispersion for the catalogue (N-BK7, fused silica, PMMA, sapphire).
// PLACEHOLDER API (lead): signatures are the contract; the optics work replaces the bodies.

/// Catalogue names accepted in scene files.
pub const CATALOGUE: &[&str] = &["N-BK7", "fused_silica", "PMMA", "sapphire"];

/// Refractive index of a catalogue material at `wavelength` nm; `None` for an unknown name.
pub fn catalogue_ior(name: &str, wavelength: f64) -> Option<f64> {
    let _ = wavelength;
    match name {
        "N-BK7" => Some(1.5168),
        "fused_silica" => Some(1.4585),
        "PMMA" => Some(1.4917),
        "sapphire" => Some(1.7682),
        _ => None,
    }
}
