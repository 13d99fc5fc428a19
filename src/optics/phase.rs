//! Phase functions: Henyey–Greenstein and Fournier–Forand (evaluation, sampling, backscatter).
// PLACEHOLDER API (lead): signatures are the contract; the optics work replaces the bodies.

/// Backscatter fraction of Henyey–Greenstein with asymmetry g.
pub fn hg_backscatter(g: f64) -> f64 {
    if g.abs() < 1e-9 {
        0.5
    } else {
        (1.0 - g) / (2.0 * g) * ((1.0 + g) / (1.0 + g * g).sqrt() - 1.0)
    }
}

/// Backscatter fraction of Fournier–Forand with relative index `n` and Junge slope `mu`.
pub fn ff_backscatter(n: f64, mu: f64) -> f64 {
    let _ = (n, mu);
    0.0183
}
