//! Reproducible packs (`poser pack`, `poser unpack`, `poser rerun`): one archive that holds a
//! scene with its includes and assets, the poser commands run on it, and the SHA-256 of every
//! file, so that a rerun on another machine can say, file by file, whether it got the same
//! bytes, and which version differs when it did not.
//!
//! | entry | content |
//! |---|---|
//! | `manifest.json` | always the first entry: format, poser's version and git commit, the pinned backend versions, the scene's entry, the `--set` list, the commands with the hashes of what each wrote, the hash of every packed file |
//! | `manifest.sig` | only in a signed pack, always the second entry: an ed25519 signature of `manifest.json` ([`sign`]) |
//! | `scene/…` | the scene file, its includes and its assets, at their paths below their common folder |
//! | `outputs/<k>/…` | with `--outputs`: the files that command `k` wrote |
//!
//! The archive is a gzip-compressed tar, written atomically. Reading ([`read`]) checks the whole
//! archive before it writes anything: only regular files and folders, relative paths without
//! `..`, at most [`MAX_ENTRIES`] entries of at most [`MAX_ENTRY_BYTES`] each and
//! [`MAX_TOTAL_BYTES`] in all, never expanding more than [`MAX_RATIO`] times its compressed size
//! (both enforced while decompressing, so a compression bomb stops after a few MiB), every file
//! listed in the manifest with the hash it has there, nothing unlisted, and a signature, when
//! there is one, that matches the manifest (and, when the reader names keys it trusts, was made
//! by one of them; an unsigned pack is then refused). It then writes into a
//! new or empty folder only (never through a link it did not create), into a temporary folder
//! first, checks that the scene names no file outside the pack
//! ([`crate::scene::load_within`]: no absolute path, no `..` out, no link out), and only then
//! moves the files into place. A pack that fails any check is refused with the entry named, and
//! nothing is written.

use crate::io::sha256;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::rc::Rc;

pub mod sign;
pub use sign::SignedBy;

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
/// Most bytes a whole pack may expand to (16 GiB).
pub const MAX_TOTAL_BYTES: u64 = 16 << 30;
/// Most a pack may expand relative to its compressed size: scene text, meshes and rendered
/// images compress a few times, a compression bomb about a thousand times.
pub const MAX_RATIO: u64 = 100;
/// The ratio is enforced once this much has been decompressed (small packs of very regular
/// text may compress better than [`MAX_RATIO`] without being a threat).
pub const RATIO_GRACE_BYTES: u64 = 8 << 20;

