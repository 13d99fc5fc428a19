//! The pinned Python environment that the Mitsuba and Blender backends run in.
//!
//! Lookup order for the interpreter: `$POSER_PYTHON`; the repository's `.venv` (created by
//! `backends/setup.sh` from `backends/requirements.txt`); `python3` on `PATH`.

use std::path::{Path, PathBuf};
use std::process::Command;

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
    let mut c = Command::new(interpreter());
    c.arg(script);
    c.env("PYTHONPATH", backends_dir());
    c.env("PYTHONDONTWRITEBYTECODE", "1");
    c
}

/// Check that a module can be imported; the error tells the user how to set the environment up.
pub fn require_module(module: &str) -> Result<(), String> {
    let py = interpreter();
    let ok = Command::new(&py)
        .args(["-c", &format!("import {module}")])
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
