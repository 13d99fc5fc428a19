//! `poser slurm`: render a survey on a SLURM cluster, one array task per shard, and a merge job.
//!
//! | option | default | meaning |
//! |---|---|---|
//! | `--shards N` | required | array tasks; task I renders the poses whose index modulo N is I |
//! | `--partition P` | cluster's | `#SBATCH --partition` |
//! | `--time T` | none | `#SBATCH --time` (SLURM's format, e.g. `4:00:00`) |
//! | `--cpus C` | 2 | `#SBATCH --cpus-per-task`, and the renderer's threads |
//! | `--set`, `--scale`, `--samples`, `--sensor`, `--backend` | | passed to every task, as to `poser render` |
//! | `--poser PATH` | this executable | the poser the jobs run (it must be reachable from the compute nodes) |
//! | `--merge` | | what the merge job runs: the truth once, then `OUT/slurm/summary.json`; fails when an image is missing |
//!
//! The scripts go into `OUT/slurm/` ([`crate::slurm`]); submit them with `OUT/slurm/submit.sh`.
use super::{CliError, SceneArgs, load_model};
use crate::backend::Backend;
use crate::slurm::Job;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The arguments of `poser slurm`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output folder of the render (on a file system the compute nodes share).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Number of array tasks (shards).
    #[arg(long)]
    pub shards: usize,
    /// SLURM partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit of each task, SLURM's format (e.g. `4:00:00`).
    #[arg(long)]
    pub time: Option<String>,
    /// CPUs per task (the renderer's threads).
    #[arg(long, default_value_t = 2)]
    pub cpus: u32,
    #[arg(long, value_enum, default_value = "native")]
    pub backend: Backend,
    /// Override samples per pixel.
    #[arg(long, value_parser = super::common::parse_samples)]
    pub samples: Option<u32>,
    /// Render at this fraction of the cameras' resolution.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Run the default sensor stage when the scene has no `[sensor]`.
    #[arg(long)]
    pub sensor: bool,
    /// The poser executable the jobs run (default: this one).
    #[arg(long)]
    pub poser: Option<PathBuf>,
    /// Run by the merge job: write the truth and `OUT/slurm/summary.json`.
    #[arg(long)]
    pub merge: bool,
}

/// `OUT/slurm/summary.json`, written by the merge job.
#[derive(Debug, Serialize)]
pub struct Summary {
    pub format: &'static str,
    pub scene: String,
    pub shards: usize,
    pub images: usize,
    pub finished: usize,
    /// Images without a complete, unchanged record (native) or without their `.exr`.
    pub missing: Vec<String>,
}

fn absolute(p: &Path) -> Result<PathBuf, CliError> {
    std::path::absolute(p).map_err(|e| CliError::Failed(format!("{}: {e}", p.display())))
}

/// The arguments every task shares with the merge job, as `poser render` takes them.
fn shared_args(args: &Args) -> Vec<String> {
    let mut v = Vec::new();
    for s in &args.scene.sets {
        v.push("--set".to_string());
        v.push(s.clone());
    }
    if let Some(s) = args.scale {
        v.push("--scale".into());
        v.push(s.to_string());
    }
    if let Some(n) = args.samples {
        v.push("--samples".into());
        v.push(n.to_string());
    }
    if args.sensor {
        v.push("--sensor".into());
    }
    v.push("--backend".into());
    v.push(args.backend.name().to_string());
    v
}

pub fn run(args: &Args) -> Result<(), CliError> {
    if args.shards == 0 {
        return Err(CliError::Usage("--shards must be at least 1".into()));
    }
    // The scene is checked here, before anything is submitted.
    let model = super::common::apply_scale(load_model(&args.scene)?, args.scale)?;
    if args.merge {
        return merge(args, model);
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::Failed(format!("{}: {e}", args.out.display())))?;
    let poser = match &args.poser {
        Some(p) => absolute(p)?,
        None => std::env::current_exe().map_err(|e| CliError::Failed(e.to_string()))?,
    };
    let job = Job {
        poser,
        scene: absolute(&args.scene.scene)?,
        out: absolute(&args.out)?,
        shards: args.shards,
        partition: args.partition.clone(),
        time: args.time.clone(),
        cpus: args.cpus,
        args: shared_args(args),
        resume: args.backend == Backend::Native,
    };
    let files = crate::slurm::scripts(&job).map_err(CliError::Usage)?;
    let paths = crate::slurm::write(&job.out, files).map_err(CliError::Failed)?;
    let images = model.poses.len() * model.cameras.len();
    eprintln!(
        "wrote {} SLURM scripts into {}: {} task(s) over {images} image(s), then a merge job",
        paths.len(),
        job.out.join("slurm").display(),
        args.shards
    );
    eprintln!(
        "submit with: {}",
        crate::slurm::shell_quote(&job.out.join("slurm/submit.sh").to_string_lossy())
    );
    Ok(())
}

/// The merge job: the truth once, then which images are finished.
fn merge(args: &Args, mut model: crate::model::Model) -> Result<(), CliError> {
    if args.sensor && model.sensor.is_none() {
        model.sensor = Some(crate::model::Sensor::default());
    }
    let out = &args.out;
    crate::truth::write(&model, &out.join("truth")).map_err(CliError::Failed)?;
    let samples = args.samples.unwrap_or(model.render.samples).max(1);
    let manifest = crate::backend::native::resume::Manifest::open(
        out,
        &crate::backend::native::resume::fingerprint(&model, samples),
    );
    let mut missing = Vec::new();
    let mut images = 0;
    for p in 0..model.poses.len() {
        for c in 0..model.cameras.len() {
            let name = model.image_name(p, c);
            images += 1;
            let done = if args.backend == Backend::Native {
                manifest.is_done(out, &name)
            } else {
                out.join(format!("{name}.exr")).is_file()
            };
            if !done {
                missing.push(name);
            }
        }
    }
    let summary = Summary {
        format: "poser slurm summary 1",
        scene: args.scene.scene.to_string_lossy().into_owned(),
        shards: args.shards,
        images,
        finished: images - missing.len(),
        missing,
    };
    let path = out.join("slurm/summary.json");
    let json = serde_json::to_vec_pretty(&summary).map_err(|e| CliError::Failed(e.to_string()))?;
    crate::io::write_atomic(&path, &json)
        .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
    eprintln!(
        "merge: {} of {} image(s) finished; truth in {}",
        summary.finished,
        summary.images,
        out.join("truth").display()
    );
    if summary.missing.is_empty() {
        Ok(())
    } else {
        Err(CliError::Failed(format!(
            "{} image(s) missing (first: {}); rerun the array: the tasks resume",
            summary.missing.len(),
            summary.missing[0]
        )))
    }
}
