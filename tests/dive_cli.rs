//! `poser dive` end to end through the built binary: the per-cylinder verdict, the one default
//! GF, the PNG plot, what the paper scene models, and a quiet exit on a closed pipe.
use std::process::{Command, Output, Stdio};

fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}
fn scene(name: &str) -> String {
    format!("{}/scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}
fn dive(name: &str, sets: &[&str]) -> (String, Output) {
    let mut c = poser();
    c.arg("dive").arg(scene(name));
    for s in sets {
        c.arg("--set").arg(s);
    }
    let out = c.output().unwrap();
    (String::from_utf8_lossy(&out.stdout).to_string(), out)
}

#[test]
fn pure_oxygen_bottom_gas_is_not_ok() {
    // The issue's case: 24 l of O₂ breathed at 15 m (pO₂ ≈ 2.5 bar) was "Verdict: OK".
    let (text, out) = dive(
        "paper_survey",
        &[
            "diver.cylinders.0.gas=\"O2\"",
            "diver.cylinders.0.volume=\"24 l\"",
            "network.strips=2",
            "network.width=2",
            "network.length=30",
        ],
    );
    assert!(out.status.success(), "{text}");
    assert!(!text.contains("Verdict: OK"), "{text}");
    assert!(text.contains("Verdict: NOT SAFE AS PLANNED"), "{text}");
    assert!(
        text.contains("gas unfit to breathe in '12 l air' (O₂)"),
        "{text}"
    );
    assert!(text.contains("pO₂ 2.53 bar at 15.0 m"), "{text}");
}

#[test]
fn oxygen_stage_is_not_pooled_with_the_back_gas() {
    // The issue's case: an 11 l O₂ cylinder added to a dive short of gas made it "enough gas".
    let two = "diver.cylinders=[{name = \"12 l air\", volume = \"12 l\", pressure = \"200 bar\", \
               gas = \"air\"}, {name = \"O2 deco\", volume = \"11 l\", pressure = \"200 bar\", \
               gas = \"O2\"}]";
    // Ten strips (51:50 at 15 m, ≈ 2760 l): more than the back gas holds above its reserve, less
    // than both cylinders pooled — the pooled check called this "enough gas".
    let (text, out) = dive(
        "paper_survey",
        &[two, "network.strips=10", "network.width=\"18 m\""],
    );
    assert!(out.status.success(), "{text}");
    assert!(text.contains("Verdict: NOT SAFE AS PLANNED"), "{text}");
    assert!(
        text.contains("not enough gas in '12 l air' (air)"),
        "the verdict names the cylinder: {text}"
    );
    assert!(text.contains("'O2 deco' O₂ (deco from 5 m"), "{text}");
    assert!(!text.contains("enough gas\n"), "{text}");
}

#[test]
fn one_default_gradient_factor() {
    // Without [diver] and with a [diver] that gives no GF: both Subsurface's 30/75.
    let (none, _) = dive("calibration_flat", &[]);
    let (partial, _) = dive("calibration_flat", &["diver.sac=\"20 l/min\""]);
    for t in [&none, &partial] {
        assert!(t.contains("GF 30/75"), "{t}");
    }
    // The defaults line credits Subsurface only with what is Subsurface's.
    assert!(!none.contains("Subsurface's defaults are used"), "{none}");
    assert!(none.contains("poser's 50 bar reserve"), "{none}");
    assert!(none.contains("sea water (1030 kg/m³)"), "{none}");
}

#[test]
fn paper_scene_states_what_it_models() {
    let (text, out) = dive("paper_survey", &[]);
    assert!(out.status.success());
    assert!(
        text.contains("1093 m of path at 0.176 m/s → 103:32 at depth"),
        "{text}"
    );
}

#[test]
fn png_plot_is_written() {
    let d = tempfile::tempdir().unwrap();
    let png = d.path().join("dive.png");
    let out = poser()
        .args(["dive", &scene("paper_survey"), "--plot"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (960, 540));
    // Text was drawn: the caption row holds dark glyph pixels on the white background.
    let dark = (0..960)
        .flat_map(|x| (5..30).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&c| c < 100))
        .count();
    assert!(dark > 50, "caption pixels: {dark}");
    // The depth line (blue) is there.
    assert!(img.pixels().any(|p| p.0 == [20, 80, 200]));
}

#[test]
fn closed_pipe_exits_quietly() {
    // `poser dive … --json | head` must not panic with "Broken pipe".
    let mut child = poser()
        .args(["dive", &scene("paper_survey"), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{err}"
    );
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        assert!(
            out.status.success() || out.status.signal() == Some(libc::SIGPIPE),
            "{:?}",
            out.status
        );
    }
}

#[test]
fn readme_two_gas_example_is_the_tools_output() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let cmd = "$ poser dive scenarios/two_gas_dive.toml\n";
    let start = readme.find(cmd).expect("README shows the two-gas command") + cmd.len();
    let shown = &readme[start..start + readme[start..].find("```").unwrap()];
    let (text, out) = dive("two_gas_dive", &[]);
    assert!(out.status.success());
    assert_eq!(
        shown, text,
        "README's dive example is stale: paste the output again"
    );
    // Per-cylinder verdict on both gases.
    assert!(text.contains("'back' air (bottom") && text.contains("'deco' EAN50 (deco from 21 m"));
}
