//! The one test-support module of the integration tests (`mod support;` in `tests/suite.rs` and
//! `tests/backends.rs`, `use crate::support;` in each suite).
//!
//! | module | what |
//! |---|---|
//! | [`glass_lens`] | the glass-lens scenes (a glass ball or rod imaging a square) and their exact images |
//! | [`model`] | the one model builder: cameras, ports, water, planes, lights, a minimal model |
//! | [`canonical`] | the canonical scenes of `tests/canonical/`, the analytic radiance oracle, and the geometry / radiometry checks every backend runs |
//! | [`column`] | the native column tests' scene (sun or sky over a flat seabed, turbid water) and one native render's means |
//! | [`lesson`] | running a lesson's quick form; its page in headless Chromium |
//! | [`mitsuba`], [`blender`], [`native`], [`plan`] | each suite's preset models, built with [`model`] |
//! | [`bench`] | `poser bench render --quick` run into a temporary folder, its report checked |
//! | [`pack`] | the `poser` command from the repository root, its output as text, a pack's entries and manifest |
//! | [`scenario`] | a shipped scenario, loaded |
//! | [`textured`] | the textured-mesh site: loading it, the disk printed in its texture against the truth |
#![allow(dead_code)]

pub mod bench;
pub mod blender;
pub mod canonical;
pub mod column;
pub mod glass_lens;
pub mod import;
pub mod lesson;
pub mod mitsuba;
pub mod model;
pub mod native;
pub mod pack;
pub mod plan;
pub mod textured;

/// Every shipped scenario and lesson scene (`scenarios/*.toml`, `scenarios/lessons/*.toml`),
/// sorted.
pub fn shipped_scenes() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in ["scenarios", "scenarios/lessons"] {
        for e in std::fs::read_dir(root.join(dir)).expect("scenarios") {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                out.push(p);
            }
        }
    }
    out.sort();
    assert!(
        out.len() >= 10 && out.iter().any(|p| p.to_string_lossy().contains("lessons")),
        "found only {out:?}"
    );
    out
}

/// The shipped scenes that `tests/in/*.toml` includes (canonical paths): the scenes the snapshot
/// suite (`tests/compile_out.rs`) already compiles with every backend.
pub fn pinned_scenes() -> Vec<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/in");
    let mut out = Vec::new();
    for e in std::fs::read_dir(&dir).expect("tests/in") {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let doc: toml::Table = toml::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        if let Some(toml::Value::Array(list)) = doc.get("include") {
            for inc in list.iter().filter_map(|v| v.as_str()) {
                out.push(dir.join(inc).canonicalize().unwrap());
            }
        }
    }
    out
}

/// `f` over every item, on as many threads as the machine has cores; the results in the items'
/// order. For suites that run one external process (Blender, a `poser` command) per shipped
/// scene in a single test: the processes are mostly single-threaded, so running them one at a
/// time left all but one core idle.
pub fn map_parallel<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let out: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|s| {
        for _ in 0..workers.min(items.len()) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    *out[i].lock().unwrap() = Some(r);
                }
            });
        }
    });
    out.into_iter()
        .map(|m| m.into_inner().unwrap().expect("every item was done"))
        .collect()
}

/// A shipped scenario (`scenarios/NAME`) as poser loads it; panics with the rendered
/// diagnostics if it does not load.
pub fn scenario(name: &str) -> poser::model::Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    match poser::scene::load(&path, &[]) {
        Ok(l) => l.model,
        Err(f) => panic!("{}", f.render()),
    }
}
