//! `poser slurm` on a real SLURM cluster: one node on loopback (slurmctld, slurmd and munge
//! from Debian, started by `backends/slurm/start.sh`). A job array renders a small scene in
//! three shards, the dependent merge job writes the truth and the summary, and the result is
//! compared byte for byte with a local run.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const SCENE: &str = "scenarios/calibration_flat.toml"; // 5 poses
const ARGS: &[&str] = &["--scale", "0.2", "--samples", "4"];

fn poser() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// Every file below `dir` except `skip` (relative path → bytes).
fn files(dir: &Path, skip: &str) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, d: &Path, skip: &str, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().to_string();
            if rel == skip {
                continue;
            }
            if p.is_dir() {
                walk(root, &p, skip, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut m = BTreeMap::new();
    walk(dir, dir, skip, &mut m);
    m
}

#[test]
fn a_slurm_job_array_writes_the_bytes_of_a_local_run() {
    let start = Instant::now();
    let up = Command::new("backends/slurm/start.sh")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        up.status.success(),
        "the one-node SLURM cluster did not start (it needs root, slurm-wlm and munge; \
         backends/setup.sh installs them):\n{}",
        String::from_utf8_lossy(&up.stderr)
    );
    let conf = String::from_utf8_lossy(&up.stdout).trim().to_string();

    let dir = tempfile::tempdir().unwrap();
    let local = dir.path().join("local");
    let o = poser()
        .args(["render", SCENE, "--quiet", "-o"])
        .arg(&local)
        .args(ARGS)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let cluster = dir.path().join("cluster");
    let o = poser()
        .args(["slurm", SCENE, "--shards", "3", "--cpus", "1", "-o"])
        .arg(&cluster)
        .args(ARGS)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(cluster.join("slurm/submit.sh"))
        .env("SLURM_CONF", &conf)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let jobs = std::fs::read_to_string(cluster.join("slurm/jobs")).unwrap();
    let ids: Vec<&str> = jobs.split_whitespace().collect();
    assert_eq!(ids.len(), 2, "{jobs}");
    let logs = cluster.join("slurm/logs");
    let log_text = || {
        let mut s = String::new();
        for e in std::fs::read_dir(&logs).unwrap() {
            let p = e.unwrap().path();
            s += &format!(
                "== {}\n{}",
                p.display(),
                std::fs::read_to_string(&p).unwrap_or_default()
            );
        }
        s
    };
    // Wait for the array and the merge job to leave the queue.
    loop {
        let q = Command::new("squeue")
            .env("SLURM_CONF", &conf)
            .args(["-h", "-o", "%i %T %r", "-j", &ids.join(",")])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&q.stdout).to_string();
        if q.status.success() && text.trim().is_empty() {
            break;
        }
        // A failed render task leaves the merge job waiting for ever: say so at once.
        assert!(
            !text.contains("DependencyNeverSatisfied"),
            "a render task failed:\n{text}\n{}",
            log_text()
        );
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "jobs still queued after 10 min:\n{text}"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    let summary: serde_json::Value = serde_json::from_slice(
        &std::fs::read(cluster.join("slurm/summary.json"))
            .unwrap_or_else(|e| panic!("no summary ({e}); logs:\n{}", log_text())),
    )
    .unwrap();
    assert_eq!(summary["images"], 5, "{summary}");
    assert_eq!(summary["finished"], 5, "{summary}\n{}", log_text());
    // Three render logs and one merge log.
    assert_eq!(
        std::fs::read_dir(&logs).unwrap().count(),
        4,
        "{}",
        log_text()
    );

    let (a, b) = (files(&local, "slurm"), files(&cluster, "slurm"));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "different file lists"
    );
    for (k, v) in &a {
        assert!(
            b[k] == *v,
            "{k} differs between the local run and the SLURM array"
        );
    }
    assert!(a.keys().any(|k| k.starts_with("truth/")));
    eprintln!(
        "SLURM test: 3 array tasks and a merge job, byte-identical to a local run, in {:.1} s wall",
        start.elapsed().as_secs_f64()
    );
}
