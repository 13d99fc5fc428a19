//! Camera networks: expand a network description (explicit poses, lawnmower with optional
//! cross strips, planar spiral, orbit/spherical spiral) into rig poses along a swim path.
//!
//! | parameter | unit | default | meaning |
//! |---|---|---|---|
//! | `altitude` | m | — | camera height above the nominal seabed (or derived from `gsd`) |
//! | `gsd` | m/px | — | ground sampling distance wanted at nadir, through the port |
//! | `overlap` | fraction | 0.8 | forward overlap between consecutive images |
//! | `sidelap` | fraction | 0.6 | overlap between neighbouring strips |
//! | `trigger` | — | overlap | exposures by distance (m), time (s) or from `overlap` |
//! | `tilt` | rad | 0 | oblique tilt forward from nadir |
//! | `obliques` | rad | none | a second pass over the same strips, tilted forward by this angle |

use crate::model::{NetworkSummary, Pose, RigPose};
use crate::optics::project::Projector;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// A hand-held camera's wobble about the planned poses (σ per axis, m; σ of a rotation about a
/// random axis, rad), seeded.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Jitter {
    pub position: f64,
    pub rotation: f64,
    pub seed: u64,
}

/// Apply `j` to every pose: pose `i` draws from its own stream seeded by `(seed, i)`, so a pose
/// keeps its wobble when the network grows.
pub fn jitter(poses: &mut [RigPose], j: &Jitter) {
    if j.position == 0.0 && j.rotation == 0.0 {
        return;
    }
    let gauss = crate::rng::SplitMix64::normal;
    for (i, p) in poses.iter_mut().enumerate() {
        let mut r = crate::rng::SplitMix64(
            j.seed.wrapping_mul(0x2545_F491_4F6C_DD1D)
                ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let d = DVec3::new(gauss(&mut r), gauss(&mut r), gauss(&mut r));
        let axis = DVec3::new(gauss(&mut r), gauss(&mut r), gauss(&mut r));
        let angle = j.rotation * gauss(&mut r);
        p.world_from_rig.translation += j.position * d;
        if axis.length() > 0.0 {
            let q = glam::DQuat::from_axis_angle(axis.normalize(), angle);
            p.world_from_rig.rotation = DMat3::from_quat(q) * p.world_from_rig.rotation;
        }
    }
}

/// When exposures are taken along a strip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Trigger {
    /// Spacing derived from the forward overlap and the along-track footprint.
    Overlap,
    /// Every `0` metres of path.
    Distance(f64),
    /// Every `0` seconds at the swim speed.
    Time(f64),
}

/// One explicitly given pose.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ExplicitPose {
    /// Entrance-pupil position of the rig, world, m.
    pub position: DVec3,
    /// Orientation: either look at a point (with an up hint) or a full rotation.
    pub orientation: Orientation,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Orientation {
    /// Optical axis towards `target`; image "up" (−y) as close as possible to `up`.
    LookAt { target: DVec3, up: DVec3 },
    /// `world_from_rig` rotation.
    Rotation { rotation: DMat3 },
}

/// A network in SI units, as produced by the scene resolver.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum NetworkSpec {
    Explicit {
        poses: Vec<ExplicitPose>,
    },
    /// Parallel strips over a `width`×`length` rectangle centred on `center` (xy; z ignored),
    /// strips run along `heading` (rad, clockwise from north). `strips` forces the number of
    /// strips (else from `sidelap`). `cross_strips` adds a perpendicular pass.
    Lawnmower {
        center: DVec3,
        width: f64,
        length: f64,
        heading: f64,
        altitude: f64,
        overlap: f64,
        sidelap: f64,
        strips: Option<u32>,
        cross_strips: bool,
        tilt: f64,
        /// Tilt of a second, oblique pass over the same strips, rad (0: none).
        obliques: f64,
        trigger: Trigger,
    },
    /// Archimedean spiral around `center` out to `radius`, nadir, turns `1 − sidelap`
    /// footprints apart.
    Spiral {
        center: DVec3,
        radius: f64,
        altitude: f64,
        overlap: f64,
        sidelap: f64,
        trigger: Trigger,
    },
    /// Rings on the sphere of `radius` about `center`, one ring per `elevations` entry (rad above
    /// the horizontal plane of `center`), camera looking at `center`, `per_ring` images each.
    Orbit {
        center: DVec3,
        radius: f64,
        elevations: Vec<f64>,
        per_ring: u32,
    },
}

