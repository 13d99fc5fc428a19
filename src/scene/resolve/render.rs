//! The `[render]` settings shared by every backend: samples per pixel, seed, bounces,
//! dispersion, the outputs written (`rgb`, `depth`, `truth`), the exposure and the native
//! renderer's illumination denoiser, noise target and daylight estimator.

use crate::model::*;
use crate::scene::check;
use crate::scene::diag::{Diagnostic, Span};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab};
use crate::scene::source::{Node, Val};
use crate::units::Dim;

/// Where `[render]` keys the whole-model checks point at were written (absent: defaulted).
#[derive(Default)]
pub(super) struct RenderSpans {
    pub daylight: Option<Span>,
    pub bounces: Option<Span>,
}

/// `[render]`, with every default filled in.
/// `at`: where `daylight` and `bounces` were written, for the checks on the whole model
/// (the column applies; the bounce limit keeps the daylight).
pub(super) fn render(
    cx: &mut Cx,
    node: Option<&Node>,
    fallback: Span,
    at: &mut RenderSpans,
) -> RenderSettings {
    let mut r = Tab::open(cx, node, F::Scene::render, fallback);
    let samples = r.u32(cx, F::Render::samples, 64);
    if samples == 0 {
        let sp = r.span_of(F::Render::samples);
        cx.push(
            Diagnostic::error("E0220", "at least one sample per pixel is needed")
                .label(sp, "0 samples")
                .help("use e.g. `samples = 64`"),
        );
    }
    let seed = r.opt_u64(cx, F::Render::seed).unwrap_or(0);
    // Raised to what the water column needs when not written (`super::default_bounces`).
    let max_bounces = r.u32(cx, F::Render::bounces, super::DEFAULT_BOUNCES);
    // 0 would end every path at its first surface: a black image, every light dropped.
    check::at_least(cx, &r, F::Render::bounces, max_bounces, 1);
    let dispersion = r.bool(cx, F::Render::dispersion, false);
    let outputs = outputs(cx, &mut r);
    let exposure = r.f64(cx, F::Render::exposure, Dim::Number, 1.0);
    check::positive(cx, &r, F::Render::exposure, exposure, "");
    let denoise = r
        .choice(cx, F::Render::denoise, &["none", "illumination"])
        .unwrap_or("none");
    let radius = r.f64(cx, F::Render::denoise_radius, Dim::Number, 2.0);
    check::positive(cx, &r, F::Render::denoise_radius, radius, "px");
    let denoise_radius = (denoise == "illumination" && radius > 0.0).then_some(radius);
    let noise = noise_target(cx, &mut r, samples);
    let (daylight, texture_filter, surface_from_below, sampler) = estimators(cx, &mut r);
    at.daylight = r
        .has(F::Render::daylight)
        .then(|| r.span_of(F::Render::daylight));
    at.bounces = r
        .has(F::Render::bounces)
        .then(|| r.span_of(F::Render::bounces));
    r.finish(cx);
    RenderSettings {
        samples,
        seed,
        max_bounces,
        dispersion,
        outputs,
        exposure,
        denoise_radius,
        noise,
        daylight,
        texture_filter,
        surface_from_below,
        sampler,
        crop: None,
    }
}

/// `outputs`: which of `rgb`, `depth` and `truth` are written (all three by default).
fn outputs(cx: &mut Cx, r: &mut Tab) -> Vec<String> {
    match r.get(F::Render::outputs) {
        None => vec!["rgb".to_string(), "depth".into(), "truth".into()],
        Some(n) => match &n.val {
            Val::Array(a) => {
                let mut out = Vec::new();
                for x in a {
                    match &x.val {
                        Val::Str(s) if ["rgb", "depth", "truth"].contains(&s.as_str()) => {
                            out.push(s.clone())
                        }
                        _ => {
                            let mut d = Diagnostic::error("E0221", "unknown output")
                                .label(x.span, "expected \"rgb\", \"depth\" or \"truth\"");
                            if let Val::Str(s) = &x.val
                                && let Some(m) =
                                    crate::scene::reader::did_you_mean(s, ["rgb", "depth", "truth"])
                            {
                                d = d.help(format!("did you mean `{m}`?"));
                            } else {
                                d = d.help("outputs = [\"rgb\", \"depth\", \"truth\"]");
                            }
                            cx.push(d);
                        }
                    }
                }
                out
            }
            v => {
                cx.push(crate::scene::reader::type_error(
                    n,
                    "render.outputs",
                    "a list of strings",
                    v,
                ));
                vec![]
            }
        },
    }
}

