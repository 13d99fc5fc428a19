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
    /// Unpack only if the pack is signed by this ed25519 public key (PEM, `KEY.pub` from
    /// `poser keygen`); repeatable: any of the keys.
    #[arg(long, value_name = "KEY")]
    pub trust: Vec<PathBuf>,
}

/// The public keys `--trust` names.
pub(super) fn trusted_keys(
    paths: &[PathBuf],
) -> Result<Vec<ed25519_dalek::VerifyingKey>, CliError> {
    paths
        .iter()
        .map(|p| pack::sign::read_verifying_key(p))
        .collect::<Result<_, _>>()
        .map_err(CliError::Usage)
}

pub fn run(args: &Args) -> Result<(), CliError> {
    pack::fresh_folder(&args.out).map_err(CliError::Usage)?;
    let trusted = trusted_keys(&args.trust)?;
    let checked = pack::read(&args.pack, &args.out, &trusted).map_err(CliError::Failed)?;
    let m = &checked.manifest;
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
    println!(
        "{}",
        pack::sign::judge(&checked.signed_by, &trusted).unwrap_or_default()
    );
    for d in m.versions.differences(&Versions::current()) {
        println!("version: {d}");
    }
    Ok(())
}
