//! `poser rerun`: unpack a reproducible pack, run its recorded commands again, and report file
//! by file whether the outputs have the recorded bytes, naming every version that differs from
//! the pack's (`src/pack`). Writes `OUT/pack/` (the scene), `OUT/outputs/<k>/` (what command
//! `k` wrote) and `OUT/rerun.json`; exits 1 when any output differs.
use super::CliError;
use crate::pack::{self, Verdict, Versions};
use serde::Serialize;
use std::path::PathBuf;

/// The arguments of `poser rerun`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The pack (`.poserpack`).
    pub pack: PathBuf,
    /// An empty (or new) folder for the scene, the outputs and the report.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Run the pack only if it is signed by this ed25519 public key (PEM, `KEY.pub` from
    /// `poser keygen`); an unsigned pack, or one signed by another key, is refused.
    /// Repeatable: any of the keys.
    #[arg(long, value_name = "KEY")]
    pub trust: Vec<PathBuf>,
}

#[derive(Serialize)]
struct Report {
    identical: bool,
    /// `unsigned`, or the signing key's fingerprint.
    signed_by: String,
    /// Whether the signing key was one of `--trust`'s.
    trusted: bool,
    version_differences: Vec<String>,
    commands: Vec<CommandReport>,
}

#[derive(Serialize)]
struct CommandReport {
    command: String,
    files: Vec<(String, Verdict)>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    // New or empty, and not a link (a rerun never writes through a link it did not create).
    pack::fresh_folder(&args.out).map_err(|e| {
        CliError::Usage(format!(
            "{e}; rerun into a new folder so that no earlier file is mistaken for an output"
        ))
    })?;
    let trusted = super::unpack::trusted_keys(&args.trust)?;
    let checked =
        pack::read(&args.pack, &args.out.join("pack"), &trusted).map_err(CliError::Failed)?;
    let signature = pack::sign::judge(&checked.signed_by, &trusted).unwrap_or_default();
    println!("{}: {signature}", args.pack.display());
    let m = &checked.manifest;
    let scene = args.out.join("pack").join(&m.scene);
    let mut commands = Vec::new();
    let _ = crate::backend::python::take_used();
    for (k, c) in m.commands.iter().enumerate() {
        let dir = args.out.join("outputs").join(k.to_string());
        eprintln!("rerun: `poser {}`", c.argv.join(" "));
        super::pack::run_recorded(&c.argv, &scene, &m.sets, &dir)?;
        let now = pack::hash_dir(&dir).map_err(CliError::Failed)?;
        commands.push(CommandReport {
            command: c.argv.join(" "),
            files: pack::compare(&c.outputs, &now),
        });
    }
    let identical = commands
        .iter()
        .all(|c| c.files.iter().all(|(_, v)| *v == Verdict::Identical));
    // The installed Python packages, asked where this rerun used Python (or, when the pack
    // recorded some, of the interpreter it would use).
    let mut now = Versions::current();
    let fallback = (!m.versions.installed.is_empty()).then(crate::backend::python::interpreter);
    let mut asked = Vec::new();
    match super::pack::installed_where_used(fallback) {
        Ok(v) => now.installed = v,
        Err(e) => asked.push(format!("installed Python packages not known here: {e}")),
    }
    let mut version_differences = m.versions.differences(&now);
    version_differences.extend(asked);
    let report = Report {
        identical,
        signed_by: match &checked.signed_by {
            pack::SignedBy::Unsigned => "unsigned".into(),
            pack::SignedBy::Signed(k) => pack::sign::fingerprint(k),
        },
        trusted: !trusted.is_empty(),
        version_differences,
        commands,
    };
    let json = serde_json::to_vec_pretty(&report).map_err(|e| CliError::Failed(e.to_string()))?;
    let path = args.out.join("rerun.json");
    crate::io::write_atomic(&path, &json)
        .map_err(|e| CliError::Failed(format!("{}: {e}", path.display())))?;
    for c in &report.commands {
        let count = |v: Verdict| c.files.iter().filter(|(_, x)| *x == v).count();
        println!(
            "poser {}: {} identical, {} differ, {} missing, {} new",
            c.command,
            count(Verdict::Identical),
            count(Verdict::Differs),
            count(Verdict::Missing),
            count(Verdict::New)
        );
        for (f, v) in c.files.iter().filter(|(_, v)| *v != Verdict::Identical) {
            println!("  {v:?}: {f}");
        }
    }
    for d in &report.version_differences {
        println!("version: {d}");
    }
    if identical {
        println!(
            "every output is byte-identical to the pack's ({})",
            path.display()
        );
        Ok(())
    } else {
        Err(CliError::Failed(format!(
            "the rerun's outputs differ from the pack's{}; see {}",
            if report.version_differences.is_empty() {
                " with the same versions".to_string()
            } else {
                format!(
                    " (versions differ: {})",
                    report.version_differences.join("; ")
                )
            },
            path.display()
        )))
    }
}
