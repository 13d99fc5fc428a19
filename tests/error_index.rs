//! The error index (`docs/errors.md`), generated like rustc's: every diagnostic code raised in
//! `src/` with the message it prints and the module that raises it, and, where the invalid
//! corpus (`tests/invalid/`) has one, a scene that raises it with what poser prints (the
//! corpus' snapshot). `poser validate --explain CODE` prints one entry from the copy compiled
//! into the binary.
//!
//! A stale index fails here; regenerate it with
//! `POSER_UPDATE_DOCS=1 cargo test --test suite error_index::` and commit `docs/errors.md`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One code: its kind, the distinct messages raising it, the modules, the first example.
#[derive(Default)]
struct Entry {
    messages: Vec<String>,
    modules: Vec<String>,
    example: Option<(String, String, String)>,
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().collect();
    entries.sort_by_key(|e| e.path());
    for e in entries {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The string literal starting at `s[i]` (a `"`), unescaped as far as the index needs:
/// `\"`, `\\`, and a `\` line continuation (which swallows the newline and the indentation).
fn literal(s: &str, i: usize) -> Option<String> {
    let b = s.as_bytes();
    if b.get(i) != Some(&b'"') {
        return None;
    }
    let mut out = String::new();
    let mut chars = s[i + 1..].chars();
    while let Some(c) = chars.next() {
        match c {
            '"' => return Some(out),
            '\\' => match chars.next()? {
                '\n' => {
                    let rest = chars.as_str();
                    chars = rest.trim_start().chars();
                }
                'n' => out.push(' '),
                other => out.push(other),
            },
            c => out.push(c),
        }
    }
    None
}

/// Every `Diagnostic::error(CODE, MESSAGE)` / `warning(…)` in `src/`: code → (kind, messages,
/// modules). A code held in a variable takes the message of the call that follows it.
fn scan(root: &Path) -> BTreeMap<String, Entry> {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let mut index: BTreeMap<String, Entry> = BTreeMap::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        // Unit tests (a module at the end of the file) raise made-up codes: left out.
        let s = text.split("#[cfg(test)]").next().unwrap_or("");
        let module = f.strip_prefix(root).unwrap().display().to_string();
        let mut calls: Vec<(usize, Option<String>, String)> = Vec::new();
        for kind in ["Diagnostic::error(", "Diagnostic::warning("] {
            for (at, _) in s.match_indices(kind) {
                let args = s[at + kind.len()..].trim_start();
                let args_at = s.len() - args.len();
                let code = literal(&s, args_at).filter(|c| is_code(c));
                let rest = match args.find(',') {
                    Some(k) => args[k + 1..].trim_start(),
                    None => continue,
                };
                let rest = rest.strip_prefix("format!(").unwrap_or(rest).trim_start();
                let Some(message) = literal(&s, s.len() - rest.len()) else {
                    continue;
                };
                calls.push((at, code, message));
            }
        }
        calls.sort_by_key(|c| c.0);
        // Every code literal in the file: the call it is the first argument of, or else the
        // next call after it (a code chosen into a variable).
        for (at, _) in s.match_indices('"') {
            let Some(code) = literal(&s, at).filter(|c| is_code(c)) else {
                continue;
            };
            let call = calls
                .iter()
                .find(|c| c.1.as_deref() == Some(&code) && c.0 < at && at - c.0 < 60)
                .or_else(|| {
                    calls
                        .iter()
                        .find(|c| c.0 > at && c.0 - at < 400 && c.1.is_none())
                });
            let Some((_, _, message)) = call else {
                continue;
            };
            let e = index.entry(code).or_default();
            if !e.messages.contains(message) {
                e.messages.push(message.clone());
            }
            if !e.modules.contains(&module) {
                e.modules.push(module.clone());
            }
        }
    }
    index
}

fn is_code(c: &str) -> bool {
    c.len() == 5
        && (c.starts_with('E') || c.starts_with('W'))
        && c[1..].bytes().all(|b| b.is_ascii_digit())
}

/// The invalid corpus: code → (file, scene text, what poser prints), first file by name.
fn examples(root: &Path, index: &mut BTreeMap<String, Entry>) {
    let mut files: Vec<_> = std::fs::read_dir(root.join("tests/invalid"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap_or_default();
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let snap = root.join(format!(
            "tests/snapshots/suite__diagnostics__invalid_corpus@{name}.snap"
        ));
        let Ok(snap) = std::fs::read_to_string(&snap) else {
            continue;
        };
        // The snapshot opens with a `---` line; its body follows the next `---` line.
        let body = snap
            .strip_prefix("---\n")
            .and_then(|s| s.split_once("\n---\n"))
            .map_or("", |(_, body)| body)
            .trim_end();
        let codes = text
            .lines()
            .find_map(|l| l.strip_prefix("# expect:"))
            .unwrap_or("");
        for code in codes.split_whitespace() {
            if let Some(e) = index.get_mut(code)
                && e.example.is_none()
            {
                e.example = Some((
                    format!("tests/invalid/{name}"),
                    text.trim_end().to_string(),
                    body.to_string(),
                ));
            }
        }
    }
}

fn render(index: &BTreeMap<String, Entry>) -> String {
    let mut s = String::from(
        "# Diagnostic codes\n\n\
         Every error (`E…`) and warning (`W…`) poser prints about a scene, with its message, the \
         module that raises it and, where the test corpus has one, a scene that raises it and \
         what poser prints. `poser validate --explain CODE` prints one entry.\n\n\
         Generated by `tests/error_index.rs` from `src/` and `tests/invalid/` \
         (`POSER_UPDATE_DOCS=1 cargo test --test suite error_index::`); do not edit by hand. \
         `{…}` in a message is filled in from the scene.\n\n\
         | code | kind | message |\n|---|---|---|\n",
    );
    for (code, e) in index {
        let kind = if code.starts_with('E') {
            "error"
        } else {
            "warning"
        };
        s.push_str(&format!(
            "| [{code}](#{}) | {kind} | {} |\n",
            code.to_lowercase(),
            e.messages[0].replace('|', "\\|")
        ));
    }
    for (code, e) in index {
        let kind = if code.starts_with('E') {
            "error"
        } else {
            "warning"
        };
        s.push_str(&format!("\n## {code}\n\n"));
        for m in &e.messages {
            s.push_str(&format!("{kind}: {m}\n\n"));
        }
        let modules: Vec<String> = e.modules.iter().map(|m| format!("`{m}`")).collect();
        s.push_str(&format!("Raised in {}.\n", modules.join(", ")));
        match &e.example {
            Some((file, scene, printed)) => s.push_str(&format!(
                "\nExample (`{file}`):\n\n```toml\n{scene}\n```\n\n```text\n{printed}\n```\n"
            )),
            None => s.push_str("\nThe invalid corpus has no example of it yet.\n"),
        }
    }
    s
}

fn generated() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut index = scan(root);
    examples(root, &mut index);
    render(&index)
}

#[test]
fn the_error_index_is_fresh() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("docs/errors.md");
    let want = generated();
    if std::env::var_os("POSER_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "docs/errors.md is stale: run `POSER_UPDATE_DOCS=1 cargo test --test suite error_index::`"
    );
}

