//! `poser column`: solve the scene's water column ([`crate::optics::column`]) and write its
//! profiles (`column.json`, `column.csv`, `column.svg`, [`crate::column`]); prints the summary
//! `explain` shows.
use super::{CliError, SceneArgs};
use std::path::PathBuf;

/// The arguments of `poser column`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output folder (created).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Photons per channel (more: smaller errors, longer solve).
    #[arg(long)]
    pub photons: Option<usize>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let model = super::load_model(&args.scene)?;
    let mut input = model.column_input().map_err(|why| {
        CliError::Failed(format!(
            "{}: the water column does not apply: {why}",
            args.scene.scene.display()
        ))
    })?;
    if let Some(n) = args.photons {
        if n == 0 {
            return Err(CliError::Failed("--photons must be at least 1".into()));
        }
        input.photons = n;
    }
    let col = crate::optics::column::solve(&input)
        .map_err(|e| CliError::Failed(format!("{}: {e}", args.scene.scene.display())))?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::Failed(format!("{}: {e}", args.out.display())))?;
    let write = |name: &str, bytes: &[u8]| {
        let p = args.out.join(name);
        crate::io::write_atomic(&p, bytes)
            .map_err(|e| CliError::Failed(format!("{}: {e}", p.display())))
    };
    let doc = crate::column::json(&model, &input, &col);
    let text = serde_json::to_string_pretty(&doc).map_err(|e| CliError::Failed(e.to_string()))?;
    write("column.json", text.as_bytes())?;
    write("column.csv", crate::column::csv(&col).as_bytes())?;
    let svg = crate::column::svg(&col, &format!("{}: the water column's light", model.name))
        .map_err(CliError::Failed)?;
    write("column.svg", svg.as_bytes())?;
    println!(
        "water column of {} (seabed at {} m):",
        model.name, col.depth
    );
    for line in crate::column::summary(&col) {
        println!("{line}");
    }
    println!(
        "wrote column.json, column.csv, column.svg into {}",
        args.out.display()
    );
    Ok(())
}
