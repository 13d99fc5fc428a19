//! `poser export` files in real glTF tools (full tier: `cargo test --test backends`; needs node with
//! the pinned npm packages of `backends/gltf/` and Debian's `chromium`, both installed by
//! `backends/setup.sh`):
//!
//! | test | what |
//! |---|---|
//! | [`khronos_validator_finds_no_error_in_any_scenario`] | every shipped scenario and lesson (and a synthetic scene with an area light, with a cylinder or a tilted flat port) exported, then run through the Khronos glTF validator (`gltf-validator`, `backends/gltf/validate.mjs`): zero errors; warnings, infos and hints are reported |
//! | [`three_js_loads_and_renders_the_export`] | headless Chromium opens `backends/gltf/view.html` (three.js's `GLTFLoader`) on exports served from a temporary folder: the meshes, lines, cameras and lights three.js found equal the file's; the screenshot is not uniform |
//!
//! Everything is written into a temporary folder (the page and the exports are served from it
//! by a small HTTP server in this test, with `node_modules` linked in).

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn tools() -> PathBuf {
    let dir = root().join("backends/gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir() && dir.join("node_modules/three").is_dir(),
        "the pinned npm packages of backends/gltf are missing\n  help: run backends/setup.sh \
         (it runs `npm ci --prefix backends/gltf`)"
    );
    dir
}

fn scenarios() -> Vec<PathBuf> {
    support::shipped_scenes()
}

/// `poser export` of `scene` into `dir`; the path of the `.glb`.
fn export(scene: &Path, dir: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap().to_string_lossy().to_string();
    export_with(scene, &[], &dir.join(format!("{stem}.glb")))
}

fn export_with(scene: &Path, sets: &[&str], glb: &Path) -> PathBuf {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_poser"));
    cmd.arg("export").arg(scene).arg("-o").arg(glb);
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    let o = cmd.current_dir(root()).output().expect("run poser");
    assert!(
        o.status.success(),
        "poser export {} {sets:?} failed:\n{}",
        scene.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    glb.to_path_buf()
}

/// A scene with what the shipped ones lack: an area light (an emissive mesh), point and spot
/// lights, the sun; exported with a cylinder port and with a tilted flat port.
fn synthetic(dir: &Path) -> Vec<PathBuf> {
    let scene = dir.join("synthetic.toml");
    let base = root().join("tests/invalid/shared/base.toml");
    std::fs::write(
        &scene,
        format!(
            "include = [{:?}]\n\
             [sun]\nelevation = \"50 deg\"\n\
             [[lights]]\ntype = \"point\"\nposition = [0.1, 0, 0]\n\
             [[lights]]\ntype = \"spot\"\nposition = [0.2, 0, 0]\n\
             [[lights]]\ntype = \"area\"\nposition = [0, 0, -1]\n\
             [[lights]]\ntype = \"ambient\"\n\
             [[objects]]\nshape = \"sphere\"\nradius = 0.3\nposition = [0, 0, -5]\n",
            base.to_string_lossy()
        ),
    )
    .unwrap();
    vec![
        export_with(
            &scene,
            &["camera.port.type=cylinder"],
            &dir.join("synthetic_cylinder.glb"),
        ),
        export_with(
            &scene,
            &["camera.port.type=flat", "camera.port.tilt=5 deg"],
            &dir.join("synthetic_tilted_flat.glb"),
        ),
    ]
}

#[test]
fn khronos_validator_finds_no_error_in_any_scenario() {
    let tools = tools();
    let tmp = tempfile::tempdir().unwrap();
    let mut files: Vec<PathBuf> = support::map_parallel(&scenarios(), |s| export(s, tmp.path()));
    files.extend(synthetic(tmp.path()));
    let o = Command::new("node")
        .arg(tools.join("validate.mjs"))
        .args(&files)
        .output()
        .expect("run node (help: run backends/setup.sh, which installs nodejs and npm)");
    assert!(
        o.status.success(),
        "the validator failed to run:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    let mut reports = 0;
    let mut bad = Vec::new();
    println!("Khronos glTF validator: file, errors, warnings, infos, hints");
    for line in text.lines() {
        let r: serde_json::Value = serde_json::from_str(line).unwrap();
        let file = Path::new(r["file"].as_str().unwrap())
            .file_name()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let n = |k: &str| {
            r[k].as_u64()
                .unwrap_or_else(|| panic!("{file}: no `{k}` in {r}"))
        };
        println!(
            "  {file}: {} errors, {} warnings, {} infos, {} hints (validator {})",
            n("errors"),
            n("warnings"),
            n("infos"),
            n("hints"),
            r["validatorVersion"]
        );
        for m in r["messages"].as_array().unwrap() {
            if m["severity"].as_u64() == Some(0) {
                bad.push(format!(
                    "{file}: {} at {}: {}",
                    m["code"], m["pointer"], m["message"]
                ));
            }
        }
        if n("errors") > 0 && bad.is_empty() {
            bad.push(format!("{file}: {} errors", n("errors")));
        }
        reports += 1;
    }
    assert_eq!(reports, files.len(), "one report per file:\n{text}");
    assert!(bad.is_empty(), "validation errors:\n{}", bad.join("\n"));
}

/// A static file server for `dir` on a free local port (a thread per connection); its URL.
fn serve(dir: PathBuf) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { continue };
            let dir = dir.clone();
            std::thread::spawn(move || {
                let mut reader = BufReader::new(stream.try_clone().unwrap());
                let mut request = String::new();
                if reader.read_line(&mut request).is_err() {
                    return;
                }
                loop {
                    let mut h = String::new();
                    if reader.read_line(&mut h).map_or(true, |n| n == 0) || h.trim().is_empty() {
                        break;
                    }
                }
                let target = request.split_whitespace().nth(1).unwrap_or("/");
                let path = target
                    .split('?')
                    .next()
                    .unwrap_or("/")
                    .trim_start_matches('/');
                // The page's `hold` request (view.html?hold=1) is answered after half a
                // second: while one is pending, Chromium's virtual time stands still.
                if path == "hold" {
                    std::thread::sleep(std::time::Duration::from_millis(500));
                    let _ = write!(
                        stream,
                        "HTTP/1.1 204 No Content\r\nConnection: close\r\n\r\n"
                    );
                    return;
                }
                let file = dir.join(path);
                let ok = !path.split('/').any(|c| c == "..") && file.is_file();
                let (status, body) = if ok {
                    ("200 OK", std::fs::read(&file).unwrap_or_default())
                } else {
                    ("404 Not Found", b"not found".to_vec())
                };
                let mime = match file.extension().and_then(|e| e.to_str()) {
                    Some("html") => "text/html; charset=utf-8",
                    Some("js" | "mjs") => "text/javascript",
                    Some("glb") => "model/gltf-binary",
                    Some("json") => "application/json",
                    _ => "application/octet-stream",
                };
                let _ = write!(
                    stream,
                    "HTTP/1.1 {status}\r\nContent-Type: {mime}\r\nContent-Length: {}\r\n\
                     Connection: close\r\n\r\n",
                    body.len()
                );
                let _ = stream.write_all(&body);
            });
        }
    });
    url
}

