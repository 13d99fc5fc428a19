//! `explain`: the resolved model's key numbers for a person — image count, GSD, footprint,
//! indices per channel, lateral colour, what will be modelled and why. A report on a
//! [`Model`] (read-only, no I/O), what `poser explain` prints and Python's `Scene.explain()`
//! returns; it owns no computation of its own beyond the nadir GSD, calling the planner's
//! footprint, the texture budget and the water column for the rest.
use crate::model::{Daylight, IorSource, LensModel, Model, Phase, Port, SeaSurface};
use crate::optics::project::Projector;
use std::fmt::Write;

/// Nadir GSD (m/px) of camera `c` at distance `h` through its port into water of index `n`.
fn gsd(m: &Model, c: usize, h: f64) -> f64 {
    let cam = &m.cameras[c];
    let mag = match (&cam.port, &m.water) {
        (Port::Flat { .. }, Some(w)) => w.ior[1],
        _ => 1.0,
    };
    h / (cam.fx * mag)
}

/// The text `poser explain` prints.
pub fn explain(m: &Model) -> String {
    let mut s = String::new();
    survey(&mut s, m);
    water(&mut s, m);
    cameras(&mut s, m);
    contents(&mut s, m);
    daylight(&mut s, m);

    if let Some(d) = &m.diver {
        let _ = writeln!(
            s,
            "diver: {:.2} m/s, SAC {:.1} l/min, GF {:.0}/{:.0}, {} cylinder{}",
            d.speed,
            d.sac * 60e3,
            d.gf_low * 100.0,
            d.gf_high * 100.0,
            d.cylinders.len(),
            if d.cylinders.len() == 1 { "" } else { "s" }
        );
    }
    s
}

/// The scene, its images and network, the path, and the site.
fn survey(s: &mut String, m: &Model) {
    let _ = writeln!(s, "scene {} ({})", m.name, m.source);
    if !m.description.is_empty() {
        let _ = writeln!(s, "  {}", m.description);
    }
    let images = m.poses.len() * m.cameras.len();
    let _ = writeln!(
        s,
        "images: {images} ({} rig pose{} × {} camera{}), network: {}",
        m.poses.len(),
        if m.poses.len() == 1 { "" } else { "s" },
        m.cameras.len(),
        if m.cameras.len() == 1 { "" } else { "s" },
        m.network.kind
    );
    if m.network.path_length > 0.0 || m.network.duration > 0.0 {
        let _ = writeln!(
            s,
            "path: {:.1} m at {:.2} m/s, {:.1} min{}",
            m.network.path_length,
            m.network.speed,
            m.network.duration / 60.0,
            if m.network.strips > 0 {
                format!(", {} strips", m.network.strips)
            } else {
                String::new()
            }
        );
    }
    let surface = match m.site.surface {
        SeaSurface::None => "not modelled".to_string(),
        SeaSurface::Flat => "flat".to_string(),
        SeaSurface::Waves {
            height,
            wavelength,
            wind_speed,
        } => {
            format!("waves {height} m high, {wavelength} m long, wind {wind_speed} m/s")
        }
    };
    let _ = writeln!(
        s,
        "site: seabed at {:.2} m, sea surface {surface}",
        m.site.depth
    );
}

