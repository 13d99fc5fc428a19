//! `poser bench mesh`: a large textured photogrammetric site (issue 36, "Scale"). It writes,
//! deterministically ([`crate::geometry::bommie`]: fixed seed, nothing from the clock in the
//! data), a coral bommie on a rubble seabed as a height field of N triangles (default
//! 5 000 000) in OBJ + MTL (`map_Kd`) + a JPEG of P² texels (default 8192²), the way Metashape
//! and OpenMVS export a model, with a poser scene that places it as a `mesh` object under a camera with two strobes; then it times
//! each stage as poser runs it:
//!
//! | stage | what runs |
//! |---|---|
//! | `write` | writing the files (not part of the goal) |
//! | `load` | [`crate::scene::load`] (the front end reads the mesh and probes its image) and [`crate::texture::mapped::prepare_object`] (the OBJ parsed, the JPEG decoded to linear 16-bit, the level chosen) |
//! | `bvh` | [`crate::texture::Textured::of_model`] on the prepared mesh |
//! | `truth` | [`crate::truth::write_in`] on that BVH (the targets' pixels, occlusion against the site) |
//! | `render` | one native render through [`crate::backend::Backend`] (which builds its own scene: the prepared mesh is reused, the BVH is built again) |
//!
//! Each stage gives wall time, CPU time (`getrusage`, user + system, this process only) and the
//! process's peak resident memory so far (`VmHWM`, cumulative; reset after `write` where the
//! kernel allows, so that it counts from the load on). The render is checked against the
//! texture: the site's west half is warm and its east half cool, and the ratio of red to blue
//! at two points the camera sees on either side must follow.

use crate::backend::{Backend, RenderOptions};
use crate::geometry::bommie::{self, HALF, height};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to generate.
#[derive(Debug, Clone)]
pub struct Options {
    /// Triangles of the height field (exactly this many are written).
    pub triangles: u64,
    /// Side of the square texture, texels.
    pub texture: u32,
    /// Samples per pixel of the render.
    pub samples: u32,
    /// Keep the generated files (and the render) here; else a temporary folder.
    pub keep: Option<PathBuf>,
}

impl Options {
    /// The full bench (5 M triangles, 8192²) or `--quick` (500 000, 2048²).
    pub fn new(quick: bool) -> Options {
        Options {
            triangles: if quick { 500_000 } else { 5_000_000 },
            texture: if quick { 2048 } else { 8192 },
            samples: 2,
            keep: None,
        }
    }
}

/// One stage's cost.
#[derive(Debug, Clone, Serialize)]
pub struct Stage {
    pub name: String,
    pub wall_s: f64,
    /// User + system CPU seconds of this process (every thread; no children).
    pub cpu_s: f64,
    /// `VmHWM` at the stage's end: the process's peak resident bytes so far (cumulative).
    pub peak_rss_bytes: u64,
    /// `VmRSS` at the stage's end, bytes.
    pub rss_bytes: u64,
}

/// The bench's result.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub threads: usize,
    pub triangles_written: u64,
    pub vertices_written: u64,
    pub texture_side: u32,
    pub obj_bytes: u64,
    pub image_bytes: u64,
    /// Triangles and vertices of the mesh as loaded.
    pub triangles_loaded: u64,
    pub vertices_loaded: u64,
    /// Triangles in the BVH (degenerate ones dropped).
    pub triangles_in_bvh: u64,
    /// Texels of the decoded image, and of the level the renderer uses.
    pub texels_loaded: u64,
    pub texels_used: u64,
    pub level: u32,
    /// Whether `VmHWM` could be reset after writing (else it includes the writing's peak).
    pub peak_reset_after_write: bool,
    pub stages: Vec<Stage>,
    pub render: RenderCheck,
    /// Load + BVH wall seconds, and the peak resident bytes at the end of the BVH stage.
    pub load_bvh_s: f64,
    pub load_bvh_peak_bytes: u64,
    /// Load + BVH ≤ 10 s and ≤ 2 GiB.
    pub goal_met: bool,
}

