//! Headless Chromium for the lesson pages (Debian's `chromium`, installed by backends/setup.sh
//! when run as root): the DOM it builds, a screenshot's grey-level variance, a `data-key` cell,
//! and the check that a page references nothing outside itself.

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

/// The page holds no reference to anything outside itself.
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
