//! Validation of a built [`Model`]: one pass over the structure that checks what every back end
//! relies on, wherever the model came from (the front end, a model built in Rust by the bench,
//! the Python module or a test), as naga's `valid/` checks a module whichever front end made it.
//!
//! The front end reports a bad scene as a located diagnostic long before this pass (a span, a
//! caret, a `help:` line). This pass has no source to point into: it names the offending value
//! by its path in the model (`cameras[0].port.thickness`), and finds every problem, not only the
//! first. [`crate::Model::validate`] runs it; the back ends run it before they compile or
//! render.
//!
//! | checked | rule |
//! |---|---|
//! | every number a back end reads | finite (no NaN, no ±∞) |
//! | poses (rig, camera on the rig, lights' frames, objects, targets) | rotation orthonormal and right-handed (within 1e-6) |
//! | cameras | `width`, `height` ≥ 1; `fx`, `fy`, `pixel_pitch`, `focal_length` > 0 |
//! | ports | glass and layer thicknesses > 0, radii > 0, axis and normal unit vectors, glass index ≥ 1 |
//! | water | index ≥ 1, absorption and scattering ≥ 0, phase parameters in range |
//! | sun, lights | unit directions, irradiance, intensity and radiance ≥ 0, sizes > 0, cone half-angle in (0, π/2] |
//! | objects | sizes and scale > 0, albedo ≥ 0, a glass object's index ≥ 1, a glass object a box, a uniformly scaled sphere or a round cylinder |
//! | targets | sizes > 0, at least one row and column |
//! | render | `samples` ≥ 1, `exposure` > 0, a noise target > 0, a crop inside every camera's image |

use crate::{Light, LightKind, Model, Object, Phase, Port, Pose, Rgb, Shape, Target, TargetKind};
use glam::DVec3;

/// How far a rotation may be from orthonormal, or a direction from unit length.
const TOLERANCE: f64 = 1e-6;

/// One value of the model that breaks a rule: where (its path in the model) and what.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub path: String,
    pub message: String,
}

/// Every problem of a model that is not valid.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    pub problems: Vec<Problem>,
}

impl std::fmt::Display for Invalid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the model is not valid:")?;
        for p in &self.problems {
            write!(f, "\n  {}: {}", p.path, p.message)?;
        }
        Ok(())
    }
}

impl std::error::Error for Invalid {}

/// Checks `model` (see the module's table).
pub fn validate(model: &Model) -> Result<(), Invalid> {
    let mut c = Checker::default();
    for (i, cam) in model.cameras.iter().enumerate() {
        camera(&mut c, &format!("cameras[{i}]"), cam);
    }
    if let Some(w) = &model.water {
        water(&mut c, w);
    }
    c.finite("site.depth", model.site.depth);
    c.finite("site.altitude", model.site.altitude);
    if let Some(sun) = &model.sun {
        c.finite("sun.elevation", sun.elevation);
        c.finite("sun.azimuth", sun.azimuth);
        c.non_negative_rgb("sun.irradiance", sun.irradiance);
        c.non_negative_rgb("sun.irradiance_water", sun.irradiance_water);
        c.unit("sun.direction_air", sun.direction_air);
        c.unit("sun.direction_water", sun.direction_water);
    }
    for (i, l) in model.lights.iter().enumerate() {
        light(&mut c, &format!("lights[{i}]"), l);
    }
    for (i, o) in model.objects.iter().enumerate() {
        object(&mut c, &format!("objects[{i}]"), o);
    }
    for (i, t) in model.targets.iter().enumerate() {
        target(&mut c, &format!("targets[{i}]"), t);
    }
    for (i, p) in model.poses.iter().enumerate() {
        c.pose(&format!("poses[{i}].world_from_rig"), &p.world_from_rig);
        c.finite(&format!("poses[{i}].time"), p.time);
    }
    if !model.poses.is_empty() && model.cameras.is_empty() {
        c.push(
            "cameras",
            "poses are given but no camera takes their images".into(),
        );
    }
    let r = &model.render;
    if r.samples == 0 {
        c.push("render.samples", "must be at least 1".into());
    }
    c.positive("render.exposure", r.exposure);
    if let Some(d) = r.denoise_radius {
        c.positive("render.denoise_radius", d);
    }
    if let Some(n) = &r.noise {
        c.positive("render.noise.relative", n.relative);
    }
    if let Some(k) = r.crop {
        for (i, cam) in model.cameras.iter().enumerate() {
            if !k.fits(cam.width, cam.height) {
                c.push(
                    "render.crop",
                    format!(
                        "{}×{} px at ({}, {}) is not a non-empty part of cameras[{i}]'s {}×{} image",
                        k.width, k.height, k.x, k.y, cam.width, cam.height
                    ),
                );
            }
        }
    }
    if c.problems.is_empty() {
        Ok(())
    } else {
        Err(Invalid {
            problems: c.problems,
        })
    }
}

