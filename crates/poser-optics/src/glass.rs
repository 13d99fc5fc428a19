//! Port materials: Sellmeier dispersion for the catalogue (N-BK7, fused silica, PMMA, sapphire).
//!
//! `n² = 1 + Σ Bᵢ λ²/(λ² − Cᵢ)`, λ in µm, indices relative to air.
//!
//! | name | source | n_d (587.6 nm) |
//! |---|---|---|
//! | `N-BK7` | Schott datasheet | 1.516798 |
//! | `fused_silica` | Malitson, JOSA 55:1205 (1965) | 1.458462 |
//! | `PMMA` | Szczurowski 2013 (refractiveindex.info) | 1.490594 |
//! | `sapphire` | Malitson & Dodge 1972, ordinary ray (c-axis-normal window) | 1.768170 |

/// Catalogue names accepted in scene files.
pub const CATALOGUE: &[&str] = &["N-BK7", "fused_silica", "PMMA", "sapphire"];

/// Sellmeier coefficients `(B1, B2, B3, C1, C2, C3)` with C in µm².
fn sellmeier(name: &str) -> Option<[f64; 6]> {
    Some(match name {
        "N-BK7" => [
            1.03961212,
            0.231792344,
            1.01046945,
            0.00600069867,
            0.0200179144,
            103.560653,
        ],
        // Malitson gives resonance wavelengths; they must be squared.
        "fused_silica" => [
            0.6961663,
            0.4079426,
            0.8974794,
            0.0684043 * 0.0684043,
            0.1162414 * 0.1162414,
            9.896161 * 9.896161,
        ],
        "PMMA" => [0.99654, 0.18964, 0.00411, 0.00787, 0.02191, 3.85727],
        "sapphire" => [
            1.4313493,
            0.65054713,
            5.3414021,
            0.0726631 * 0.0726631,
            0.1193242 * 0.1193242,
            18.028251 * 18.028251,
        ],
        _ => return None,
    })
}

/// Refractive index of a catalogue material at `wavelength` nm; `None` for an unknown name.
pub fn catalogue_ior(name: &str, wavelength: f64) -> Option<f64> {
    let [b1, b2, b3, c1, c2, c3] = sellmeier(name)?;
    let l2 = (wavelength * 1e-3).powi(2);
    let n2 = 1.0 + b1 * l2 / (l2 - c1) + b2 * l2 / (l2 - c2) + b3 * l2 / (l2 - c3);
    Some(n2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sellmeier_matches_reference_table() {
        // docs/optics.md §2.3; printed to 1e-6.
        let table = [
            ("N-BK7", [1.525320, 1.518522, 1.516798, 1.514520]),
            ("fused_silica", [1.465566, 1.459911, 1.458462, 1.456535]),
            ("sapphire", [1.779350, 1.770446, 1.768170, 1.765148]),
            ("PMMA", [1.499752, 1.492400, 1.490594, 1.488275]),
        ];
        for (name, want) in table {
            for (l, w) in [450.0, 550.0, 587.6, 650.0].iter().zip(want) {
                let n = catalogue_ior(name, *l).unwrap();
                assert!((n - w).abs() < 1.5e-6, "{name} at {l}: {n} vs {w}");
            }
        }
        assert!(catalogue_ior("unobtainium", 550.0).is_none());
        for name in CATALOGUE {
            assert!(catalogue_ior(name, 550.0).is_some());
        }
    }
}