#[test]
fn every_code_has_a_message_and_most_an_example() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut index = scan(root);
    // Every code literal in `src/` was found with its message (the scanner did not miss one).
    assert!(index.len() >= 100, "only {} codes found", index.len());
    for (code, e) in &index {
        assert!(!e.messages.is_empty(), "{code}: no message");
        assert!(
            e.messages.iter().all(|m| !m.trim().is_empty()),
            "{code}: an empty message"
        );
    }
    assert!(index.contains_key("E0042"), "a code chosen into a variable");
    examples(root, &mut index);
    let with = index.values().filter(|e| e.example.is_some()).count();
    // Measured: 56 of 104 when the index was made; the corpus only grows.
    assert!(with >= 56, "only {with} codes have an example");
    // Each example shows what poser prints for it: a diagnostic with that code.
    for (code, e) in &index {
        if let Some((file, _, out)) = &e.example {
            assert!(
                out.contains(&format!("[{code}]")),
                "{code}: the example {file} shows no `[{code}]` in its output: {out:?}"
            );
        }
    }
}

#[test]
fn validate_explain_prints_one_entry() {
    let bin = env!("CARGO_BIN_EXE_poser");
    let out = Command::new(bin)
        .args(["validate", "--explain", "E0290"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("## E0290"), "{text}");
    assert!(text.contains("albedo must be between 0 and 1"), "{text}");
    assert!(text.contains("albedo = 1.5"), "the example scene: {text}");
    assert!(
        text.contains("error[E0290]"),
        "what poser prints for it: {text}"
    );
    assert!(!text.contains("## E0291"), "one entry only: {text}");
    // Lower case is accepted; an unknown code is a clear error.
    let lower = Command::new(bin)
        .args(["validate", "--explain", "w0239"])
        .output()
        .unwrap();
    assert!(lower.status.success());
    assert!(String::from_utf8_lossy(&lower.stdout).contains("render.bounces"));
    let unknown = Command::new(bin)
        .args(["validate", "--explain", "E9999"])
        .output()
        .unwrap();
    assert!(!unknown.status.success());
    let err = String::from_utf8_lossy(&unknown.stderr);
    assert!(
        err.contains("E9999") && err.contains("docs/errors.md"),
        "{err}"
    );
}
