//! `poser pack`: one reproducible archive of a scene (its file, includes and assets), the
//! commands run on it and the SHA-256 of what they wrote, with poser's version and commit and
//! the pinned backend versions (`src/pack`, docs/packs.md).
use super::{CliError, Command, SceneArgs, load_scene};
use crate::pack::{self, Manifest, Versions};
use clap::Parser;
use std::path::{Path, PathBuf};

/// The arguments of `poser pack`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The pack to write (e.g. `experiment.poserpack`).
    #[arg(short, long)]
    pub out: PathBuf,
    /// A command to run now and record with the hashes of its outputs, e.g.
    /// `--run "render --scale 0.25 --samples 8"` (`render`, `truth` or `compile`; arguments
    /// separated by spaces; the scene, the `--set`s and the output folder are supplied).
    /// Repeatable.
    #[arg(long = "run", value_name = "COMMAND")]
    pub runs: Vec<String>,
    /// Put the outputs themselves into the pack too (default: only their hashes).
    #[arg(long)]
    pub outputs: bool,
    /// Sign the pack with this ed25519 private key (PKCS #8 PEM, from `poser keygen` or
    /// `openssl genpkey -algorithm ed25519`); a reader checks it with `--trust KEY.pub`.
    #[arg(long, value_name = "KEY")]
    pub sign: Option<PathBuf>,
}

/// Run a recorded command on `scene` with `sets`, writing into `out`.
pub(super) fn run_recorded(
    argv: &[String],
    scene: &Path,
    sets: &[String],
    out: &Path,
) -> Result<(), CliError> {
    pack::check_command(argv).map_err(CliError::Usage)?;
    let mut full: Vec<String> = vec!["poser".into(), argv[0].clone()];
    full.push(scene.display().to_string());
    for s in sets {
        full.push("--set".into());
        full.push(s.clone());
    }
    full.push("-o".into());
    full.push(out.display().to_string());
    full.extend(argv[1..].iter().cloned());
    let cli = super::Cli::try_parse_from(&full)
        .map_err(|e| CliError::Usage(format!("`{}`: {e}", argv.join(" "))))?;
    match cli.command {
        c @ (Command::Render(_) | Command::Truth(_) | Command::Compile(_)) => super::dispatch(c),
        _ => Err(CliError::Usage(format!(
            "`{}`: a pack records only {}",
            argv[0],
            pack::COMMANDS.join(", ")
        ))),
    }
}

/// The Python packages installed where the commands just run used Python (the interpreter they
/// started), or, with `fallback`, where they would have; empty when none did.
pub(super) fn installed_where_used(
    fallback: Option<std::path::PathBuf>,
) -> Result<std::collections::BTreeMap<String, String>, String> {
    use crate::backend::python;
    let Some(py) = python::take_used().into_iter().next().or(fallback) else {
        return Ok(Default::default());
    };
    let v = python::installed_versions(&py)?;
    eprintln!(
        "Python used by the commands ({}): {}",
        py.display(),
        v.iter()
            .map(|(n, v)| format!("{n} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(v)
}

pub fn run(args: &Args) -> Result<(), CliError> {
    // The key first: a wrong key file should not cost the commands' run time.
    let key = args
        .sign
        .as_deref()
        .map(pack::sign::read_signing_key)
        .transpose()
        .map_err(CliError::Usage)?;
    let loaded = load_scene(&args.scene)?;
    for f in &loaded.files {
        if f.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
        {
            return Err(CliError::Failed(format!(
                "{}: a `.gltf` may refer to files beside it, which a pack does not follow\n  help: export the mesh as one binary `.glb` (e.g. from Blender) and name that in the scene",
                f.display()
            )));
        }
    }
    let entries = pack::scene_entries(&loaded.files).map_err(CliError::Failed)?;
    let commands: Vec<Vec<String>> = args
        .runs
        .iter()
        .map(|r| r.split_whitespace().map(String::from).collect())
        .collect();
    for c in &commands {
        pack::check_command(c).map_err(CliError::Usage)?;
    }
    // Run every command on a staged copy laid out as `poser rerun` lays it out, so that what
    // is recorded is what a rerun of this pack produces.
    let work = tempfile::tempdir().map_err(|e| CliError::Failed(e.to_string()))?;
    for (file, rel) in &entries {
        let dst = work.path().join("pack").join(rel);
        std::fs::create_dir_all(dst.parent().unwrap())
            .and_then(|_| std::fs::copy(file, &dst))
            .map_err(|e| CliError::Failed(format!("{}: {e}", dst.display())))?;
    }
    let scene = work.path().join("pack").join(&entries[0].1);
    // Packed, the scene must read only packed files: an absolute include, or a `..` or link
    // that leaves the packed folder, would read the packer's own files on every rerun.
    if let Err(f) = crate::scene::load_within(
        &scene,
        &args.scene.sets,
        &work.path().join("pack").join(pack::SCENE_DIR),
    ) {
        let prefix = format!("{}/", work.path().join("pack").display());
        let outside: String = f
            .diagnostics
            .iter()
            .filter(|d| d.code == "E0012")
            .map(|d| d.rendered.replace(&prefix, ""))
            .collect();
        if !outside.is_empty() {
            return Err(CliError::Failed(format!(
                "the scene names files a pack cannot hold as they are named:\n{}",
                outside.trim_end()
            )));
        }
    }
    let mut recorded = Vec::new();
    let mut dirs = Vec::new();
    let _ = crate::backend::python::take_used();
    for (k, argv) in commands.iter().enumerate() {
        let dir = work.path().join("outputs").join(k.to_string());
        eprintln!("pack: running `poser {}`", argv.join(" "));
        run_recorded(argv, &scene, &args.scene.sets, &dir)?;
        let outputs = pack::hash_dir(&dir).map_err(CliError::Failed)?;
        recorded.push(pack::Command {
            argv: argv.clone(),
            outputs,
        });
        dirs.push(dir);
    }
    let mut versions = Versions::current();
    versions.installed = installed_where_used(None).map_err(CliError::Failed)?;
    for n in versions.unpinned() {
        eprintln!(
            "pack: note: {n} (backends/requirements.txt); a rerun compares with the installed version"
        );
    }
    let mut manifest = Manifest {
        format: pack::FORMAT.into(),
        versions,
        scene: entries[0].1.clone(),
        sets: args.scene.sets.clone(),
        commands: recorded,
        files: Vec::new(),
        outputs_included: args.outputs,
    };
    pack::write(&args.out, &mut manifest, &entries, &dirs, key.as_ref())
        .map_err(CliError::Failed)?;
    let outputs: usize = manifest.commands.iter().map(|c| c.outputs.len()).sum();
    eprintln!(
        "wrote {}: {} scene file(s), {} command(s), {} output hash(es){}; poser {} ({})",
        args.out.display(),
        entries.len(),
        manifest.commands.len(),
        outputs,
        if args.outputs {
            ", outputs included"
        } else {
            ""
        },
        manifest.versions.poser,
        manifest.versions.commit
    );
    match &key {
        Some(k) => eprintln!(
            "signed with key {}",
            pack::sign::fingerprint(&k.verifying_key())
        ),
        None => eprintln!("unsigned (sign with --sign KEY; make a key with `poser keygen`)"),
    }
    Ok(())
}
