//! Resumable native renders: `OUT/render-manifest.json` records every finished image with the
//! SHA-256 of each of its files, written (atomically) right after the image's last file. A
//! render stopped at any point, even by SIGKILL, leaves only whole files (each is written to a
//! temporary file, then renamed) and a manifest of the images that are complete; with
//! `--resume` the next run skips those and renders the rest.
//!
//! | field | meaning |
//! |---|---|
//! | `fingerprint` | SHA-256 of poser's version, the resolved model and the samples per pixel: a manifest from another scene, setting or poser is ignored |
//! | `images` | image name → file name → SHA-256 |
//!
//! An image counts as done only when every file it lists still exists with its hash. Renders
//! running at once into one folder (shards of a SLURM array) update the manifest under a lock.

use crate::io::sha256;
use crate::model::Model;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The manifest's file name in the output folder.
pub const FILE: &str = "render-manifest.json";
/// The lock file that serialises updates of the manifest by renders running at once (an empty
/// file beside it; `flock`, which Linux's NFS client maps to POSIX locks across nodes).
pub const LOCK: &str = ".render-manifest.lock";

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Manifest {
    pub fingerprint: String,
    pub images: BTreeMap<String, BTreeMap<String, String>>,
}

/// What decides an image's bytes: poser's version, the resolved model (but the path it was
/// loaded from), the samples per pixel.
pub fn fingerprint(model: &Model, samples: u32) -> String {
    // Not the scene's path as typed: a relative and an absolute path to one scene (a local run
    // and a SLURM task) render the same bytes.
    let mut m = model.clone();
    m.source.clear();
    let mut bytes = serde_json::to_vec(&m).unwrap_or_default();
    bytes.extend_from_slice(env!("CARGO_PKG_VERSION").as_bytes());
    bytes.extend_from_slice(option_env!("POSER_GIT_COMMIT").unwrap_or("").as_bytes());
    bytes.extend_from_slice(&samples.to_le_bytes());
    sha256(&bytes)
}

impl Manifest {
    /// The manifest in `out` when it has this fingerprint (so that runs into one folder one
    /// after another, such as shards, add to it), else an empty one.
    pub fn open(out: &Path, fingerprint: &str) -> Manifest {
        match std::fs::read(out.join(FILE))
            .ok()
            .and_then(|b| serde_json::from_slice::<Manifest>(&b).ok())
        {
            Some(m) if m.fingerprint == fingerprint => m,
            _ => Manifest {
                fingerprint: fingerprint.to_string(),
                images: BTreeMap::new(),
            },
        }
    }

    /// Whether image `name` is recorded and every one of its files still has its hash.
    pub fn is_done(&self, out: &Path, name: &str) -> bool {
        self.images.get(name).is_some_and(|files| {
            !files.is_empty()
                && files
                    .iter()
                    .all(|(f, h)| std::fs::read(out.join(f)).is_ok_and(|b| sha256(&b) == *h))
        })
    }

    /// Record image `name` as finished with `files` (paths inside `out`), and write the
    /// manifest. Renders into one folder may run at once (the shards of a SLURM job array):
    /// under an exclusive lock on [`LOCK`], the manifest on disk is read again and this run's
    /// images are merged into it, so that no shard's record is lost.
    pub fn record(&mut self, out: &Path, name: &str, files: &[PathBuf]) -> Result<(), String> {
        let mut map = BTreeMap::new();
        for f in files {
            let b = std::fs::read(f).map_err(|e| format!("{}: {e}", f.display()))?;
            let rel = f
                .strip_prefix(out)
                .unwrap_or(f)
                .to_string_lossy()
                .replace('\\', "/");
            map.insert(rel, sha256(&b));
        }
        let lock_path = out.join(LOCK);
        let lock = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(|e| format!("{}: {e}", lock_path.display()))?;
        lock.lock()
            .map_err(|e| format!("{}: cannot lock: {e}", lock_path.display()))?;
        let on_disk = Manifest::open(out, &self.fingerprint);
        for (k, v) in on_disk.images {
            self.images.entry(k).or_insert(v);
        }
        self.images.insert(name.to_string(), map);
        let json = serde_json::to_vec_pretty(self).map_err(|e| e.to_string())?;
        let path = out.join(FILE);
        let written =
            crate::io::write_atomic(&path, &json).map_err(|e| format!("{}: {e}", path.display()));
        drop(lock);
        written
    }
}
