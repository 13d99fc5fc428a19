//! `poser unpack`: check a reproducible pack (paths, entry types, sizes and compression ratio,
//! every hash, a scene that names nothing outside the pack) and write its files into a new or
//! empty folder that is not a link; a pack that fails a check writes nothing (`src/pack`).
use super::CliError;
use crate::pack::{self, Versions};
use std::path::PathBuf;

/// The arguments of `poser unpack`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The pack (`.poserpack`).
    pub pack: PathBuf,
    /// The folder to write its files into: new, or empty (not a link).
    #[arg(short, long)]
    pub out: PathBuf,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    pack::fresh_folder(&args.out).map_err(CliError::Usage)?;
    let m = pack::read(&args.pack, &args.out).map_err(CliError::Failed)?;
    println!(
        "unpacked {} file(s) into {}; the scene is {}",
        m.files.len(),
        args.out.display(),
        args.out.join(&m.scene).display()
    );
    if !m.sets.is_empty() {
        println!("with --set {}", m.sets.join(" --set "));
    }
    for c in &m.commands {
        println!("recorded: poser {}", c.argv.join(" "));
    }
    for d in m.versions.differences(&Versions::current()) {
        println!("version: {d}");
    }
    Ok(())
}
