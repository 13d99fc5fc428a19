//! Reproducible packs (`poser pack`, `poser unpack`, `poser rerun`): one archive that holds a
//! scene with its includes and assets, the poser commands run on it, and the SHA-256 of every
//! file, so that a rerun on another machine can say, file by file, whether it got the same
//! bytes, and which version differs when it did not.
//!
//! | entry | content |
//! |---|---|
//! | `manifest.json` | always the first entry: format, poser's version and git commit, the pinned backend versions, the scene's entry, the `--set` list, the commands with the hashes of what each wrote, the hash of every packed file |
//! | `scene/…` | the scene file, its includes and its assets, at their paths below their common folder |
//! | `outputs/<k>/…` | with `--outputs`: the files that command `k` wrote |
//!
//! The archive is a gzip-compressed tar, written atomically. Reading ([`read`]) checks the whole
//! archive before it writes anything: only regular files and folders, relative paths without
//! `..`, at most [`MAX_ENTRIES`] entries of at most [`MAX_ENTRY_BYTES`] each, every file listed
//! in the manifest with the hash it has there, nothing unlisted. A pack that fails any check is
//! refused with the entry named, and nothing is written.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// The manifest's format tag.
pub const FORMAT: &str = "poserpack/1";
/// Name of the manifest entry.
pub const MANIFEST: &str = "manifest.json";
/// Folder of the scene files inside a pack.
pub const SCENE_DIR: &str = "scene";
/// Folder of the packed outputs.
pub const OUTPUTS_DIR: &str = "outputs";
/// Most entries a pack may hold.
pub const MAX_ENTRIES: usize = 100_000;
/// Largest entry a pack may hold (bytes).
pub const MAX_ENTRY_BYTES: u64 = 2 << 30;
/// Commands a pack may record: each reads the scene and writes only into its `-o` folder.
pub const COMMANDS: [&str; 3] = ["render", "truth", "compile"];

/// The pinned Python environment of the Mitsuba, Blender and COLMAP backends, as built into
/// this binary.
const REQUIREMENTS: &str = include_str!("../../backends/requirements.txt");

/// One file and its hash.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileHash {
    /// Path with `/` separators (inside the pack, or inside a command's output folder).
    pub path: String,
    pub sha256: String,
    pub bytes: u64,
}

/// Versions that decide whether a rerun can give the same bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Versions {
    /// poser's crate version.
    pub poser: String,
    /// The git commit poser was built from (`unknown` outside a git checkout).
    pub commit: String,
    /// The pinned Python packages (`backends/requirements.txt`): name → version.
    pub backends: BTreeMap<String, String>,
}

impl Versions {
    /// The versions of this build.
    pub fn current() -> Versions {
        let backends = REQUIREMENTS
            .lines()
            .filter_map(|l| {
                let l = l.split('#').next()?.trim();
                let (name, version) = l.split_once("==")?;
                Some((name.trim().to_string(), version.trim().to_string()))
            })
            .collect();
        Versions {
            poser: env!("CARGO_PKG_VERSION").to_string(),
            commit: option_env!("POSER_GIT_COMMIT")
                .unwrap_or("unknown")
                .to_string(),
            backends,
        }
    }

    /// What differs between `self` (the pack's) and `now`, one line each.
    pub fn differences(&self, now: &Versions) -> Vec<String> {
        let mut out = Vec::new();
        if self.poser != now.poser {
            out.push(format!(
                "poser {} (pack) vs {} (here)",
                self.poser, now.poser
            ));
        }
        if self.commit != now.commit {
            out.push(format!(
                "poser commit {} (pack) vs {} (here)",
                self.commit, now.commit
            ));
        }
        let names: std::collections::BTreeSet<&String> =
            self.backends.keys().chain(now.backends.keys()).collect();
        for n in names {
            let (a, b) = (self.backends.get(n), now.backends.get(n));
            if a != b {
                let show = |v: Option<&String>| v.map_or("none".to_string(), |v| v.clone());
                out.push(format!("{n} {} (pack) vs {} (here)", show(a), show(b)));
            }
        }
        out
    }
}