/// How often a page that has not finished loading (or drawing), or whose Chromium failed, is
/// opened again. In one test binary with the other full-tier suites, Blender and the renders
/// load the machine while this runs.
const ATTEMPTS: usize = 8;

/// One headless Chromium run of `action` on `url`; attempt `attempt` (from 0) waits that many
/// times 3 s of real time first (a loaded machine gets time to settle) and gives the page a
/// virtual-time budget that grows with it.
fn chromium_run(profile: &Path, action: &str, url: &str, attempt: usize) -> std::process::Output {
    if attempt > 0 {
        eprintln!("{url}: attempt {} of {ATTEMPTS}", attempt + 1);
        std::thread::sleep(std::time::Duration::from_secs(3 * attempt as u64));
    }
    Command::new(support::lesson::chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--hide-scrollbars",
            "--window-size=800,600",
        ])
        .arg(format!("--virtual-time-budget={}", 60_000 * (1 + attempt)))
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(action)
        .arg(url)
        .output()
        .expect("run chromium")
}

/// The text of the `data-key` cell `key`.
fn cell(dom: &str, key: &str) -> u64 {
    let tag = format!("data-key=\"{key}\">");
    let i = dom
        .find(&tag)
        .unwrap_or_else(|| panic!("no cell `{key}` in the page:\n{dom}"))
        + tag.len();
    let j = dom[i..].find('<').unwrap() + i;
    dom[i..j]
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("cell `{key}` is `{}`", &dom[i..j]))
}

