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

/// Apply `--crop` (after `--scale`): the rectangle must lie inside every camera's image.
pub fn apply_crop(model: &mut Model, crop: Option<crate::model::Crop>) -> Result<(), CliError> {
    let Some(c) = crop else { return Ok(()) };
    if let Some(cam) = model
        .cameras
        .iter()
        .find(|cam| !c.fits(cam.width, cam.height))
    {
        return Err(CliError::Usage(format!(
            "--crop {},{},{},{}: the rectangle leaves camera `{}`'s {}×{} image\n  help: X + W ≤ {} and Y + H ≤ {} (pixels of the image as rendered, after --scale)",
            c.x, c.y, c.width, c.height, cam.name, cam.width, cam.height, cam.width, cam.height
        )));
    }
    model.render.crop = Some(c);
    Ok(())
}

/// `--crop X,Y,W,H`: four whole numbers, the width and height at least 1.
pub fn parse_crop(s: &str) -> Result<crate::model::Crop, String> {
    let err = || format!("`{s}`: expected X,Y,W,H in whole pixels, e.g. `--crop 100,80,64,48`");
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| err())?;
    let [x, y, width, height] = v[..] else {
        return Err(err());
    };
    if width == 0 || height == 0 {
        return Err(format!(
            "`{s}`: the rectangle is empty (W and H must be at least 1)"
        ));
    }
    Ok(crate::model::Crop {
        x,
        y,
        width,
        height,
    })
}

/// `--samples N`: samples per pixel, at least one (a zero is refused, as `render.samples = 0`
/// is in a scene, instead of silently rendering one).
/// `--poses`: pose indices, counted from 0, as a comma-separated list of indices and
/// inclusive ranges (`0,3,5`, `0-9`, `0-4,10-14`), kept in the order given, repeats dropped.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseList(pub Vec<usize>);

pub fn parse_poses(s: &str) -> Result<PoseList, String> {
    let help = "help: give pose indices from 0, e.g. `--poses 0,3,5` or `--poses 0-9`";
    let index = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|_| format!("`{}` is not a pose index\n  {help}", t.trim()))
    };
    let mut out = Vec::new();
    for item in s.split(',') {
        let (a, b) = match item.split_once('-') {
            Some((a, b)) => (index(a)?, index(b)?),
            None => (index(item)?, index(item)?),
        };
        if b < a {
            return Err(format!(
                "`{}` is an empty range (it ends before it starts)\n  {help}",
                item.trim()
            ));
        }
        for i in a..=b {
            if !out.contains(&i) {
                out.push(i);
            }
        }
    }
    Ok(PoseList(out))
}

pub fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(0) => Err("at least one sample per pixel is needed\n  help: use e.g. `--samples 64`, or leave it out to use the scene's `render.samples`".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "`{s}` is not a whole number of samples per pixel\n  help: use e.g. `--samples 64`"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_lists_take_indices_and_ranges() {
        assert_eq!(parse_poses("0,3,5").unwrap().0, vec![0, 3, 5]);
        assert_eq!(parse_poses("0-3").unwrap().0, vec![0, 1, 2, 3]);
        assert_eq!(parse_poses("4, 0-2,1").unwrap().0, vec![4, 0, 1, 2]);
        assert_eq!(parse_poses("7-7").unwrap().0, vec![7]);
        let e = parse_poses("3-1").unwrap_err();
        assert!(e.contains("empty range") && e.contains("help:"), "{e}");
        let e = parse_poses("0-x").unwrap_err();
        assert!(e.contains("`x` is not a pose index"), "{e}");
        assert!(parse_poses("-1").is_err());
    }
}
