//! SLURM job arrays for a survey's render: one array task per shard, then a dependent merge job
//! that writes the ground truth once and checks that every image is finished.
//!
//! `poser slurm SCENE -o OUT --shards N` writes, under `OUT/slurm/`:
//!
//! | file | content |
//! |---|---|
//! | `render.sbatch` | a job array `0..N-1`; task `I` runs `poser render SCENE -o OUT --shard I/N --resume --skip-truth` with `--cpus-per-task` threads |
//! | `merge.sbatch` | `poser slurm SCENE -o OUT --shards N --merge`: the truth, then `OUT/slurm/summary.json` (fails when an image is missing) |
//! | `submit.sh` | `sbatch` of the array, then of the merge job with `--dependency=afterok:<array>` |
//! | `logs/` | the jobs' standard output and error (`render-<job>_<task>.out`, `merge-<job>.out`) |
//!
//! The scripts hold data, never code from the scene: every path and `--set` value is quoted
//! for the shell ([`shell_quote`]), and the partition and time limit, which go on `#SBATCH`
//! lines, must match SLURM's own syntax ([`check_sbatch_value`]). The jobs run in `OUT/slurm/`
//! (where `submit.sh` changes to), so no user string appears unquoted in the scripts.
//!
//! Shards render into the same folder at once; the render manifest is updated under a lock
//! ([`crate::backend::native::resume`]), and a task that SLURM requeues resumes where it was
//! stopped. The union of the shards is byte-identical to one local run.

use std::path::{Path, PathBuf};

/// One survey render as a SLURM job array.
#[derive(Debug, Clone)]
pub struct Job {
    /// The poser executable the jobs run (absolute).
    pub poser: PathBuf,
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// The output folder (absolute).
    pub out: PathBuf,
    pub shards: usize,
    /// `--partition` (none: the cluster's default).
    pub partition: Option<String>,
    /// `--time`, SLURM's format (e.g. `2:00:00`, `1-12:00:00`).
    pub time: Option<String>,
    /// `--cpus-per-task`, also the renderer's thread count.
    pub cpus: u32,
    /// The arguments shared by the render tasks and the merge job (`--set`, `--scale`,
    /// `--samples`, `--sensor`, `--backend`), one per element, unquoted.
    pub args: Vec<String>,
    /// Whether the tasks pass `--resume` (the native backend's manifest).
    pub resume: bool,
}

/// `s` as one word for a POSIX shell: single-quoted, with `'` written as `'\''`.
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// A partition name or time limit for an `#SBATCH` line: letters, digits and `-_.:,` only
/// (SLURM's partition names and time formats need nothing else), so that it cannot add
/// another option or a line.
pub fn check_sbatch_value(what: &str, v: &str) -> Result<(), String> {
    if !v.is_empty()
        && v.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.:,".contains(c))
    {
        Ok(())
    } else {
        Err(format!(
            "{what} `{v}`: only letters, digits and `-_.:,` may go on an #SBATCH line"
        ))
    }
}

fn header(job: &Job, name: &str, output: &str, array: Option<usize>) -> String {
    let mut s = String::from("#!/bin/bash\n");
    s.push_str(&format!("#SBATCH --job-name={name}\n"));
    if let Some(n) = array {
        s.push_str(&format!("#SBATCH --array=0-{}\n", n - 1));
    }
    s.push_str(&format!("#SBATCH --cpus-per-task={}\n", job.cpus.max(1)));
    s.push_str("#SBATCH --ntasks=1\n");
    if let Some(p) = &job.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &job.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    s.push_str(&format!("#SBATCH --output=logs/{output}\n"));
    s.push_str("#SBATCH --requeue\n");
    s
}

fn command(job: &Job, sub: &str, tail: &[String]) -> String {
    let mut words = vec![
        shell_quote(&job.poser.to_string_lossy()),
        sub.to_string(),
        shell_quote(&job.scene.to_string_lossy()),
        "-o".into(),
        shell_quote(&job.out.to_string_lossy()),
    ];
    words.extend(job.args.iter().map(|a| shell_quote(a)));
    words.extend(tail.iter().cloned());
    words.join(" ")
}