/// The water's indices, absorption, scattering and phase function, and the sun.
fn water(s: &mut String, m: &Model) {
    match &m.water {
        None => {
            let _ = writeln!(s, "water: none (survey in air)");
        }
        Some(w) => {
            let src = match &w.ior_source {
                IorSource::Constant => "given as a constant".to_string(),
                IorSource::Seawater {
                    temperature,
                    salinity,
                    depth,
                } => {
                    format!("Quan–Fry at {temperature} °C, {salinity} PSU, {depth} m")
                }
            };
            let _ = writeln!(
                s,
                "water: n = [{:.5}, {:.5}, {:.5}] (R, G, B at 650/550/450 nm), {src}",
                w.ior[0], w.ior[1], w.ior[2]
            );
            let phase = match w.phase {
                Phase::HenyeyGreenstein { g } => format!("Henyey–Greenstein g = {g}"),
                Phase::FournierForand { n, mu, backscatter } => {
                    format!("Fournier–Forand n = {n}, μ = {mu} (backscatter {backscatter:.4})")
                }
            };
            let _ = writeln!(
                s,
                "       σa = [{:.4}, {:.4}, {:.4}] 1/m, σs = [{:.4}, {:.4}, {:.4}] 1/m{}, {phase}",
                w.absorption[0],
                w.absorption[1],
                w.absorption[2],
                w.scattering[0],
                w.scattering[1],
                w.scattering[2],
                w.jerlov
                    .as_ref()
                    .map(|j| format!(" (Jerlov {j})"))
                    .unwrap_or_default(),
            );
        }
    }
    if let Some(sun) = &m.sun {
        let _ = writeln!(
            s,
            "sun: elevation {:.1}°, azimuth {:.1}°, in water {:.1}° from vertical",
            sun.elevation.to_degrees(),
            sun.azimuth.to_degrees(),
            (-sun.direction_water.z)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        );
    }
}

/// Distance used for GSD: the network altitude, or the mean distance to the targets.
fn gsd_distance(m: &Model) -> Option<f64> {
    m.network.altitude.or_else(|| {
        let mut sum = 0.0;
        let mut n = 0usize;
        for p in &m.poses {
            for t in &m.targets {
                sum += (t.pose.translation - p.world_from_rig.translation).length();
                n += 1;
            }
        }
        (n > 0).then(|| sum / n as f64)
    })
}

/// One camera's port, in words.
fn port_text(port: &Port) -> String {
    match port {
        Port::None => "none".to_string(),
        Port::Flat {
            distance,
            thickness,
            glass,
            normal,
            outer_layers,
        } => {
            let mut s = format!(
                "flat {} {:.1} mm thick, {:.1} mm from the pupil, tilt {:.2}°, n = [{:.4}, {:.4}, {:.4}]",
                glass.name,
                thickness * 1e3,
                distance * 1e3,
                normal.z.clamp(-1.0, 1.0).acos().to_degrees(),
                glass.ior[0],
                glass.ior[1],
                glass.ior[2]
            );
            for l in outer_layers {
                s.push_str(&format!(
                    "; then {} {:.1} mm, n = [{:.4}, {:.4}, {:.4}]",
                    l.glass.name,
                    l.thickness * 1e3,
                    l.glass.ior[0],
                    l.glass.ior[1],
                    l.glass.ior[2]
                ));
            }
            s
        }
        Port::Dome {
            center,
            inner_radius,
            thickness,
            glass,
        } => format!(
            "dome {} r = {:.1} mm, {:.1} mm thick, decentred {:.2} mm, n = [{:.4}, {:.4}, {:.4}]",
            glass.name,
            inner_radius * 1e3,
            thickness * 1e3,
            center.length() * 1e3,
            glass.ior[0],
            glass.ior[1],
            glass.ior[2]
        ),
        Port::Cylinder {
            inner_radius,
            thickness,
            glass,
            ..
        } => format!(
            "cylinder {} r = {:.1} mm, {:.1} mm thick, n = [{:.4}, {:.4}, {:.4}]",
            glass.name,
            inner_radius * 1e3,
            thickness * 1e3,
            glass.ior[0],
            glass.ior[1],
            glass.ior[2]
        ),
    }
}

