//! `poser evaluate --mode images` renders into `OUT/images.partial/` and renames it to
//! `OUT/images/` only when the set is finished; a run cut short is resumed; without a terminal
//! the render's progress comes as plain lines with the time left. No Python: COLMAP's step
//! fails after the images are in place (`POSER_PYTHON` names no interpreter).

use std::path::Path;
use std::process::{Command, Output};

const SCENE: &str = "scenarios/reef_strip.toml";
/// A small network of small images, rendered in a second or two.
const SMALL: [&str; 8] = [
    "--scale",
    "0.05",
    "--samples",
    "1",
    "--set",
    "network.length=3",
    "--set",
    "network.width=2",
];

fn evaluate(out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["evaluate", SCENE, "--mode", "images"])
        .args(SMALL)
        .arg("-o")
        .arg(out)
        .env("POSER_PYTHON", "/nonexistent/python3")
        .output()
        .unwrap()
}

fn pngs(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    v.sort();
    v
}

#[test]
fn the_images_folder_appears_only_when_finished_and_a_cut_run_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ev");
    // A run cut short after its first image: what `poser render` leaves for pose 0 alone, in
    // the folder the evaluation renders into.
    let partial = out.join("images.partial");
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["render", SCENE, "--poses", "0", "--quiet"])
        .args(SMALL)
        .arg("-o")
        .arg(&partial)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(pngs(&partial).len(), 1);
    // An earlier run's finished folder, replaced whole.
    std::fs::create_dir_all(out.join("images")).unwrap();
    std::fs::write(out.join("images/stale.png"), b"old").unwrap();

    let o = evaluate(&out);
    let err = String::from_utf8_lossy(&o.stderr);
    // COLMAP cannot run here: the evaluation fails after the render, naming the interpreter.
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("/nonexistent/python3"), "{err}");
    // The image pose 0 already had is kept, the others are rendered.
    let total: usize = err
        .lines()
        .find_map(|l| l.strip_prefix("resume: 1 of "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no resume line: {err}"));
    assert!(total > 1, "{err}");
    assert!(
        !partial.exists(),
        "the finished render is renamed into place"
    );
    let names = pngs(&out.join("images"));
    assert_eq!(names.len(), total, "{names:?}");
    assert!(!names.contains(&"stale.png".to_string()), "{names:?}");
    assert!(!out.join("images.old").exists());

    // Stderr is not a terminal here: progress comes as plain lines, each tenth of the rows,
    // with the time left, and a closing line.
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("rendering")).collect();
    assert!(lines.len() >= 3, "{err}");
    assert!(
        lines
            .iter()
            .any(|l| l.contains(" rows (") && l.contains("left")),
        "{err}"
    );
    assert!(
        lines.last().unwrap().starts_with("rendering: done, "),
        "{err}"
    );
}

#[test]
fn quiet_prints_no_progress() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("q");
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["render", SCENE, "--quiet", "--poses", "0"])
        .args(SMALL)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(!err.lines().any(|l| l.starts_with("rendering")), "{err}");
}
