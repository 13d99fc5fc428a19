//! The sun: NOAA solar position, and refraction of sunlight through a flat sea surface.
// PLACEHOLDER API (lead): signatures are the contract; the optics work replaces the bodies.

use glam::DVec3;

/// Solar elevation and azimuth (rad; azimuth clockwise from north) at `latitude`,
/// `longitude` (degrees, east positive) and an ISO-8601 date-time with offset
/// (`"2024-06-21T10:30:00+02:00"`).
pub fn position(latitude: f64, longitude: f64, datetime: &str) -> Result<(f64, f64), String> {
    let _ = (latitude, longitude, datetime);
    Err("solar position is not implemented yet".into())
}

/// Direction sunlight propagates in air (world, z up) for elevation/azimuth (rad).
pub fn direction_from(elevation: f64, azimuth: f64) -> DVec3 {
    let c = elevation.cos();
    -DVec3::new(c * azimuth.sin(), c * azimuth.cos(), elevation.sin())
}

/// Refract sunlight propagating along `dir_air` through a flat surface into water of index
/// `n_water`: returns (direction in water, factor on normal irradiance
/// `T_Fresnel · cos θa / cos θw`).
pub fn refract_into_water(dir_air: DVec3, n_water: f64) -> (DVec3, f64) {
    let _ = n_water;
    (dir_air, 1.0)
}
