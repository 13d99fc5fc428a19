//! The EXIF block of the camera files: what outside photogrammetry software (COLMAP,
//! Metashape) reads about the camera that took an image — make, model, software, the lens's
//! in-air focal length, its 35 mm equivalent, the sensor's pixel density and the image size,
//! and the exposure — as the TIFF structure that a JPEG's APP1 `Exif` segment and a PNG's
//! `eXIf` chunk carry. No date or time is written, so the bytes depend on the scene alone.
//!
//! | tag | value |
//! |---|---|
//! | `Make`, `Model`, `Software` | `"poser"`, the camera's name (`"poser camera"` for the unnamed single camera), `"poser <version>"` |
//! | `FocalLength` | the lens's focal length in air, mm (not the effective one behind a port: `docs/sensor.md`) |
//! | `FocalLengthIn35mmFilm` | `FocalLength × 43.27 mm / sensor diagonal`, rounded to whole mm (a SHORT) |
//! | `FocalPlaneXResolution`, `FocalPlaneYResolution`, `FocalPlaneResolutionUnit` | pixels per cm across and down (`fx / f`, `fy / f`), unit 3 (cm) |
//! | `PixelXDimension`, `PixelYDimension` | the image size, pixels |
//! | `ExposureTime`, `FNumber`, `PhotographicSensitivity` | the exposure the sensor stage chose |
//! | `ExifVersion`, `ColorSpace` | `"0232"`; 1 (sRGB) with the sRGB tone curve, else 0xFFFF (uncalibrated) |

use super::Exposure;
use crate::model::{Camera, Sensor, ToneCurve};
use exif::experimental::Writer;
use exif::{Field, In, Rational, Tag, Value};

/// Diagonal of the 36 × 24 mm frame, mm: the 35 mm equivalent focal length is the focal
/// length scaled by this over the sensor's diagonal (CIPA DC-008, Exif 2.32, FocalLengthIn35mmFilm).
pub const FULL_FRAME_DIAGONAL_MM: f64 = 43.266_615_305_567_87;

/// What the EXIF block says about the camera of one image, in the units EXIF writes.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraTags {
    /// `Model`.
    pub model: String,
    /// `FocalLength`, mm: the lens's focal length in air.
    pub focal_length_mm: f64,
    /// `FocalLengthIn35mmFilm`, mm.
    pub focal_35mm: u16,
    /// `FocalPlaneXResolution`, `FocalPlaneYResolution`: pixels per cm.
    pub pixels_per_cm: [f64; 2],
    /// `PixelXDimension`, `PixelYDimension`.
    pub size: [u32; 2],
}

impl CameraTags {
    /// The tags of `cam` for an image `width` × `height` pixels (`cam` at that size: see
    /// [`super::files::at_image_size`]).
    pub fn of(cam: &Camera, width: u32, height: u32) -> CameraTags {
        let f = cam.focal_length;
        // Pixel pitch across and down, m: f / fx and f / fy (square unless fx ≠ fy).
        let (px, py) = (f / cam.fx, f / cam.fy);
        let diagonal_mm = 1e3 * (width as f64 * px).hypot(height as f64 * py);
        let f35 = (1e3 * f * FULL_FRAME_DIAGONAL_MM / diagonal_mm).round();
        CameraTags {
            model: if cam.name == crate::model::DEFAULT_CAMERA_NAME {
                "poser camera".to_string()
            } else {
                cam.name.clone()
            },
            focal_length_mm: 1e3 * f,
            focal_35mm: if f35.is_finite() {
                f35.clamp(0.0, u16::MAX as f64) as u16
            } else {
                0
            },
            pixels_per_cm: [0.01 / px, 0.01 / py],
            size: [width, height],
        }
    }
}

