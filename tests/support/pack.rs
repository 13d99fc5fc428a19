//! Packs as the tests drive them: the `poser` command run from the repository root, its output
//! as text, and a pack's entries and manifest read back.

use flate2::read::GzDecoder;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Output};

pub fn poser() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The entries of a pack: (path bytes, entry type, data).
pub fn entries(pack: &Path) -> Vec<(Vec<u8>, tar::EntryType, Vec<u8>)> {
    let mut ar = tar::Archive::new(GzDecoder::new(std::fs::File::open(pack).unwrap()));
    ar.entries()
        .unwrap()
        .map(|e| {
            let mut e = e.unwrap();
            let mut d = Vec::new();
            e.read_to_end(&mut d).unwrap();
            (e.path_bytes().to_vec(), e.header().entry_type(), d)
        })
        .collect()
}

pub fn manifest(pack: &Path) -> serde_json::Value {
    let e = entries(pack);
    assert_eq!(e[0].0, b"manifest.json");
    serde_json::from_slice(&e[0].2).unwrap()
}
