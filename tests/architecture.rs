//! The layering rules of poser's tree, checked on the source text (a small scan of `crate::…`
//! and `super::…` paths in code, comments skipped):
//!
//! | rule | why |
//! |---|---|
//! | `src/optics` imports nothing of `crate::scene` or `crate::model` | the optics is pure math on its own value types (`optics::types`, re-exported by the model) |
//! | no backend imports another (`backend/native`, `backend/mitsuba`, `backend/blender`) | backends are peers; `compare`, `bench` and the commands reach them through `backend::Backend` |
//! | nothing outside `src/scene` names `scene::format` | only the front end reads the raw scene format; everything else uses the resolved model |

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every source file as (path relative to `src/`, code with `//` comments removed).
fn sources() -> Vec<(String, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    assert!(files.len() > 20, "found only {} source files", files.len());
    files
        .into_iter()
        .map(|p| {
            let rel = p
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let code: String = std::fs::read_to_string(&p)
                .unwrap()
                .lines()
                .map(|l| match l.find("//") {
                    // `//` inside a string literal ("http://…") is rare in paths we look for;
                    // dropping the rest of such a line can only hide, never invent, a hit.
                    Some(i) => &l[..i],
                    None => l,
                })
                .collect::<Vec<_>>()
                .join("\n");
            (rel, code)
        })
        .collect()
}

/// The `crate::a::b…` paths of a file (the module chain after `crate::`), including the
/// members of `use crate::{a::…, b::…}` groups.
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while let Some(k) = code[i..].find("crate::") {
        let start = i + k;
        let before_ok =
            start == 0 || !(bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_');
        let mut j = start + "crate::".len();
        if before_ok {
            if code[j..].starts_with('{') {
                // A group: take its top-level members.
                let end = code[j..].find('}').map_or(code.len(), |e| j + e);
                for m in code[j + 1..end].split(',') {
                    let m: String = m.split_whitespace().collect();
                    if !m.is_empty() {
                        out.push(m);
                    }
                }
                j = end;
            } else {
                let end = code[j..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                    .map_or(code.len(), |e| j + e);
                out.push(code[j..end].trim_end_matches(':').to_string());
                j = end;
            }
        }
        i = j.max(start + 1);
    }
    out
}

/// The backend a source file belongs to, if any.
fn backend_of(rel: &str) -> Option<&'static str> {
    for b in ["native", "mitsuba", "blender"] {
        if rel == format!("backend/{b}.rs") || rel.starts_with(&format!("backend/{b}/")) {
            return Some(b);
        }
    }
    None
}

fn violations() -> Vec<String> {
    let mut bad = Vec::new();
    for (rel, code) in sources() {
        let paths = crate_paths(&code);
        if rel.starts_with("optics/") {
            for p in &paths {
                if p == "scene"
                    || p.starts_with("scene::")
                    || p == "model"
                    || p.starts_with("model::")
                {
                    bad.push(format!("src/{rel}: optics imports crate::{p}"));
                }
            }
        }
        if let Some(me) = backend_of(&rel) {
            for other in ["native", "mitsuba", "blender"]
                .into_iter()
                .filter(|&b| b != me)
            {
                let hit = paths.iter().any(|p| {
                    p == &format!("backend::{other}")
                        || p.starts_with(&format!("backend::{other}::"))
                }) || code.contains(&format!("super::{other}"));
                if hit {
                    bad.push(format!(
                        "src/{rel}: backend `{me}` imports backend `{other}`"
                    ));
                }
            }
        }
        if !rel.starts_with("scene/") {
            for p in &paths {
                if p == "scene::format" || p.starts_with("scene::format::") {
                    bad.push(format!(
                        "src/{rel}: reads the raw scene format (crate::{p})"
                    ));
                }
            }
        }
    }
    bad
}

#[test]
fn the_layering_rules_hold() {
    let bad = violations();
    assert!(bad.is_empty(), "layering rules broken:\n{}", bad.join("\n"));
}

/// The scan itself finds what it must (so the rule test cannot pass by finding nothing).
#[test]
fn the_scan_sees_imports() {
    let p = crate_paths(
        "use crate::model::{Camera, Port};\nlet x = crate::optics::phase::hg_eval(g, c);\nuse crate::{backend::mitsuba, scene::format::Scene};",
    );
    assert_eq!(
        p,
        [
            "model",
            "optics::phase::hg_eval",
            "backend::mitsuba",
            "scene::format::Scene"
        ]
    );
    let all = sources();
    let uses_model = all
        .iter()
        .filter(|(_, c)| crate_paths(c).iter().any(|p| p.starts_with("model")))
        .count();
    assert!(
        uses_model > 10,
        "only {uses_model} files seen importing the model"
    );
    assert_eq!(backend_of("backend/mitsuba.rs"), Some("mitsuba"));
    assert_eq!(backend_of("backend/native/integrator.rs"), Some("native"));
    assert_eq!(backend_of("backend/mod.rs"), None);
}
