//! Analytic radiometry: the closed-form radiance of a scene simple enough to have one, the
//! oracle the backends' images are checked against (`poser compare`, the canonical tests).
//!
//! | scene requirement | why |
//! |---|---|
//! | water, no scattering, no wavy surface | Beer–Lambert on straight legs is exact only without in-scattering and without caustics |
//! | exactly one object: a plane without pattern, no targets | a uniform Lambertian patch, nothing else in the light's or camera's way |
//! | one light: a spot (rig or world) and no sun, or the sun and no light | delta lights have a closed-form irradiance |
//! | the central window (a quarter of the width and height, centred) sees the patch, inside the spot's cone | |
//!
//! Radiance through pixel (u, v) of camera 0 at pose 0 (channel c):
//! `L = ρ/π · E · exp(−σa s) · T · (n_cam/n_w)²` with `E = I cosθ/d² · exp(−σa d)` for a spot at
//! distance d (or `E_w cosθw · exp(−σa·depth/cosθw)` for the refracted sun), `s` the water path
//! from the port to the patch, `T` the port's Fresnel transmittance along the camera ray and
//! `n_cam` the index around the entrance pupil (1 behind a port, `n_w` without one): the n² law
//! of radiance at the port (docs/render-conventions.md).

use super::LinearImage;
use crate::model::{LightKind, Model, Mount, Port, SeaSurface, Shape};

/// Why the scene has no analytic radiance, or `Ok` when it has one.
pub fn applies(model: &Model) -> Result<(), String> {
    if model.render.crop.is_some() {
        return Err("a cropped render (the oracle's window is the whole image's centre)".into());
    }
    let water = model
        .water
        .as_ref()
        .ok_or("no water (the oracle models Beer–Lambert legs in water)")?;
    if water.scattering.iter().any(|&s| s > 0.0) {
        return Err("scattering water (in-scattered light has no closed form)".into());
    }
    if matches!(model.site.surface, SeaSurface::Waves { .. }) && model.sun.is_some() {
        return Err("sun through waves (caustics)".into());
    }
    if model.objects.len() != 1 || !model.targets.is_empty() {
        return Err("more than one surface (the oracle has one Lambertian patch)".into());
    }
    let o = &model.objects[0];
    if !matches!(o.shape, Shape::Plane { .. }) || o.material.pattern.is_some() {
        return Err("the object is not a uniform plane".into());
    }
    match (&model.sun, model.lights.as_slice()) {
        (Some(_), []) => {}
        (None, [l]) if matches!(l.kind, LightKind::Spot { .. }) => {}
        _ => return Err("not a single spot light or the sun alone".into()),
    }
    let proj = model.projector(0, 1)?;
    let (x0, x1, y0, y1) = window(proj.width as usize, proj.height as usize);
    for (x, y) in [(x0, y0), (x1 - 1, y0), (x0, y1 - 1), (x1 - 1, y1 - 1)] {
        radiance(model, x as f64 + 0.5, y as f64 + 0.5, 1)
            .map_err(|e| format!("the central window: {e}"))?;
    }
    Ok(())
}

/// The central window: a quarter of the image's width and height, centred (x0, x1, y0, y1;
/// ends exclusive). 40×30 px of a 160×120 image.
pub fn window(width: usize, height: usize) -> (usize, usize, usize, usize) {
    let (w, h) = ((width / 4).max(1), (height / 4).max(1));
    let (cx, cy) = (width / 2, height / 2);
    (cx - w / 2, cx - w / 2 + w, cy - h / 2, cy - h / 2 + h)
}

/// Analytic radiance through pixel (u, v) of camera 0 at pose 0, channel `c`; an error when the
/// pixel does not see the patch lit by the light. Call [`applies`] first for the scene's
/// other requirements.
pub fn radiance(model: &Model, u: f64, v: f64, c: usize) -> Result<f64, String> {
    let proj = model.projector(0, c)?;
    let (o, d, t) = proj
        .pixel_ray_world(0, u, v)
        .map_err(|_| format!("pixel ({u}, {v}) has no ray through the port"))?;
    let obj = &model.objects[0];
    let n = obj.pose.rotation.z_axis;
    let s = (obj.pose.translation - o).dot(n) / d.dot(n);
    if s.is_nan() || s <= 0.0 {
        return Err("the patch is behind the camera".into());
    }
    let p = o + s * d;
    if let Shape::Plane { width, height } = obj.shape {
        let local = obj.pose.rotation.transpose() * (p - obj.pose.translation);
        let (hw, hh) = (0.5 * width * obj.scale.x, 0.5 * height * obj.scale.y);
        if local.x.abs() > hw || local.y.abs() > hh {
            return Err("a pixel misses the patch".into());
        }
    }
    let water = model.water.as_ref().ok_or("no water")?;
    let sa = water.absorption[c];
    let rho = obj.material.albedo[c];
    let e = if let (Some(sun), Some(dirs)) = (&model.sun, model.sun_directions_water()) {
        // Each channel's own refracted direction.
        let dz = -dirs[c].z;
        sun.irradiance_water[c] * dz * (-sa * (-p.z) / dz).exp()
    } else {
        let l = &model.lights[0];
        let LightKind::Spot {
            position,
            direction,
            half_angle,
            intensity,
        } = &l.kind
        else {
            return Err("the light is not a spot".into());
        };
        let (pos, axis) = match l.mount {
            Mount::Rig => (
                model.poses[0].world_from_rig.transform_point(*position),
                model.poses[0].world_from_rig.transform_vector(*direction),
            ),
            Mount::World => (*position, *direction),
        };
        let to_l = pos - p;
        let dl = to_l.length();
        if (-to_l / dl).dot(axis.normalize()) < half_angle.cos() {
            return Err("a pixel's patch point is outside the spot's cone".into());
        }
        intensity[c] * (to_l / dl).dot(n).max(0.0) / (dl * dl) * (-sa * dl).exp()
    };
    let n_cam = match model.cameras[0].port {
        Port::None => water.ior[c],
        _ => 1.0,
    };
    Ok(rho / std::f64::consts::PI * e * (-sa * s).exp() * t * (n_cam / water.ior[c]).powi(2))
}

/// Rendered / analytic − 1 per channel over the central [`window`] of `img` (pose 0, camera
/// 0), or why the scene has no analytic radiance.
pub fn window_error(model: &Model, img: &LinearImage) -> Result<[f64; 3], String> {
    applies(model)?;
    let (x0, x1, y0, y1) = window(img.width, img.height);
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let (mut got, mut want) = (0.0, 0.0);
        for y in y0..y1 {
            for x in x0..x1 {
                got += img.rgb[y * img.width + x][c] as f64;
                want += radiance(model, x as f64 + 0.5, y as f64 + 0.5, c)?;
            }
        }
        *o = got / want - 1.0;
    }
    Ok(out)
}