/// `x` as an unsigned rational with the largest power-of-ten denominator (at most 10⁹) whose
/// numerator fits in 32 bits: six significant digits or more for any value from 0.001 up,
/// which covers every tag written here. A value that is not finite or not positive is 0/1.
pub fn rational(x: f64) -> Rational {
    if !(x.is_finite() && x > 0.0) {
        return Rational { num: 0, denom: 1 };
    }
    let mut den = 1_000_000_000u32;
    while den > 1 && (x * den as f64).round() > u32::MAX as f64 {
        den /= 10;
    }
    let num = (x * den as f64).round().min(u32::MAX as f64) as u32;
    Rational { num, denom: den }
}

fn ascii(tag: Tag, s: &str) -> Field {
    // EXIF ASCII is 7-bit; anything else in a camera name becomes `?`.
    let bytes = s
        .chars()
        .map(|c| {
            if c.is_ascii() && !c.is_ascii_control() {
                c as u8
            } else {
                b'?'
            }
        })
        .collect();
    Field {
        tag,
        ifd_num: In::PRIMARY,
        value: Value::Ascii(vec![bytes]),
    }
}

fn field(tag: Tag, value: Value) -> Field {
    Field {
        tag,
        ifd_num: In::PRIMARY,
        value,
    }
}

/// The EXIF block (a little-endian TIFF structure, without the `Exif\0\0` prefix: the image
/// encoders add what their container needs) for an image of `camera` taken at `exposure`.
pub fn block(camera: &CameraTags, sensor: &Sensor, exposure: &Exposure) -> Result<Vec<u8>, String> {
    let short = |v: u16| Value::Short(vec![v]);
    let long = |v: u32| Value::Long(vec![v]);
    let rat = |x: f64| Value::Rational(vec![rational(x)]);
    let fields = [
        ascii(Tag::Make, "poser"),
        ascii(Tag::Model, &camera.model),
        ascii(
            Tag::Software,
            &format!("poser {}", env!("CARGO_PKG_VERSION")),
        ),
        field(Tag::ExifVersion, Value::Undefined(b"0232".to_vec(), 0)),
        field(
            Tag::ColorSpace,
            short(if sensor.tone == ToneCurve::Srgb {
                1
            } else {
                0xFFFF
            }),
        ),
        field(Tag::FocalLength, rat(camera.focal_length_mm)),
        field(Tag::FocalLengthIn35mmFilm, short(camera.focal_35mm)),
        field(Tag::FocalPlaneXResolution, rat(camera.pixels_per_cm[0])),
        field(Tag::FocalPlaneYResolution, rat(camera.pixels_per_cm[1])),
        field(Tag::FocalPlaneResolutionUnit, short(3)),
        field(Tag::PixelXDimension, long(camera.size[0])),
        field(Tag::PixelYDimension, long(camera.size[1])),
        field(Tag::ExposureTime, rat(exposure.shutter)),
        field(Tag::FNumber, rat(exposure.f_number)),
        field(
            Tag::PhotographicSensitivity,
            short(exposure.iso.round().clamp(0.0, u16::MAX as f64) as u16),
        ),
    ];
    let mut writer = Writer::new();
    for f in &fields {
        writer.push_field(f);
    }
    let mut out = std::io::Cursor::new(Vec::new());
    writer
        .write(&mut out, true)
        .map_err(|e| format!("EXIF block: {e}"))?;
    Ok(out.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rationals_keep_six_significant_digits() {
        for x in [16.0, 2659.574_468, 0.004_321, 1.0 / 3.0, 98_765.4321] {
            let r = rational(x);
            let back = r.num as f64 / r.denom as f64;
            assert!((back / x - 1.0).abs() < 1e-6, "{x} → {}/{}", r.num, r.denom);
        }
        assert_eq!(rational(f64::NAN).num, 0);
        assert_eq!(rational(-1.0).num, 0);
    }

    #[test]
    fn the_diagonal_is_that_of_36_by_24_mm() {
        assert!((FULL_FRAME_DIAGONAL_MM - 36f64.hypot(24.0)).abs() < 1e-12);
    }
}