/// One recorded command.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// The command's arguments after the scene, the `--set`s and `-o` (which a rerun supplies),
    /// e.g. `["render", "--scale", "0.25", "--samples", "8"]`.
    pub argv: Vec<String>,
    /// What it wrote, relative to its output folder, sorted.
    pub outputs: Vec<FileHash>,
}

/// The manifest (`manifest.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: String,
    pub versions: Versions,
    /// The scene file's path inside the pack (`scene/…`).
    pub scene: String,
    /// `--set` overrides applied by every command.
    pub sets: Vec<String>,
    pub commands: Vec<Command>,
    /// Every packed file but the manifest: scene files, then outputs when included.
    pub files: Vec<FileHash>,
    /// Whether the outputs themselves are in the pack (else only their hashes).
    pub outputs_included: bool,
}

/// SHA-256 of `bytes`, lower-case hex.
pub fn sha256(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// Every regular file below `dir`, with paths relative to it (`/`-separated), sorted.
/// Symbolic links are skipped: a command's outputs are regular files. The native renderer's
/// resume bookkeeping (`render-manifest.json`, which fingerprints the scene's absolute paths)
/// is not an output and is skipped too.
pub fn hash_dir(dir: &Path) -> Result<Vec<FileHash>, String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<FileHash>) -> Result<(), String> {
        let rd = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for e in rd {
            let e = e.map_err(|e| format!("{}: {e}", dir.display()))?;
            let ty = e.file_type().map_err(|e| e.to_string())?;
            let p = e.path();
            if ty.is_dir() {
                walk(root, &p, out)?;
            } else if ty.is_file() && e.file_name() != crate::backend::native::resume::FILE {
                let bytes = std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))?;
                out.push(FileHash {
                    path: rel_string(p.strip_prefix(root).unwrap())?,
                    sha256: sha256(&bytes),
                    bytes: bytes.len() as u64,
                });
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort_by(|a, b| a.path.cmp(&b.path));
    Ok(out)
}

fn rel_string(p: &Path) -> Result<String, String> {
    let mut parts = Vec::new();
    for c in p.components() {
        match c {
            Component::Normal(s) => parts.push(
                s.to_str()
                    .ok_or_else(|| format!("{}: not a UTF-8 path", p.display()))?
                    .to_string(),
            ),
            _ => return Err(format!("{}: not a plain relative path", p.display())),
        }
    }
    Ok(parts.join("/"))
}

/// The scene files (`files[0]` the scene itself) as (file, path inside the pack), relative to
/// their deepest common folder.
pub fn scene_entries(files: &[PathBuf]) -> Result<Vec<(PathBuf, String)>, String> {
    let abs: Vec<PathBuf> = files
        .iter()
        .map(|f| {
            f.canonicalize()
                .map_err(|e| format!("{}: {e}", f.display()))
        })
        .collect::<Result<_, _>>()?;
    let mut root = abs
        .first()
        .and_then(|p| p.parent())
        .ok_or("no scene file")?
        .to_path_buf();
    while !abs.iter().all(|p| p.starts_with(&root)) {
        root = root
            .parent()
            .ok_or("the scene's files share no folder")?
            .to_path_buf();
    }
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for p in abs {
        let rel = format!(
            "{SCENE_DIR}/{}",
            rel_string(p.strip_prefix(&root).unwrap())?
        );
        if seen.insert(rel.clone()) {
            out.push((p, rel));
        }
    }
    Ok(out)
}