/// What the expansion needs to know about the camera and the site.
#[derive(Debug, Clone)]
pub struct NetworkContext {
    /// Image size, px, and focal length, px, of the (first) camera.
    pub width: u32,
    pub height: u32,
    pub focal_px: f64,
    /// Factor by which the port magnifies (flat port: ≈ n_water; dome or no port: 1).
    pub magnification: f64,
    /// z of the nominal seabed (world).
    pub seabed_z: f64,
    /// Swim speed, m/s.
    pub speed: f64,
    /// The first camera's exact projection through its port into the water (camera frame, G
    /// channel). With it, footprints and spacings come from exact refraction; without it
    /// (`None`), from the paraxial `magnification`.
    pub exact: Option<std::sync::Arc<Projector>>,
}

/// Image axis a spacing is along: `Along` = image v (the swim direction of a lawnmower strip),
/// `Across` = image u (between strips).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    Along,
    Across,
}

/// Lines across the image on which [`NetworkContext::overlap_for`] measures the shared part.
const LINES: usize = 32;

impl NetworkContext {
    /// Where pixel (u, v) of a nadir camera at altitude `h` meets a flat seabed, in the camera
    /// frame (x along u, y along v), through the exact port.
    fn ground(pr: &Projector, h: f64, u: f64, v: f64) -> Option<DVec3> {
        let ray = pr.camera_ray(u, v).ok()?;
        let (o, d) = (ray.origin, ray.dir);
        if !(d.z > 1e-12) {
            return None;
        }
        let t = (h - o.z) / d.z;
        (t > 0.0).then(|| o + d * t)
    }