fn camera(c: &mut Checker, at: &str, cam: &crate::Camera) {
    if cam.width == 0 || cam.height == 0 {
        c.push(
            &format!("{at}.width"),
            format!("the image is {}×{} pixels", cam.width, cam.height),
        );
    }
    for (key, v) in [
        ("fx", cam.fx),
        ("fy", cam.fy),
        ("pixel_pitch", cam.pixel_pitch),
        ("focal_length", cam.focal_length),
    ] {
        c.positive(&format!("{at}.{key}"), v);
    }
    c.finite(&format!("{at}.cx"), cam.cx);
    c.finite(&format!("{at}.cy"), cam.cy);
    let d = &cam.distortion;
    for (key, v) in [
        ("k1", d.k1),
        ("k2", d.k2),
        ("k3", d.k3),
        ("p1", d.p1),
        ("p2", d.p2),
    ] {
        c.finite(&format!("{at}.distortion.{key}"), v);
    }
    for (key, v) in [
        ("focus_distance", cam.focus_distance),
        ("f_number", cam.f_number),
    ] {
        if let Some(v) = v {
            c.positive(&format!("{at}.{key}"), v);
        }
    }
    c.pose(&format!("{at}.rig_from_camera"), &cam.rig_from_camera);
    port(c, &format!("{at}.port"), &cam.port);
}

fn port(c: &mut Checker, at: &str, port: &Port) {
    match port {
        Port::None => return,
        Port::Flat {
            normal,
            distance,
            thickness,
            outer_layers,
            ..
        } => {
            c.unit(&format!("{at}.normal"), *normal);
            c.non_negative(&format!("{at}.distance"), *distance);
            c.positive(&format!("{at}.thickness"), *thickness);
            for (i, l) in outer_layers.iter().enumerate() {
                c.positive(&format!("{at}.outer_layers[{i}].thickness"), l.thickness);
                c.index(&format!("{at}.outer_layers[{i}].glass.ior"), l.glass.ior);
            }
        }
        Port::Dome {
            center,
            inner_radius,
            thickness,
            ..
        } => {
            c.finite_vec(&format!("{at}.center"), *center);
            c.positive(&format!("{at}.inner_radius"), *inner_radius);
            c.positive(&format!("{at}.thickness"), *thickness);
        }
        Port::Cylinder {
            axis_point,
            axis,
            inner_radius,
            thickness,
            ..
        } => {
            c.finite_vec(&format!("{at}.axis_point"), *axis_point);
            c.unit(&format!("{at}.axis"), *axis);
            c.positive(&format!("{at}.inner_radius"), *inner_radius);
            c.positive(&format!("{at}.thickness"), *thickness);
        }
    }
    if let Some(g) = port.glass() {
        c.index(&format!("{at}.glass.ior"), g.ior);
    }
}

fn water(c: &mut Checker, w: &crate::Water) {
    c.index("water.ior", w.ior);
    c.non_negative_rgb("water.absorption", w.absorption);
    c.non_negative_rgb("water.scattering", w.scattering);
    match w.phase {
        Phase::HenyeyGreenstein { g } => {
            if !(g.abs() < 1.0) {
                c.push("water.phase.g", format!("must be in (−1, 1), is {g}"));
            }
        }
        Phase::FournierForand { n, mu, .. } => {
            if !(n > 1.0 && n.is_finite()) {
                c.push("water.phase.n", format!("must be > 1, is {n}"));
            }
            if !(mu > 3.0 && mu <= 5.0) {
                c.push("water.phase.mu", format!("must be in (3, 5], is {mu}"));
            }
        }
    }
}

