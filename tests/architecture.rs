//! The layering rules of poser's tree, checked on the source text: a small scan of the
//! `crate::…`, `super::…` and `self::…` paths in code (comments skipped), each resolved to
//! the module it names from the file's module and the inline `mod … {}` around it, and every
//! `use` group expanded, nested groups included (`use crate::{optics::{glass, water},
//! model::Model};` names `optics::glass`, `optics::water` and `model::Model`).
//!
//! | rule | why |
//! |---|---|
//! | the optics crate (`crates/poser-optics`) depends on no path crate and on glam, serde and rayon only | the optics is pure math on its own value types (`optics::types`, re-exported by the model); the compiler now keeps it from naming the scene or the model, since it cannot see them, so only its manifest is checked |
//! | no backend imports another (`backend/native`, `backend/mitsuba`, `backend/blender`) | backends are peers; `compare`, `bench` and the commands reach them through `backend::Backend` |
//! | nothing outside `src/scene` names `scene::format`, but for the importers (`src/import/`), which may name its key constants (`scene::format::types`) | only the front end reads the raw scene format; everything else uses the resolved model; the importers *write* the format, naming each key through the constant the reader names it by |
//! | no backend names the front end's insides (`scene::reader`, `resolve`, `check`, `format`, `source`) | a backend works from the resolved model; it may load a scene (`scene::load`, in its tests) and format numbers as diagnostics do (`scene::diag`) |
//! | nothing outside `src/cli` (and `src/main.rs`) imports `crate::cli` | the library sits under the CLI: `explain`, point lists and channel names live in the library, for the CLI, Python and the fuzz targets alike |
//! | no function in `src/` or the optics crate is over 150 lines, but for a commented allowlist that may only shrink | a long function is a list of steps that wants names |
//! | every source file of `src/` and the optics crate opens with a `//!` header | the header says which one idea the file owns |
//! | no two top-level modules of `src/` import each other, directly or through others | each module sits above or below another, so it can be read, tested and moved on its own; a cycle inside one module (a port's files and `port/mod.rs`) is allowed |
//!
//! Each hole a scan can have is planted in a probe test below, which expects the violation.

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