/// Write a pack: the manifest (its `files` are filled in here), the scene files, and with
/// `outputs` the folder each command wrote (`outputs[k]` for `manifest.commands[k]`).
pub fn write(
    path: &Path,
    manifest: &mut Manifest,
    scene_files: &[(PathBuf, String)],
    outputs: &[PathBuf],
) -> Result<(), String> {
    let mut entries: Vec<(String, Vec<u8>)> = Vec::new();
    for (file, rel) in scene_files {
        let bytes = std::fs::read(file).map_err(|e| format!("{}: {e}", file.display()))?;
        entries.push((rel.clone(), bytes));
    }
    if manifest.outputs_included {
        for (k, dir) in outputs.iter().enumerate() {
            for f in hash_dir(dir)? {
                let bytes = std::fs::read(dir.join(&f.path)).map_err(|e| e.to_string())?;
                entries.push((format!("{OUTPUTS_DIR}/{k}/{}", f.path), bytes));
            }
        }
    }
    manifest.files = entries
        .iter()
        .map(|(p, b)| FileHash {
            path: p.clone(),
            sha256: sha256(b),
            bytes: b.len() as u64,
        })
        .collect();
    let json = serde_json::to_vec_pretty(manifest).map_err(|e| e.to_string())?;
    crate::io::write_atomic_with(path, |tmp| {
        let archive = || -> std::io::Result<()> {
            let file = std::fs::File::create(tmp)?;
            let gz = flate2::write::GzEncoder::new(file, flate2::Compression::default());
            let mut tar = tar::Builder::new(gz);
            tar.mode(tar::HeaderMode::Deterministic);
            append(&mut tar, MANIFEST, &json)?;
            for (p, b) in &entries {
                append(&mut tar, p, b)?;
            }
            tar.into_inner()?.finish()?;
            Ok(())
        };
        archive().map_err(|e| format!("{}: {e}", path.display()))
    })
}

fn append<W: std::io::Write>(
    tar: &mut tar::Builder<W>,
    path: &str,
    bytes: &[u8],
) -> std::io::Result<()> {
    let mut h = tar::Header::new_gnu();
    h.set_size(bytes.len() as u64);
    h.set_mode(0o644);
    h.set_mtime(0);
    h.set_entry_type(tar::EntryType::Regular);
    tar.append_data(&mut h, path, bytes)
}

/// A checked path inside a pack: relative, `/`-separated, plain components only.
fn safe_entry_path(raw: &[u8]) -> Result<String, String> {
    let s = std::str::from_utf8(raw).map_err(|_| "a path that is not UTF-8".to_string())?;
    let s = s.trim_end_matches('/');
    if s.is_empty()
        || s.starts_with('/')
        || s.contains('\\')
        || s.split('/')
            .any(|c| c.is_empty() || c == "." || c == ".." || c.contains(':'))
    {
        return Err(format!("`{s}`: not a plain relative path"));
    }
    Ok(s.to_string())
}

fn open(pack: &Path) -> Result<tar::Archive<flate2::read::GzDecoder<std::fs::File>>, String> {
    let f = std::fs::File::open(pack).map_err(|e| format!("{}: {e}", pack.display()))?;
    Ok(tar::Archive::new(flate2::read::GzDecoder::new(f)))
}

