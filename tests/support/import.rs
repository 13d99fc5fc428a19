//! Comparing a model with the one `poser import` gives back (the import round trips).

use poser::model::Model;
use serde_json::Value;
use std::path::Path;

/// The round trips compile at this fraction of the cameras' resolution (`poser compile
/// --scale`): the poses, intrinsics, water and lights they compare are the same at any size,
/// and the textures baked for the coarser pixels are 1/100 of the texels (a full-size
/// dome_orbit bakes a 45 MB sand texture).
pub const ROUND_TRIP_SCALE: f64 = 0.05;

/// Rig poses a round trip compiles, spread over the network (the first always among them): the
/// poses, intrinsics, water and lights it compares are per view, and a shipped survey's
/// thousands of views (2 180 in paper_survey, 891 water shape keys in a deformation lesson's
/// Blender scene) only repeat them.
pub const ROUND_TRIP_POSES: usize = 6;

/// Texel (m) of the textures a round trip bakes, at least: the poses, intrinsics, water and
/// lights it compares do not depend on it, and at [`ROUND_TRIP_SCALE`] the planned texel
/// (half the finest GSD) still made baking (the `noise` pattern's value noise) and the
/// importer's 16-bit re-encoding of each texel most of a round trip's time.
pub const ROUND_TRIP_TEXEL: f64 = 0.05;

/// Load `scene`, scale its cameras by [`ROUND_TRIP_SCALE`], keep [`ROUND_TRIP_POSES`] of its
/// rig poses, coarsen its baked textures to [`ROUND_TRIP_TEXEL`] and compile that model for
/// `backend` into `out` (the library's `Backend::compile`, which `poser compile` calls); the
/// compiled model, or why the backend refused the scene.
pub fn load_and_compile(scene: &Path, backend: &str, out: &Path) -> Result<Model, String> {
    let mut model = poser::scene::load(scene, &[])
        .map_err(|e| e.render())
        .expect("a shipped scene loads")
        .model
        .with_resolution_scale(ROUND_TRIP_SCALE);
    let step = model.poses.len().div_ceil(ROUND_TRIP_POSES).max(1);
    model.poses = model.poses.iter().step_by(step).cloned().collect();
    // Baked textures at a coarse texel: the comparison reads none of their texels, and the
    // import still reads (and re-encodes) every texture file the compile wrote.
    for o in &mut model.objects {
        if o.material.is_baked() {
            o.material.texel = Some(o.material.texel.unwrap_or(0.0).max(ROUND_TRIP_TEXEL));
        }
    }
    let backend = poser::backend::Backend::parse(backend).expect("a backend name");
    match backend.compile(&model, out) {
        Ok(()) => Ok(model),
        Err(why) => Err(format!("refused by the {backend} backend: {}", why.trim())),
    }
}

/// Numbers of `a` and `b` (JSON of model parts) agree within `rel` relative (1e-12 absolute).
pub fn close(a: &Value, b: &Value, rel: f64, path: &str) -> Result<(), String> {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() <= 1e-12 + rel * x.abs().max(y.abs()) {
                Ok(())
            } else {
                Err(format!("{path}: {x} vs {y}"))
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .try_for_each(|(i, (p, q))| close(p, q, rel, &format!("{path}[{i}]"))),
        (Value::Object(x), Value::Object(y)) => x.iter().try_for_each(|(k, v)| match y.get(k) {
            Some(w) => close(v, w, rel, &format!("{path}.{k}")),
            None => Err(format!("{path}.{k} missing")),
        }),
        _ if a == b => Ok(()),
        _ => Err(format!("{path}: {a} vs {b}")),
    }
}

fn json<T: serde::Serialize>(v: &T) -> Value {
    serde_json::to_value(v).unwrap()
}

