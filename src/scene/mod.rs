//! The scene format front end: TOML scene files (with includes and `--set` overrides) →
//! diagnostics → the resolved [`Model`](crate::model::Model).
//!
//! Pipeline: [`source`] reads files into a spanned tree and merges includes and overrides;
//! [`resolve`] reads every table through [`reader`] (unit conversion, unknown keys, type
//! errors — all collected, never stopping at the first) into the model; [`check`] runs the
//! whole-scene physical checks; [`diag`] renders everything rustc-style. The format itself
//! (every table, key, unit and default) is documented in `docs/format.md`.
// `!(x > 0.0)` is deliberate throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
pub mod check;
pub mod diag;
pub mod format;
pub mod points_file;
pub mod reader;
pub mod resolve;
pub mod source;

pub use diag::{Diagnostic, Severity, Span};
/// The generated JSON Schema and Markdown reference of the format (`poser schema`); the raw
/// format types themselves stay inside the front end.
pub use format::{format_markdown, schema_json};

use crate::model::Model;
use std::path::{Path, PathBuf};

/// A successfully loaded scene, with its warnings.
pub struct Loaded {
    pub model: Model,
    pub warnings: Vec<Diagnostic>,
    /// Every file the scene was read from, in reading order without repeats: the scene file,
    /// its includes, then its assets (meshes, point lists). A reproducible pack holds these.
    pub files: Vec<PathBuf>,
}

impl Loaded {
    /// All warnings, rendered.
    pub fn render_warnings(&self) -> String {
        self.warnings.iter().map(|d| d.rendered.as_str()).collect()
    }
}

/// A scene that failed to load; `render` gives the full diagnostic text.
pub struct Failure {
    /// Errors and warnings, in source order of discovery.
    pub diagnostics: Vec<Diagnostic>,
}

impl std::fmt::Debug for Failure {
    /// The rendered diagnostics, so `load(..).unwrap()` panics with a readable message.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render())
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render())
    }
}

impl Failure {
    pub fn render(&self) -> String {
        let mut s: String = self
            .diagnostics
            .iter()
            .map(|d| d.rendered.as_str())
            .collect();
        let n = self.errors().count();
        s.push_str(&format!(
            "error: the scene is invalid ({n} error{})\n",
            if n == 1 { "" } else { "s" }
        ));
        s
    }
    pub fn errors(&self) -> impl Iterator<Item = &Diagnostic> {
        self.diagnostics.iter().filter(|d| d.is_error())
    }
}

/// Load, validate and resolve a scene file with `--set KEY=VALUE` overrides.
pub fn load(path: &Path, sets: &[String]) -> Result<Loaded, Failure> {
    load_sources(path, sets, source::Sources::default())
}

/// [`load`] for a scene unpacked from a pack: every file it names (includes, meshes, point
/// lists) must be inside `root` — a relative path without `..` that no link leads out of —
/// or it is not read and error `E0012` names it. `root` must exist.
pub fn load_within(path: &Path, sets: &[String], root: &Path) -> Result<Loaded, Failure> {
    let root = root.canonicalize().map_err(|e| Failure {
        diagnostics: vec![{
            let mut d = Diagnostic::error("E0012", format!("{}: {e}", root.display()))
                .help("unpack the pack again into a new folder");
            d.finish(&source::Sources::default());
            d
        }],
    })?;
    let sources = source::Sources {
        root: Some(root),
        ..Default::default()
    };
    load_sources(path, sets, sources)
}

fn load_sources(
    path: &Path,
    sets: &[String],
    mut sources: source::Sources,
) -> Result<Loaded, Failure> {
    let mut diags = Vec::new();
    let root = source::load_file(path, &mut sources, &mut diags, &mut Vec::new(), None);
    let Some(mut root) = root else {
        return Err(finish_failure(diags, &sources));
    };
    source::apply_sets(&mut root, sets, &mut sources, &mut diags);
    source::unset_leftovers(&mut root, "", &mut diags);
    let included = sources
        .included_at
        .iter()
        .enumerate()
        .map(|(i, at)| at.map(|at| (at, sources.files[i].0.clone())))
        .collect();
    let mut cx = reader::Cx {
        diags,
        files: Vec::new(),
        included,
    };
    let (model, spans) = resolve::resolve(&root, path, &sources, &mut cx);
    check::scene(&mut cx, &model, &spans);
    let mut diags = std::mem::take(&mut cx.diags);
    for d in &mut diags {
        d.finish(&sources);
    }
    if diags.iter().any(|d| d.is_error()) {
        Err(Failure { diagnostics: diags })
    } else {
        let mut files: Vec<PathBuf> = Vec::new();
        for f in sources.paths.iter().flatten().chain(&cx.files) {
            if !files.contains(f) {
                files.push(f.clone());
            }
        }
        Ok(Loaded {
            model,
            warnings: diags,
            files,
        })
    }
}

fn finish_failure(mut diags: Vec<Diagnostic>, sources: &source::Sources) -> Failure {
    for d in &mut diags {
        d.finish(sources);
    }
    Failure { diagnostics: diags }
}
