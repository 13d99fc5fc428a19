//! `poser bench render` run as a user runs it: the quick bench into a temporary folder holding a
//! README copy, with the report, plot and README block checked on the way.

use poser::bench::render::{README_BEGIN, README_END, Report};
use std::process::Command;

pub fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}

/// Run the quick bench on the scenes matching `only` with `backends`, into a temporary folder
/// holding a README copy; returns the folder and the parsed report.
pub fn bench(only: &str, backends: &str) -> (tempfile::TempDir, Report) {
    let dir = tempfile::tempdir().unwrap();
    let readme = dir.path().join("README.md");
    std::fs::write(
        &readme,
        format!("# x\n\nbefore\n\n{README_BEGIN}\nstale\n{README_END}\n\nafter\n"),
    )
    .unwrap();
    let json = dir.path().join("render.json");
    let svg = dir.path().join("render.svg");
    let out = poser()
        .args(["bench", "render", "--quick", "--only", only, "--backends"])
        .arg(backends)
        .arg("--json")
        .arg(&json)
        .arg("--plot")
        .arg(&svg)
        .arg("--readme")
        .arg(&readme)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Report = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The printed report is the one in the JSON.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.trim_end(), report.to_markdown().trim_end());
    // The README's block, and only it, was replaced.
    let text = std::fs::read_to_string(&readme).unwrap();
    assert!(
        text.starts_with("# x\n\nbefore\n\n") && text.ends_with("\n\nafter\n"),
        "{text}"
    );
    assert!(text.contains(&report.readme_block()) && !text.contains("stale"));
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(
        plot.starts_with("<svg") && plot.contains(only),
        "{plot:.200}"
    );
    (dir, report)
}