/// `back` (imported) against `model` (the original): every camera's world pose at each of
/// `views` (original pose index, camera name; `back`'s poses are the views' in order, one per
/// rig pose) to 1e-9, the intrinsics to 1e-12, the water, the lights in the world at the first
/// view's pose and the sun to 1e-9 relative.
pub fn same_model(model: &Model, back: &Model, views: &[(usize, String)]) -> Result<(), String> {
    let n_cams = model.cameras.len();
    // Poses: world_from_camera of every imported view (the imported rig's frame may differ).
    if back.poses.len() * n_cams != views.len() || back.cameras.len() != n_cams {
        return Err(format!(
            "{} poses × {} cameras for {} views",
            back.poses.len(),
            back.cameras.len(),
            views.len()
        ));
    }
    let index = |m: &Model, name: &str| m.cameras.iter().position(|c| c.name == name).unwrap();
    for (k, (p, name)) in views.iter().enumerate() {
        let (p, name) = (*p, name.as_str());
        let (a, b) = (
            model.world_from_camera(p, index(model, name)),
            back.world_from_camera(k / n_cams, if n_cams == 1 { 0 } else { index(back, name) }),
        );
        let dr = (a.rotation - b.rotation)
            .to_cols_array()
            .iter()
            .map(|x| x.abs())
            .fold(0.0, f64::max);
        let dt = (a.translation - b.translation).length();
        if dr > 1e-9 || dt > 1e-9 {
            return Err(format!(
                "pose {p}, camera {name}: rotation off by {dr:e}, centre by {dt:e} m"
            ));
        }
    }
    // Intrinsics, camera by camera.
    for c in &model.cameras {
        let d = if n_cams == 1 {
            &back.cameras[0]
        } else {
            &back.cameras[index(back, &c.name)]
        };
        if (c.width, c.height) != (d.width, d.height) {
            return Err("image size differs".into());
        }
        for (what, x, y) in [
            ("fx", c.fx, d.fx),
            ("fy", c.fy, d.fy),
            ("cx", c.cx, d.cx),
            ("cy", c.cy, d.cy),
        ] {
            if (x - y).abs() > 1e-12 * x.abs().max(1.0) {
                return Err(format!("{}: {what}: {x} vs {y}", c.name));
            }
        }
    }
    // Water.
    match (&model.water, &back.water) {
        (None, None) => {}
        (Some(w), Some(v)) => {
            close(
                &json(&w.absorption),
                &json(&v.absorption),
                1e-9,
                "absorption",
            )?;
            close(
                &json(&w.scattering),
                &json(&v.scattering),
                1e-9,
                "scattering",
            )?;
            if let (
                poser::model::Phase::HenyeyGreenstein { g },
                poser::model::Phase::HenyeyGreenstein { g: h },
            ) = (&w.phase, &v.phase)
                && (g - h).abs() > 1e-9
            {
                return Err(format!("g: {g} vs {h}"));
            }
        }
        _ => return Err("water present in one model only".into()),
    }
    // Lights, by name, in the world at the first imported pose (rig frames may differ).
    let p0 = views[0].0;
    let mut a: Vec<_> = model
        .lights
        .iter()
        .map(|l| {
            (
                l.name.clone(),
                json(&l.in_world(&model.poses[p0].world_from_rig)),
            )
        })
        .collect();
    let mut b: Vec<_> = back
        .lights
        .iter()
        .map(|l| {
            (
                l.name.clone(),
                json(&l.in_world(&back.poses[0].world_from_rig)),
            )
        })
        .collect();
    a.sort_by(|x, y| x.0.cmp(&y.0));
    b.sort_by(|x, y| x.0.cmp(&y.0));
    if a.iter().map(|x| &x.0).ne(b.iter().map(|x| &x.0)) {
        return Err(format!(
            "lights {:?} vs {:?}",
            a.iter().map(|x| &x.0).collect::<Vec<_>>(),
            b.iter().map(|x| &x.0).collect::<Vec<_>>()
        ));
    }
    for ((n, x), (_, y)) in a.iter().zip(&b) {
        close(x, y, 1e-9, &format!("light {n}"))?;
    }
    // The sun as Mitsuba sees it: its direction and irradiance in the water.
    match (&model.sun, &back.sun) {
        (None, None) => {}
        (Some(s), Some(t)) => {
            close(
                &json(&s.direction_water),
                &json(&t.direction_water),
                1e-9,
                "sun direction",
            )?;
            close(
                &json(&s.irradiance_water),
                &json(&t.irradiance_water),
                1e-9,
                "sun irradiance",
            )?;
        }
        _ => return Err("sun present in one model only".into()),
    }
    Ok(())
}