/// Check a pack completely (see the module's table) and return its manifest; nothing is
/// written.
pub fn check(pack: &Path) -> Result<Manifest, String> {
    let shown = pack.display();
    let mut ar = open(pack)?;
    let mut manifest: Option<Manifest> = None;
    let mut seen: BTreeMap<String, (String, u64)> = BTreeMap::new();
    let entries = ar
        .entries()
        .map_err(|e| format!("{shown}: not a poser pack ({e})"))?;
    for (i, e) in entries.enumerate() {
        let mut e = e.map_err(|e| format!("{shown}: unreadable entry {i} ({e})"))?;
        if i >= MAX_ENTRIES {
            return Err(format!("{shown}: more than {MAX_ENTRIES} entries"));
        }
        let raw = e.path_bytes().into_owned();
        let path = safe_entry_path(&raw).map_err(|m| format!("{shown}: entry {i}: {m}"))?;
        let ty = e.header().entry_type();
        if ty.is_dir() {
            continue;
        }
        if !ty.is_file() {
            return Err(format!(
                "{shown}: `{path}` is a {:?} entry; a pack holds regular files only",
                ty
            ));
        }
        let size = e.header().size().map_err(|e| format!("{shown}: {e}"))?;
        if size > MAX_ENTRY_BYTES {
            return Err(format!(
                "{shown}: `{path}` declares {size} bytes, more than the {MAX_ENTRY_BYTES} allowed"
            ));
        }
        if i == 0 {
            if path != MANIFEST {
                return Err(format!(
                    "{shown}: the first entry is `{path}`, not `{MANIFEST}`"
                ));
            }
            let mut text = Vec::new();
            e.read_to_end(&mut text).map_err(|e| e.to_string())?;
            let m: Manifest =
                serde_json::from_slice(&text).map_err(|e| format!("{shown}: {MANIFEST}: {e}"))?;
            if m.format != FORMAT {
                return Err(format!(
                    "{shown}: format `{}`; this poser reads `{FORMAT}`",
                    m.format
                ));
            }
            manifest = Some(m);
            continue;
        }
        let mut h = Sha256::new();
        let n = std::io::copy(&mut (&mut e).take(MAX_ENTRY_BYTES + 1), &mut h)
            .map_err(|e| format!("{shown}: `{path}`: {e}"))?;
        if seen.insert(path.clone(), (hex(&h.finalize()), n)).is_some() {
            return Err(format!("{shown}: `{path}` appears twice"));
        }
    }
    let m = manifest.ok_or_else(|| format!("{shown}: empty archive"))?;
    for f in &m.files {
        match seen.remove(&f.path) {
            None => return Err(format!("{shown}: `{}` is listed but missing", f.path)),
            Some((h, n)) if h != f.sha256 || n != f.bytes => {
                return Err(format!(
                    "{shown}: `{}` does not have the SHA-256 the manifest gives: the pack was changed after it was written",
                    f.path
                ));
            }
            Some(_) => {}
        }
    }
    if let Some(extra) = seen.keys().next() {
        return Err(format!("{shown}: `{extra}` is not listed in the manifest"));
    }
    if !m.files.iter().any(|f| f.path == m.scene) || !m.scene.starts_with("scene/") {
        return Err(format!(
            "{shown}: the scene `{}` is not among the packed scene files",
            m.scene
        ));
    }
    for c in &m.commands {
        check_command(&c.argv).map_err(|e| format!("{shown}: {e}"))?;
    }
    Ok(m)
}

/// A recorded command must be one of [`COMMANDS`], with no scene, `--set` or output of its
/// own (a rerun supplies them).
pub fn check_command(argv: &[String]) -> Result<(), String> {
    let Some(first) = argv.first() else {
        return Err("an empty command".into());
    };
    if !COMMANDS.contains(&first.as_str()) {
        return Err(format!(
            "`{first}`: a pack records only {}",
            COMMANDS.join(", ")
        ));
    }
    for a in &argv[1..] {
        let flag = a.split('=').next().unwrap_or(a);
        if matches!(flag, "-o" | "--out" | "--set" | "--images") || a.starts_with("-o") {
            return Err(format!(
                "`{}`: `{flag}` is supplied by the pack (the scene's `--set`s and the output folder)",
                argv.join(" ")
            ));
        }
    }
    Ok(())
}