/// Each camera: sensor, lens, port, and the GSD and footprint at the survey distance.
fn cameras(s: &mut String, m: &Model) {
    let dist = gsd_distance(m);
    for (i, c) in m.cameras.iter().enumerate() {
        let _ = writeln!(
            s,
            "camera {}: {}×{} px, f = {:.2} mm ({:.1} px), pitch {:.2} µm, {}",
            c.name,
            c.width,
            c.height,
            c.focal_length * 1e3,
            c.fx,
            c.pixel_pitch * 1e6,
            match c.lens {
                LensModel::Rectilinear => "rectilinear",
                LensModel::FisheyeEquidistant => "fisheye (equidistant)",
                LensModel::FisheyeEquisolid => "fisheye (equisolid)",
            }
        );
        let port = port_text(&c.port);
        let _ = writeln!(s, "  port: {port}");
        if let Some(h) = dist {
            let g = gsd(m, i, h);
            // The footprint through the exact port (the paraxial g·width overstates it for a
            // wide lens behind a flat port); the paraxial value where no ray reaches the bed.
            let (fw, fh) = Projector::for_camera(c, 1, m.ambient_ior()[1])
                .ok()
                .and_then(|pr| crate::plan::network::footprint_exact(&pr, h))
                .unwrap_or((g * c.width as f64, g * c.height as f64));
            let _ = writeln!(
                s,
                "  at {:.2} m: GSD {:.2} mm/px at the centre, footprint {:.2} × {:.2} m",
                h,
                g * 1e3,
                fw,
                fh
            );
        }
    }
}

/// Overlap, targets, objects and lights, texture budgets, lateral colour, and what will be
/// modelled.
fn contents(s: &mut String, m: &Model) {
    if let Some(o) = m.network.overlap {
        let _ = writeln!(
            s,
            "overlap {:.0} %, side-lap {:.0} %",
            o * 100.0,
            m.network.sidelap.unwrap_or(0.0) * 100.0
        );
    }
    let _ = writeln!(
        s,
        "targets: {} ({} known points); objects: {}; lights: {}",
        m.targets.len(),
        m.targets.iter().map(|t| t.points.len()).sum::<usize>(),
        m.objects.len(),
        m.lights.len()
    );
    for i in 0..m.objects.len() {
        mesh_extent(s, m, i);
        match crate::texture::mapped::plan_object(m, i) {
            Ok(Some(p)) => {
                for (k, line) in p.lines().into_iter().enumerate() {
                    if k == 0 {
                        let _ = writeln!(s, "textured mesh `{}`: {line}", m.objects[i].name);
                    } else {
                        let _ = writeln!(s, "{line}");
                    }
                }
                continue;
            }
            Ok(None) => {}
            Err(e) => {
                let _ = writeln!(s, "textured mesh `{}`: {e}", m.objects[i].name);
                continue;
            }
        }
        match crate::texture::bake::plan(m, i) {
            Ok(Some(t)) => {
                let _ = writeln!(s, "texture of `{}`: {t}", m.objects[i].name);
            }
            Ok(None) => {}
            Err(e) => {
                let _ = writeln!(s, "texture of `{}`: {e}", m.objects[i].name);
            }
        }
    }
    let _ = writeln!(
        s,
        "lateral colour (R–B) at the corners: {:.3} px",
        m.needs.lateral_color_px
    );
    let _ = writeln!(s, "will be modelled:");
    for r in &m.needs.reasons {
        let _ = writeln!(s, "  - {r}");
    }
}

/// For a mesh object, the size of its bounding box in metres (after `offset`, up axis and
/// scale: the object frame, before rotation) and where its centre lands in the scene.
fn mesh_extent(s: &mut String, m: &Model, i: usize) {
    let o = &m.objects[i];
    if !matches!(o.shape, crate::model::Shape::Mesh { .. }) {
        return;
    }
    let base = std::path::Path::new(&m.source)
        .parent()
        .unwrap_or(std::path::Path::new("."));
    match crate::geometry::mesh::shape_mesh(&o.shape, base).map(|l| l.bounds()) {
        Ok(Some((lo, hi))) => {
            let (a, b) = (lo * o.scale, hi * o.scale);
            let size = (b - a).abs();
            let c = o.pose.transform_point(0.5 * (a + b));
            let _ = writeln!(
                s,
                "mesh `{}`: extent {:.3} × {:.3} × {:.3} m (x × y × z after offset, up axis and scale), centre at ({:.3}, {:.3}, {:.3}) m",
                o.name, size.x, size.y, size.z, c.x, c.y, c.z
            );
        }
        Ok(None) => {}
        Err(e) => {
            let _ = writeln!(s, "mesh `{}`: {e}", o.name);
        }
    }
}