fn light(c: &mut Checker, at: &str, l: &Light) {
    match &l.kind {
        LightKind::Point {
            position,
            intensity,
        } => {
            c.finite_vec(&format!("{at}.position"), *position);
            c.non_negative_rgb(&format!("{at}.intensity"), *intensity);
        }
        LightKind::Spot {
            position,
            direction,
            half_angle,
            intensity,
        } => {
            c.finite_vec(&format!("{at}.position"), *position);
            c.unit(&format!("{at}.direction"), *direction);
            if !(*half_angle > 0.0 && *half_angle <= std::f64::consts::FRAC_PI_2) {
                c.push(
                    &format!("{at}.half_angle"),
                    format!("must be in (0, π/2] rad, is {half_angle}"),
                );
            }
            c.non_negative_rgb(&format!("{at}.intensity"), *intensity);
        }
        LightKind::Area {
            frame,
            width,
            height,
            radiance,
        } => {
            c.pose(&format!("{at}.frame"), frame);
            c.positive(&format!("{at}.width"), *width);
            c.positive(&format!("{at}.height"), *height);
            c.non_negative_rgb(&format!("{at}.radiance"), *radiance);
        }
        LightKind::Ambient { radiance } => c.non_negative_rgb(&format!("{at}.radiance"), *radiance),
    }
}

fn object(c: &mut Checker, at: &str, o: &Object) {
    c.pose(&format!("{at}.pose"), &o.pose);
    for (axis, v) in ["x", "y", "z"].into_iter().zip(o.scale.to_array()) {
        c.positive(&format!("{at}.scale.{axis}"), v);
    }
    c.non_negative_rgb(&format!("{at}.material.albedo"), o.material.albedo);
    if let Some(g) = &o.material.glass {
        c.index(&format!("{at}.material.glass.ior"), g.ior);
        match o.shape {
            Shape::Box { .. } => {}
            // The back ends' exact spheres (Mitsuba's `sphere`) take no other scale.
            Shape::Sphere { .. } if o.scale.max_element() > o.scale.min_element() => c.push(
                &format!("{at}.scale"),
                format!("a glass sphere must be scaled uniformly (got {})", o.scale),
            ),
            Shape::Cylinder { .. } if o.scale.x != o.scale.y => c.push(
                &format!("{at}.scale"),
                format!(
                    "a glass cylinder must be scaled alike on x and y (got {})",
                    o.scale
                ),
            ),
            Shape::Sphere { .. } | Shape::Cylinder { .. } => {}
            _ => c.push(
                &format!("{at}.shape"),
                "a glass object must be a box, a sphere or a cylinder".into(),
            ),
        }
    }
    let sizes: Vec<(&str, f64)> = match &o.shape {
        Shape::Mesh { offset, .. } => {
            c.finite_vec(&format!("{at}.shape.offset"), *offset);
            vec![]
        }
        Shape::Plane { width, height } => vec![("width", *width), ("height", *height)],
        Shape::Box { size } => vec![("size.x", size.x), ("size.y", size.y), ("size.z", size.z)],
        Shape::Sphere { radius } | Shape::Coral { radius, .. } => vec![("radius", *radius)],
        Shape::Cylinder { radius, height } => vec![("radius", *radius), ("height", *height)],
        Shape::Seabed {
            width,
            length,
            roughness,
            resolution,
            relief,
            ..
        } => {
            c.non_negative(&format!("{at}.shape.roughness"), *roughness);
            for (k, p) in relief.iter().enumerate() {
                c.finite_vec(&format!("{at}.shape.relief[{k}]"), *p);
            }
            vec![
                ("width", *width),
                ("length", *length),
                ("resolution", *resolution),
            ]
        }
        Shape::Boulders {
            width,
            length,
            radius,
            ..
        } => vec![("width", *width), ("length", *length), ("radius", *radius)],
    };
    for (key, v) in sizes {
        c.positive(&format!("{at}.shape.{key}"), v);
    }
}