/// Check `pack` (see [`check`]), then write its files below `dest`. Returns the manifest.
pub fn read(pack: &Path, dest: &Path) -> Result<Manifest, String> {
    let m = check(pack)?;
    let mut ar = open(pack)?;
    for e in ar.entries().map_err(|e| e.to_string())? {
        let mut e = e.map_err(|e| e.to_string())?;
        if !e.header().entry_type().is_file() {
            continue;
        }
        let path = safe_entry_path(&e.path_bytes())?;
        let mut bytes = Vec::new();
        e.read_to_end(&mut bytes).map_err(|e| e.to_string())?;
        let target = dest.join(&path);
        crate::io::write_atomic(&target, &bytes)
            .map_err(|e| format!("{}: {e}", target.display()))?;
    }
    Ok(m)
}

/// How one output file of a rerun compares with the pack's record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Identical,
    Differs,
    Missing,
    New,
}

/// Compare what a rerun wrote (`now`) with what the pack records (`then`), file by file.
pub fn compare(then: &[FileHash], now: &[FileHash]) -> Vec<(String, Verdict)> {
    let a: BTreeMap<&str, &str> = then
        .iter()
        .map(|f| (f.path.as_str(), f.sha256.as_str()))
        .collect();
    let b: BTreeMap<&str, &str> = now
        .iter()
        .map(|f| (f.path.as_str(), f.sha256.as_str()))
        .collect();
    let mut names: Vec<&str> = a.keys().chain(b.keys()).copied().collect();
    names.sort();
    names.dedup();
    names
        .into_iter()
        .map(|n| {
            let v = match (a.get(n), b.get(n)) {
                (Some(x), Some(y)) if x == y => Verdict::Identical,
                (Some(_), Some(_)) => Verdict::Differs,
                (Some(_), None) => Verdict::Missing,
                _ => Verdict::New,
            };
            (n.to_string(), v)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_paths_must_be_plain_and_relative() {
        for bad in [
            "../x",
            "/etc/passwd",
            "scene/../../x",
            "a//b",
            "./a",
            "C:/x",
            "a\\..\\b",
        ] {
            assert!(safe_entry_path(bad.as_bytes()).is_err(), "{bad}");
        }
        assert_eq!(
            safe_entry_path(b"scene/a/b.toml").unwrap(),
            "scene/a/b.toml"
        );
        assert_eq!(safe_entry_path(b"outputs/0/").unwrap(), "outputs/0");
    }

    #[test]
    fn recorded_commands_are_limited() {
        let v = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
        assert!(check_command(&v("render --scale 0.25 --samples 4")).is_ok());
        assert!(check_command(&v("truth")).is_ok());
        assert!(check_command(&v("evaluate --mode images")).is_err());
        assert!(check_command(&v("render -o /tmp/x")).is_err());
        assert!(check_command(&v("render --out=/tmp/x")).is_err());
        assert!(check_command(&v("render -o/tmp")).is_err());
        assert!(check_command(&v("render --set a=1")).is_err());
        assert!(check_command(&[]).is_err());
    }

    #[test]
    fn versions_name_what_differs() {
        let a = Versions::current();
        assert!(a.differences(&a).is_empty());
        assert!(a.backends.get("mitsuba").is_some_and(|v| !v.is_empty()));
        let mut b = a.clone();
        b.backends.insert("mitsuba".into(), "0.0.1".into());
        b.commit = "0000000".into();
        let d = a.differences(&b);
        assert_eq!(d.len(), 2, "{d:?}");
        assert!(d.iter().any(|l| l.starts_with("mitsuba ")));
    }

    #[test]
    fn comparison_sorts_files_into_four_verdicts() {
        let f = |p: &str, h: &str| FileHash {
            path: p.into(),
            sha256: h.into(),
            bytes: 1,
        };
        let then = [f("a", "1"), f("b", "2"), f("c", "3")];
        let now = [f("a", "1"), f("b", "9"), f("d", "4")];
        let v = compare(&then, &now);
        assert_eq!(
            v,
            vec![
                ("a".into(), Verdict::Identical),
                ("b".into(), Verdict::Differs),
                ("c".into(), Verdict::Missing),
                ("d".into(), Verdict::New)
            ]
        );
    }
}
