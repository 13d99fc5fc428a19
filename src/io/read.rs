//! Reading the files a scene names, the one bounded way: regular files only (a folder,
//! device, socket or named pipe is refused before it is opened), non-blocking, at most a cap
//! of bytes; the caps for meshes and other assets; the refusal's reason in words. The front
//! end, the mesh and texture loaders, the importers and the pack's key all read through it.

use std::path::Path;

/// Largest side of an image a mesh may name (or a generated texture may have), texels.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Largest other file a scene names (a point list, an MTL, an image, a glTF's buffer): 256 MiB.
pub const MAX_ASSET_BYTES: u64 = 256 << 20;

/// Largest mesh file a `mesh` object names (glTF, OBJ or PLY): 1 GiB. A photogrammetric model of
/// 5 M triangles is about 380 MB of OBJ text (`poser bench mesh`); the loader's own limit is
/// `geometry::meshfile::MAX_ELEMENTS` vertices or triangles.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// Why a file a scene names was not read ([`read_capped`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// It could not be looked at or opened (missing, permission denied, …): the reason.
    Unreadable(String),
    /// It is not a regular file: what it is ("a folder", "a named pipe (FIFO)", …).
    NotAFile(&'static str),
    /// It holds more than the cap allows.
    TooLarge { bytes: u64, cap: u64 },
}

impl Refusal {
    /// The reason, to follow "cannot read `file`: ".
    pub fn reason(&self) -> String {
        match self {
            Refusal::Unreadable(r) => r.clone(),
            Refusal::NotAFile(what) => format!("it is {what}, not a regular file"),
            Refusal::TooLarge { bytes, cap } => format!(
                "it is {}, more than the {} a scene may name",
                size_text(*bytes),
                size_text(*cap)
            ),
        }
    }
}

/// `1.5 MiB`-style size.
pub fn size_text(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else if bytes >= 1 << 20 {
        format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
    } else if bytes >= 1 << 10 {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    } else {
        format!("{bytes} bytes")
    }
}

/// What a non-regular file is.
fn file_kind(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// Read a file a scene names — the scene itself, an include, a mesh, a point list — the one way
/// the front end reads files: only a regular file (a folder, device, socket or named pipe is
/// refused from its metadata, before it is opened), opened non-blocking so that a named pipe
/// swapped in meanwhile cannot block, and of at most `cap` bytes (checked on the metadata and
/// again while reading, so a file that grows cannot exceed it).
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>, Refusal> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| Refusal::Unreadable(io_reason(&e)))?;
    if !meta.is_file() {
        return Err(Refusal::NotAFile(file_kind(meta.file_type())));
    }
    if meta.len() > cap {
        return Err(Refusal::TooLarge {
            bytes: meta.len(),
            cap,
        });
    }
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let f = opts
        .open(path)
        .map_err(|e| Refusal::Unreadable(io_reason(&e)))?;
    let meta = f
        .metadata()
        .map_err(|e| Refusal::Unreadable(io_reason(&e)))?;
    if !meta.is_file() {
        return Err(Refusal::NotAFile(file_kind(meta.file_type())));
    }
    let mut bytes = Vec::with_capacity(meta.len().min(cap) as usize);
    f.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Refusal::Unreadable(io_reason(&e)))?;
    if bytes.len() as u64 > cap {
        return Err(Refusal::TooLarge {
            bytes: bytes.len() as u64,
            cap,
        });
    }
    Ok(bytes)
}

/// Where a file that should be text is not: the byte offset of its first NUL or invalid UTF-8
/// byte, and that byte. `None` for text.
pub fn not_text(bytes: &[u8]) -> Option<(usize, u8)> {
    // `contains` on bytes is a memchr; a byte-by-byte `position` took a third of a second on a
    // 365 MB OBJ. Only the block that holds a NUL is searched byte by byte.
    const BLOCK: usize = 1 << 16;
    let nul = bytes
        .chunks(BLOCK)
        .position(|c| c.contains(&0))
        .and_then(|k| {
            let at = k * BLOCK;
            bytes[at..].iter().position(|&b| b == 0).map(|p| at + p)
        });
    let bad = std::str::from_utf8(bytes).err().map(|e| e.valid_up_to());
    let at = match (nul, bad) {
        (Some(a), Some(b)) => a.min(b),
        (a, b) => a.or(b)?,
    };
    Some((at, bytes[at]))
}

/// An I/O error in a few words ("no such file", "permission denied", "is a directory").
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => {
            let s = e.to_string();
            // "Is a directory (os error 21)" → "is a directory"
            s.split(" (os error").next().unwrap_or(&s).to_lowercase()
        }
    }
}