/// The share of the cameras' view that hits no object under water: it looks past the scene's
/// objects (a seabed patch smaller than the network's footprint, an oblique view over its edge)
/// into water without a bottom. The solved column lights that water as if the seabed went on at
/// the site's depth, traced daylight leaves it bottomless: where the share is not zero the two
/// estimators differ (docs/column.md, "Views past the seabed").
fn bottomless(s: &mut String, past: Option<f64>) {
    let Some(past) = past else {
        return;
    };
    if past > 0.0 {
        let _ = writeln!(
            s,
            "  {:.2} % of the cameras' view (16 × 12 rays through up to 64 images) looks down past \
             every object into water without a bottom, which the column lights as if \
             the seabed went on at the site's depth and traced daylight leaves bottomless (help: \
             widen the seabed past the network's footprint, or add one)",
            100.0 * past
        );
    }
}

/// Daylight in the native renderer: the water column, or traced, and why.
fn daylight(s: &mut String, m: &Model) {
    let past = crate::geometry::seen::views_past_seabed(m);
    let (column, why) = m.daylight_choice(past);
    let _ = writeln!(s, "daylight (native): {why}");
    if let Some(input) = &column {
        match crate::optics::column::solve(input) {
            Ok(col) => {
                for line in crate::column::summary(&col) {
                    let _ = writeln!(s, "{line}");
                }
            }
            Err(e) => {
                let _ = writeln!(s, "  the column cannot be solved: {e}; daylight is traced");
            }
        }
    }
    // Under "auto" the choice above already names views past the seabed.
    if m.column_input().is_ok() && (column.is_some() || m.render.daylight == Daylight::Traced) {
        bottomless(s, past);
    }
    if let Some(gain) = m.surface_reflection_gain() {
        let gain = gain
            .map(|g| g.map_or("black".into(), |g| format!("{:+.1} %", g * 100.0)))
            .join(" / ");
        let _ = if m.underside() == crate::optics::column::Top::Open {
            writeln!(
                s,
                "  the sea surface is open from below (render.surface_from_below = \"open\"): \
                 reflecting the light that comes up (Fresnel, total beyond the critical angle), \
                 with the sky through Snell's window, would change E_d at the seabed by {gain} (R / G / B)"
            )
        } else {
            writeln!(
                s,
                "  the sea surface reflects the light that comes up (Fresnel, total beyond the \
                 critical angle) and shows the sky through Snell's window: E_d at the seabed \
                 differs by {gain} (R / G / B) from the open surface of Mitsuba and Cycles"
            )
        };
    }
    if column.is_none() && m.water.is_some() {
        // What the bounce limit leaves out of the traced daylight (W0239, docs/column.md).
        let b = m.render.max_bounces;
        match m.bounce_cut() {
            Some(cut) => {
                let _ = writeln!(
                    s,
                    "  traced daylight ends paths after render.bounces = {b} scatterings: \
                     cuts off {} of the daylight the cameras see (R / G / B){}",
                    cut.shares_text(),
                    match cut.needed {
                        Some(n) if n > b => format!("; {n} bounces cut off ≤ 1 %"),
                        Some(_) => String::new(),
                        None => "; more than 254 bounces would be needed".into(),
                    }
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "  traced daylight ends paths after render.bounces = {b} scatterings \
                     (the water is not a column: what the limit cuts off is not measured)"
                );
            }
        }
    }
}
