//! `poser lesson` pages in real headless Chromium (Debian's `chromium`, installed by
//! backends/setup.sh when run as root), and running a lesson's quick form: shared by the
//! lesson test files.
//!
//! | item | what |
//! |---|---|
//! | [`run_lesson`], [`run_lesson_with`], [`run_lesson_on_threads`] | `poser lesson SCENE` into a temporary folder (with `--set` overrides; on N threads); its `lesson.json` |
//! | [`check_page`] | the page is self-contained, shows its images, plots and try-next lines, and its screenshot is not blank; returns Chromium's DOM |
//! | [`cell`] | the text of a `data-key` cell of the DOM |
//! | [`dump_dom`], [`screenshot_variance`] | Chromium's DOM and the grey-level variance of its screenshot |

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn chromium() -> PathBuf {
    for name in ["chromium", "chromium-browser"] {
        if let Ok(o) = Command::new("which").arg(name).output()
            && o.status.success()
        {
            return PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
        }
    }
    panic!(
        "headless Chromium is missing\n  help: run backends/setup.sh as root (it runs \
         `apt-get install -y chromium`), or install Debian's `chromium` package"
    );
}

pub fn chromium_args(out: &Path) -> Vec<String> {
    vec![
        "--headless".into(),
        "--no-sandbox".into(),
        "--disable-gpu".into(),
        "--hide-scrollbars".into(),
        format!("--user-data-dir={}", out.join("chromium-profile").display()),
    ]
}

/// The DOM as Chromium built it.
pub fn dump_dom(page: &Path, out: &Path) -> String {
    let o = Command::new(chromium())
        .args(chromium_args(out))
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("run chromium");
    assert!(
        o.status.success(),
        "chromium --dump-dom failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A screenshot of the page; returns the variance of its grey levels (0..255).
pub fn screenshot_variance(page: &Path, out: &Path) -> f64 {
    let shot = out.join("screenshot.png");
    let o = Command::new(chromium())
        .args(chromium_args(out))
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--window-size=1200,1600")
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("run chromium");
    assert!(
        o.status.success() && shot.exists(),
        "chromium --screenshot failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let img = image::open(&shot).expect("read the screenshot").to_luma8();
    let n = img.pixels().len() as f64;
    let mean = img.pixels().map(|p| p[0] as f64).sum::<f64>() / n;
    img.pixels()
        .map(|p| (p[0] as f64 - mean).powi(2))
        .sum::<f64>()
        / n
}

/// The text of the `data-key` cell `key` in the DOM.
pub fn cell<'a>(dom: &'a str, key: &str) -> &'a str {
    let tag = format!("data-key=\"{key}\">");
    let i = dom
        .find(&tag)
        .unwrap_or_else(|| panic!("no cell `{key}` in the page"))
        + tag.len();
    let j = dom[i..].find('<').unwrap() + i;
    &dom[i..j]
}

pub fn run_lesson(scene: &str, name: &str) -> (tempfile::TempDir, PathBuf, serde_json::Value) {
    run_lesson_with(scene, name, &[])
}

/// [`run_lesson`] with `--set` overrides on top of the quick form.
pub fn run_lesson_with(
    scene: &str,
    name: &str,
    sets: &[&str],
) -> (tempfile::TempDir, PathBuf, serde_json::Value) {
    run_lesson_in(scene, name, sets, None)
}

/// [`run_lesson`] on a pool of `threads` threads (`RAYON_NUM_THREADS`).
pub fn run_lesson_on_threads(
    scene: &str,
    name: &str,
    threads: usize,
) -> (tempfile::TempDir, PathBuf, serde_json::Value) {
    run_lesson_in(scene, name, &[], Some(threads))
}

fn run_lesson_in(
    scene: &str,
    name: &str,
    sets: &[&str],
    threads: Option<usize>,
) -> (tempfile::TempDir, PathBuf, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join(name);
    let mut args = vec!["lesson", scene, "-o", out.to_str().unwrap(), "--quiet"];
    for s in sets {
        args.extend(["--set", s]);
    }
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_poser"));
    cmd.args(&args).current_dir(env!("CARGO_MANIFEST_DIR"));
    if let Some(n) = threads {
        cmd.env("RAYON_NUM_THREADS", n.to_string());
    }
    let o = cmd.output().expect("run poser");
    assert!(
        o.status.success(),
        "poser lesson {scene} failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lesson.json")).unwrap()).unwrap();
    (tmp, out, json)
}

pub fn rows(json: &serde_json::Value) -> &Vec<serde_json::Value> {
    json["results"]["rows"].as_array().unwrap()
}

pub fn row<'a>(json: &'a serde_json::Value, label: &str) -> &'a serde_json::Value {
    rows(json)
        .iter()
        .find(|r| r["label"] == label)
        .unwrap_or_else(|| panic!("no row `{label}`"))
}

pub fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

pub fn slug(label: &str) -> String {
    poser::lesson::slug(label)
}

/// The page is self-contained and shows its images, plots, and try-next lines.
pub fn check_page(out: &Path, json: &serde_json::Value) -> String {
    let page = out.join("index.html");
    let html = std::fs::read_to_string(&page).unwrap();
    for bad in [
        "src=\"http",
        "href=\"http",
        "url(",
        "<script",
        "src=\"/",
        "src=\"file:",
    ] {
        assert!(
            !html.contains(bad),
            "the page is not self-contained: `{bad}`"
        );
    }
    let dom = dump_dom(&page, out);
    let n = rows(json).len();
    assert!(
        dom.matches("src=\"data:image/png;base64,").count() >= n,
        "images missing"
    );
    assert!(dom.matches("<svg").count() >= n, "plots missing");
    for t in json["try_next"].as_array().unwrap() {
        let cmd = t["command"].as_str().unwrap();
        assert!(cmd.contains("--set"), "{cmd}");
    }
    assert!(dom.contains("Try next"));
    // Every shipped lesson opens with its answer in plain words.
    assert!(
        dom.contains("What this shows"),
        "no `What this shows` on the page"
    );
    let var = screenshot_variance(&page, out);
    assert!(
        var > 200.0,
        "the screenshot looks blank (grey-level variance {var:.1})"
    );
    dom
}
pub fn assert_self_contained(html: &str) {
    for bad in [
        "src=\"http",
        "href=\"http",
        "url(",
        "<script",
        "src=\"/",
        "src=\"file:",
    ] {
        assert!(
            !html.contains(bad),
            "the page is not self-contained: `{bad}`"
        );
    }
}