/// The render, against the texture.
#[derive(Debug, Clone, Serialize)]
pub struct RenderCheck {
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    /// Mean linear RGB of the image.
    pub mean: [f64; 3],
    /// (R/B west) / (R/B east) of the decoded texture around the two points, and of the
    /// render around their pixels.
    pub texture_ratio: f64,
    pub render_ratio: f64,
}

/// Depth of the site's base below the surface, m.
const DEPTH: f64 = 12.0;
/// The two points compared on either side of the colour boundary, m from the site's centre.
const PROBE_X: f64 = 0.25;

/// Run the bench.
pub fn run(opts: &Options) -> Result<Report, String> {
    if opts.triangles < 2 || opts.triangles > crate::geometry::meshfile::MAX_ELEMENTS as u64 {
        return Err(format!(
            "--triangles {}: between 2 and {}",
            opts.triangles,
            crate::geometry::meshfile::MAX_ELEMENTS
        ));
    }
    if !(16..=crate::texture::mapped::MAX_TEXTURE_SIDE).contains(&opts.texture) {
        return Err(format!(
            "--texture {}: between 16 and {}",
            opts.texture,
            crate::texture::mapped::MAX_TEXTURE_SIDE
        ));
    }
    if opts.samples == 0 {
        return Err("at least one sample per pixel".into());
    }
    let tmp;
    let dir = match &opts.keep {
        Some(d) => {
            std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
            d.clone()
        }
        None => {
            tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
            tmp.path().to_path_buf()
        }
    };
    let mut stages = Vec::new();
    let mut clock = Clock::start();
    let written = write_site(&dir, opts)?;
    stages.push(clock.lap("write"));
    let peak_reset = reset_peak();
    let scene = dir.join("scene.toml");
    let model = crate::scene::load(&scene, &[])
        .map_err(|f| f.render())?
        .model;
    let prepared = crate::texture::mapped::prepare_object(&model, 0)?
        .ok_or("the site is not a textured mesh")?;
    stages.push(clock.lap("load"));
    let bvh = crate::texture::Textured::of_model(&model)?;
    stages.push(clock.lap("bvh"));
    crate::truth::write_in(&model, &bvh, &dir.join("render/truth"))?;
    stages.push(clock.lap("truth"));
    let triangles_in_bvh = bvh.triangle_count() as u64;
    drop(bvh);
    let render_opts = RenderOptions {
        samples: Some(opts.samples),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    Backend::Native.render(&model, &dir.join("render"), &render_opts)?;
    stages.push(clock.lap("render"));
    let render = check_render(&model, &dir.join("render"), &prepared, opts.samples)?;
    let (texels_loaded, texels_used, level) = texels(&prepared);
    let load_bvh_s = stages[1].wall_s + stages[2].wall_s;
    let load_bvh_peak_bytes = stages[2].peak_rss_bytes;
    Ok(Report {
        threads: rayon::current_num_threads(),
        triangles_written: opts.triangles,
        vertices_written: written.vertices,
        texture_side: opts.texture,
        obj_bytes: written.obj_bytes,
        image_bytes: written.image_bytes,
        triangles_loaded: prepared.mesh().triangles.len() as u64,
        vertices_loaded: prepared.mesh().positions.len() as u64,
        triangles_in_bvh,
        texels_loaded,
        texels_used,
        level,
        peak_reset_after_write: peak_reset,
        stages,
        render,
        load_bvh_s,
        load_bvh_peak_bytes,
        goal_met: load_bvh_s <= 10.0 && load_bvh_peak_bytes <= 2 << 30,
    })
}

/// Texels of the full-size image, of the level used, and the level.
fn texels(p: &crate::texture::mapped::Prepared) -> (u64, u64, u32) {
    let m = &p.plan.materials[0];
    (
        m.size.0 as u64 * m.size.1 as u64,
        m.level_size.0 as u64 * m.level_size.1 as u64,
        m.level,
    )
}

/// Wall and CPU time since the last lap.
struct Clock {
    wall: Instant,
    cpu: f64,
}

impl Clock {
    fn start() -> Clock {
        Clock {
            wall: Instant::now(),
            cpu: super::evaluate::self_cpu_seconds(),
        }
    }

    fn lap(&mut self, name: &str) -> Stage {
        let (wall, cpu) = (
            self.wall.elapsed().as_secs_f64(),
            super::evaluate::self_cpu_seconds(),
        );
        // The resident size first, then the high-water mark, which the kernel updates lazily
        // and other threads of the process may raise in between: the peak is at least the
        // size read before it.
        let rss_bytes = status_bytes("VmRSS:");
        let stage = Stage {
            name: name.into(),
            wall_s: wall,
            cpu_s: (cpu - self.cpu).max(0.0),
            peak_rss_bytes: status_bytes("VmHWM:").max(rss_bytes),
            rss_bytes,
        };
        *self = Clock::start();
        stage
    }
}

/// A `kB` line of `/proc/self/status` in bytes (0 where there is none).
fn status_bytes(key: &str) -> u64 {
    let text = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// Reset `VmHWM` to the current resident size (Linux ≥ 4.0: `5` into `clear_refs`).
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

// ------------------------------------------------------------------------------------------
// The site
// ------------------------------------------------------------------------------------------

/// Write the site ([`bommie::write`]) into `dir/site/` and `scene.toml` into `dir`.
fn write_site(dir: &Path, opts: &Options) -> Result<bommie::Written, String> {
    let written = bommie::write(&dir.join("site"), opts.triangles, opts.texture)?;
    crate::io::write_atomic(&dir.join("scene.toml"), scene_text().as_bytes())
        .map_err(|e| format!("scene.toml: {e}"))?;
    Ok(written)
}

/// The scene: the site 12 m down, a 640 × 427 camera behind a flat port 1.5 m above the site's
/// base looking straight down, two strobes, and two checkerboards on stands above the rubble.
fn scene_text() -> String {
    let top = -DEPTH + 0.75;
    format!(
        r#"# poser bench mesh: a textured photogrammetric site (OBJ + MTL + JPEG), written by the bench.
name = "bench_mesh"

[site]
depth = "{depth} m"
surface = "flat"

[water]
absorption = [0.35, 0.07, 0.03]
scattering = [0.02, 0.025, 0.03]

[camera]
width = 640
height = 427
pixel_pitch = "56 um"
focal_length = "35 mm"
lens = "rectilinear"

[camera.port]
type = "flat"
material = "N-BK7"
thickness = "10 mm"
pupil_distance = "25 mm"

[[lights]]
name = "left_strobe"
type = "spot"
mount = "rig"
position = [-0.35, 0.0, 0.05]
aim = [0.2, 0.0, 1.0]
beam_angle = "110 deg"
power = "60 W"

[[lights]]
name = "right_strobe"
type = "spot"
mount = "rig"
position = [0.35, 0.0, 0.05]
aim = [-0.2, 0.0, 1.0]
beam_angle = "110 deg"
power = "60 W"

[[objects]]
name = "site"
shape = "mesh"
path = "site/model.obj"
position = [0.0, 0.0, -{depth}]

[[targets]]
name = "north_board"
type = "checkerboard"
cols = 7
rows = 5
square = "20 mm"
position = [0.0, 0.33, {top}]

[[targets]]
name = "south_board"
type = "checkerboard"
cols = 7
rows = 5
square = "20 mm"
position = [0.0, -0.33, {top}]

[network]
type = "explicit"
speed = "0.2 m/s"

[[network.poses]]
position = [0.0, 0.0, {cam}]
look_at = [0.0, 0.0, -{depth}]
up = [0.0, 1.0, 0.0]

[render]
samples = 2
seed = 36
bounces = 2
"#,
        depth = DEPTH,
        cam = -DEPTH + 1.5,
    )
}

// ------------------------------------------------------------------------------------------
// The check and the report
// ------------------------------------------------------------------------------------------

/// The render's mean, and the red-to-blue ratio west against east in the texture and in the
/// render around the pixels where the two probe points project.
fn check_render(
    model: &crate::model::Model,
    dir: &Path,
    prepared: &crate::texture::mapped::Prepared,
    samples: u32,
) -> Result<RenderCheck, String> {
    let img = crate::image::read_exr(&dir.join(format!("{}.exr", model.image_name(0, 0))))?;
    let n = img.rgb.len().max(1) as f64;
    let mean = [0, 1, 2].map(|c| img.rgb.iter().map(|p| p[c] as f64).sum::<f64>() / n);
    let proj = model.projector(0, 1)?;
    let cam_from_world = model.world_from_camera(0, 0).inverse();
    let o = &model.objects[0];
    let look = prepared.looks.first();
    let mut tex = [[0.0; 3]; 2];
    let mut ren = [[0.0; 3]; 2];
    for (k, x) in [-PROBE_X, PROBE_X].into_iter().enumerate() {
        // A 10 cm square around the probe: the texture's mean there, the render's around its
        // projection.
        for (dx, dy) in (0..25).map(|q| {
            (
                0.1 * ((q % 5) as f64 / 4.0 - 0.5),
                0.1 * ((q / 5) as f64 / 4.0 - 0.5),
            )
        }) {
            let (px, py) = (x + dx, dy);
            let uv = [(px + HALF) / (2.0 * HALF), (HALF - py) / (2.0 * HALF)];
            let t = match look {
                Some(crate::texture::mapped::Look::Image(i)) => i.sample(uv[0], uv[1]),
                _ => [0.0; 3],
            };
            let world = o
                .pose
                .transform_point(glam::DVec3::new(px, py, height(px, py)));
            let pix = proj
                .project_camera(cam_from_world.transform_point(world))
                .map_err(|_| format!("the probe point at x = {px:+.2} m is not in view"))?;
            let (i, j) = (pix[0].floor() as i64, pix[1].floor() as i64);
            if i < 0 || j < 0 || i >= img.width as i64 || j >= img.height as i64 {
                return Err(format!("the probe point at x = {px:+.2} m is not in view"));
            }
            let p = img.rgb[j as usize * img.width as usize + i as usize];
            for c in 0..3 {
                tex[k][c] += t[c];
                ren[k][c] += p[c] as f64;
            }
        }
    }
    let ratio = |m: [[f64; 3]; 2]| (m[0][0] / m[0][2]) / (m[1][0] / m[1][2]);
    Ok(RenderCheck {
        width: img.width,
        height: img.height,
        samples,
        mean,
        texture_ratio: ratio(tex),
        render_ratio: ratio(ren),
    })
}

fn gib(b: u64) -> String {
    format!("{:.2}", b as f64 / (1u64 << 30) as f64)
}

/// The report as Markdown.
pub fn table(r: &Report) -> String {
    let mut s = format!(
        "{} threads; {} triangles written ({} vertices, OBJ {:.0} MB), {} loaded, {} in the BVH; \
         texture {}² ({:.1} MB JPEG), {} texels decoded, level {} used ({} texels).\n\n",
        r.threads,
        r.triangles_written,
        r.vertices_written,
        r.obj_bytes as f64 / 1e6,
        r.triangles_loaded,
        r.triangles_in_bvh,
        r.texture_side,
        r.image_bytes as f64 / 1e6,
        r.texels_loaded,
        r.level,
        r.texels_used,
    );
    s += "| stage | wall, s | CPU, s | peak RSS so far, GiB | RSS after, GiB |\n|---|---|---|---|---|\n";
    for st in &r.stages {
        s += &format!(
            "| {} | {:.2} | {:.2} | {} | {} |\n",
            st.name,
            st.wall_s,
            st.cpu_s,
            gib(st.peak_rss_bytes),
            gib(st.rss_bytes)
        );
    }
    s += &format!(
        "\nPeak RSS is `VmHWM`, cumulative{}.\n\
         Load + BVH: {:.2} s, peak {} GiB: the goal (≤ 10 s, ≤ 2 GiB) is {}.\n\
         Render {}×{}, {} spp: mean RGB {:.4} {:.4} {:.4}; red/blue west over east: texture {:.2}, render {:.2}.\n",
        if r.peak_reset_after_write {
            " from the end of `write` (reset there)"
        } else {
            " from the process's start (could not be reset after `write`)"
        },
        r.load_bvh_s,
        gib(r.load_bvh_peak_bytes),
        if r.goal_met { "met" } else { "NOT met" },
        r.render.width,
        r.render.height,
        r.render.samples,
        r.render.mean[0],
        r.render.mean[1],
        r.render.mean[2],
        r.render.texture_ratio,
        r.render.render_ratio,
    );
    s
}
