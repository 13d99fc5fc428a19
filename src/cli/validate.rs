//! `poser validate`: check scenes, print every diagnostic (errors and warnings) with
//! file:line:column, and a one-line verdict per scene. Exit 0 when all are valid, 1 when any
//! is invalid (or has warnings under `--deny-warnings`).
use super::CliError;
use std::path::PathBuf;

/// The arguments of `poser validate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene files.
    #[arg(required_unless_present = "explain")]
    pub scenes: Vec<PathBuf>,
    /// Print what a diagnostic code means, with an example (the error index, docs/errors.md).
    #[arg(long, value_name = "CODE")]
    pub explain: Option<String>,
    /// Override values in every scene (`KEY=VALUE`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Treat warnings as errors.
    #[arg(long)]
    pub deny_warnings: bool,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    if let Some(code) = &args.explain {
        return match crate::scene::diag::explain(code) {
            Some(text) => {
                println!("{text}");
                Ok(())
            }
            None => Err(CliError::Usage(format!(
                "no diagnostic code `{code}` (help: the codes are listed in docs/errors.md; a \
                 code is E or W and four digits, e.g. E0290)"
            ))),
        };
    }
    let (scenes, sets, deny_warnings) = (&args.scenes, &args.sets, args.deny_warnings);
    let mut bad = 0usize;
    for scene in scenes {
        let shown = crate::scene::source::display(scene);
        match crate::scene::load(scene, sets) {
            Ok(loaded) => {
                eprint!("{}", loaded.render_warnings());
                let w = loaded.warnings.len();
                if deny_warnings && w > 0 {
                    bad += 1;
                    eprintln!(
                        "error: {shown}: {w} warning{} (denied by --deny-warnings)",
                        plural(w)
                    );
                } else if w > 0 {
                    println!(
                        "ok: {shown} ({} images, {w} warning{})",
                        image_count(&loaded.model),
                        plural(w)
                    );
                } else {
                    println!("ok: {shown} ({} images)", image_count(&loaded.model));
                }
            }
            Err(failure) => {
                bad += 1;
                eprint!("{}", failure.render());
            }
        }
    }
    if bad > 0 {
        if scenes.len() > 1 {
            eprintln!("{bad} of {} scenes invalid", scenes.len());
        }
        Err(CliError::Invalid)
    } else {
        Ok(())
    }
}

fn image_count(m: &crate::model::Model) -> usize {
    m.poses.len() * m.cameras.len()
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}
