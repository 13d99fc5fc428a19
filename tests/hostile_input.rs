//! What a user shares must be safe to open: every file a scene names — the scene itself, its
//! includes, meshes and point lists — is read only when it is a regular file under a size cap,
//! so an include of `/dev/zero` or of a named pipe is refused at once (it used to eat memory or
//! hang forever) with a diagnostic at the `include` entry; a binary file gives one "not a text
//! file" error that echoes none of its bytes; `--samples 0` is refused instead of rendering one
//! sample.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Run poser with `args`; kill it after `limit` (then the test fails). Returns (exit code,
/// stdout + stderr, how long it took).
fn poser(args: &[&std::ffi::OsStr], limit: Duration) -> (Option<i32>, String, Duration) {
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("poser {args:?} still running after {limit:?}: it hangs or reads without end");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let took = t0.elapsed();
    let o = child.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code(), text, took)
}

fn validate(scene: &Path) -> (Option<i32>, String, Duration) {
    poser(
        &["validate".as_ref(), scene.as_os_str()],
        Duration::from_secs(5),
    )
}

/// A small valid scene: the canonical pinhole scene including `includes` (after its own
/// `common.toml`), with `tables` appended. Returns its path and text.
fn scene(dir: &Path, includes: &[&str], tables: &str) -> (PathBuf, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/canonical");
    let common = std::fs::read_to_string(root.join("common.toml")).unwrap();
    std::fs::write(dir.join("common.toml"), common).unwrap();
    let own = std::fs::read_to_string(root.join("pinhole_air.toml")).unwrap();
    let mut list = vec!["\"common.toml\"".to_string()];
    list.extend(includes.iter().map(|i| format!("\"{i}\"")));
    let text = format!(
        "include = [{}]\n{}\n{tables}",
        list.join(", "),
        own.replacen("include = [\"common.toml\"]\n", "", 1)
    );
    let p = dir.join("scene.toml");
    std::fs::write(&p, &text).unwrap();
    (p, text)
}

/// `scene.toml:LINE:COL` of the first `needle` in `text`.
fn loc(text: &str, needle: &str) -> String {
    let at = text.find(needle).unwrap();
    let line = 1 + text[..at].matches('\n').count();
    let col = 1 + at - text[..at].rfind('\n').map_or(0, |i| i + 1);
    format!("scene.toml:{line}:{col}")
}

/// Make a named pipe (nobody ever writes to it: opening it for reading blocks forever).
fn mkfifo(p: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo");
}

/// The refusal is quick, is an error (exit 1), names the file and the entry's place
/// (`scene.toml:LINE:COL`), and has a help line.
fn refused_at(out: &(Option<i32>, String, Duration), what: &[&str], at: &str) {
    let (code, text, took) = out;
    assert_eq!(*code, Some(1), "{text}");
    assert!(*took < Duration::from_secs(1), "took {took:?}:\n{text}");
    for w in what {
        assert!(text.contains(w), "`{w}` missing from:\n{text}");
    }
    assert!(text.contains(at), "no location `{at}` in:\n{text}");
    assert!(text.contains("help:"), "no help line in:\n{text}");
}

#[test]
fn an_include_of_dev_zero_is_refused_at_once_where_it_is_named() {
    let d = tempfile::tempdir().unwrap();
    let (p, text) = scene(d.path(), &["/dev/zero"], "");
    let out = validate(&p);
    refused_at(
        &out,
        &["cannot read `/dev/zero`", "a character device"],
        &loc(&text, "\"/dev/zero\""),
    );
}

#[test]
fn an_include_of_a_named_pipe_is_refused_at_once_where_it_is_named() {
    let d = tempfile::tempdir().unwrap();
    mkfifo(&d.path().join("water.toml"));
    let p = d.path().join("scene.toml");
    std::fs::write(&p, "name = \"x\"\ninclude = [\"water.toml\"]\n").unwrap();
    let out = validate(&p);
    refused_at(
        &out,
        &["water.toml", "a named pipe (FIFO)"],
        "scene.toml:2:12",
    );
}