fn target(c: &mut Checker, at: &str, t: &Target) {
    c.pose(&format!("{at}.pose"), &t.pose);
    for (i, p) in t.points.iter().enumerate() {
        c.finite_vec(&format!("{at}.points[{i}]"), p.world);
    }
    // (key, size that must be > 0), (key, count that must be ≥ 1).
    type Checks = (Vec<(&'static str, f64)>, Vec<(&'static str, u32)>);
    let (sizes, counts): Checks = match t.kind {
        TargetKind::Checkerboard { cols, rows, square } => (
            vec![("square", square)],
            vec![("cols", cols), ("rows", rows)],
        ),
        TargetKind::CircleGrid {
            cols,
            rows,
            spacing,
            diameter,
        } => (
            vec![("spacing", spacing), ("diameter", diameter)],
            vec![("cols", cols), ("rows", rows)],
        ),
        TargetKind::Coded {
            spacing, diameter, ..
        } => (vec![("spacing", spacing), ("diameter", diameter)], vec![]),
        TargetKind::ScaleBar {
            length,
            width,
            diameter,
        } => (
            vec![("length", length), ("width", width), ("diameter", diameter)],
            vec![],
        ),
        TargetKind::SiemensStar { diameter, spokes } => {
            (vec![("diameter", diameter)], vec![("spokes", spokes)])
        }
        TargetKind::Disk { diameter } => (vec![("diameter", diameter)], vec![]),
        TargetKind::TestObject {
            size,
            levels,
            step,
            diameter,
        } => (
            vec![("size", size), ("step", step), ("diameter", diameter)],
            vec![("levels", levels)],
        ),
    };
    for (key, v) in sizes {
        c.positive(&format!("{at}.kind.{key}"), v);
    }
    for (key, n) in counts {
        if n == 0 {
            c.push(&format!("{at}.kind.{key}"), "must be at least 1".into());
        }
    }
}

/// Collects the problems of one pass.
#[derive(Default)]
struct Checker {
    problems: Vec<Problem>,
}

impl Checker {
    fn push(&mut self, path: &str, message: String) {
        self.problems.push(Problem {
            path: path.to_string(),
            message,
        });
    }

    fn finite(&mut self, path: &str, v: f64) {
        if !v.is_finite() {
            self.push(path, format!("must be finite, is {v}"));
        }
    }

    fn positive(&mut self, path: &str, v: f64) {
        if !(v > 0.0 && v.is_finite()) {
            self.push(path, format!("must be finite and > 0, is {v}"));
        }
    }

    fn non_negative(&mut self, path: &str, v: f64) {
        if !(v >= 0.0 && v.is_finite()) {
            self.push(path, format!("must be finite and ≥ 0, is {v}"));
        }
    }

    fn non_negative_rgb(&mut self, path: &str, v: Rgb) {
        if !v.iter().all(|x| *x >= 0.0 && x.is_finite()) {
            self.push(
                path,
                format!("must be finite and ≥ 0 per channel, is {v:?}"),
            );
        }
    }

    /// A refractive index per channel: finite and ≥ 1.
    fn index(&mut self, path: &str, v: Rgb) {
        if !v.iter().all(|x| *x >= 1.0 && x.is_finite()) {
            self.push(
                path,
                format!("must be finite and ≥ 1 per channel, is {v:?}"),
            );
        }
    }

    fn finite_vec(&mut self, path: &str, v: DVec3) {
        if !v.is_finite() {
            self.push(path, format!("must be finite, is {v}"));
        }
    }

    fn unit(&mut self, path: &str, v: DVec3) {
        if !v.is_finite() || (v.length() - 1.0).abs() > TOLERANCE {
            self.push(path, format!("must be a unit vector, is {v}"));
        }
    }

    fn pose(&mut self, path: &str, p: &Pose) {
        self.finite_vec(&format!("{path}.translation"), p.translation);
        let r = p.rotation;
        let off = (r.transpose() * r - glam::DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        // `!(… <= …)` also catches NaN.
        if !(off <= TOLERANCE) || !((r.determinant() - 1.0).abs() <= TOLERANCE) {
            self.push(
                &format!("{path}.rotation"),
                format!(
                    "must be a rotation (orthonormal, determinant 1), is {:?}",
                    r.to_cols_array()
                ),
            );
        }
    }
}
