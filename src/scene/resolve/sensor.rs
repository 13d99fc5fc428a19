//! Resolution of the optional `[sensor]` table into [`crate::model::Sensor`] (documented in
//! [`crate::scene::format::Sensor`]; the model and formulas are in `docs/sensor.md`).
//!
//! | key | resolved to | check |
//! |---|---|---|
//! | `full_well`, `read_noise` | e⁻ | > 0, ≥ 0 |
//! | `quantum_efficiency` | per channel, e⁻/photon | in (0, 1] |
//! | `bits`, `black_level` | ADC bits, DN | 8..=16, < full scale / 2 |
//! | `iso`, `base_iso` | gain = iso / base_iso | > 0 |
//! | `exposure`, `shutter`, `f_number`, `transmittance` | exposure | `auto`/`manual`, > 0 |
//! | `meter`, `percentile`, `target` | auto exposure | fractions in (0, 1] |
//! | `white_balance` | `none`, `grey_world` or gains | gains > 0 |
//! | `tone`, `gamma` | tone curve | gamma > 0 |
//! | `format`, `quality` | JPEG (quality 1..=100) or PNG | |
//! | `noise` | shot + read noise on | |

use crate::model::*;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Node, Val};
use crate::units::Dim;

/// `[sensor]`, or `None` when the table is absent. `camera_f_number` is the first camera's
/// aperture (the default of `sensor.f_number`).
pub fn sensor(
    cx: &mut Cx,
    node: Option<&Node>,
    camera_f_number: Option<f64>,
    fallback: Span,
) -> Option<Sensor> {
    // Read even when absent (every getter then gives its default), so that the key record
    // that keeps the reader and the schema in step sees every key.
    let mut t = Tab::open(cx, node, F::Scene::sensor, fallback);
    let d = Sensor::default();
    let full_well = t.f64(cx, F::Sensor::full_well, Dim::Number, d.full_well);
    check::positive(cx, &t, F::Sensor::full_well, full_well, "e⁻");
    let read_noise = t.f64(cx, F::Sensor::read_noise, Dim::Number, d.read_noise);
    if !(read_noise >= 0.0) {
        cx.push(
            Diagnostic::error("E0222", "`sensor.read_noise` must not be negative")
                .label(t.span_of(F::Sensor::read_noise), format!("{read_noise} e⁻"))
                .help("read noise is an RMS value in electrons, e.g. `read_noise = 3`"),
        );
    }
    let qe = t.rgb(
        cx,
        F::Sensor::quantum_efficiency,
        Dim::Fraction,
        d.quantum_efficiency,
    );
    if qe.iter().any(|q| !(*q > 0.0 && *q <= 1.0)) {
        cx.push(
            Diagnostic::error("E0223", "`sensor.quantum_efficiency` must be in (0, 1]")
                .label(t.span_of(F::Sensor::quantum_efficiency), format!("{qe:?}"))
                .help("electrons per photon, e.g. `quantum_efficiency = [0.45, 0.55, 0.45]`"),
        );
    }
    let bits = t.u32(cx, F::Sensor::bits, d.bits);
    if !(8..=16).contains(&bits) {
        cx.push(
            Diagnostic::error("E0224", "`sensor.bits` must be between 8 and 16")
                .label(t.span_of(F::Sensor::bits), format!("{bits} bits"))
                .help("cameras digitise with 10 to 14 bits, e.g. `bits = 12`"),
        );
    }
    let bits = bits.clamp(8, 16);
    let black_level = t.u32(cx, F::Sensor::black_level, 1 << (bits - 6));
    if black_level >= (1 << (bits - 1)) {
        cx.push(
            Diagnostic::error("E0225", "`sensor.black_level` is too large")
                .label(
                    t.span_of(F::Sensor::black_level),
                    format!("{black_level} DN of {} DN full scale", (1u32 << bits) - 1),
                )
                .help("keep the black level below half of the ADC range, e.g. 64 DN at 12 bits"),
        );
    }
    let iso = t.f64(cx, F::Sensor::iso, Dim::Number, d.iso);
    check::positive(cx, &t, F::Sensor::iso, iso, "");
    let base_iso = t.f64(cx, F::Sensor::base_iso, Dim::Number, d.base_iso);
    check::positive(cx, &t, F::Sensor::base_iso, base_iso, "");
    let mode = t
        .choice(cx, F::Sensor::exposure, &["auto", "manual"])
        .unwrap_or("auto");
    let shutter = t.f64(cx, F::Sensor::shutter, Dim::Time, d.shutter);
    check::positive(cx, &t, F::Sensor::shutter, shutter, "s");
    let f_number = t
        .opt_f64(cx, F::Sensor::f_number, Dim::Number)
        .or(camera_f_number)
        .unwrap_or(d.f_number);
    check::positive(cx, &t, F::Sensor::f_number, f_number, "");
    let transmittance = t.f64(cx, F::Sensor::transmittance, Dim::Fraction, d.transmittance);
    fraction(cx, &t, F::Sensor::transmittance, transmittance);
    let meter = match t.choice(cx, F::Sensor::meter, &["highlights", "average"]) {
        Some("average") => Meter::Average,
        _ => Meter::Highlights,
    };
    let percentile = t.f64(cx, F::Sensor::percentile, Dim::Fraction, 0.99);
    fraction(cx, &t, F::Sensor::percentile, percentile);
    let target = t.f64(
        cx,
        F::Sensor::target,
        Dim::Fraction,
        if meter == Meter::Average { 0.18 } else { 0.85 },
    );
    fraction(cx, &t, F::Sensor::target, target);
    let exposure = if mode == "manual" {
        SensorExposure::Manual
    } else {
        SensorExposure::Auto {
            meter,
            percentile,
            target,
        }
    };
    let white_balance = white_balance(cx, &mut t);
    let tone = match t.choice(cx, F::Sensor::tone, &["srgb", "gamma", "linear"]) {
        Some("linear") => ToneCurve::Linear,
        Some("gamma") => ToneCurve::Gamma(0.0),
        _ => ToneCurve::Srgb,
    };
    let gamma = t.f64(cx, F::Sensor::gamma, Dim::Number, 2.2);
    check::positive(cx, &t, F::Sensor::gamma, gamma, "");
    let tone = match tone {
        ToneCurve::Gamma(_) => ToneCurve::Gamma(gamma),
        x => x,
    };
    let quality = t.u32(cx, F::Sensor::quality, 95);
    if !(1..=100).contains(&quality) {
        cx.push(
            Diagnostic::error("E0226", "`sensor.quality` must be between 1 and 100")
                .label(t.span_of(F::Sensor::quality), format!("{quality}"))
                .help("JPEG quality as cameras write it is 85 to 98, e.g. `quality = 95`"),
        );
    }
    let format = match t.choice(cx, F::Sensor::format, &["jpeg", "png"]) {
        Some("png") => SensorFormat::Png,
        _ => SensorFormat::Jpeg(quality.clamp(1, 100) as u8),
    };
    let noise = t.bool(cx, F::Sensor::noise, true);
    t.finish(cx);
    node?;
    Some(Sensor {
        full_well,
        read_noise,
        quantum_efficiency: qe,
        bits,
        black_level,
        iso,
        base_iso,
        exposure,
        shutter,
        f_number,
        transmittance,
        white_balance,
        tone,
        format,
        noise,
    })
}