#[test]
fn a_named_pipe_or_device_as_the_scene_itself_is_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("scene.toml");
    mkfifo(&fifo);
    for (p, what) in [
        (fifo.as_path(), "a named pipe (FIFO)"),
        (Path::new("/dev/zero"), "a character device"),
    ] {
        let (code, text, took) = validate(p);
        assert_eq!(code, Some(1), "{text}");
        assert!(took < Duration::from_secs(1), "took {took:?}");
        assert!(text.contains(what) && text.contains("help:"), "{text}");
    }
}

#[test]
fn a_scene_file_larger_than_the_cap_is_refused_without_reading_it() {
    let d = tempfile::tempdir().unwrap();
    let cap = poser::scene::source::MAX_SCENE_BYTES;
    let big = d.path().join("big.toml");
    {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&big).unwrap());
        let line = format!("# {}\n", "x".repeat(1021));
        for _ in 0..(cap / 1024 + 1) {
            f.write_all(line.as_bytes()).unwrap();
        }
    }
    assert!(std::fs::metadata(&big).unwrap().len() > cap);
    let (code, text, took) = validate(&big);
    assert_eq!(code, Some(1), "{text}");
    assert!(took < Duration::from_secs(1), "took {took:?}");
    assert!(
        text.contains("big.toml")
            && text.contains("more than the 16.0 MiB")
            && text.contains("help:"),
        "{text}"
    );
    // Included, it is refused at the include.
    let p = d.path().join("scene.toml");
    std::fs::write(&p, "include = [\"big.toml\"]\n").unwrap();
    let out = validate(&p);
    refused_at(&out, &["more than the 16.0 MiB"], "scene.toml:1:12");
}

#[test]
fn a_mesh_or_points_file_that_is_a_pipe_or_device_is_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    mkfifo(&d.path().join("pipe.glb"));
    mkfifo(&d.path().join("pipe.csv"));
    let (p, text) = scene(
        d.path(),
        &[],
        "[[objects]]\nshape = \"mesh\"\npath = \"pipe.glb\"\n\n[[targets]]\nname = \"gcp\"\ntype = \"points_file\"\nfile = \"pipe.csv\"\n",
    );
    let out = validate(&p);
    refused_at(
        &out,
        &["a named pipe (FIFO)", "pipe.glb", "pipe.csv"],
        &loc(&text, "\"pipe.glb\""),
    );
    assert!(out.1.contains(&loc(&text, "\"pipe.csv\"")), "{}", out.1);
    let (p, text) = scene(
        d.path(),
        &[],
        "[[objects]]\nshape = \"mesh\"\npath = \"/dev/zero\"\n",
    );
    let out = validate(&p);
    refused_at(&out, &["a character device"], &loc(&text, "\"/dev/zero\""));
}

/// A binary file named as a scene (or included) is one error: "not a text file", where, and a
/// help line, and none of its bytes reach the terminal (no escape sequence, no NUL).
#[test]
fn a_binary_scene_is_one_error_that_echoes_none_of_its_bytes() {
    let d = tempfile::tempdir().unwrap();
    // Text, then an escape sequence that would clear the screen, then NULs and bytes that are
    // not UTF-8 (a PNG's signature).
    let mut bytes = b"name = \"x\"\n# \x1b[2J\x1b]0;owned\x07 \x00\x00\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend((0..=255u8).cycle().take(4096));
    let bin = d.path().join("photo.toml");
    std::fs::write(&bin, &bytes).unwrap();
    let inc = d.path().join("scene.toml");
    std::fs::write(&inc, "include = [\"photo.toml\"]\n").unwrap();
    for (p, at) in [(&bin, "photo.toml:2:"), (&inc, "photo.toml:2:")] {
        let (code, text, took) = validate(p);
        assert_eq!(code, Some(1), "{text}");
        assert!(took < Duration::from_secs(1));
        assert!(
            text.contains("`") && text.contains("is not a text file"),
            "{text}"
        );
        assert!(text.contains("a NUL byte here"), "{text}");
        assert!(text.contains(at), "{text}");
        assert!(text.contains("help:"), "{text}");
        // One error for the file (the including scene may have others of its own).
        assert_eq!(text.matches("error[E0010]").count(), 1, "{text}");
        if p == &bin {
            assert_eq!(text.matches("error[").count(), 1, "{text}");
        }
        assert!(
            !text
                .chars()
                .any(|c| c.is_control() && c != '\n' && c != '\t'),
            "control characters echoed: {text:?}"
        );
        assert!(
            !text.contains("owned") || text.contains("?[2J?]0;owned?"),
            "{text:?}"
        );
    }
    // Not UTF-8 from the first byte: an image named as a scene.
    let png = d.path().join("image.toml");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR").unwrap();
    let (code, text, _) = validate(&png);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("image.toml:1:1") && text.contains("byte 0x89, not UTF-8"),
        "{text}"
    );
    assert!(!text.contains("IHDR"), "{text}");
}