/// The module path of a source file (`optics/port/mod.rs` → `optics::port`; `lib.rs` → root).
fn module_of(rel: &str) -> Vec<String> {
    let rel = rel.trim_end_matches(".rs");
    let mut m: Vec<String> = rel.split('/').map(str::to_string).collect();
    if matches!(m.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        m.pop();
    }
    m
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Expand a use tree at the start of `s` (`a::b`, `a::{b, c::{d, e}}`, `{a, b}`, `a::*`,
/// `a as b`) into its paths; returns them and the bytes read.
fn use_tree(s: &str) -> (Vec<Vec<String>>, usize) {
    let b = s.as_bytes();
    let mut i = 0;
    let skip_ws = |i: &mut usize| {
        while *i < b.len() && b[*i].is_ascii_whitespace() {
            *i += 1;
        }
    };
    let mut prefix: Vec<String> = Vec::new();
    loop {
        skip_ws(&mut i);
        if i < b.len() && b[i] == b'{' {
            // A group: each member is a tree of its own.
            let mut out = Vec::new();
            i += 1;
            loop {
                skip_ws(&mut i);
                if i >= b.len() {
                    return (out, i);
                }
                if b[i] == b'}' {
                    i += 1;
                    break;
                }
                if b[i] == b',' {
                    i += 1;
                    continue;
                }
                let (members, n) = use_tree(&s[i..]);
                i += n;
                // Past the member's tail (`as name`, or what is not a path) to `,` or `}`.
                while i < b.len() && b[i] != b',' && b[i] != b'}' {
                    i += 1;
                }
                for m in members {
                    out.push(prefix.iter().cloned().chain(m).collect());
                }
            }
            return (out, i);
        }
        let start = i;
        while i < b.len() && (is_ident(b[i]) || b[i] == b'*') {
            i += 1;
        }
        if i == start {
            break;
        }
        prefix.push(s[start..i].to_string());
        let mut j = i;
        skip_ws(&mut j);
        if s[j..].starts_with("::") {
            i = j + 2;
        } else {
            break;
        }
    }
    if prefix.is_empty() {
        return (vec![], i);
    }
    (vec![prefix], i)
}

/// Every path of a file (`rel`, relative to `src/`) that starts at `crate::`, `super::` or
/// `self::`, resolved to the module chain it names from the crate root (`super::model::Model`
/// in `optics/mod.rs` is `model::Model`; inline `mod tests { … }` add a level), use groups
/// expanded, `self` members and globs folded into their parent. Braces are counted to know
/// the inline modules; braces in string literals can only shift, never invent, a module.
fn paths_of(rel: &str, code: &str) -> Vec<String> {
    let module = module_of(rel);
    let b = code.as_bytes();
    let mut out = Vec::new();
    // One entry per open brace: the name of the inline module it opens, if it does.
    let mut braces: Vec<Option<String>> = Vec::new();
    let mut pending: Option<String> = None;
    let mut i = 0;
    while i < b.len() {
        let boundary = i == 0 || !(is_ident(b[i - 1]) || b[i - 1] == b':');
        match b[i] {
            b'{' => braces.push(pending.take()),
            b'}' => {
                braces.pop();
            }
            b';' => pending = None,
            _ => {}
        }
        if boundary && b[i..].starts_with(b"mod ") {
            let name: String = code[i + 4..]
                .trim_start()
                .bytes()
                .take_while(|&c| is_ident(c))
                .map(char::from)
                .collect();
            pending = Some(name);
            i += 4;
            continue;
        }
        let starts = [&b"crate::"[..], b"super::", b"self::"]
            .iter()
            .any(|k| b[i..].starts_with(k));
        if !(starts && boundary) {
            i += 1;
            continue;
        }
        let (trees, n) = use_tree(&code[i..]);
        let mut here: Vec<String> = module.clone();
        here.extend(braces.iter().flatten().cloned());
        for tree in trees {
            let mut base = here.clone();
            let mut segs = tree.into_iter().peekable();
            match segs.peek().map(String::as_str) {
                Some("crate") => {
                    base.clear();
                    segs.next();
                }
                Some("self") => {
                    segs.next();
                }
                _ => {}
            }
            while segs.peek().map(String::as_str) == Some("super") {
                segs.next();
                base.pop();
            }
            let mut full: Vec<String> = base;
            full.extend(segs.filter(|s| s != "self" && s != "*"));
            if !full.is_empty() {
                out.push(full.join("::"));
            }
        }
        i += n.max(1);
    }
    out
}

/// The `crate::…` paths of code at the crate root (what [`paths_of`] gives for `lib.rs`).
fn crate_paths(code: &str) -> Vec<String> {
    paths_of("lib.rs", code)
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

/// `p` is module `m` or inside it.
fn under(p: &str, m: &str) -> bool {
    p == m || p.starts_with(&format!("{m}::"))
}

/// The front end's insides, which no backend names.
const FRONT_END_INSIDES: [&str; 5] = [
    "scene::reader",
    "scene::resolve",
    "scene::check",
    "scene::format",
    "scene::source",
];

/// The rules broken by `files` (path relative to `src/`, code without comments).
fn violations_in(files: &[(String, String)]) -> Vec<String> {
    let mut bad = Vec::new();
    for (rel, code) in files {
        let paths = paths_of(rel, code);
        if let Some(me) = backend_of(rel) {
            for other in ["native", "mitsuba", "blender"]
                .into_iter()
                .filter(|&b| b != me)
            {
                if paths.iter().any(|p| under(p, &format!("backend::{other}"))) {
                    bad.push(format!(
                        "src/{rel}: backend `{me}` imports backend `{other}`"
                    ));
                }
            }
            for p in &paths {
                if FRONT_END_INSIDES.iter().any(|m| under(p, m)) {
                    bad.push(format!(
                        "src/{rel}: backend `{me}` reaches into the front end (crate::{p})"
                    ));
                }
            }
        }
        if !rel.starts_with("scene/") {
            let keys_only = rel.starts_with("import/");
            for p in paths
                .iter()
                .filter(|p| under(p, "scene::format"))
                .filter(|p| !(keys_only && under(p, "scene::format::types")))
            {
                bad.push(format!(
                    "src/{rel}: reads the raw scene format (crate::{p})"
                ));
            }
        }
        if !rel.starts_with("cli/") && rel != "cli.rs" && rel != "main.rs" {
            for p in paths.iter().filter(|p| under(p, "cli")) {
                bad.push(format!(
                    "src/{rel}: the library imports the CLI (crate::{p})"
                ));
            }
        }
    }
    bad
}

fn violations() -> Vec<String> {
    violations_in(&sources())
}

/// The top-level modules of `src/` (a file's first path component; `lib.rs` and `main.rs`
/// left out) and, for each, the top-level modules its code names.
fn module_graph(
    files: &[(String, String)],
) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    let mut g: std::collections::BTreeMap<String, std::collections::BTreeSet<String>> =
        Default::default();
    for (rel, code) in files {
        let Some(me) = module_of(rel).first().cloned() else {
            continue;
        };
        let to = g.entry(me.clone()).or_default();
        for p in paths_of(rel, code) {
            let top = p.split("::").next().unwrap_or_default().to_string();
            if top != me && !top.is_empty() {
                to.insert(top);
            }
        }
    }
    g
}

/// Every set of two or more top-level modules that import one another (the graph's strongly
/// connected components), each sorted.
fn module_cycles(files: &[(String, String)]) -> Vec<Vec<String>> {
    let g = module_graph(files);
    let reach = |from: &String| {
        let mut seen = std::collections::BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(m) = stack.pop() {
            for n in g.get(&m).into_iter().flatten() {
                if seen.insert(n.clone()) {
                    stack.push(n.clone());
                }
            }
        }
        seen
    };
    let reaches: std::collections::BTreeMap<&String, _> = g.keys().map(|m| (m, reach(m))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for m in g.keys() {
        let group: Vec<String> = g
            .keys()
            .filter(|n| reaches[m].contains(*n) && reaches[*n].contains(m))
            .cloned()
            .collect();
        if group.len() > 1 && !out.contains(&group) {
            out.push(group);
        }
    }
    out
}

#[test]
fn no_two_top_level_modules_import_each_other() {
    let files = sources();
    let g = module_graph(&files);
    assert!(
        g.len() > 20 && g["backend"].contains("model"),
        "the module graph is too thin: {g:?}"
    );
    let cycles = module_cycles(&files);
    assert!(
        cycles.is_empty(),
        "top-level modules that import each other (move the shared piece below both, as \
         `io::read` and `noise` are): {cycles:?}"
    );
}

/// A cycle through a third module, with `super::` and grouped paths, is found.
#[test]
fn probe_a_cycle_between_top_level_modules() {
    let files = [
        ("pack/mod.rs", "use crate::{io::sha256, model::Model};"),
        ("io.rs", "fn f() { super::backend::native::resume::FILE; }"),
        (
            "backend/native/resume.rs",
            "use super::super::super::pack::hash_dir;",
        ),
        ("model.rs", ""),
    ]
    .map(|(r, c)| (r.to_string(), c.to_string()));
    assert_eq!(
        module_cycles(&files),
        vec![vec![
            "backend".to_string(),
            "io".to_string(),
            "pack".to_string()
        ]]
    );
    assert!(module_cycles(&files[1..]).is_empty());
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
            "model::Camera",
            "model::Port",
            "optics::phase::hg_eval",
            "backend::mitsuba",
            "scene::format::Scene"
        ]
    );
    let all = sources();
    let uses_model = all
        .iter()
        .filter(|(rel, c)| paths_of(rel, c).iter().any(|p| under(p, "model")))
        .count();
    assert!(
        uses_model > 10,
        "only {uses_model} files seen importing the model"
    );
    assert_eq!(backend_of("backend/mitsuba.rs"), Some("mitsuba"));
    assert_eq!(backend_of("backend/native/integrator.rs"), Some("native"));
    assert_eq!(backend_of("backend/mod.rs"), None);
    assert_eq!(module_of("optics/port/mod.rs"), ["optics", "port"]);
    assert_eq!(module_of("optics/glass.rs"), ["optics", "glass"]);
    assert!(module_of("lib.rs").is_empty());
}

/// The violations found in one planted file.
fn planted(rel: &str, code: &str) -> Vec<String> {
    violations_in(&[(rel.to_string(), code.to_string())])
}

/// Assert that planting `code` in `rel` breaks a rule, with a message containing `what`.
fn expect_caught(rel: &str, code: &str, what: &str) {
    let bad = planted(rel, code);
    assert!(
        bad.iter().any(|b| b.contains(what)),
        "`{code}` in src/{rel} was not caught ({what}): {bad:?}"
    );
}

// The optics once had a scan rule here (no `crate::scene`, no `crate::model`); it is now a
// crate of its own, and the compiler refuses such an import (see `optics_crate_*` below). The
// probes of path resolution use the rules that are still scanned.

#[test]
fn probe_super_path_to_the_cli() {
    expect_caught(
        "export/mod.rs",
        "use super::cli::CliError;",
        "the library imports the CLI (crate::cli::CliError)",
    );
    // `super` of a file module is its parent, not the root.
    expect_caught(
        "points.rs",
        "use super::cli::CliError;",
        "the library imports the CLI (crate::cli::CliError)",
    );
}

#[test]
fn probe_super_super_from_a_nested_module() {
    expect_caught(
        "truth/colmap.rs",
        "use super::super::cli::common;",
        "the library imports the CLI (crate::cli::common)",
    );
    expect_caught(
        "backend/native/integrator.rs",
        "use super::super::super::scene::format::Scene;",
        "reads the raw scene format (crate::scene::format::Scene)",
    );
    // An inline module adds a level: `super` in `mod tests` is the file's module.
    expect_caught(
        "geometry/bvh.rs",
        "pub fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::super::super::cli::Cli;\n}",
        "the library imports the CLI (crate::cli::Cli)",
    );
    // …and resolves correctly: these name `backend::cli`, `geometry::cli`, not the CLI.
    assert!(planted("backend/native/camera.rs", "use super::super::cli::X;").is_empty());
    assert!(
        planted(
            "geometry/bvh.rs",
            "mod tests {\n    use super::f;\n}\nuse super::cli;"
        )
        .is_empty()
    );
}

#[test]
fn probe_nested_use_groups() {
    expect_caught(
        "export/gltf.rs",
        "use crate::{optics::{glass, water}, cli::Cli};",
        "the library imports the CLI (crate::cli::Cli)",
    );
    expect_caught(
        "export/gltf.rs",
        "use crate::{\n    optics::{glass::{self, Glass}, water},\n    scene::{format::{Scene}},\n};",
        "reads the raw scene format (crate::scene::format::Scene)",
    );
    expect_caught(
        "export/gltf.rs",
        "use super::{glass, super::cli::{self}};",
        "the library imports the CLI (crate::cli)",
    );
    assert_eq!(
        crate_paths("use crate::{optics::{glass, water as w}, model::*};"),
        ["optics::glass", "optics::water", "model"]
    );
}

/// The importers write the format: they may name its key constants (`scene::format::types`),
/// nothing else of it; no one else may name even those.
#[test]
fn probe_importers_name_only_the_format_keys() {
    assert!(planted("import/mitsuba.rs", "use crate::scene::format::types as F;").is_empty());
    assert!(
        planted(
            "import/blender.rs",
            "use super::super::scene::format::types::{Light, Camera};"
        )
        .is_empty()
    );
    expect_caught(
        "import/mod.rs",
        "use crate::scene::format::{types as F, schema_json};",
        "reads the raw scene format (crate::scene::format::schema_json)",
    );
    expect_caught(
        "import/verify.rs",
        "let s = crate::scene::format::docgen::format_markdown();",
        "reads the raw scene format (crate::scene::format::docgen::format_markdown)",
    );
    expect_caught(
        "importer.rs",
        "use crate::scene::format::types as F;",
        "reads the raw scene format (crate::scene::format::types)",
    );
    expect_caught(
        "backend/native/mod.rs",
        "use crate::scene::format::types as F;",
        "reads the raw scene format (crate::scene::format::types)",
    );
    expect_caught(
        "explain.rs",
        "use crate::scene::format::types::Light;",
        "reads the raw scene format (crate::scene::format::types::Light)",
    );
}

#[test]
fn probe_front_end_insides_from_a_backend() {
    expect_caught(
        "backend/native/mod.rs",
        "use crate::scene::reader::Cx;",
        "reaches into the front end (crate::scene::reader::Cx)",
    );
    expect_caught(
        "backend/mitsuba/view.rs",
        "fn f() { let t = crate::scene::reader::Tab::new(); }",
        "crate::scene::reader::Tab::new",
    );
    expect_caught(
        "backend/blender/data.rs",
        "use super::super::super::scene::{resolve, diag};",
        "crate::scene::resolve",
    );
    // A backend may load a scene (in its tests) and format numbers like the diagnostics.
    assert!(
        planted(
            "backend/native/mod.rs",
            "let m = crate::scene::load(p, &[]);\nlet s = crate::scene::diag::num(1.0);"
        )
        .is_empty()
    );
}

#[test]
fn probe_backends_are_peers() {
    expect_caught(
        "backend/native/integrator.rs",
        "use super::super::mitsuba::view;",
        "backend `native` imports backend `mitsuba`",
    );
    expect_caught(
        "backend/blender/mod.rs",
        "use crate::backend::{native::{render_one}, Backend};",
        "backend `blender` imports backend `native`",
    );
}

#[test]
fn probe_the_library_under_the_cli() {
    expect_caught(
        "export/gltf.rs",
        "use crate::cli::project::parse_points;",
        "the library imports the CLI (crate::cli::project::parse_points)",
    );
    expect_caught(
        "bench/mod.rs",
        "fn f() { super::super::cli::explain::explain(m) }",
        "the library imports the CLI (crate::cli::explain::explain)",
    );
    expect_caught(
        "lib.rs",
        "use self::cli::CliError;",
        "the library imports the CLI",
    );
    // The CLI's own modules and the binary may.
    assert!(
        planted(
            "cli/render.rs",
            "use super::{CliError, SceneArgs};\nuse crate::cli::common;"
        )
        .is_empty()
    );
    assert!(planted("main.rs", "use crate::cli::main;").is_empty());
}

// ---- Function length ----------------------------------------------------------------------

/// The longest a function in `src/` may be, in lines from its `fn` line to its closing brace.
/// A longer function is a list of steps that wants names; split it.
const MAX_FN_LINES: usize = 150;

/// The functions still over [`MAX_FN_LINES`], as `file::name` with their line count when the
/// check was written. The list may only shrink: a function not on it may not grow past the
/// limit, and one on it may not grow past its count (split it instead). Delete an entry once its
/// function is split; the check fails on an entry that is no longer over the limit.
const LONG_FNS: &[(&str, usize)] = &[];

/// `code` with the insides of comments, strings and character literals blanked to spaces (line
/// breaks kept), so that braces can be counted and `fn` found in code only.
fn blank_non_code(code: &str) -> Vec<u8> {
    let b = code.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to.min(b.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        let prev_ident = i > 0 && is_ident(b[i - 1]);
        if b[i..].starts_with(b"//") {
            let end = b[i..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(b.len(), |e| i + e);
            blank(&mut out, i, end);
            i = end;
        } else if b[i..].starts_with(b"/*") {
            let (mut depth, mut j) = (1, i + 2);
            while j < b.len() && depth > 0 {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            blank(&mut out, i, j);
            i = j;
        } else if !prev_ident && (b[i] == b'r' || b[i..].starts_with(b"br")) && {
            let k = i + if b[i] == b'b' { 2 } else { 1 };
            let h = b[k..].iter().take_while(|&&c| c == b'#').count();
            b.get(k + h) == Some(&b'"')
        } {
            // A raw string: r"…", r#"…"#, br"…".
            let k = i + if b[i] == b'b' { 2 } else { 1 };
            let h = b[k..].iter().take_while(|&&c| c == b'#').count();
            let mut close = vec![b'"'];
            close.extend(std::iter::repeat_n(b'#', h));
            let body = k + h + 1;
            let end = b[body..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(b.len(), |e| body + e + close.len());
            blank(&mut out, body, end - close.len().min(end - body));
            i = end;
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            blank(&mut out, i + 1, j);
            i = j + 1;
        } else if b[i] == b'\'' {
            // A character literal ('x', '\n', '\u{7f}', 'é'), or else a lifetime ('a).
            if b.get(i + 1) == Some(&b'\\') {
                let mut j = i + 2;
                while j < b.len() && b[j] != b'\'' {
                    j += 1;
                }
                blank(&mut out, i + 1, j);
                i = j + 1;
            } else {
                let ch = code[i + 1..].chars().next().map_or(1, char::len_utf8);
                if b.get(i + 1 + ch) == Some(&b'\'') {
                    blank(&mut out, i + 1, i + 1 + ch);
                    i += 2 + ch;
                } else {
                    i += 1;
                }
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Every function with a body in `code`, as (name, length in lines), nested ones included.
fn fn_lengths(code: &str) -> Vec<(String, usize)> {
    let b = blank_non_code(code);
    let line_at = |i: usize| b[..i].iter().filter(|&&c| c == b'\n').count();
    let mut found = Vec::new();
    let mut i = 0;
    while let Some(at) = b[i..].windows(3).position(|w| w == b"fn ") {
        let start = i + at;
        i = start + 3;
        if start > 0 && is_ident(b[start - 1]) {
            continue;
        }
        let name_from = start
            + 3
            + b[start + 3..]
                .iter()
                .take_while(|c| c.is_ascii_whitespace())
                .count();
        let name_len = b[name_from..].iter().take_while(|&&c| is_ident(c)).count();
        if name_len == 0 {
            continue;
        }
        let name = String::from_utf8_lossy(&b[name_from..name_from + name_len]).into_owned();
        // The body opens at the first `{` outside the signature's brackets; a `;` first means
        // a declaration without a body (in a trait or an `extern` block).
        let mut depth = 0i32;
        let mut j = name_from + name_len;
        let open = loop {
            match b.get(j) {
                None => break None,
                Some(b'(' | b'[' | b'<') => depth += 1,
                Some(b')' | b']') => depth -= 1,
                Some(b'>') if b[j - 1] != b'-' && b[j - 1] != b'=' => depth -= 1,
                Some(b';') if depth <= 0 => break None,
                Some(b'{') if depth <= 0 => break Some(j),
                _ => {}
            }
            j += 1;
        };
        let Some(open) = open else { continue };
        let mut depth = 0usize;
        let mut k = open;
        while k < b.len() {
            match b[k] {
                b'{' => depth += 1,
                b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                _ => {}
            }
            k += 1;
        }
        found.push((name, line_at(k) - line_at(start) + 1));
    }
    found
}

/// The source trees the per-file rules cover (function length, headers), each with the prefix
/// its files are named by: `src/` by the path inside it (`plan/dive.rs`), the optics crate by
/// the path from the repository root (`crates/poser-optics/src/column.rs`), and so the model
/// crate. The third number: the fewest files the scan must find there (fewer means it missed some).
const TREES: [(&str, &str, usize); 3] = [
    ("src", "", 100),
    (OPTICS_SRC, "crates/poser-optics/src/", 10),
    ("crates/poser-model/src", "crates/poser-model/src/", 2),
];

/// The optics crate's sources.
const OPTICS_SRC: &str = "crates/poser-optics/src";

/// Every source file of [`TREES`] as (name, full text).
fn tree_files() -> Vec<(String, String)> {
    let mut all = Vec::new();
    for (dir, prefix, fewest) in TREES {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
        let mut files = Vec::new();
        rust_files(&root, &mut files);
        files.sort();
        assert!(
            files.len() >= fewest,
            "found only {} files in {dir}",
            files.len()
        );
        for p in files {
            let rel = p
                .strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            all.push((
                format!("{prefix}{rel}"),
                std::fs::read_to_string(&p).unwrap(),
            ));
        }
    }
    all
}

/// Every function of [`TREES`] as (`file::name`, lines).
fn all_fn_lengths() -> Vec<(String, usize)> {
    let mut all = Vec::new();
    for (rel, text) in tree_files() {
        for (name, n) in fn_lengths(&text) {
            all.push((format!("{rel}::{name}"), n));
        }
    }
    all
}

/// The breaches of the length rule in `fns` against `allowed`.
fn length_violations(fns: &[(String, usize)], allowed: &[(&str, usize)]) -> Vec<String> {
    let mut bad = Vec::new();
    for (name, n) in fns {
        match allowed.iter().find(|(a, _)| a == name) {
            None if *n > MAX_FN_LINES => bad.push(format!(
                "{name} is {n} lines, over the limit of {MAX_FN_LINES}: split it into named steps"
            )),
            Some((_, cap)) if n > cap => bad.push(format!(
                "{name} grew to {n} lines, past its allowlisted {cap}: split it"
            )),
            _ => {}
        }
    }
    for (a, _) in allowed {
        if !fns.iter().any(|(name, n)| name == a && *n > MAX_FN_LINES) {
            bad.push(format!(
                "{a} is allowlisted but no longer over {MAX_FN_LINES} lines (or gone): drop it from LONG_FNS"
            ));
        }
    }
    bad
}

#[test]
fn no_function_is_over_the_length_limit() {
    let fns = all_fn_lengths();
    assert!(fns.len() > 500, "found only {} functions", fns.len());
    let optics = fns
        .iter()
        .filter(|(f, _)| f.starts_with("crates/poser-optics/"))
        .count();
    assert!(
        optics > 100,
        "found only {optics} functions in the optics crate"
    );
    let mut long: Vec<_> = fns.iter().filter(|(_, n)| *n > MAX_FN_LINES).collect();
    long.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let bad = length_violations(&fns, LONG_FNS);
    assert!(
        bad.is_empty(),
        "function length:\n{}\n\nall over the limit now:\n{}",
        bad.join("\n"),
        long.iter()
            .map(|(f, n)| format!("    (\"{f}\", {n}),"))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The scan measures what it must: strings, comments and character literals holding braces do
/// not end a body early, nested functions and methods are measured, bodiless declarations are not.
#[test]
fn the_length_scan_measures_functions() {
    let code = "fn a() {\n    let s = \"}}}\";\n    let c = '}';\n    // }\n    /* } */\n    let r = r#\"}\"#;\n    fn inner<'a>(x: &'a str) -> &'a str {\n        x\n    }\n}\ntrait T {\n    fn decl(&self) -> Vec<u8>;\n    fn with_body(&self) where Self: Sized { }\n}\n";
    assert_eq!(
        fn_lengths(code),
        [
            ("a".to_string(), 10),
            ("inner".to_string(), 3),
            ("with_body".to_string(), 1)
        ]
    );
}

/// A planted long function is caught; an allowlisted one may not grow, and an allowlist entry
/// that is no longer long must go, so the list can only shrink.
#[test]
fn probe_a_long_function() {
    let body = "    step();\n".repeat(MAX_FN_LINES);
    let code = format!("fn long_one() {{\n{body}}}\nfn short() {{}}\n");
    let fns: Vec<_> = fn_lengths(&code)
        .into_iter()
        .map(|(n, l)| (format!("planted.rs::{n}"), l))
        .collect();
    assert_eq!(
        fns[0],
        ("planted.rs::long_one".to_string(), MAX_FN_LINES + 2)
    );
    let bad = length_violations(&fns, &[]);
    assert!(
        bad.len() == 1 && bad[0].contains("planted.rs::long_one is 152 lines, over the limit"),
        "{bad:?}"
    );
    assert!(length_violations(&fns, &[("planted.rs::long_one", MAX_FN_LINES + 2)]).is_empty());
    let grew = length_violations(&fns, &[("planted.rs::long_one", MAX_FN_LINES + 1)]);
    assert!(
        grew.len() == 1 && grew[0].contains("grew to 152 lines"),
        "{grew:?}"
    );
    let stale = length_violations(
        &fns,
        &[("planted.rs::long_one", 152), ("planted.rs::short", 200)],
    );
    assert!(
        stale.len() == 1
            && stale[0].contains("planted.rs::short is allowlisted but no longer over"),
        "{stale:?}"
    );
}

// ---- File headers -------------------------------------------------------------------------

/// The files of `files` (name, full text) whose first line is not a `//!` header.
fn header_violations(files: &[(String, String)]) -> Vec<String> {
    files
        .iter()
        .filter(|(_, text)| !text.starts_with("//!"))
        .map(|(rel, _)| format!("{rel}: no `//!` header saying what the file owns"))
        .collect()
}

#[test]
fn every_source_file_opens_with_its_header() {
    let files = tree_files();
    assert!(
        files
            .iter()
            .any(|(f, _)| f == "crates/poser-optics/src/lib.rs"),
        "the optics crate is not scanned"
    );
    let bad = header_violations(&files);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn probe_a_file_without_a_header() {
    let bad = header_violations(&[
        ("a.rs".into(), "//! Owns a.\nfn a() {}\n".into()),
        ("b.rs".into(), "// a plain comment\n//! too late\n".into()),
        ("c.rs".into(), "\n//! after a blank line\n".into()),
    ]);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].starts_with("b.rs:") && bad[1].starts_with("c.rs:"));
}

// ---- The optics crate's dependencies ------------------------------------------------------

/// A stage crate's allowed dependencies: `deps`, the crates it may name; `paths`, those of
/// them that may be path dependencies (the stages below it).
struct Stage {
    name: &'static str,
    deps: &'static [&'static str],
    paths: &'static [&'static str],
}

/// The optics: vectors, serialisation of its value types, and the thread pool of the
/// water-column solver; no stage of poser.
const OPTICS: Stage = Stage {
    name: "the optics",
    deps: &["glam", "rayon", "serde"],
    paths: &[],
};

/// The model: the optics (its value types), vectors and serialisation; nothing above it.
const MODEL: Stage = Stage {
    name: "the model",
    deps: &["glam", "poser-optics", "serde"],
    paths: &["poser-optics"],
};

/// What breaks a stage crate's isolation in its manifest `manifest`, with the workspace's
/// manifest `workspace` (for `workspace = true` entries): a dependency by path other than the
/// stage's `paths` (`poser` itself, or a stage above it), or a crate not in its `deps`, in any
/// dependency table (normal, dev, build, per target). That the optics code names nothing of
/// the scene or the model, and the model nothing of the scene or the back ends, is then the
/// compiler's to enforce: they cannot see them.
fn manifest_violations(manifest: &str, workspace: &str, stage: &Stage) -> Vec<String> {
    let m: toml::Table = toml::from_str(manifest).expect("the optics manifest parses");
    let w: toml::Table = toml::from_str(workspace).expect("the workspace manifest parses");
    let shared = w
        .get("workspace")
        .and_then(|t| t.get("dependencies"))
        .and_then(toml::Value::as_table);
    let mut tables: Vec<(String, &toml::Table)> = Vec::new();
    for kind in ["dependencies", "dev-dependencies", "build-dependencies"] {
        if let Some(t) = m.get(kind).and_then(toml::Value::as_table) {
            tables.push((kind.to_string(), t));
        }
    }
    for (target, t) in m
        .get("target")
        .and_then(toml::Value::as_table)
        .into_iter()
        .flatten()
    {
        for kind in ["dependencies", "dev-dependencies", "build-dependencies"] {
            if let Some(d) = t.get(kind).and_then(toml::Value::as_table) {
                tables.push((format!("target.{target}.{kind}"), d));
            }
        }
    }
    let mut bad = Vec::new();
    for (kind, deps) in tables {
        for (name, spec) in deps {
            let inherited = spec.get("workspace").and_then(toml::Value::as_bool) == Some(true);
            let resolved = if inherited {
                shared.and_then(|s| s.get(name))
            } else {
                Some(spec)
            };
            let crate_name = spec
                .get("package")
                .and_then(toml::Value::as_str)
                .unwrap_or(name);
            if resolved.is_some_and(|r| r.get("path").is_some())
                && !stage.paths.contains(&crate_name)
            {
                bad.push(format!(
                    "[{kind}] {name}: a path dependency ({} sees only {:?})",
                    stage.name, stage.paths
                ));
            }
            if !stage.deps.contains(&crate_name) {
                bad.push(format!(
                    "[{kind}] {name}: not one of {}'s crates {:?}",
                    stage.name, stage.deps
                ));
            }
        }
    }
    bad
}

fn read_manifest(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

/// The optics crate depends on no other crate of poser and on glam, serde and rayon only;
/// `src/` keeps no optics of its own (`poser::optics` is the crate, re-exported).
#[test]
fn optics_crate_depends_on_no_stage() {
    let manifest = read_manifest("crates/poser-optics/Cargo.toml");
    let bad = manifest_violations(&manifest, &read_manifest("Cargo.toml"), &OPTICS);
    assert!(
        bad.is_empty(),
        "crates/poser-optics/Cargo.toml:\n{}",
        bad.join("\n")
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for old in ["src/optics.rs", "src/rng.rs"] {
        assert!(
            !root.join(old).exists(),
            "{old} is back: the optics lives in its crate"
        );
    }
    // An empty `src/optics/` left by a checkout is harmless; a source file in it is not.
    let mut stray = Vec::new();
    if root.join("src/optics").is_dir() {
        rust_files(&root.join("src/optics"), &mut stray);
    }
    assert!(stray.is_empty(), "{stray:?}: the optics lives in its crate");
    let lib = read_manifest("src/lib.rs");
    assert!(
        lib.contains("pub use poser_optics as optics;"),
        "poser::optics is not re-exported"
    );
}

#[test]
fn probe_optics_crate_dependencies() {
    let workspace = "[workspace.dependencies]\nglam = \"0.34\"\nmodel = { path = \"crates/m\" }\n";
    let ok = "[dependencies]\nglam = { workspace = true }\nserde = \"1\"\n";
    assert!(manifest_violations(ok, workspace, &OPTICS).is_empty());
    for (planted, what) in [
        (
            "[dependencies]\nposer = { path = \"../..\" }\n",
            "poser: a path dependency",
        ),
        (
            "[dev-dependencies]\nposer = { path = \"../..\" }\n",
            "[dev-dependencies] poser",
        ),
        (
            "[dependencies]\nmodel = { workspace = true }\n",
            "model: a path dependency",
        ),
        (
            "[dependencies]\nglam = { path = \"../glam\" }\n",
            "glam: a path dependency",
        ),
        (
            "[dependencies]\ntoml = \"1\"\n",
            "toml: not one of the optics's crates",
        ),
        (
            "[dependencies]\nv = { package = \"nalgebra\", version = \"0.34\" }\n",
            "v: not one",
        ),
        (
            "[target.'cfg(unix)'.dependencies]\nlibc = \"0.2\"\n",
            "[target.cfg(unix).dependencies] libc",
        ),
    ] {
        let bad = manifest_violations(planted, workspace, &OPTICS);
        assert!(
            bad.iter().any(|b| b.contains(what)),
            "`{planted}` was not caught ({what}): {bad:?}"
        );
    }
}

// ---- The model crate's dependencies -------------------------------------------------------

/// The model crate depends on the optics crate, glam and serde only, so that it cannot name
/// the scene format, a back end or the CLI; `src/` keeps no model of its own (`poser::model`
/// is the crate, re-exported).
#[test]
fn model_crate_depends_on_the_optics_only() {
    let manifest = read_manifest("crates/poser-model/Cargo.toml");
    let bad = manifest_violations(&manifest, &read_manifest("Cargo.toml"), &MODEL);
    assert!(
        bad.is_empty(),
        "crates/poser-model/Cargo.toml:\n{}",
        bad.join("\n")
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(
        !root.join("src/model.rs").exists() && !root.join("src/model").exists(),
        "src/model is back: the model lives in its crate"
    );
    assert!(
        read_manifest("src/lib.rs").contains("pub use poser_model as model;"),
        "poser::model is not re-exported"
    );
}

#[test]
fn probe_model_crate_dependencies() {
    let workspace = "[workspace.dependencies]\nglam = \"0.34\"\n";
    let ok = "[dependencies]\nglam = { workspace = true }\nposer-optics = { path = \"../poser-optics\" }\n";
    assert!(manifest_violations(ok, workspace, &MODEL).is_empty());
    for (planted, what) in [
        (
            "[dependencies]\nposer = { path = \"../..\" }\n",
            "poser: a path dependency",
        ),
        (
            "[dependencies]\ntoml = \"1\"\n",
            "toml: not one of the model's crates",
        ),
        (
            "[dev-dependencies]\nposer-scene = { path = \"../poser-scene\" }\n",
            "[dev-dependencies] poser-scene: a path dependency",
        ),
    ] {
        let bad = manifest_violations(planted, workspace, &MODEL);
        assert!(
            bad.iter().any(|b| b.contains(what)),
            "`{planted}` was not caught ({what}): {bad:?}"
        );
    }
}