/// The size limits a pack is read with (the constants above; smaller in tests).
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    pub entries: usize,
    pub entry_bytes: u64,
    pub total_bytes: u64,
    pub ratio: u64,
    pub ratio_grace: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            entries: MAX_ENTRIES,
            entry_bytes: MAX_ENTRY_BYTES,
            total_bytes: MAX_TOTAL_BYTES,
            ratio: MAX_RATIO,
            ratio_grace: RATIO_GRACE_BYTES,
        }
    }
}
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
    /// The Python packages installed where the commands ran Python, asked of the interpreter
    /// they ran with ([`crate::backend::python::installed_versions`]): distribution name →
    /// version, and `python` itself. Empty (and not written) when no command used Python.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub installed: BTreeMap<String, String>,
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
            installed: BTreeMap::new(),
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
        // Installed packages are compared when both sides asked their interpreter.
        if !self.installed.is_empty() && !now.installed.is_empty() {
            let names: std::collections::BTreeSet<&String> =
                self.installed.keys().chain(now.installed.keys()).collect();
            for n in names {
                let (a, b) = (self.installed.get(n), now.installed.get(n));
                if a != b {
                    let show =
                        |v: Option<&String>| v.map_or("not installed".to_string(), |v| v.clone());
                    out.push(format!(
                        "installed {n} {} (pack) vs {} (here)",
                        show(a),
                        show(b)
                    ));
                }
            }
        }
        out
    }

    /// Installed packages whose version is not the pinned one, one line each.
    pub fn unpinned(&self) -> Vec<String> {
        self.installed
            .iter()
            .filter_map(|(n, v)| {
                let pinned = self.backends.get(n)?;
                (pinned != v).then(|| format!("{n} {v} is installed, {pinned} is pinned"))
            })
            .collect()
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
                    sha256: crate::io::sha256(&bytes),
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
/// With `key`, the pack is signed ([`sign`]).
pub fn write(
    path: &Path,
    manifest: &mut Manifest,
    scene_files: &[(PathBuf, String)],
    outputs: &[PathBuf],
    key: Option<&ed25519_dalek::SigningKey>,
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
    let total: u64 = entries.iter().map(|(_, b)| b.len() as u64).sum();
    if let Some((p, b)) = entries
        .iter()
        .find(|(_, b)| b.len() as u64 > MAX_ENTRY_BYTES)
    {
        return Err(format!(
            "`{p}` is {} bytes, more than the {MAX_ENTRY_BYTES} a pack entry may hold",
            b.len()
        ));
    }
    if total > MAX_TOTAL_BYTES {
        return Err(format!(
            "the pack would hold {total} bytes, more than the {MAX_TOTAL_BYTES} a pack may hold; pack without `--outputs`"
        ));
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
    let signature = key.map(|k| sign::sign(k, &json));
    crate::io::write_atomic_with(path, |tmp| {
        let archive = || -> std::io::Result<()> {
            let file = std::fs::File::create(tmp)?;
            let gz = flate2::write::GzEncoder::new(file, flate2::Compression::default());
            let mut tar = tar::Builder::new(gz);
            tar.mode(tar::HeaderMode::Deterministic);
            append(&mut tar, MANIFEST, &json)?;
            if let Some(sig) = &signature {
                append(&mut tar, sign::SIGNATURE, sig)?;
            }
            for (p, b) in &entries {
                append(&mut tar, p, b)?;
            }
            tar.into_inner()?.finish()?;
            Ok(())
        };
        archive().map_err(|e| format!("{}: {e}", path.display()))?;
        // A pack that unpacking would refuse as a compression bomb is not written.
        let compressed = std::fs::metadata(tmp)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .len();
        if total > RATIO_GRACE_BYTES && total > MAX_RATIO.saturating_mul(compressed.max(1)) {
            return Err(format!(
                "{}: the files compress more than {MAX_RATIO} times ({total} bytes into {compressed}), which `poser unpack` refuses as a compression bomb",
                path.display()
            ));
        }
        Ok(())
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

/// Counts the compressed bytes the decompressor has taken from the pack file.
struct Counted<R> {
    inner: R,
    n: Rc<Cell<u64>>,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let k = self.inner.read(buf)?;
        self.n.set(self.n.get() + k as u64);
        Ok(k)
    }
}

/// The decompressed stream, stopped with an error (and the reason in `tripped`) as soon as it
/// has given more than the total cap, or more than the ratio cap times the compressed bytes
/// taken so far.
struct Limited<R> {
    inner: R,
    out: u64,
    compressed: Rc<Cell<u64>>,
    limits: Limits,
    tripped: Tripped,
}

impl<R: Read> Read for Limited<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let k = self.inner.read(buf)?;
        self.out += k as u64;
        let l = &self.limits;
        let why = if self.out > l.total_bytes {
            Some(format!(
                "expands to more than {} bytes in all",
                l.total_bytes
            ))
        } else if self.out > l.ratio_grace
            && self.out > l.ratio.saturating_mul(self.compressed.get().max(1))
        {
            Some(format!(
                "expands more than {} times its compressed size ({} bytes from {}): a compression bomb",
                l.ratio,
                self.out,
                self.compressed.get()
            ))
        } else {
            None
        };
        if let Some(why) = why {
            *self.tripped.borrow_mut() = Some(why.clone());
            return Err(std::io::Error::other(why));
        }
        Ok(k)
    }
}

type PackReader = Limited<flate2::read::GzDecoder<Counted<std::fs::File>>>;
/// Which limit stopped the reading, once one has.
type Tripped = Rc<RefCell<Option<String>>>;

/// Open a pack for reading under `limits`; the second item says which limit stopped it.
fn open(pack: &Path, limits: &Limits) -> Result<(tar::Archive<PackReader>, Tripped), String> {
    let f = std::fs::File::open(pack).map_err(|e| format!("{}: {e}", pack.display()))?;
    let meta = f
        .metadata()
        .map_err(|e| format!("{}: {e}", pack.display()))?;
    if !meta.is_file() {
        return Err(format!("{}: not a regular file", pack.display()));
    }
    let compressed = Rc::new(Cell::new(0));
    let tripped = Rc::new(RefCell::new(None));
    let reader = Limited {
        inner: flate2::read::GzDecoder::new(Counted {
            inner: f,
            n: compressed.clone(),
        }),
        out: 0,
        compressed,
        limits: *limits,
        tripped: tripped.clone(),
    };
    Ok((tar::Archive::new(reader), tripped))
}

/// An I/O error while reading a pack: the limit that stopped it when one did.
fn read_error(
    shown: &std::path::Display,
    what: &str,
    e: std::io::Error,
    tripped: &RefCell<Option<String>>,
) -> String {
    match tripped.borrow().as_ref() {
        Some(why) => format!("{shown}: the pack {why}; refused"),
        None => format!("{shown}: {what} ({e})"),
    }
}

/// A pack that passed [`check`]: its manifest, and who signed it (a signature found is one
/// that matches the manifest; whether its key is trusted is the reader's to say, [`sign::judge`]).
#[derive(Debug, Clone)]
pub struct Checked {
    pub manifest: Manifest,
    pub signed_by: SignedBy,
    /// SHA-256 of the `manifest.json` and `manifest.sig` entries that were checked, so that
    /// unpacking can tell when the pack file changed since.
    manifest_sha256: String,
    signature_sha256: Option<String>,
}

/// Check a pack completely (see the module's table); nothing is written.
pub fn check(pack: &Path) -> Result<Checked, String> {
    check_with(pack, &Limits::default())
}

/// [`check`] under other limits.
pub fn check_with(pack: &Path, limits: &Limits) -> Result<Checked, String> {
    let shown = pack.display();
    let (mut ar, tripped) = open(pack, limits)?;
    let mut manifest: Option<Manifest> = None;
    let mut manifest_bytes = Vec::new();
    let mut signature: Option<Vec<u8>> = None;
    let mut seen: BTreeMap<String, (String, u64)> = BTreeMap::new();
    let mut declared: u64 = 0;
    let entries = ar
        .entries()
        .map_err(|e| read_error(&shown, "not a poser pack", e, &tripped))?;
    for (i, e) in entries.enumerate() {
        let mut e =
            e.map_err(|e| read_error(&shown, &format!("unreadable entry {i}"), e, &tripped))?;
        if i >= limits.entries {
            return Err(format!("{shown}: more than {} entries", limits.entries));
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
        if size > limits.entry_bytes {
            return Err(format!(
                "{shown}: `{path}` declares {size} bytes, more than the {} allowed",
                limits.entry_bytes
            ));
        }
        declared = declared.saturating_add(size);
        if declared > limits.total_bytes {
            return Err(format!(
                "{shown}: the entries up to `{path}` declare {declared} bytes, more than the {} a pack may hold",
                limits.total_bytes
            ));
        }
        if i == 0 {
            if path != MANIFEST {
                return Err(format!(
                    "{shown}: the first entry is `{path}`, not `{MANIFEST}`"
                ));
            }
            let mut text = Vec::new();
            (&mut e)
                .take(64 << 20)
                .read_to_end(&mut text)
                .map_err(|e| read_error(&shown, MANIFEST, e, &tripped))?;
            let m: Manifest =
                serde_json::from_slice(&text).map_err(|e| format!("{shown}: {MANIFEST}: {e}"))?;
            if m.format != FORMAT {
                return Err(format!(
                    "{shown}: format `{}`; this poser reads `{FORMAT}`",
                    m.format
                ));
            }
            manifest = Some(m);
            manifest_bytes = text;
            continue;
        }
        if path == sign::SIGNATURE {
            if i != 1 {
                return Err(format!(
                    "{shown}: `{}` is entry {i}; a signature is the second entry",
                    sign::SIGNATURE
                ));
            }
            let mut sig = Vec::new();
            (&mut e)
                .take(64 << 10)
                .read_to_end(&mut sig)
                .map_err(|e| read_error(&shown, sign::SIGNATURE, e, &tripped))?;
            signature = Some(sig);
            continue;
        }
        let mut h = Sha256::new();
        let n = std::io::copy(&mut (&mut e).take(limits.entry_bytes + 1), &mut h)
            .map_err(|e| read_error(&shown, &format!("`{path}`"), e, &tripped))?;
        if seen
            .insert(path.clone(), (crate::io::hex(&h.finalize()), n))
            .is_some()
        {
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
    let signed_by = match &signature {
        None => SignedBy::Unsigned,
        Some(sig) => SignedBy::Signed(
            sign::verify(sig, &manifest_bytes).map_err(|e| format!("{shown}: {e}; refused"))?,
        ),
    };
    Ok(Checked {
        manifest: m,
        signed_by,
        manifest_sha256: sha256(&manifest_bytes),
        signature_sha256: signature.as_deref().map(sha256),
    })
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

/// A folder a pack may be written into: new, or an empty folder that is not a link. A link is
/// refused even when it points at an empty folder: reading a pack never writes through a link
/// it did not create.
pub fn fresh_folder(dest: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(dest) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(format!("{}: {e}", dest.display())),
        Ok(m) if m.file_type().is_symlink() => Err(format!(
            "{} is a symbolic link; unpack into a new folder (a pack never writes through a link)",
            dest.display()
        )),
        Ok(m) if !m.is_dir() => Err(format!("{} exists and is not a folder", dest.display())),
        Ok(_) => {
            let mut rd = std::fs::read_dir(dest).map_err(|e| format!("{}: {e}", dest.display()))?;
            if rd.next().is_some() {
                Err(format!(
                    "{} is not empty; unpack into a new or empty folder so that no earlier file is mixed with the pack's (or written through)",
                    dest.display()
                ))
            } else {
                Ok(())
            }
        }
    }
}

/// Check `pack` (see [`check`]), then write its files below `dest`, a new or empty folder
/// ([`fresh_folder`]). The files are written into a temporary folder inside `dest` first, the
/// scene is checked to name no file outside the pack, and only then are they moved into place:
/// a pack that fails anything leaves `dest` as it was (a folder it created is removed).
/// With `trusted` keys, the pack must be signed by one of them ([`sign::judge`]); without, any
/// pack whose signature, if it has one, matches its manifest is read. Returns the checked pack.
pub fn read(
    pack: &Path,
    dest: &Path,
    trusted: &[ed25519_dalek::VerifyingKey],
) -> Result<Checked, String> {
    read_with(pack, dest, trusted, &Limits::default())
}

/// [`read`] under other limits.
pub fn read_with(
    pack: &Path,
    dest: &Path,
    trusted: &[ed25519_dalek::VerifyingKey],
    limits: &Limits,
) -> Result<Checked, String> {
    fresh_folder(dest)?;
    let checked = check_with(pack, limits)?;
    sign::judge(&checked.signed_by, trusted).map_err(|e| format!("{}: {e}", pack.display()))?;
    let m = &checked.manifest;
    let created = !dest.exists();
    if let Some(parent) = dest.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    }
    if created {
        std::fs::create_dir(dest).map_err(|e| format!("{}: {e}", dest.display()))?;
    }
    let result = (|| {
        let staging = tempfile::Builder::new()
            .prefix(crate::io::TEMP_PREFIX)
            .tempdir_in(dest)
            .map_err(|e| format!("{}: {e}", dest.display()))?;
        extract(pack, &checked, staging.path(), limits)?;
        confined(m, staging.path()).map_err(|e| format!("{}: {e}", pack.display()))?;
        let rd = std::fs::read_dir(staging.path()).map_err(|e| e.to_string())?;
        for e in rd {
            let e = e.map_err(|e| e.to_string())?;
            let to = dest.join(e.file_name());
            if std::fs::symlink_metadata(&to).is_ok() {
                return Err(format!(
                    "{} appeared while unpacking; nothing more was written",
                    to.display()
                ));
            }
            std::fs::rename(e.path(), &to).map_err(|e| format!("{}: {e}", to.display()))?;
        }
        Ok(())
    })();
    if result.is_err() && created {
        let _ = std::fs::remove_dir(dest);
    }
    result.map(|()| checked)
}

/// Write the pack's files into `dir` (a fresh temporary folder: every folder below it is made
/// here, files are created new, so nothing is written through a link), hashing each as it is
/// written against what [`check_with`] accepted (the pack file may have changed since): the
/// manifest and signature entries by their own hashes, every other file by the manifest's.
fn extract(pack: &Path, checked: &Checked, dir: &Path, limits: &Limits) -> Result<(), String> {
    let shown = pack.display();
    let m = &checked.manifest;
    let want: BTreeMap<&str, &FileHash> = m.files.iter().map(|f| (f.path.as_str(), f)).collect();
    let (mut ar, tripped) = open(pack, limits)?;
    let entries = ar
        .entries()
        .map_err(|e| read_error(&shown, "not a poser pack", e, &tripped))?;
    for e in entries {
        let mut e = e.map_err(|e| read_error(&shown, "unreadable entry", e, &tripped))?;
        if !e.header().entry_type().is_file() {
            continue;
        }
        let path = safe_entry_path(&e.path_bytes()).map_err(|m| format!("{shown}: {m}"))?;
        let target = dir.join(&path);
        let mut at = dir.to_path_buf();
        let parts: Vec<&str> = path.split('/').collect();
        for part in &parts[..parts.len() - 1] {
            at.push(part);
            match std::fs::symlink_metadata(&at) {
                Ok(md) if md.is_dir() => {}
                Ok(_) => {
                    return Err(format!(
                        "{shown}: `{path}`: a file stands where a folder should"
                    ));
                }
                Err(_) => std::fs::create_dir(&at).map_err(|e| format!("{}: {e}", at.display()))?,
            }
        }
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&target)
            .map_err(|e| format!("{}: {e}", target.display()))?;
        let mut w = HashingWriter {
            inner: std::io::BufWriter::new(file),
            h: Sha256::new(),
        };
        let n = std::io::copy(&mut (&mut e).take(limits.entry_bytes + 1), &mut w)
            .map_err(|e| read_error(&shown, &format!("`{path}`"), e, &tripped))?;
        std::io::Write::flush(&mut w.inner).map_err(|e| format!("{}: {e}", target.display()))?;
        let hash = crate::io::hex(&w.h.finalize());
        let ok = if path == MANIFEST {
            hash == checked.manifest_sha256
        } else if path == sign::SIGNATURE {
            checked.signature_sha256.as_ref() == Some(&hash)
        } else {
            want.get(path.as_str())
                .is_some_and(|f| f.sha256 == hash && f.bytes == n)
        };
        if !ok {
            return Err(format!(
                "{shown}: `{path}` changed while it was unpacked; nothing was written"
            ));
        }
    }
    Ok(())
}

/// Writes through and hashes what it writes.
struct HashingWriter<W> {
    inner: W,
    h: Sha256,
}

impl<W: std::io::Write> std::io::Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.h.update(&buf[..k]);
        Ok(k)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The unpacked scene (in `dir`) names no file outside the pack's scene folder: read by the
/// front end confined to it ([`crate::scene::load_within`]); any `E0012` refuses the pack.
/// Other problems of the scene are left to the commands that run it.
fn confined(m: &Manifest, dir: &Path) -> Result<(), String> {
    let scene = dir.join(&m.scene);
    let root = dir.join(SCENE_DIR);
    let Err(f) = crate::scene::load_within(&scene, &m.sets, &root) else {
        return Ok(());
    };
    let prefix = format!("{}/", dir.display());
    let outside: Vec<String> = f
        .diagnostics
        .iter()
        .filter(|d| d.code == "E0012")
        .map(|d| d.rendered.replace(&prefix, ""))
        .collect();
    if outside.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the scene names files outside the pack; refused\n{}",
            outside.join("").trim_end()
        ))
    }
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

    /// A pack of `files` (path below `scene/`, bytes), written by [`write`].
    fn pack_of(dir: &Path, files: &[(&str, Vec<u8>)]) -> PathBuf {
        let mut entries = Vec::new();
        for (rel, bytes) in files {
            let p = dir.join(rel.replace('/', "_"));
            std::fs::write(&p, bytes).unwrap();
            entries.push((p, format!("{SCENE_DIR}/{rel}")));
        }
        let mut m = Manifest {
            format: FORMAT.into(),
            versions: Versions::current(),
            scene: entries[0].1.clone(),
            sets: vec![],
            commands: vec![],
            files: vec![],
            outputs_included: false,
        };
        let pack = dir.join("p.poserpack");
        write(&pack, &mut m, &entries, &[], None).unwrap();
        pack
    }

    /// Bytes that do not compress (xorshift).
    fn noise(n: usize, seed: u64) -> Vec<u8> {
        let mut x = seed | 1;
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x as u8
            })
            .collect()
    }

    /// The total cap and the ratio cap refuse a pack while it is decompressed, and reading it
    /// then writes nothing (not even the folder); the default caps accept the same packs.
    #[test]
    fn total_and_ratio_caps_refuse_while_decompressing() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a");
        std::fs::create_dir(&a).unwrap();
        let pack = pack_of(
            &a,
            &[
                ("s.toml", b"name = \"x\"\n".to_vec()),
                ("one.bin", noise(64 << 10, 1)),
                ("two.bin", noise(64 << 10, 2)),
            ],
        );
        let m = check(&pack).unwrap().manifest;
        // What the entries declare; the stream is larger (headers, padding, the end blocks).
        let declared = m.files.iter().map(|f| f.bytes).sum::<u64>()
            + serde_json::to_vec_pretty(&m).unwrap().len() as u64;
        let small = Limits {
            total_bytes: 100 << 10,
            ..Limits::default()
        };
        let e = check_with(&pack, &small).unwrap_err();
        assert!(
            e.contains("declare") && e.contains("more than the 102400"),
            "{e}"
        );
        let just = Limits {
            total_bytes: declared,
            ..Limits::default()
        };
        let e = check_with(&pack, &just).unwrap_err();
        assert!(
            e.contains(&format!("expands to more than {declared} bytes")),
            "{e}"
        );
        let out = d.path().join("out");
        assert!(read_with(&pack, &out, &[], &small).is_err());
        assert!(!out.exists(), "a refused pack created its folder");

        let b = d.path().join("b");
        std::fs::create_dir(&b).unwrap();
        let zeros = pack_of(
            &b,
            &[
                ("s.toml", b"name = \"x\"\n".to_vec()),
                ("zeros.bin", vec![0; 4 << 20]),
            ],
        );
        assert!(check(&zeros).is_ok(), "4 MiB of zeros is under the grace");
        let tight = Limits {
            ratio: 10,
            ratio_grace: 256 << 10,
            ..Limits::default()
        };
        let e = check_with(&zeros, &tight).unwrap_err();
        assert!(
            e.contains("more than 10 times") && e.contains("compression bomb"),
            "{e}"
        );
        // Stopped soon after the grace, not at the end of the 4 MiB.
        let got: u64 = e
            .split('(')
            .nth(1)
            .and_then(|x| x.split(' ').next())
            .and_then(|x| x.parse().ok())
            .unwrap();
        assert!(got < 1 << 20, "decompressed {got} bytes before stopping");
        assert!(read_with(&zeros, &out, &[], &tight).is_err());
        assert!(!out.exists());
        assert!(read_with(&zeros, &out, &[], &Limits::default()).is_ok());
        assert_eq!(
            std::fs::read(out.join("scene/zeros.bin")).unwrap().len(),
            4 << 20
        );
    }

    #[test]
    fn writing_refuses_a_pack_that_reading_would_refuse_as_a_bomb() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("zeros.bin");
        std::fs::write(&p, vec![0u8; (RATIO_GRACE_BYTES + (1 << 20)) as usize]).unwrap();
        let mut m = Manifest {
            format: FORMAT.into(),
            versions: Versions::current(),
            scene: "scene/zeros.bin".into(),
            sets: vec![],
            commands: vec![],
            files: vec![],
            outputs_included: false,
        };
        let pack = d.path().join("x.poserpack");
        let e = write(&pack, &mut m, &[(p, "scene/zeros.bin".into())], &[], None).unwrap_err();
        assert!(e.contains("compression bomb"), "{e}");
        assert!(!pack.exists());
    }

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
        // Installed versions: compared when both sides have them.
        let mut p = a.clone();
        p.installed = [
            ("mitsuba", "3.9.1"),
            ("numpy", "1.26.4"),
            ("python", "3.11.2"),
        ]
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .into();
        assert!(p.differences(&a).is_empty(), "here did not ask");
        assert!(p.unpinned().is_empty());
        let mut q = p.clone();
        q.installed.insert("mitsuba".into(), "3.8.0".into());
        q.installed.remove("numpy");
        q.installed.insert("pycolmap".into(), "4.2.1".into());
        assert_eq!(
            p.differences(&q),
            [
                "installed mitsuba 3.9.1 (pack) vs 3.8.0 (here)",
                "installed numpy 1.26.4 (pack) vs not installed (here)",
                "installed pycolmap not installed (pack) vs 4.2.1 (here)",
            ]
        );
        assert_eq!(
            q.unpinned(),
            ["mitsuba 3.8.0 is installed, 3.9.1 is pinned"]
        );
        // A pack without the field reads as one that used no Python, and writes none.
        let json = serde_json::to_string(&a).unwrap();
        assert!(!json.contains("installed"));
        assert_eq!(serde_json::from_str::<Versions>(&json).unwrap(), a);
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
