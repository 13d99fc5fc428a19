//! What every subcommand shares: the error type that maps to exit codes, and loading a scene
//! with its diagnostics printed.

use super::SceneArgs;
use crate::model::Model;
use std::process::ExitCode;

#[derive(Debug)]
pub enum CliError {
    /// The scene is invalid; its diagnostics were already printed. Exit 1.
    Invalid,
    /// The command line is wrong. Exit 2.
    Usage(String),
    /// The run failed (I/O, renderer, …). Exit 1.
    Failed(String),
}

impl CliError {
    pub fn report(self) -> ExitCode {
        match self {
            CliError::Invalid => ExitCode::from(1),
            CliError::Usage(m) => {
                eprintln!("error: {m}");
                ExitCode::from(2)
            }
            CliError::Failed(m) => {
                eprintln!("error: {m}");
                ExitCode::from(1)
            }
        }
    }
}

impl From<String> for CliError {
    fn from(s: String) -> Self {
        CliError::Failed(s)
    }
}

/// Load, validate and resolve a scene; print its diagnostics (warnings too) to stderr.
pub fn load_model(args: &SceneArgs) -> Result<Model, CliError> {
    load_scene(args).map(|l| l.model)
}

/// [`load_model`], keeping the list of files the scene was read from.
pub fn load_scene(args: &SceneArgs) -> Result<crate::scene::Loaded, CliError> {
    match crate::scene::load(&args.scene, &args.sets) {
        Ok(loaded) => {
            if !loaded.warnings.is_empty() {
                eprint!("{}", loaded.render_warnings());
            }
            Ok(loaded)
        }
        Err(failure) => {
            eprint!("{}", failure.render());
            Err(CliError::Invalid)
        }
    }
}

/// Apply `--scale` (a preview at a fraction of the cameras' resolution, same field of view),
/// checking the factor.
pub fn apply_scale(model: Model, scale: Option<f64>) -> Result<Model, CliError> {
    match scale {
        None => Ok(model),
        Some(s) => model
            .with_checked_resolution_scale(s)
            .map_err(|e| CliError::Usage(format!("--{e}"))),
    }
}

/// `--samples N`: samples per pixel, at least one (a zero is refused, as `render.samples = 0`
/// is in a scene, instead of silently rendering one).
pub fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(0) => Err("at least one sample per pixel is needed\n  help: use e.g. `--samples 64`, or leave it out to use the scene's `render.samples`".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "`{s}` is not a whole number of samples per pixel\n  help: use e.g. `--samples 64`"
        )),
    }
}
