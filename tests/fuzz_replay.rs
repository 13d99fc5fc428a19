//! The fuzz targets' checks (`fuzz/checks.rs`) replayed on stable over the committed corpus:
//! the invalid-scene corpus and every scenario (scene target), the invalid corpus (compile
//! target: none of them may compile, and nothing may be written outside the output folder),
//! and `fuzz/corpus/<target>/` (seeds and whatever fuzzing found and was kept; the `import`
//! target has only its own corpus). The nightly
//! libFuzzer runs are `fuzz/run.sh`.
#[path = "../fuzz/checks.rs"]
mod checks;

use std::path::{Path, PathBuf};

fn files(dir: &Path, ext: Option<&str>) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    v.retain(|p| p.is_file() && ext.is_none_or(|e| p.extension().is_some_and(|x| x == e)));
    v.sort();
    v
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn scene_target_replays_the_corpus() {
    let mut n = 0;
    for dir in ["tests/invalid", "scenarios", "scenarios/lessons"] {
        for p in files(&root().join(dir), Some("toml")) {
            checks::scene_at(&p);
            checks::scene(&std::fs::read(&p).unwrap());
            n += 1;
        }
    }
    for p in files(&root().join("fuzz/corpus/scene"), None) {
        checks::scene(&std::fs::read(&p).unwrap());
        n += 1;
    }
    assert!(n > 70, "only {n} corpus files");
}

#[test]
fn compile_target_replays_the_corpus() {
    let mut n = 0;
    for p in files(&root().join("tests/invalid"), Some("toml")) {
        checks::compile_at(&p);
        n += 1;
    }
    for p in files(&root().join("fuzz/corpus/compile"), None) {
        checks::compile(&std::fs::read(&p).unwrap());
        n += 1;
    }
    assert!(n > 60, "only {n} corpus files");
}

#[test]
fn project_csv_target_replays_the_corpus() {
    let seeds = files(&root().join("fuzz/corpus/project_csv"), None);
    assert!(seeds.len() >= 3, "project_csv seeds missing");
    for p in seeds {
        checks::project_csv(&std::fs::read(&p).unwrap());
    }
}

#[test]
fn import_target_replays_the_corpus() {
    let seeds = files(&root().join("fuzz/corpus/import"), None);
    assert!(seeds.len() >= 5, "import seeds missing");
    let mut kinds = std::collections::BTreeSet::new();
    for p in seeds {
        let data = std::fs::read(&p).unwrap();
        kinds.insert(data.first().map(|k| k % 4));
        checks::import(&data);
    }
    assert_eq!(kinds.len(), 4, "a seed of every kind: {kinds:?}");
}
