//! Sharding and resuming native renders: shards into one folder write exactly the files of one
//! whole run; a render killed with SIGKILL and resumed renders only what was missing and ends
//! with the same bytes as an uninterrupted run, with no temporary file left behind.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SCENE: &str = "scenarios/calibration_flat.toml"; // 5 poses

/// 160 × 120 pixels: byte equality of sharded, resumed and whole runs holds at any size, and an
/// image still takes about 0.7 s, ample for the kill between the first and the last (measured:
/// a whole run 3.6 s here, 12 s at the 0.2 this was).
const SCALE: &str = "0.1";

fn render(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "render",
            SCENE,
            "--scale",
            SCALE,
            "--samples",
            "4",
            "--quiet",
            "-o",
        ])
        .arg(out)
        .args(extra);
    c
}

/// Every file below `dir` (relative path → bytes).
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().to_string();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut m = BTreeMap::new();
    walk(dir, dir, &mut m);
    m
}

fn same(a: &Path, b: &Path) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "different file lists"
    );
    for (k, v) in &fa {
        assert!(fb[k] == *v, "{k} differs");
    }
}

fn finished_images(out: &Path) -> usize {
    std::fs::read(out.join("render-manifest.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|m| m["images"].as_object().map(|o| o.len()))
        .unwrap_or(0)
}

#[test]
fn shards_write_the_files_of_one_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    assert!(render(&whole, &[]).status().unwrap().success());
    let shards = dir.path().join("shards");
    for sh in ["2/3", "0/3", "1/3"] {
        let o = render(&shards, &["--shard", sh]).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    same(&whole, &shards);
    assert_eq!(finished_images(&whole), 5);
    // A bad shard is a usage error.
    for bad in ["3/3", "1/0", "x/2", "1"] {
        let o = render(&dir.path().join("bad"), &["--shard", bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--shard {bad}");
    }
}

#[test]
fn shards_running_at_once_write_the_files_of_one_whole_run() {
    // As the tasks of a SLURM array do (with `--resume`): the manifest is updated under a lock,
    // so no shard's record is lost (without it, the last writer wins and the others' images
    // are forgotten), and a shard starting late cleans up only the temporary files of dead
    // runs, not another shard's write in progress (which then failed to rename it).
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    assert!(render(&whole, &[]).status().unwrap().success());
    let shards = dir.path().join("shards");
    let children: Vec<_> = ["0/5", "1/5", "2/5", "3/5", "4/5"]
        .iter()
        .map(|sh| {
            render(&shards, &["--shard", sh, "--resume"])
                .stderr(Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    same(&whole, &shards);
    assert_eq!(finished_images(&shards), 5);
}

#[test]
fn a_killed_render_resumes_where_it_stopped_with_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    assert!(render(&whole, &[]).status().unwrap().success());

    let cut = dir.path().join("cut");
    let mut child = render(&cut, &[]).stderr(Stdio::null()).spawn().unwrap();
    let start = Instant::now();
    // Kill it (SIGKILL) as soon as the first image is recorded and before the last.
    loop {
        if finished_images(&cut) >= 1 {
            child.kill().unwrap();
            break;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render finished before it could be killed; make it slower"
        );
        assert!(start.elapsed() < Duration::from_secs(600));
        std::thread::sleep(Duration::from_millis(2));
    }
    child.wait().unwrap();
    let done = finished_images(&cut);
    assert!(
        (1..5).contains(&done),
        "{done} images finished before the kill"
    );

    let o = render(&cut, &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let k = err
        .lines()
        .find_map(|l| l.strip_prefix("resume: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse::<usize>().ok())
        .unwrap_or_else(|| panic!("no resume line in {err}"));
    assert!(k >= done && k < 5, "resumed {k}, {done} were recorded");
    same(&whole, &cut);
    assert!(
        !files(&cut).keys().any(|k| k.contains(".poser-")),
        "a temporary file was left behind"
    );
}

#[test]
fn a_resumed_image_whose_file_changed_is_rendered_again() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    assert!(
        render(&out, &["--poses", "0,1"])
            .status()
            .unwrap()
            .success()
    );
    let before = files(&out);
    std::fs::write(out.join("img_0002.png"), b"not a png").unwrap();
    let o = render(&out, &["--poses", "0,1", "--resume"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("resume: 1 of 2"), "{err}");
    assert_eq!(files(&out), before);
    // Another scene (here another seed): nothing recorded counts.
    let o = render(
        &out,
        &["--poses", "0,1", "--resume", "--set", "render.seed=9"],
    )
    .output()
    .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("resume: 0 of 2"));
}
