//! `poser lesson SCENE -o DIR`: run a lesson scene (one with a `[lesson]` table, see
//! `docs/lessons.md`) and write `DIR/index.html`, one self-contained page, with `lesson.json`
//! and each variant's own outputs in `DIR/<variant>/`.
//!
//! | option | default | meaning |
//! |---|---|---|
//! | `-o DIR` | required | output directory |
//! | `--full` | off | the full form (`lesson.full` overrides) instead of the quick one (`lesson.quick`) |
//! | `--set KEY=VALUE` | none | applied to every variant, after the form's and the variant's own |
//! | `--quiet` | off | no progress lines |
use super::{CliError, SceneArgs};
use crate::lesson::{self, Options, html};
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Arguments of `poser lesson`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory (index.html, lesson.json, one folder per variant).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Run the lesson's full form (documented in the scene) instead of its quick form.
    #[arg(long)]
    pub full: bool,
    /// No progress lines.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let opts = Options {
        full: args.full,
        sets: args.scene.sets.clone(),
    };
    let quiet = args.quiet;
    let progress = move |what: &str| {
        if !quiet {
            eprintln!("lesson: {what}");
        }
    };
    let report = match lesson::run(&args.scene.scene, &args.out, &opts, &progress) {
        Ok(r) => r,
        Err(e) => {
            // Scene errors come rendered (with their own `error:` lines); print them as is.
            if e.contains("error: the scene is invalid") {
                eprint!("{e}");
                return Err(CliError::Invalid);
            }
            return Err(CliError::Failed(e));
        }
    };
    html::write(&report, &args.out).map_err(CliError::Failed)?;
    eprintln!(
        "lesson `{}` ({} form) in {:.0} s: {}",
        report.title,
        report.form,
        report.seconds,
        args.out.join("index.html").display()
    );
    Ok(())
}