/// The files of `OUT/slurm/` (name, content, executable).
pub fn scripts(job: &Job) -> Result<Vec<(&'static str, String, bool)>, String> {
    if job.shards == 0 {
        return Err("--shards must be at least 1".into());
    }
    if let Some(p) = &job.partition {
        check_sbatch_value("--partition", p)?;
    }
    if let Some(t) = &job.time {
        check_sbatch_value("--time", t)?;
    }
    for (what, p) in [
        ("poser", &job.poser),
        ("scene", &job.scene),
        ("output", &job.out),
    ] {
        if !p.is_absolute() {
            return Err(format!("{what} path {} is not absolute", p.display()));
        }
    }
    let n = job.shards;
    let threads = "export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-1}\"\n";
    let mut tail = vec![
        format!("--shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\""),
        "--skip-truth".into(),
        "--quiet".into(),
    ];
    if job.resume {
        tail.push("--resume".into());
    }
    let render = format!(
        "{}# Written by poser {}: task I renders shard I of {n} (the poses whose index modulo {n} is I).\nset -euo pipefail\n{threads}exec {}\n",
        header(job, "poser-render", "render-%A_%a.out", Some(n)),
        env!("CARGO_PKG_VERSION"),
        command(job, "render", &tail),
    );
    let merge = format!(
        "{}# Written by poser {}: after every shard, the ground truth once and OUT/slurm/summary.json.\nset -euo pipefail\n{threads}exec {}\n",
        header(job, "poser-merge", "merge-%j.out", None),
        env!("CARGO_PKG_VERSION"),
        command(job, "slurm", &[format!("--shards {n}"), "--merge".into()]),
    );
    let submit = "#!/bin/bash\n\
        # Submit the render array, then the merge job once every task has succeeded.\n\
        set -euo pipefail\n\
        cd \"$(dirname \"$0\")\"\n\
        mkdir -p logs\n\
        render=$(sbatch --parsable render.sbatch)\n\
        render=${render%%;*}\n\
        merge=$(sbatch --parsable --dependency=afterok:\"$render\" merge.sbatch)\n\
        merge=${merge%%;*}\n\
        echo \"submitted: render array $render, merge job $merge\"\n\
        echo \"$render $merge\" > jobs\n"
        .to_string();
    Ok(vec![
        ("render.sbatch", render, false),
        ("merge.sbatch", merge, false),
        ("submit.sh", submit, true),
    ])
}

/// Write `files` ([`scripts`]) into `OUT/slurm/` (atomically, the executable ones with mode
/// 755); their paths.
pub fn write(out: &Path, files: Vec<(&'static str, String, bool)>) -> Result<Vec<PathBuf>, String> {
    let dir = out.join("slurm");
    std::fs::create_dir_all(dir.join("logs")).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut paths = Vec::new();
    for (name, text, exec) in files {
        let path = dir.join(name);
        crate::io::write_atomic(&path, text.as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if exec {
            make_executable(&path)?;
        }
        paths.push(path);
    }
    Ok(paths)
}

#[cfg(unix)]
fn make_executable(path: &Path) -> Result<(), String> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(not(unix))]
fn make_executable(_: &Path) -> Result<(), String> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> Job {
        Job {
            poser: "/opt/poser bin/poser".into(),
            scene: "/data/it's a scene.toml".into(),
            out: "/scratch/out $(rm -rf ~)".into(),
            shards: 4,
            partition: Some("short".into()),
            time: Some("1-02:00:00".into()),
            cpus: 8,
            args: vec!["--set".into(), "network.name=\"a'b; rm\"".into()],
            resume: true,
        }
    }

    #[test]
    fn scripts_quote_every_user_string() {
        let s = scripts(&job()).unwrap();
        let render = &s[0].1;
        assert!(render.contains("#SBATCH --array=0-3\n"), "{render}");
        assert!(render.contains("#SBATCH --partition=short\n"));
        assert!(render.contains("#SBATCH --time=1-02:00:00\n"));
        assert!(render.contains("#SBATCH --cpus-per-task=8\n"));
        assert!(render.contains(r"'/data/it'\''s a scene.toml'"), "{render}");
        assert!(render.contains("'/scratch/out $(rm -rf ~)'"), "{render}");
        assert!(
            render.contains(r#"'network.name="a'\''b; rm"'"#),
            "{render}"
        );
        assert!(render.contains("--shard \"${SLURM_ARRAY_TASK_ID}/4\""));
        assert!(render.contains("--resume"));
        let merge = &s[1].1;
        assert!(merge.contains("--merge") && merge.contains("--shards 4"));
        assert!(!merge.contains("--array"));
        assert!(s[2].1.contains("--dependency=afterok:"));
        assert!(s[2].2);
    }

    #[test]
    fn sbatch_lines_refuse_options_and_newlines() {
        for bad in ["short\n#SBATCH --wrap=x", "a b", "", "p;q", "a\\b"] {
            let mut j = job();
            j.partition = Some(bad.into());
            assert!(scripts(&j).is_err(), "{bad:?}");
        }
        let mut j = job();
        j.time = Some("1:00:00 --mem=1".into());
        assert!(scripts(&j).is_err());
        let mut j = job();
        j.shards = 0;
        assert!(scripts(&j).is_err());
        let mut j = job();
        j.scene = "relative.toml".into();
        assert!(scripts(&j).is_err());
    }

    #[test]
    fn shell_quote_round_trips_through_sh() {
        let s = "a'b\"c $(x) `y` \\ \n z";
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!("printf %s {}", shell_quote(s)))
            .output()
            .unwrap();
        assert_eq!(String::from_utf8(out.stdout).unwrap(), s);
    }
}