    /// Exact shared share of the image for a neighbour displaced by `s` along `axis`: on each
    /// of [`LINES`] pixel lines parallel to the axis, the part of the line whose ground points
    /// the neighbour also sees on its sensor (an interval, found by bisection on the pixel
    /// coordinate, so the result is continuous in `s`), averaged over the lines.
    fn shared(pr: &Projector, h: f64, s: f64, axis: Axis) -> f64 {
        let (len, other) = match axis {
            Axis::Along => (pr.height, pr.width),
            Axis::Across => (pr.width, pr.height),
        };
        let shift = match axis {
            Axis::Along => DVec3::new(0.0, s, 0.0),
            Axis::Across => DVec3::new(s, 0.0, 0.0),
        };
        let pixel = |line: f64, t: f64| match axis {
            Axis::Along => (line, t),
            Axis::Across => (t, line),
        };
        // Seen by the neighbour: the ground point, moved back by the shift, is on its sensor.
        let seen = |line: f64, t: f64| {
            let (u, v) = pixel(line, t);
            Self::ground(pr, h, u, v).is_some_and(|g| pr.project_camera(g - shift).is_ok())
        };
        let mut total = 0.0;
        let mut lines = 0usize;
        for i in 0..LINES {
            let line = (i as f64 + 0.5) / LINES as f64 * other;
            lines += 1;
            if !seen(line, len) {
                continue; // the far end is not shared: nothing on this line is
            }
            if seen(line, 0.0) {
                total += 1.0;
                continue;
            }
            let (mut lo, mut hi) = (0.0, len);
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if seen(line, mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            total += (len - hi) / len;
        }
        if lines == 0 {
            0.0
        } else {
            total / lines as f64
        }
    }

    /// Overlap (the share of one image's pixels whose ground point the neighbour also sees)
    /// between two nadir images `s` metres apart along `axis`, at altitude `h`, over a flat
    /// seabed: exact through the port when [`NetworkContext::exact`] is set, else paraxial.
    pub fn overlap_for(&self, h: f64, s: f64, axis: Axis) -> f64 {
        match &self.exact {
            Some(pr) => Self::shared(pr, h, s, axis),
            None => {
                let (across, along) = self.paraxial_footprint(h);
                let l = if axis == Axis::Along { along } else { across };
                (1.0 - s / l).clamp(0.0, 1.0)
            }
        }
    }

    /// Spacing between nadir images along `axis` that gives overlap `o` at altitude `h`; the
    /// inverse of [`NetworkContext::overlap_for`] (bisection on the exact overlap, to 1e-6 of
    /// the footprint).
    pub fn spacing_for(&self, h: f64, o: f64, axis: Axis) -> f64 {
        let (across, along) = self.footprint_at(h);
        let l = if axis == Axis::Along { along } else { across };
        let Some(pr) = &self.exact else {
            return (1.0 - o) * l;
        };
        let (mut lo, mut hi) = (0.0, 2.0 * l.max(1e-9));
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if Self::shared(pr, h, mid, axis) >= o {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo < 1e-6 * l {
                break;
            }
        }
        lo
    }

    fn paraxial_footprint(&self, h: f64) -> (f64, f64) {
        let g = self.gsd_at(h);
        (self.width as f64 * g, self.height as f64 * g)
    }

    /// Nadir GSD at altitude `h`, m/px.
    pub fn gsd_at(&self, h: f64) -> f64 {
        h / (self.focal_px * self.magnification)
    }
    /// Altitude giving nadir GSD `gsd`.
    pub fn altitude_for_gsd(&self, gsd: f64) -> f64 {
        gsd * self.focal_px * self.magnification
    }
    /// Footprint (across-track, along-track) at altitude `h`, m: [`footprint_exact`]
    /// through the port when [`NetworkContext::exact`] is set
    /// (a flat port narrows the edges of a wide lens's view; the paraxial footprint
    /// overstates it), else paraxial.
    pub fn footprint_at(&self, h: f64) -> (f64, f64) {
        match self.exact.as_deref().and_then(|pr| footprint_exact(pr, h)) {
            Some(f) => f,
            None => self.paraxial_footprint(h),
        }
    }
}

/// Exact footprint (across = image u, along = image v) of a nadir camera at distance `h`
/// above a flat seabed, m: the mean lengths of the edges between the corner pixels' ground
/// points through the port (the survey's definition, [`crate::plan::survey`]). `None` where a
/// corner's ray never reaches the seabed.
pub fn footprint_exact(pr: &Projector, h: f64) -> Option<(f64, f64)> {
    let (w, hh) = (pr.width, pr.height);
    let g = |u, v| NetworkContext::ground(pr, h, u, v);
    let (a, b, c, d) = (g(0.0, 0.0)?, g(w, 0.0)?, g(w, hh)?, g(0.0, hh)?);
    let across = 0.5 * ((b - a).length() + (c - d).length());
    let along = 0.5 * ((d - a).length() + (c - b).length());
    Some((across, along))
}

/// Rotation `world_from_rig` for a camera looking along `forward` with image-up near `up`.
pub fn look_rotation(forward: DVec3, up: DVec3) -> Option<DMat3> {
    let z = forward.try_normalize()?;
    // Image y points down, i.e. opposite to the up hint projected onto the image plane.
    let y = (-(up - z * up.dot(z))).try_normalize()?;
    let x = y.cross(z);
    Some(DMat3::from_cols(x, y, z))
}

/// Largest number of rig poses a network may expand to (a typo in a spacing must not hang).
pub const MAX_POSES: usize = 100_000;

/// Expand a network into rig poses and its summary. Errors are messages for the user (the
/// resolver attaches them to the network's span).
pub fn expand(
    spec: &NetworkSpec,
    ctx: &NetworkContext,
) -> Result<(Vec<RigPose>, NetworkSummary), String> {
    if !(ctx.speed.is_finite() && ctx.speed > 0.0) {
        return Err(format!(
            "swim speed must be a positive number of m/s, got {}",
            ctx.speed
        ));
    }
    if !(ctx.focal_px.is_finite() && ctx.focal_px > 0.0 && ctx.magnification > 0.0) {
        return Err("the camera's focal length must be positive".into());
    }
    let mut b = Builder::new(ctx.speed);
    let mut summary = NetworkSummary {
        speed: ctx.speed,
        ..Default::default()
    };
    match spec {
        NetworkSpec::Explicit { poses } => {
            summary.kind = "explicit".into();
            explicit_poses(&mut b, poses)?;
            summary.strips = 1;
        }
        NetworkSpec::Lawnmower {
            center,
            width,
            length,
            heading,
            altitude,
            overlap,
            sidelap,
            strips,
            cross_strips,
            tilt,
            obliques,
            trigger,
        } => {
            summary.kind = if *cross_strips {
                "lawnmower+cross".into()
            } else {
                "lawnmower".into()
            };
            positive(*altitude, "altitude")?;
            nonneg(*width, "area width")?;
            nonneg(*length, "area length")?;
            fraction(*overlap, "overlap")?;
            fraction(*sidelap, "sidelap")?;
            let z = ctx.seabed_z + altitude;
            let along = along_spacing(
                trigger,
                ctx.spacing_for(*altitude, *overlap, Axis::Along),
                ctx.speed,
            )?;
            let strip_gap = ctx.spacing_for(*altitude, *sidelap, Axis::Across);
            let mut passes = vec![(*heading, *width, *length, *tilt)];
            if *cross_strips {
                passes.push((
                    heading + std::f64::consts::FRAC_PI_2,
                    *length,
                    *width,
                    *tilt,
                ));
            }
            if *obliques != 0.0 {
                passes.push((*heading, *width, *length, *obliques));
                summary.kind.push_str("+obliques");
            }
            let c0 = DVec3::new(center.x, center.y, z);
            let (strip_no, strip_spacing_used) =
                lawnmower_strips(&mut b, &passes, *strips, strip_gap, along, c0)?;
            summarise_flight(&mut summary, ctx, *altitude, along, *overlap, *sidelap);
            summary.strip_spacing = strip_spacing_used;
            summary.sidelap = strip_spacing_used
                .filter(|&s| s > 0.0)
                .map(|s| ctx.overlap_for(*altitude, s, Axis::Across));
            summary.strips = strip_no;
        }
        NetworkSpec::Spiral {
            center,
            radius,
            altitude,
            overlap,
            sidelap,
            trigger,
        } => {
            summary.kind = "spiral".into();
            positive(*altitude, "altitude")?;
            positive(*radius, "spiral radius")?;
            fraction(*overlap, "overlap")?;
            fraction(*sidelap, "sidelap")?;
            let along = along_spacing(
                trigger,
                ctx.spacing_for(*altitude, *overlap, Axis::Along),
                ctx.speed,
            )?;
            let turn = ctx.spacing_for(*altitude, *sidelap, Axis::Across);
            let bcoef = turn / std::f64::consts::TAU;
            let theta_end = radius / bcoef;
            let s_end = spiral_arc(bcoef, theta_end);
            // Saturating: an absurd radius gives a count `check_count` refuses, not an overflow.
            let n = ((s_end / along + 1e-9).floor() as usize).saturating_add(1);
            check_count(n, 1)?;
            let c0 = DVec3::new(center.x, center.y, ctx.seabed_z + altitude);
            spiral_poses(&mut b, c0, bcoef, along, n);
            summarise_flight(&mut summary, ctx, *altitude, along, *overlap, *sidelap);
            summary.strip_spacing = Some(turn);
            summary.sidelap = Some(ctx.overlap_for(*altitude, turn, Axis::Across));
            summary.strips = (theta_end / std::f64::consts::TAU).ceil() as u32;
        }
        NetworkSpec::Orbit {
            center,
            radius,
            elevations,
            per_ring,
        } => {
            summary.kind = "orbit".into();
            positive(*radius, "orbit radius")?;
            finite3(*center, "orbit centre")?;
            if elevations.is_empty() {
                return Err("an orbit needs at least one ring (`elevations`)".into());
            }
            if *per_ring == 0 {
                return Err("`per_ring` must be at least 1".into());
            }
            check_count(elevations.len(), *per_ring as usize)?;
            orbit_poses(&mut b, *center, *radius, elevations, *per_ring)?;
            summary.strips = elevations.len() as u32;
        }
    }
    if b.poses.is_empty() {
        return Err("the network has no poses".into());
    }
    summary.path = b.path;
    summary.path_length = b.distance;
    summary.duration = b.distance / ctx.speed;
    Ok((b.poses, summary))
}

/// The poses of an explicit network, in order, each at its position, looking at its target
/// or with its rotation.
/// The summary of a flight at `altitude` taking an image every `along`: the overlap that
/// gives, and the overlap and sidelap asked for (the sidelap it gives is the pattern's).
fn summarise_flight(
    summary: &mut NetworkSummary,
    ctx: &NetworkContext,
    altitude: f64,
    along: f64,
    overlap: f64,
    sidelap: f64,
) {
    summary.altitude = Some(altitude);
    summary.spacing = Some(along);
    summary.overlap = Some(ctx.overlap_for(altitude, along, Axis::Along));
    summary.overlap_requested = Some(overlap);
    summary.sidelap_requested = Some(sidelap);
}

fn explicit_poses(b: &mut Builder, poses: &[ExplicitPose]) -> Result<(), String> {
    for (i, p) in poses.iter().enumerate() {
        finite3(p.position, "pose position")?;
        let rot = match &p.orientation {
            Orientation::LookAt { target, up } => {
                finite3(*target, "look_at target")?;
                look_rotation(*target - p.position, *up).ok_or_else(|| {
                    format!("pose {}: the look-at target coincides with the position or the up vector is parallel to the view direction", i + 1)
                })?
            }
            Orientation::Rotation { rotation } => *rotation,
        };
        b.travel_to(p.position);
        b.shoot(rot, 0);
    }
    Ok(())
}

/// The strips of a lawnmower's passes (heading, width, length, tilt) over the area centred on
/// `c0` (at the altitude's depth): `strips` of them per pass, else as many as `strip_gap` asks,
/// boustrophedon, a pose every `along` m. Returns the number of strips and the spacing of the
/// first pass's.
fn lawnmower_strips(
    b: &mut Builder,
    passes: &[(f64, f64, f64, f64)],
    strips: Option<u32>,
    strip_gap: f64,
    along: f64,
    c0: DVec3,
) -> Result<(u32, Option<f64>), String> {
    let mut strip_no = 0u32;
    let mut strip_spacing_used = None;
    for &(h, w, l, pass_tilt) in passes {
        let a = DVec3::new(h.sin(), h.cos(), 0.0);
        let c = DVec3::new(h.cos(), -h.sin(), 0.0);
        let n_strips = match strips {
            Some(n) if n >= 1 => n as usize,
            Some(_) => return Err("`strips` must be at least 1".into()),
            None => {
                let s = strip_gap;
                if w <= 0.0 {
                    1
                } else {
                    ((w / s - 1e-9).ceil() as usize).saturating_add(1)
                }
            }
        };
        check_count(n_strips, 1)?;
        let ss = if n_strips > 1 {
            w / (n_strips - 1) as f64
        } else {
            0.0
        };
        strip_spacing_used.get_or_insert(ss);
        // Saturating: an absurd length gives a count `check_count` refuses, not an overflow.
        let per_strip = ((l / along + 1e-9).floor() as usize).saturating_add(1);
        check_count(n_strips, per_strip)?;
        let span = (per_strip - 1) as f64 * along;
        for i in 0..n_strips {
            // One strip runs down the middle of the area.
            let off = if n_strips == 1 {
                0.0
            } else {
                -w / 2.0 + i as f64 * ss
            };
            let dir = if i % 2 == 0 { a } else { -a };
            let base = c0 + c * off;
            let rot = nadir_rotation(dir, pass_tilt);
            for k in 0..per_strip {
                let s = -span / 2.0 + k as f64 * along;
                b.travel_to(base + dir * s);
                b.shoot(rot, strip_no);
            }
            strip_no += 1;
        }
    }
    Ok((strip_no, strip_spacing_used))
}

/// `n` poses along the Archimedean spiral r = `bcoef` θ around `c0`, `along` m apart, nadir,
/// heading along the tangent; the strip is the turn.
fn spiral_poses(b: &mut Builder, c0: DVec3, bcoef: f64, along: f64, n: usize) {
    let mut theta = 0.0;
    for k in 0..n {
        let target = k as f64 * along;
        theta = spiral_theta(bcoef, target, theta);
        let r = bcoef * theta;
        let p = DVec3::new(c0.x + r * theta.cos(), c0.y + r * theta.sin(), c0.z);
        // Tangent of (r cos θ, r sin θ): (b cos θ − r sin θ, b sin θ + r cos θ).
        let t = DVec3::new(
            bcoef * theta.cos() - r * theta.sin(),
            bcoef * theta.sin() + r * theta.cos(),
            0.0,
        )
        .normalize();
        b.travel_to(p);
        b.shoot(
            nadir_rotation(t, 0.0),
            (theta / std::f64::consts::TAU) as u32,
        );
    }
}

/// The rings of an orbit around `center`: `per_ring` poses on each elevation, looking at the
/// centre.
fn orbit_poses(
    b: &mut Builder,
    center: DVec3,
    radius: f64,
    elevations: &[f64],
    per_ring: u32,
) -> Result<(), String> {
    for (ring, &e) in elevations.iter().enumerate() {
        if !(e.is_finite() && e.abs() < std::f64::consts::FRAC_PI_2 + 1e-12) {
            return Err(format!(
                "ring elevation {} deg is outside [-90, 90]",
                e.to_degrees()
            ));
        }
        for k in 0..per_ring {
            let phi = std::f64::consts::TAU * k as f64 / per_ring as f64;
            let p = center + radius * DVec3::new(e.cos() * phi.cos(), e.cos() * phi.sin(), e.sin());
            let up = if e.cos() < 1e-6 {
                DVec3::new(-phi.cos(), -phi.sin(), 0.0) * e.signum()
            } else {
                DVec3::Z
            };
            let rot = look_rotation(center - p, up).ok_or("degenerate orbit pose")?;
            b.travel_to(p);
            b.shoot(rot, ring as u32);
        }
    }
    Ok(())
}

/// Accumulates the swim path and the poses along it.
struct Builder {
    speed: f64,
    path: Vec<DVec3>,
    distance: f64,
    poses: Vec<RigPose>,
}

impl Builder {
    fn new(speed: f64) -> Self {
        Builder {
            speed,
            path: Vec::new(),
            distance: 0.0,
            poses: Vec::new(),
        }
    }
    fn travel_to(&mut self, p: DVec3) {
        if let Some(last) = self.path.last() {
            let d = last.distance(p);
            if d == 0.0 {
                return;
            }
            self.distance += d;
        }
        self.path.push(p);
    }
    fn shoot(&mut self, rotation: DMat3, strip: u32) {
        let position = *self.path.last().expect("travel_to before shoot");
        self.poses.push(RigPose {
            name: format!("img_{:04}", self.poses.len() + 1),
            world_from_rig: Pose {
                rotation,
                translation: position,
            },
            time: self.distance / self.speed,
            strip,
        });
    }
}

/// Nadir camera travelling along `dir` (horizontal unit), image top towards the travel
/// direction, tilted forward by `tilt` rad about the image x axis.
fn nadir_rotation(dir: DVec3, tilt: f64) -> DMat3 {
    let z = -DVec3::Z;
    let y = -dir;
    let x = y.cross(z);
    let (s, c) = tilt.sin_cos();
    let z2 = c * z - s * y;
    let y2 = c * y + s * z;
    DMat3::from_cols(x, y2, z2)
}

/// Spacing between exposures along a strip: `for_overlap` (from the requested overlap) unless
/// the trigger is a distance or a time.
fn along_spacing(trigger: &Trigger, for_overlap: f64, speed: f64) -> Result<f64, String> {
    let s = match trigger {
        Trigger::Overlap => for_overlap,
        Trigger::Distance(d) => *d,
        Trigger::Time(t) => t * speed,
    };
    if s.is_finite() && s > 0.0 {
        Ok(s)
    } else {
        Err(format!(
            "the spacing between exposures must be positive, got {s} m"
        ))
    }
}

fn check_count(a: usize, b: usize) -> Result<(), String> {
    match a.checked_mul(b) {
        Some(n) if n <= MAX_POSES => Ok(()),
        _ => Err(format!(
            "the network would have more than {MAX_POSES} poses; increase the spacing or shrink the area"
        )),
    }
}

fn positive(v: f64, what: &str) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{what} must be a positive number, got {v}"))
    }
}
fn nonneg(v: f64, what: &str) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what} must be zero or positive, got {v}"))
    }
}
fn fraction(v: f64, what: &str) -> Result<(), String> {
    if v.is_finite() && (0.0..1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!("{what} must be in [0, 1), got {v}"))
    }
}
fn finite3(v: DVec3, what: &str) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{what} has a non-finite coordinate"))
    }
}

