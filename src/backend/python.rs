//! The pinned Python environment that the Mitsuba and Blender backends run in.
//!
//! Lookup order for the interpreter: `$POSER_PYTHON`; the repository's `.venv` (created by
//! `backends/setup.sh` from `backends/requirements.txt`); `python3` on `PATH`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// The interpreters started in this process, so that `poser pack` and `poser rerun` can
/// record the packages installed where a run used Python ([`take_used`]).
static USED: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

fn mark_used(py: &Path) {
    USED.lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(py.to_path_buf());
}

/// The interpreters started (by [`command`] or [`require_module`]) since the last call, and
/// forget them.
pub fn take_used() -> Vec<PathBuf> {
    std::mem::take(&mut *USED.lock().unwrap_or_else(|e| e.into_inner()))
        .into_iter()
        .collect()
}

/// The Python distributions whose installed versions a pack records (the backends' packages;
/// OpenCV under each of its wheel names).
pub const RECORDED_PACKAGES: [&str; 8] = [
    "mitsuba",
    "bpy",
    "pycolmap",
    "numpy",
    "opencv-python-headless",
    "opencv-python",
    "opencv-contrib-python",
    "opencv-contrib-python-headless",
];

/// Ask `py` (with the backends' `PYTHONPATH`, as the backends run it) which of
/// [`RECORDED_PACKAGES`] are installed and at which version (`importlib.metadata`, the
/// version pip reports; nothing is imported), and its own version as `python`. Packages not
/// installed are left out.
pub fn installed_versions(py: &Path) -> Result<BTreeMap<String, String>, String> {
    let names = RECORDED_PACKAGES
        .iter()
        .map(|n| format!("{n:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    const SCRIPT: &str = r#"import json, sys
from importlib import metadata
out = {"python": "%d.%d.%d" % sys.version_info[:3]}
for d in [NAMES]:
    try:
        out[d] = metadata.version(d)
    except metadata.PackageNotFoundError:
        pass
print(json.dumps(out))
"#;
    let script = SCRIPT.replace("NAMES", &names);
    let out = Command::new(py)
        .args(["-c", &script])
        .env("PYTHONPATH", backends_dir())
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .map_err(|e| format!("cannot run {}: {e}", py.display()))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(format!(
            "{} could not list its packages: {}",
            py.display(),
            err.lines().last().unwrap_or("no message")
        ));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| {
        format!(
            "{} listed its packages in a form poser does not read ({e})",
            py.display()
        )
    })
}

/// Root of the poser source tree (where `backends/` lives).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Directory of the Python back-end sources (`backends/`).
pub fn backends_dir() -> PathBuf {
    repo_root().join("backends")
}

/// The Python interpreter to use.
pub fn interpreter() -> PathBuf {
    if let Some(p) = std::env::var_os("POSER_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = repo_root().join(".venv/bin/python");
    if venv.exists() {
        return venv;
    }
    PathBuf::from("python3")
}

/// A `Command` running `script` with the pinned interpreter, with `backends/` on `PYTHONPATH`.
pub fn command(script: &Path) -> Command {
    let py = interpreter();
    mark_used(&py);
    let mut c = Command::new(py);
    c.arg(script);
    c.env("PYTHONPATH", backends_dir());
    c.env("PYTHONDONTWRITEBYTECODE", "1");
    c
}

/// Check that a module is installed; the error tells the user how to set the environment up.
/// The module is found (`importlib.util.find_spec`), not imported: importing `bpy` takes
/// seconds, and every render and import checked it before starting the script that imports it
/// anyway (a module that is installed but fails to import fails there, with its traceback).
pub fn require_module(module: &str) -> Result<(), String> {
    let py = interpreter();
    mark_used(&py);
    let ok = Command::new(&py)
        .args([
            "-c",
            &format!(
                "import importlib.util, sys\nsys.exit(importlib.util.find_spec({module:?}) is None)"
            ),
        ])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if ok {
        Ok(())
    } else {
        Err(format!(
            "Python module `{module}` is not available to {}\n  help: run `backends/setup.sh` \
             (creates .venv with the pinned packages) or set POSER_PYTHON",
            py.display()
        ))
    }
}

/// Write an embedded Python script (its source compiled into the binary, so an installed
/// `poser` needs no source tree) into the scratch directory `work`; returns its path.
pub fn embedded_script(work: &Path, name: &str, source: &str) -> Result<PathBuf, String> {
    let p = work.join(name);
    crate::io::write_atomic(&p, source.as_bytes()).map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

/// Paths of the request and the result a [`run_json`] call for script `name` uses in `work`.
pub fn json_paths(work: &Path, name: &str) -> (PathBuf, PathBuf) {
    let stem = name.trim_end_matches(".py");
    (
        work.join(format!("{stem}.request.json")),
        work.join(format!("{stem}.result.json")),
    )
}

/// Run an embedded JSON-in, JSON-out script (`script.py REQUEST RESULT`) in the pinned
/// environment: write `req`, run, read the result. A failure is reported as `what failed: …`
/// with the script's last `error: ` line, or the tail of its stderr.
pub fn run_json<T: serde::de::DeserializeOwned>(
    work: &Path,
    name: &str,
    source: &str,
    req: &impl serde::Serialize,
    what: &str,
) -> Result<T, String> {
    let (req_path, res_path) = json_paths(work, name);
    let bytes = serde_json::to_vec(req).map_err(|e| e.to_string())?;
    crate::io::write_atomic(&req_path, &bytes)
        .map_err(|e| format!("{}: {e}", req_path.display()))?;
    let script = embedded_script(work, name, source)?;
    let out = command(&script)
        .arg(&req_path)
        .arg(&res_path)
        .output()
        .map_err(|e| {
            format!(
                "cannot run {}: {e}\n  help: run `backends/setup.sh` or set POSER_PYTHON",
                interpreter().display()
            )
        })?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let msg = err
            .lines()
            .rev()
            .find(|l| l.starts_with("error: "))
            .map(|l| l.trim_start_matches("error: ").to_string())
            .unwrap_or_else(|| {
                let tail: Vec<&str> = err.lines().rev().take(12).collect();
                tail.into_iter().rev().collect::<Vec<_>>().join("\n")
            });
        return Err(format!("{what} failed: {msg}"));
    }
    let text = std::fs::read(&res_path).map_err(|e| format!("{}: {e}", res_path.display()))?;
    serde_json::from_slice(&text).map_err(|e| format!("{}: {e}", res_path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in interpreter: a shell script that prints `stdout` and exits with `code`.
    #[cfg(unix)]
    fn fake(dir: &Path, name: &str, stdout: &str, code: i32) -> PathBuf {
        use std::os::unix::fs::PermissionsExt;
        let p = dir.join(name);
        std::fs::write(
            &p,
            format!("#!/bin/sh\ncat <<'EOF'\n{stdout}\nEOF\necho oops >&2\nexit {code}\n"),
        )
        .unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
        p
    }

    #[cfg(unix)]
    #[test]
    fn installed_versions_are_read_from_the_interpreter() {
        let d = tempfile::tempdir().unwrap();
        let ok = fake(
            d.path(),
            "ok",
            r#"{"python": "3.11.2", "mitsuba": "3.8.0", "numpy": "1.26.4"}"#,
            0,
        );
        let v = installed_versions(&ok).unwrap();
        assert_eq!(v["mitsuba"], "3.8.0");
        assert_eq!(v.len(), 3);
        let bad = fake(d.path(), "bad", "", 1);
        let e = installed_versions(&bad).unwrap_err();
        assert!(e.contains("could not list its packages: oops"), "{e}");
        let junk = fake(d.path(), "junk", "hello", 0);
        assert!(installed_versions(&junk).is_err());
        assert!(
            installed_versions(&d.path().join("missing"))
                .unwrap_err()
                .starts_with("cannot run")
        );
    }

    #[test]
    fn starting_python_is_remembered_until_taken() {
        let _ = take_used();
        let _ = command(Path::new("x.py"));
        // Other tests may start Python meanwhile: only this one's interpreter is certain.
        assert!(take_used().contains(&interpreter()));
    }
}