#[test]
fn three_js_loads_and_renders_the_export() {
    let tools = tools();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    std::fs::create_dir(&site).unwrap();
    std::fs::copy(tools.join("view.html"), site.join("view.html")).unwrap();
    std::os::unix::fs::symlink(tools.join("node_modules"), site.join("node_modules")).unwrap();
    let url = serve(site.clone());
    // A survey with the sun, a stereo rig with spots and a seabed, a dome orbit, a drone
    // over waves (one pose: the path is a point).
    for name in [
        "scenarios/reef_strip.toml",
        "scenarios/lessons/subsea_metrology.toml",
        "scenarios/dome_orbit.toml",
        "scenarios/lessons/uav_through_waves.toml",
    ] {
        let scene = root().join(name);
        let glb = export(&scene, &site);
        let file = glb.file_name().unwrap().to_string_lossy().to_string();

        // What the file holds.
        let bytes = std::fs::read(&glb).unwrap();
        let doc = gltf::Gltf::from_slice(&bytes).unwrap().document;
        let (mut triangles, mut lines, mut points) = (0, 0, 0);
        for m in doc.meshes() {
            for p in m.primitives() {
                match p.mode() {
                    gltf::mesh::Mode::Triangles => triangles += 1,
                    gltf::mesh::Mode::LineStrip => lines += 1,
                    gltf::mesh::Mode::Points => points += 1,
                    other => panic!("{name}: unexpected primitive mode {other:?}"),
                }
            }
        }
        let cameras = doc.nodes().filter(|n| n.camera().is_some()).count() as u64;
        let lights = doc.lights().map_or(0, |l| l.count()) as u64;
        let model = poser::scene::load(&scene, &[]).ok().unwrap().model;
        assert_eq!(
            cameras,
            (model.poses.len() * model.cameras.len()) as u64,
            "{name}"
        );

        // What three.js loaded.
        let profile = tmp.path().join(format!("profile-{file}"));
        // `hold=1`: the page keeps a request pending until it has loaded (view.html), so
        // that the virtual-time budget cannot run out first on a loaded machine.
        let page = format!("{url}/view.html?hold=1&glb={file}");
        // Headless Chromium's virtual time can run out before a loaded machine has fetched and
        // parsed three.js: a page that is still loading is asked for again (ATTEMPTS times).
        let mut dom = String::new();
        for attempt in 0..ATTEMPTS {
            let o = chromium_run(&profile, "--dump-dom", &page, attempt);
            dom = format!(
                "{}\n(chromium: {}; stderr: {})",
                String::from_utf8_lossy(&o.stdout),
                o.status,
                String::from_utf8_lossy(&o.stderr)
            );
            if o.status.success() && !dom.contains("data-status=\"loading\"") {
                break;
            }
        }
        assert!(
            dom.contains("data-status=\"ok\""),
            "{name}: the page did not finish loading:\n{dom}"
        );
        assert_eq!(cell(&dom, "meshes"), triangles as u64, "{name}: meshes");
        assert_eq!(cell(&dom, "lines"), lines as u64, "{name}: lines");
        assert_eq!(cell(&dom, "points"), points as u64, "{name}: points");
        assert_eq!(cell(&dom, "cameras"), cameras, "{name}: cameras");
        assert_eq!(cell(&dom, "lights"), lights, "{name}: lights");
        assert!(cell(&dom, "frames") >= 1);
        println!(
            "{name}: three.js loaded {triangles} meshes, {lines} line(s), {points} point set(s), \
             {cameras} cameras, {lights} lights"
        );

        // The overview and an exported camera's view are rendered, not blank.
        for (label, query) in [
            ("overview", String::new()),
            ("camera 0", "&camera=0".into()),
        ] {
            let shot = tmp
                .path()
                .join(format!("{file}-{}.png", label.replace(' ', "")));
            let (mut mean, mut sd) = (0.0, 0.0);
            // As above: a screenshot taken before the page drew is taken again.
            for attempt in 0..ATTEMPTS {
                let o = chromium_run(
                    &profile,
                    &format!("--screenshot={}", shot.display()),
                    &format!("{page}{query}"),
                    attempt,
                );
                assert!(
                    o.status.success() && shot.exists(),
                    "chromium --screenshot failed: {}",
                    String::from_utf8_lossy(&o.stderr)
                );
                let img = image::open(&shot).unwrap().to_luma8();
                // The scene's part of the window (the panel at the top left is left out).
                let (w, h) = img.dimensions();
                let px: Vec<f64> = img
                    .enumerate_pixels()
                    .filter(|(x, y, _)| *x > w / 3 || *y > h / 3)
                    .map(|(_, _, p)| p[0] as f64)
                    .collect();
                let n = px.len() as f64;
                mean = px.iter().sum::<f64>() / n;
                sd = (px.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
                if sd > 3.0 {
                    break;
                }
            }
            println!("{name}: {label} screenshot grey mean {mean:.1}, standard deviation {sd:.1}");
            assert!(
                sd > 3.0,
                "{name}: the {label} screenshot is uniform (sd {sd:.2})"
            );
        }
    }
}
