//! `poser export`: the scene as a glTF 2.0 binary preview (`.glb`) for any glTF viewer.
use super::{CliError, SceneArgs, load_model};
use std::path::PathBuf;

/// The arguments of `poser export`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The `.glb` file to write (written atomically).
    #[arg(short, long)]
    pub out: PathBuf,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let model = load_model(&args.scene)?;
    let s = crate::export::gltf::write(&model, &args.out).map_err(CliError::Failed)?;
    let surface = match s.water_surface {
        Some(kind) => format!(", the water surface ({kind})"),
        None => String::new(),
    };
    eprintln!(
        "wrote {} ({:.1} MB): {} object mesh(es), {} target(s), {} port(s){surface}, {} triangles; \
         {} camera(s) ({} pose(s) × {} camera(s)); swim path of {} point(s); {} light(s)",
        args.out.display(),
        s.bytes as f64 / 1e6,
        s.objects,
        s.targets,
        s.ports,
        s.triangles,
        s.cameras,
        model.poses.len(),
        model.cameras.len(),
        s.path_points,
        s.lights,
    );
    if !s.approximated.is_empty() {
        eprintln!("approximated:");
        for a in &s.approximated {
            eprintln!("  {a}");
        }
    }
    Ok(())
}