#[test]
fn zero_samples_on_the_command_line_is_refused_not_rendered_as_one() {
    let d = tempfile::tempdir().unwrap();
    let (p, _) = scene(d.path(), &[], "");
    let out = d.path().join("out");
    for cmd in ["render", "compare"] {
        let (code, text, _) = poser(
            &[
                cmd.as_ref(),
                p.as_os_str(),
                "--samples".as_ref(),
                "0".as_ref(),
                "-o".as_ref(),
                out.as_os_str(),
            ],
            Duration::from_secs(60),
        );
        assert_eq!(code, Some(2), "{cmd}: {text}");
        assert!(
            text.contains("--samples") && text.contains("at least one sample per pixel"),
            "{cmd}: {text}"
        );
        assert!(
            text.contains("help: use e.g. `--samples 64`"),
            "{cmd}: {text}"
        );
        assert!(!out.exists(), "{cmd}: wrote output");
    }
    // One sample is allowed.
    let (code, text, _) = poser(
        &[
            "render".as_ref(),
            p.as_os_str(),
            "--samples".as_ref(),
            "1".as_ref(),
            "--scale".as_ref(),
            "0.05".as_ref(),
            "--poses".as_ref(),
            "0".as_ref(),
            "--quiet".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        Duration::from_secs(120),
    );
    assert_eq!(code, Some(0), "{text}");
}

/// The Mitsuba importer (`poser import`), the second front end, reads the files a Mitsuba scene
/// names the same way: an `<include>` or an `obj` mesh that is a named pipe, or an include of
/// `/dev/zero` by a relative path, is refused at once where the XML names it.
#[test]
fn an_imported_mitsuba_scene_naming_a_pipe_or_device_is_refused_at_once() {
    let d = tempfile::tempdir().unwrap();
    mkfifo(&d.path().join("pipe.xml"));
    mkfifo(&d.path().join("pipe.obj"));
    std::os::unix::fs::symlink("/dev/zero", d.path().join("zero.xml")).unwrap();
    let cases = [
        (
            "inc.xml",
            "<include filename=\"pipe.xml\"/>",
            "a named pipe (FIFO)",
        ),
        (
            "zero.xml",
            "<include filename=\"zero.xml\"/>",
            "a character device",
        ),
        (
            "mesh.xml",
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>\n<shape type=\"obj\"><string name=\"filename\" value=\"pipe.obj\"/></shape>",
            "a named pipe (FIFO)",
        ),
    ];
    for (name, body, what) in cases {
        let name = format!("s_{name}");
        let xml = d.path().join(&name);
        std::fs::write(
            &xml,
            format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n"),
        )
        .unwrap();
        let out = d.path().join("out.toml");
        let (code, text, took) = poser(
            &[
                "import".as_ref(),
                xml.as_os_str(),
                "-o".as_ref(),
                out.as_os_str(),
            ],
            Duration::from_secs(5),
        );
        assert_eq!(code, Some(1), "{name}: {text}");
        assert!(took < Duration::from_secs(1), "{name}: took {took:?}");
        assert!(
            text.contains(what) && text.contains("help:"),
            "{name}: {text}"
        );
        // Where the XML names the file: the last line of the body.
        let line = 1 + body.lines().count();
        assert!(
            text.contains(&format!("{name}:{line}:")),
            "{name}: no location: {text}"
        );
        assert!(!out.exists());
    }
}
