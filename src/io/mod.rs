//! File plumbing shared by every command: atomic file writes (temporary file, then rename),
//! so that a failed run never leaves a half-written output behind, the SHA-256 of what was
//! written (packs, the renderer's resume manifest), and the one bounded way to read a file a
//! scene names ([`read`]).

pub mod read;

use std::io::Write;
use std::path::Path;

/// Prefix of the temporary files that atomic writes rename into place: a file with this prefix
/// is a write in progress or one that was cut short (the process was killed), never an output.
pub const TEMP_PREFIX: &str = ".poser-";

/// The prefix of this process's temporary files: [`TEMP_PREFIX`], then the host and the process
/// id that own them (`.poser-HOST-PID-`), so that a run cleaning up after a killed one leaves
/// alone the writes in progress of other runs into the same folder (the shards of a SLURM array).
pub fn temp_prefix() -> String {
    format!("{TEMP_PREFIX}{}-{}-", host(), std::process::id())
}

/// This machine's host name, reduced to `[A-Za-z0-9_.]` (a `-` would end it in a temp name).
fn host() -> String {
    let raw = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_default();
    let h: String = raw
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '.')
        .collect();
    if h.is_empty() { "host".into() } else { h }
}

/// Age past which a temporary file whose owner cannot be checked (another host, an older
/// poser's name without one) counts as cut short: one atomic write takes seconds.
const FOREIGN_TEMP_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// Whether the temporary file `name` (modified at `modified`) belongs to no running write:
/// its owner is a process of this host that no longer exists, or it cannot be checked and the
/// file is older than [`FOREIGN_TEMP_AGE`].
fn is_stale(name: &str, modified: Option<std::time::SystemTime>) -> bool {
    let owner = name.strip_prefix(TEMP_PREFIX).and_then(|rest| {
        let mut it = rest.splitn(3, '-');
        let (h, pid) = (it.next()?, it.next()?.parse::<u32>().ok()?);
        it.next()?;
        Some((h.to_string(), pid))
    });
    let proc_known = Path::new("/proc/self").exists();
    match owner {
        Some((h, pid)) if proc_known && h == host() => {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        }
        _ => modified
            .and_then(|m| m.elapsed().ok())
            .is_some_and(|age| age > FOREIGN_TEMP_AGE),
    }
}

/// Remove the temporary files of cut-short atomic writes directly in `dir` ([`is_stale`]: a
/// write in progress by another run into the same folder is kept); returns how many.
pub fn remove_stale_temporaries(dir: &Path) -> usize {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return 0;
    };
    rd.filter_map(Result::ok)
        .filter(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            name.starts_with(TEMP_PREFIX)
                && e.file_type().is_ok_and(|t| t.is_file())
                && is_stale(&name, e.metadata().ok().and_then(|m| m.modified().ok()))
        })
        .filter(|e| std::fs::remove_file(e.path()).is_ok())
        .count()
}

/// Write `bytes` to `path` atomically: a temporary file in the same directory, then rename.
/// Parent directories are created.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)?;
    let mut tmp = tempfile::Builder::new()
        .prefix(&temp_prefix())
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.flush()?;
    readable(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Put the finished folder `from` in place of `to`, replacing what `to` held: `to` is first
/// renamed aside (to `to` + `.old`), `from` renamed onto `to`, the old one then removed. Both
/// must be on the same file system (siblings, in poser's use). At every moment `to` is either
/// the old complete folder, absent for the instant between the two renames, or the new one.
pub fn replace_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    let mut aside = to.as_os_str().to_owned();
    aside.push(".old");
    let aside = std::path::PathBuf::from(aside);
    if aside.exists() {
        std::fs::remove_dir_all(&aside)?;
    }
    let had_old = to.exists();
    if had_old {
        std::fs::rename(to, &aside)?;
    }
    std::fs::rename(from, to)?;
    if had_old {
        std::fs::remove_dir_all(&aside)?;
    }
    Ok(())
}

/// Write with a closure that produces the file at a temporary path (for encoders that want a
/// path, such as EXR writers), then rename onto `path`.
pub fn write_atomic_with(
    path: &Path,
    f: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("tmp");
    let tmp = tempfile::Builder::new()
        .prefix(&temp_prefix())
        .suffix(&format!(".{ext}"))
        .tempfile_in(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?;
    let tmp_path = tmp.into_temp_path();
    f(&tmp_path)?;
    readable(&tmp_path).map_err(|e| format!("{}: {e}", path.display()))?;
    tmp_path
        .persist(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}

/// Temporary files are created 0600; outputs are meant to be shared, so make them 0644.
fn readable(path: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644))?;
    }
    #[cfg(not(unix))]
    let _ = path;
    Ok(())
}

/// The SHA-256 of `bytes`, as lowercase hex.
pub fn sha256(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    hex(&Sha256::digest(bytes))
}

/// Lowercase hex of a digest.
pub fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("sub/out.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let n = std::fs::read_dir(p.parent().unwrap()).unwrap().count();
        assert_eq!(n, 1, "temporary files left behind");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644);
        }
    }

    /// Images go through the path-taking writer: they must be as readable as the truth files
    /// (they were 0600, the temporary file's mode).
    #[test]
    fn path_writer_outputs_are_shareable() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("img.png");
        write_atomic_with(&p, |tmp| {
            std::fs::write(tmp, b"x").map_err(|e| e.to_string())
        })
        .unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644);
        }
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
    }

    /// A resumed run cleans up what a killed run left, but not the writes in progress of
    /// another run into the same folder (a SLURM shard lost an image to this).
    #[test]
    fn only_the_temporaries_of_dead_writers_are_removed() {
        let d = tempfile::tempdir().unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let live = format!("{}x.exr", temp_prefix());
        let dead_name = format!("{TEMP_PREFIX}{}-{dead}-y.exr", host());
        let foreign = format!("{TEMP_PREFIX}elsewhere-1-z.exr");
        for n in [&live, &dead_name, &foreign] {
            std::fs::write(d.path().join(n), b"partial").unwrap();
        }
        assert_eq!(remove_stale_temporaries(d.path()), 1);
        assert!(
            d.path().join(&live).exists(),
            "a write in progress was removed"
        );
        assert!(
            !d.path().join(&dead_name).exists(),
            "a dead writer's file stayed"
        );
        assert!(
            d.path().join(&foreign).exists(),
            "a fresh foreign write was removed"
        );
        assert!(is_stale(&foreign, Some(std::time::SystemTime::UNIX_EPOCH)));
        assert!(!is_stale(&live, Some(std::time::SystemTime::UNIX_EPOCH)));
    }

    #[test]
    fn a_finished_folder_replaces_the_old_one_whole() {
        let d = tempfile::tempdir().unwrap();
        let (new, to) = (d.path().join("images.partial"), d.path().join("images"));
        std::fs::create_dir_all(&to).unwrap();
        std::fs::write(to.join("stale.png"), b"old").unwrap();
        std::fs::create_dir_all(&new).unwrap();
        std::fs::write(new.join("a.png"), b"new").unwrap();
        replace_dir(&new, &to).unwrap();
        assert!(!new.exists() && !d.path().join("images.old").exists());
        let names: Vec<_> = std::fs::read_dir(&to)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["a.png"]);
        // Without an old folder, it is a rename.
        std::fs::create_dir_all(&new).unwrap();
        replace_dir(&new, &d.path().join("fresh")).unwrap();
        assert!(d.path().join("fresh").is_dir() && !new.exists());
    }
}
