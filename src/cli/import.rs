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
        crate::import::mitsuba::import(&args.files, &rel)
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
    Ok(())
}

fn absolute(p: &std::path::Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}
