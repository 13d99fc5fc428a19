//! `poser import`: Mitsuba 3 XML or Blender `.blend` scenes → a poser scene file and its mesh
//! assets, validated.
use super::CliError;
use std::path::PathBuf;

/// The arguments of `poser import`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Mitsuba 3 scene file(s) (`.xml`): the first gives the world (shapes, lights, water);
    /// every file adds its sensors as poses, in order (e.g. the `img_*.xml` views that
    /// `poser compile --backend mitsuba` writes). Or one Blender file (`.blend`), read by the
    /// pinned `bpy` with its scripts off.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The poser scene file to write.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Folder for the mesh assets (default: `<scene name>_assets` beside the scene file).
    #[arg(long)]
    pub assets: Option<PathBuf>,
    /// Mitsuba: the folder every file the scene names must stay inside (default: the first
    /// file's folder), for scenes whose `<path>` folders sit beside their own.
    #[arg(long)]
    pub root: Option<PathBuf>,
    /// Render the source in its own renderer (Mitsuba 3 for `.xml`, Cycles for `.blend`) and the imported scene
    /// natively (daylight traced), at a small size, print the difference per channel and per
    /// region, and fail when a channel's mean differs by more than `--tolerance`.
    #[arg(long)]
    pub verify: bool,
    /// `--verify`'s tolerance on each channel's mean, in per cent.
    #[arg(long, default_value_t = 2.0, requires = "verify")]
    pub tolerance: f64,
    /// `--verify`'s image width in pixels (the height follows the camera's aspect).
    #[arg(long, default_value_t = 64, requires = "verify")]
    pub verify_width: u32,
    /// `--verify`'s samples per pixel, in both renderers.
    #[arg(long, default_value_t = 64, requires = "verify")]
    pub verify_samples: u32,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let ext = |f: &std::path::Path| {
        f.extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase()
    };
    let blend = args.files.iter().any(|f| ext(f) == "blend");
    for f in &args.files {
        if ext(f) != "xml" && ext(f) != "blend" {
            return Err(CliError::Usage(format!(
                "{}: poser imports Mitsuba 3 scenes (.xml) and Blender files (.blend)",
                f.display()
            )));
        }
    }
    if blend && args.root.is_some() {
        return Err(CliError::Usage(
            "--root is for Mitsuba files: a Blender file is read by Blender".into(),
        ));
    }
    if blend && args.files.len() != 1 {
        return Err(CliError::Usage(
            "a Blender file is imported on its own: one .blend, no other file".into(),
        ));
    }
    let out_dir = args
        .out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("."));
    let stem = args
        .out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let assets = args.assets.clone().unwrap_or_else(|| {
        out_dir.join(format!("{}_assets", crate::import::safe_file_name(&stem)))
    });
    let rel = crate::import::relative_path(&absolute(&out_dir), &absolute(&assets));
    let imported = if blend {
        let work = tempfile::tempdir().map_err(|e| CliError::Failed(e.to_string()))?;
        crate::import::blender::import(&args.files[0], &rel, work.path())
    } else {
        crate::import::mitsuba::import_within(&args.files, &rel, args.root.as_deref())
    }
    .map_err(CliError::Failed)?;
    for n in &imported.notes {
        eprintln!("note: {}", n.render());
    }
    crate::import::write(&imported, &args.out, &assets).map_err(CliError::Failed)?;
    // The written scene goes through the front end like any other.
    let loaded = super::load_scene(&super::SceneArgs {
        scene: args.out.clone(),
        sets: Vec::new(),
    })?;
    let m = &loaded.model;
    eprintln!(
        "imported {} pose(s), {} object(s), {} light(s){}{} into {} ({} note(s); they head the file)",
        m.poses.len(),
        m.objects.len(),
        m.lights.len(),
        if m.sun.is_some() { ", the sun" } else { "" },
        if m.water.is_some() { ", water" } else { "" },
        args.out.display(),
        imported.notes.len()
    );
    if args.verify {
        verify(args, m, &out_dir, &stem, blend)?;
    }
    Ok(())
}

/// `--verify`: the source against the imported scene ([`crate::import::verify`]).
fn verify(
    args: &Args,
    m: &crate::model::Model,
    out_dir: &std::path::Path,
    stem: &str,
    blend: bool,
) -> Result<(), CliError> {
    if !(args.tolerance.is_finite() && args.tolerance > 0.0) || args.verify_width == 0 {
        return Err(CliError::Usage(
            "--tolerance and --verify-width must be positive".into(),
        ));
    }
    let width = m.cameras.first().map(|c| c.width).unwrap_or(1).max(1);
    let scale = (args.verify_width as f64 / width as f64).min(1.0);
    // The same light transport in both: the water column's daylight is native-only.
    let traced = super::load_scene(&super::SceneArgs {
        scene: args.out.clone(),
        sets: crate::bench::parity::PARITY_SETS.map(String::from).to_vec(),
    })?
    .model;
    let model = super::common::apply_scale(traced, Some(scale))?;
    let work = out_dir.join(format!("{}_verify", crate::import::safe_file_name(stem)));
    std::fs::create_dir_all(&work)
        .map_err(|e| CliError::Failed(format!("{}: {e}", work.display())))?;
    use crate::import::verify::Source;
    let source = if blend {
        Source::Blender(&args.files[0])
    } else {
        Source::Mitsuba(&args.files[0])
    };
    let c = crate::import::verify::verify(source, &model, args.verify_samples, &work)
        .map_err(|e| CliError::Failed(format!("--verify: {e}")))?;
    let cam = &model.cameras[0];
    eprintln!(
        "verify: {} rendered by {} and the imported scene natively, {}×{} px, {} spp \
         (images in {})",
        args.files[0].display(),
        source.renderer(),
        cam.width,
        cam.height,
        args.verify_samples,
        work.display()
    );
    for l in c.lines() {
        eprintln!("{l}");
    }
    let worst = 100.0 * c.worst();
    if worst > args.tolerance {
        return Err(CliError::Failed(format!(
            "--verify: a channel's mean differs by {worst:.2} %, beyond the tolerance of {} %\n  \
             help: the notes at the top of the scene file list what was dropped or approximated",
            args.tolerance
        )));
    }
    eprintln!(
        "verify: ok, every channel within {} % (worst {worst:.2} %)",
        args.tolerance
    );
    Ok(())
}

fn absolute(p: &std::path::Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}