/// Arc length of the Archimedean spiral r = bθ from 0 to θ.
fn spiral_arc(b: f64, theta: f64) -> f64 {
    0.5 * b * (theta * (1.0 + theta * theta).sqrt() + theta.asinh())
}

/// θ at arc length `s` (Newton from `guess`, monotone so it converges).
fn spiral_theta(b: f64, s: f64, guess: f64) -> f64 {
    let mut t = guess.max(0.0);
    for _ in 0..60 {
        let f = spiral_arc(b, t) - s;
        let df = b * (1.0 + t * t).sqrt();
        let step = f / df;
        t = (t - step).max(0.0);
        if step.abs() <= 1e-14 * t.max(1.0) {
            break;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx() -> NetworkContext {
        NetworkContext {
            width: 4000,
            height: 3000,
            focal_px: 3000.0,
            magnification: 1.0,
            seabed_z: -15.0,
            speed: 0.2,
            exact: None,
        }
    }

    fn is_rotation(r: DMat3) -> bool {
        (r.transpose() * r - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|v| v.abs() < 1e-12)
            && (r.determinant() - 1.0).abs() < 1e-12
    }

    #[test]
    fn one_strip_runs_down_the_middle() {
        let spec = NetworkSpec::Lawnmower {
            center: DVec3::new(2.0, -1.0, 0.0),
            width: 1.0,
            length: 4.0,
            heading: 0.0,
            altitude: 1.5,
            overlap: 0.8,
            sidelap: 0.6,
            strips: Some(1),
            cross_strips: false,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Overlap,
        };
        let (poses, s) = expand(&spec, &ctx()).unwrap();
        assert_eq!(s.strips, 1);
        assert!(poses.len() > 2);
        for p in &poses {
            assert!((p.world_from_rig.translation.x - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn lawnmower_counts_spacing_and_time() {
        // Footprint at 3 m: 4 m × 3 m. Sidelap 0.5 → strip spacing ≤ 2 m; overlap 0.8 → 0.6 m.
        let spec = NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 10.0,
            length: 6.0,
            heading: 0.0,
            altitude: 3.0,
            overlap: 0.8,
            sidelap: 0.5,
            strips: None,
            cross_strips: false,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Overlap,
        };
        let (poses, s) = expand(&spec, &ctx()).unwrap();
        assert_eq!(s.strips, 6); // 10 m / 2 m = 5 gaps
        assert_eq!(poses.len(), 6 * 11); // 6 m / 0.6 m = 10 gaps
        assert!((s.strip_spacing.unwrap() - 2.0).abs() < 1e-12);
        // Path: 6 strips of 6 m + 5 turns of 2 m.
        assert!((s.path_length - 46.0).abs() < 1e-9, "{}", s.path_length);
        assert!((s.duration - 46.0 / 0.2).abs() < 1e-9);
        let last = poses.last().unwrap();
        assert!((last.time - s.duration).abs() < 1e-9);
        for p in &poses {
            assert!(is_rotation(p.world_from_rig.rotation));
            assert!((p.world_from_rig.translation.z - (-12.0)).abs() < 1e-12);
            // Looking straight down.
            assert!(
                (p.world_from_rig.rotation.z_axis - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12
            );
        }
        // Boustrophedon: strip 1 runs opposite to strip 0; image top points along travel.
        assert!(
            (poses[0].world_from_rig.rotation.y_axis - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12
        );
        assert!(
            (poses[11].world_from_rig.rotation.y_axis - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-12
        );
    }

    #[test]
    fn cross_strips_double_the_pass() {
        let mk = |cross| NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 8.0,
            length: 8.0,
            heading: 0.3,
            altitude: 3.0,
            overlap: 0.7,
            sidelap: 0.6,
            strips: Some(4),
            cross_strips: cross,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Distance(1.0),
        };
        let (a, _) = expand(&mk(false), &ctx()).unwrap();
        let (b, sb) = expand(&mk(true), &ctx()).unwrap();
        assert_eq!(a.len(), 4 * 9);
        assert_eq!(b.len(), 2 * a.len());
        assert_eq!(sb.strips, 8);
    }

    #[test]
    fn tilt_points_the_axis_forward() {
        let spec = NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 0.0,
            length: 2.0,
            heading: 0.0,
            altitude: 3.0,
            overlap: 0.8,
            sidelap: 0.6,
            strips: None,
            cross_strips: false,
            tilt: 30f64.to_radians(),
            obliques: 0.0,
            trigger: Trigger::Distance(1.0),
        };
        let (p, _) = expand(&spec, &ctx()).unwrap();
        let z = p[0].world_from_rig.rotation.z_axis;
        assert!(
            (z - DVec3::new(0.0, 0.5, -(3f64.sqrt() / 2.0))).length() < 1e-12,
            "{z}"
        );
        assert!(is_rotation(p[0].world_from_rig.rotation));
    }

    #[test]
    fn jitter_moves_and_turns_poses_by_the_given_spread() {
        let spec = NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 20.0,
            length: 40.0,
            heading: 0.0,
            altitude: 2.0,
            overlap: 0.8,
            sidelap: 0.6,
            strips: Some(20),
            cross_strips: false,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Distance(0.1),
        };
        let (plan, _) = expand(&spec, &ctx()).unwrap();
        let mut wobbly = plan.clone();
        let j = Jitter {
            position: 0.03,
            rotation: 2f64.to_radians(),
            seed: 7,
        };
        jitter(&mut wobbly, &j);
        let n = plan.len() as f64;
        assert!(n > 5000.0);
        let var = plan
            .iter()
            .zip(&wobbly)
            .map(|(a, b)| {
                (b.world_from_rig.translation - a.world_from_rig.translation).length_squared()
            })
            .sum::<f64>()
            / (3.0 * n);
        assert!((var.sqrt() / 0.03 - 1.0).abs() < 0.03, "{}", var.sqrt());
        // Turned by |angle| about a random axis: the mean of angle² is σ².
        let ang2 = plan
            .iter()
            .zip(&wobbly)
            .map(|(a, b)| {
                let r = b.world_from_rig.rotation * a.world_from_rig.rotation.transpose();
                let c = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
                c.acos().powi(2)
            })
            .sum::<f64>()
            / n;
        assert!((ang2.sqrt() / 2f64.to_radians() - 1.0).abs() < 0.03);
        assert!(
            wobbly
                .iter()
                .all(|p| is_rotation(p.world_from_rig.rotation))
        );
        let mut again = plan.clone();
        jitter(&mut again, &j);
        assert_eq!(
            again
                .iter()
                .map(|p| p.world_from_rig.translation)
                .collect::<Vec<_>>(),
            wobbly
                .iter()
                .map(|p| p.world_from_rig.translation)
                .collect::<Vec<_>>()
        );
    }

    #[test]
    fn obliques_add_a_tilted_pass_over_the_same_strips() {
        let mk = |obliques: f64| NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 2.0,
            length: 4.0,
            heading: 0.0,
            altitude: 2.0,
            overlap: 0.8,
            sidelap: 0.6,
            strips: Some(3),
            cross_strips: false,
            tilt: 0.0,
            obliques,
            trigger: Trigger::Distance(1.0),
        };
        let (nadir, s0) = expand(&mk(0.0), &ctx()).unwrap();
        let (both, s1) = expand(&mk(30f64.to_radians()), &ctx()).unwrap();
        assert_eq!(both.len(), 2 * nadir.len());
        assert_eq!(s1.strips, 2 * s0.strips);
        assert_eq!(s1.kind, "lawnmower+obliques");
        let n = nadir.len();
        for (a, b) in nadir.iter().zip(&both[n..]) {
            // Same places, the axis tilted 30° from straight down.
            assert!((a.world_from_rig.translation - b.world_from_rig.translation).length() < 1e-12);
            let cos = -b.world_from_rig.rotation.z_axis.z;
            assert!((cos - 30f64.to_radians().cos()).abs() < 1e-12, "{cos}");
        }
        // Alternate strips look both ways along y.
        let ys: Vec<f64> = both[n..]
            .iter()
            .map(|p| p.world_from_rig.rotation.z_axis.y)
            .collect();
        assert!(ys.iter().any(|&y| y > 0.4) && ys.iter().any(|&y| y < -0.4));
    }

    #[test]
    fn orbit_looks_at_centre() {
        let c = DVec3::new(1.0, 2.0, -10.0);
        let spec = NetworkSpec::Orbit {
            center: c,
            radius: 2.0,
            elevations: vec![0.3, 0.8],
            per_ring: 12,
        };
        let (poses, s) = expand(&spec, &ctx()).unwrap();
        assert_eq!(poses.len(), 24);
        assert_eq!(s.strips, 2);
        for p in &poses {
            let t = p.world_from_rig.translation;
            assert!((t.distance(c) - 2.0).abs() < 1e-12);
            assert!((p.world_from_rig.rotation.z_axis - (c - t).normalize()).length() < 1e-12);
            assert!(is_rotation(p.world_from_rig.rotation));
            // Image up (−y) points upward in the world.
            assert!(-p.world_from_rig.rotation.y_axis.z > 0.0);
        }
    }

    #[test]
    fn spiral_spacing_is_even_along_the_path() {
        let spec = NetworkSpec::Spiral {
            center: DVec3::ZERO,
            radius: 5.0,
            altitude: 2.0,
            overlap: 0.8,
            sidelap: 0.6,
            trigger: Trigger::Distance(0.5),
        };
        let (poses, s) = expand(&spec, &ctx()).unwrap();
        assert!(poses.len() > 50);
        let r_last = poses
            .last()
            .unwrap()
            .world_from_rig
            .translation
            .truncate()
            .length();
        assert!(r_last <= 5.0 + 1e-9 && r_last > 4.0, "{r_last}");
        assert!(
            (s.path_length - 0.5 * (poses.len() - 1) as f64).abs()
                < 0.5 * 0.01 * poses.len() as f64
        );
    }

    #[test]
    fn errors_instead_of_hangs() {
        let spec = NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 1e6,
            length: 1e6,
            heading: 0.0,
            altitude: 3.0,
            overlap: 0.8,
            sidelap: 0.6,
            strips: None,
            cross_strips: false,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Distance(1e-3),
        };
        assert!(expand(&spec, &ctx()).unwrap_err().contains("more than"));
        let empty = NetworkSpec::Explicit { poses: vec![] };
        assert!(expand(&empty, &ctx()).unwrap_err().contains("no poses"));
        let bad = NetworkSpec::Lawnmower {
            center: DVec3::ZERO,
            width: 1.0,
            length: 1.0,
            heading: 0.0,
            altitude: f64::NAN,
            overlap: 0.8,
            sidelap: 0.6,
            strips: None,
            cross_strips: false,
            tilt: 0.0,
            obliques: 0.0,
            trigger: Trigger::Overlap,
        };
        assert!(expand(&bad, &ctx()).is_err());
    }

    #[test]
    fn explicit_look_at() {
        let spec = NetworkSpec::Explicit {
            poses: vec![ExplicitPose {
                position: DVec3::new(0.0, -2.0, -1.0),
                orientation: Orientation::LookAt {
                    target: DVec3::new(0.0, 0.0, -1.0),
                    up: DVec3::Z,
                },
            }],
        };
        let (p, _) = expand(&spec, &ctx()).unwrap();
        let r = p[0].world_from_rig.rotation;
        assert!((r.z_axis - DVec3::Y).length() < 1e-12);
        assert!((r.y_axis - -DVec3::Z).length() < 1e-12);
        assert!((r.x_axis - DVec3::X).length() < 1e-12);
    }
}