/// `noise` and `max_samples`: the native renderer's noise target (a relative error, or
/// "sensor"), checked against the pilot's `samples`.
fn noise_target(cx: &mut Cx, r: &mut Tab, samples: u32) -> Option<NoiseTarget> {
    let against_sensor = matches!(r.get(F::Render::noise), Some(n) if matches!(&n.val, Val::Str(s) if s == "sensor"));
    let word = match r.get(F::Render::noise) {
        Some(n) => match &n.val {
            Val::Str(s) if !against_sensor && !s.chars().any(|c| c.is_ascii_digit()) => {
                Some((s.clone(), n.span))
            }
            _ => None,
        },
        None => None,
    };
    let noise = if against_sensor {
        Some(1.0)
    } else if let Some((w, span)) = word {
        let mut d = Diagnostic::error("E0235", "`noise` takes a relative error or \"sensor\"")
            .label(span, format!("`{w}` is neither"));
        d = match crate::scene::reader::did_you_mean(&w, ["sensor"]) {
            Some(m) => d.help(format!("did you mean `\"{m}\"`?")),
            None => d.help("write e.g. `noise = \"2 %\"`, or `noise = \"sensor\"`"),
        };
        cx.push(d);
        None
    } else {
        r.opt_f64(cx, F::Render::noise, Dim::Fraction)
    };
    let max_samples = r.opt_u32(cx, F::Render::max_samples);
    let noise = match noise {
        Some(v) if !against_sensor && (v.is_nan() || v <= 0.0 || v >= 1.0) => {
            let sp = r.span_of(F::Render::noise);
            cx.push(
                Diagnostic::error("E0235", "`noise` must be a relative error in (0, 1)")
                    .label(sp, crate::scene::diag::num(v))
                    .help(
                        "write e.g. `noise = \"2 %\"` (each pixel's standard error ÷ its value), \
                         or `noise = \"sensor\"` (no more than the sensor's own noise)",
                    ),
            );
            None
        }
        Some(relative) => Some(NoiseTarget {
            relative,
            max_samples,
            against_sensor,
        }),
        None => {
            if max_samples.is_some() {
                let sp = r.span_of(F::Render::max_samples);
                cx.push(
                    Diagnostic::warning("W0236", "`max_samples` does nothing without `noise`")
                        .label(sp, "ignored")
                        .help("set a noise target, e.g. `noise = \"2 %\"`"),
                );
            }
            None
        }
    };
    if let (Some(t), Some(m)) = (noise, max_samples)
        && m < samples
    {
        let sp = r.span_of(F::Render::max_samples);
        cx.push(
            Diagnostic::error("E0237", "`max_samples` is below the pilot's `samples`")
                .label(sp, format!("{m} < {samples}"))
                .help(format!(
                    "raise it to at least {samples}, or lower `samples` (the pilot){}",
                    if t.against_sensor {
                        String::new()
                    } else {
                        format!(
                            " for a {} % target",
                            crate::scene::diag::num(100.0 * t.relative)
                        )
                    }
                )),
        );
    }
    noise
}

/// `daylight`, `texture_filter`, `surface_from_below` and `sampler`: the native renderer's
/// choices of estimator, of the sea surface's model and of its random numbers.
fn estimators(cx: &mut Cx, r: &mut Tab) -> (Daylight, TextureFilter, Underside, SamplerKind) {
    let daylight = match r.choice(cx, F::Render::daylight, &["auto", "column", "traced"]) {
        Some("column") => Daylight::Column,
        Some("traced") => Daylight::Traced,
        _ => Daylight::Auto,
    };
    let texture_filter = match r.choice(cx, F::Render::texture_filter, &["footprint", "point"]) {
        Some("point") => TextureFilter::Point,
        _ => TextureFilter::Footprint,
    };
    let underside = match r.choice(cx, F::Render::surface_from_below, &["fresnel", "open"]) {
        Some("open") => Underside::Open,
        _ => Underside::Fresnel,
    };
    let sampler = match r.choice(cx, F::Render::sampler, &["sobol", "independent"]) {
        Some("independent") => SamplerKind::Independent,
        _ => SamplerKind::Sobol,
    };
    (daylight, texture_filter, underside, sampler)
}