fn fraction(cx: &mut Cx, t: &Tab, key: &'static str, v: f64) {
    if !(v > 0.0 && v <= 1.0) {
        cx.push(
            Diagnostic::error("E0227", format!("`{}` must be in (0, 1]", t.full(key)))
                .label(t.span_of(key), format!("{v}"))
                .help(format!(
                    "give a fraction, e.g. `{key} = \"90 %\"` or `{key} = 0.9`"
                )),
        );
    }
}

fn white_balance(cx: &mut Cx, t: &mut Tab) -> WhiteBalance {
    let span = t.span_of(F::Sensor::white_balance);
    let Some(n) = t.get(F::Sensor::white_balance) else {
        return WhiteBalance::GreyWorld;
    };
    match &n.val {
        Val::Str(_) => match t.choice(cx, F::Sensor::white_balance, &["grey_world", "none"]) {
            Some("none") => WhiteBalance::None,
            _ => WhiteBalance::GreyWorld,
        },
        Val::Array(_) => {
            let g = t.rgb(cx, F::Sensor::white_balance, Dim::Number, [1.0; 3]);
            if g.iter().any(|x| !(*x > 0.0)) {
                cx.push(
                    Diagnostic::error("E0228", "white-balance gains must be positive")
                        .label(span, format!("{g:?}"))
                        .help("e.g. `white_balance = [2.4, 1.0, 1.1]`"),
                );
            }
            WhiteBalance::Fixed(g)
        }
        v => {
            cx.push(crate::scene::reader::type_error(
                n,
                "sensor.white_balance",
                "\"grey_world\", \"none\" or gains [r, g, b]",
                v,
            ));
            WhiteBalance::GreyWorld
        }
    }
}
