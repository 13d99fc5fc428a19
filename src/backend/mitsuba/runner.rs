//! `poser render --backend mitsuba`: compile into `out/mitsuba/`, write the embedded Python
//! driver ([`DRIVER_SOURCE`], `backends/mitsuba/render.py`) beside the compiled scene, run it
//! with the pinned interpreter ([`crate::backend::python`]) and follow its progress lines
//! (`progress DONE TOTAL IMAGE`, `image FILE`) on a progress bar; the report lists the images.

use super::{ViewJob, build, write};
use crate::backend::{RenderOptions, RenderReport, python};
use crate::model::Model;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::Stdio;

/// The Python render driver's source (`backends/mitsuba/render.py`), embedded in the binary so
/// that an installed `poser` does not need the source tree.
pub const DRIVER_SOURCE: &str = include_str!("../../../backends/mitsuba/render.py");

/// File name of the driver written beside the compiled scene by `render`.
pub const DRIVER_FILE: &str = "render.py";

/// Write the embedded render driver into the compiled directory; returns its path.
pub fn write_driver(scene_dir: &Path) -> Result<PathBuf, String> {
    let p = scene_dir.join(DRIVER_FILE);
    crate::io::write_atomic(&p, DRIVER_SOURCE.as_bytes())
        .map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

/// `poser render --backend mitsuba`.
pub fn render(model: &Model, out: &Path, opts: &RenderOptions) -> Result<RenderReport, String> {
    let t0 = std::time::Instant::now();
    python::require_module("mitsuba")?;
    let mut model = model.clone();
    if let Some(s) = opts.samples {
        model.render.samples = s.max(1);
    }
    let compiled = build(&model)?;
    let scene_dir = out.join("mitsuba");
    write(&compiled, &scene_dir)?;
    let poses = opts.pose_indices(model.poses.len());
    let selected: Vec<&ViewJob> = compiled
        .manifest
        .views
        .iter()
        .filter(|v| poses.contains(&v.pose))
        .collect();
    let total: usize = selected.iter().map(|v| v.passes.len()).sum();

    let driver = write_driver(&scene_dir)?;
    let mut cmd = python::command(&driver);
    cmd.arg("--scene-dir").arg(&scene_dir).arg("--out").arg(out);
    cmd.arg("--poses").arg(
        poses
            .iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>()
            .join(","),
    );
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .stdin(Stdio::null());
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("cannot run {}: {e}", python::interpreter().display()))?;
    let mut stderr = child.stderr.take().expect("piped stderr");
    let err_thread = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let bar = crate::progress::Progress::new(opts.progress, "mitsuba", "passes", total as u64);
    let mut images = Vec::new();
    if let Some(stdout) = child.stdout.take() {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            let mut it = line.split_whitespace();
            match it.next() {
                Some("progress") => {
                    let done: u64 = it.next().and_then(|s| s.parse().ok()).unwrap_or(0);
                    let _total = it.next();
                    bar.set_item(it.next().unwrap_or(""));
                    bar.set_position(done);
                }
                Some("image") => {
                    if let Some(p) = it.next() {
                        images.push(PathBuf::from(p));
                    }
                }
                _ => {}
            }
        }
    }
    let status = child.wait().map_err(|e| e.to_string())?;
    bar.finish();
    let err = err_thread.join().unwrap_or_default();
    if !status.success() {
        let tail: Vec<&str> = err.lines().rev().take(15).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(format!(
            "the Mitsuba render driver failed ({status}):\n{}\n  help: the compiled scene is in {}",
            tail.join("\n"),
            scene_dir.display()
        ));
    }
    // Images are listed by the driver as file names relative to `out`.
    let images: Vec<PathBuf> = images.into_iter().map(|p| out.join(p)).collect();
    Ok(RenderReport {
        images,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
