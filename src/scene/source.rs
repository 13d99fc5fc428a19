//! Scene sources: reading TOML files into a spanned value tree ([`Node`]), resolving
//! `include = [...]` (deep merge, cycle detection) and applying `--set a.b.c=value` overrides.
//! Every node remembers the file and byte range it came from, so diagnostics can point into
//! included files and at the command line.

use super::diag::{Diagnostic, Span};
pub use crate::io::read::{
    MAX_ASSET_BYTES, MAX_MESH_BYTES, Refusal, not_text, read_capped, size_text,
};
use crate::scene::format::types as F;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};

/// Name of the pseudo-file holding the command-line overrides.
pub const COMMAND_LINE: &str = "<command line>";

/// Largest scene or included file the front end reads: 16 MiB. A scene is text that names its
/// meshes and point lists; anything larger is not a scene, and reading it would only cost
/// memory (the parsed tree takes tens of times the text).
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// All source texts a scene was read from (the scene, its includes, the command line).
#[derive(Default)]
pub struct Sources {
    pub files: Vec<(String, String)>,
    /// File-system path of each file (None for the command line).
    pub paths: Vec<Option<PathBuf>>,
    /// When set (the canonical folder of an unpacked pack's scene), every file the scene names
    /// must be inside it: a relative path without `..` that does not leave it through a link
    /// ([`outside_root`]).
    pub root: Option<PathBuf>,
    /// Per file, the span of the `include = [...]` entry that read it (None for the scene file
    /// itself and the command line): an inherited key's diagnostic points at both.
    pub included_at: Vec<Option<Span>>,
}

impl Sources {
    pub fn add(&mut self, name: String, text: String, path: Option<PathBuf>) -> usize {
        self.files.push((name, text));
        self.paths.push(path);
        self.included_at.push(None);
        self.files.len() - 1
    }
    /// [`Sources::add`] for a file read from `path`, named by the `include` entry at
    /// `included_from` (None: the scene file itself).
    pub fn add_included(
        &mut self,
        name: String,
        text: String,
        path: &Path,
        included_from: Option<Span>,
    ) -> usize {
        let file = self.add(name, text, Some(path.to_path_buf()));
        self.included_at[file] = included_from;
        file
    }
    /// Directory of the file a span points into (for resolving relative paths).
    pub fn dir_of(&self, file: usize) -> Option<PathBuf> {
        self.paths
            .get(file)
            .and_then(|p| p.as_ref())
            .map(|p| p.parent().map(Path::to_path_buf).unwrap_or_default())
    }
}

/// The text before byte `at` (valid UTF-8 by [`not_text`]) with every control character but
/// tab and newline replaced by `?` bytes of the same length, so that spans keep their offsets
/// and a diagnostic quoting it cannot send escape sequences to the terminal.
pub fn harmless_prefix(bytes: &[u8], at: usize) -> String {
    let text = std::str::from_utf8(&bytes[..at]).unwrap_or("");
    text.chars()
        .map(|c| {
            let bidi = matches!(c, '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}');
            if (c.is_control() && c != '\n' && c != '\t') || bidi {
                "?".repeat(c.len_utf8())
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Inside a pack ([`Sources::root`] set), why `rel` — named in a scene file, `joined` once
/// resolved against that file's folder — is not allowed: an absolute path, a `..` that climbs
/// out of the pack's folder, or a link that leads out of it. `None` when it is allowed or there
/// is no root. (`..` inside the pack is fine: `poser pack` keeps a scene that includes
/// `../shared/rig.toml` at the same relative layout.)
pub fn outside_root(sources: &Sources, rel: &str, joined: &Path) -> Option<String> {
    use std::path::Component;
    let root = sources.root.as_ref()?;
    let p = Path::new(rel);
    if p.has_root()
        || p.is_absolute()
        || rel.starts_with('\\')
        || matches!(p.components().next(), Some(Component::Prefix(_)))
    {
        return Some("an absolute path".into());
    }
    // Lexically: `..` popped, the longest existing folder above it canonicalized.
    let abs = if joined.is_absolute() {
        joined.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(joined)
    };
    let mut norm = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::ParentDir => {
                norm.pop();
            }
            Component::CurDir => {}
            c => norm.push(c),
        }
    }
    // The folders only: the named file itself may be a link, judged below.
    let mut base = norm.clone();
    let mut rest: Vec<std::ffi::OsString> = base.file_name().into_iter().map(Into::into).collect();
    base.pop();
    while !base.exists() {
        match base.file_name() {
            Some(n) => {
                rest.push(n.to_os_string());
                base.pop();
            }
            None => break,
        }
    }
    let mut lexical = base.canonicalize().unwrap_or(base);
    lexical.extend(rest.iter().rev());
    if !lexical.starts_with(root) {
        return Some("a path that climbs out of the pack with `..`".into());
    }
    // As the file system resolves it (links followed).
    match joined.canonicalize() {
        Ok(c) if !c.starts_with(root) => Some("a link that leads out of the pack".into()),
        _ => None,
    }
}

/// The diagnostic of a file named at `span` that is outside the pack ([`outside_root`]).
pub fn outside_diag(rel: &str, why: &str, span: Span) -> Diagnostic {
    Diagnostic::error("E0012", format!("`{rel}` is outside the pack"))
        .label(span, format!("{why}: a pack's scene reads only its own files"))
        .help("name files packed with the scene by relative paths below its folder (`poser pack` does this for every file the scene reads)")
}

#[derive(Debug, Clone)]
pub enum Val {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime(String),
    Array(Vec<Node>),
    Table(Table),
}

#[derive(Debug, Clone)]
pub struct Node {
    pub val: Val,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Entry {
    pub key: String,
    pub key_span: Span,
    pub node: Node,
}

/// A table with its entries in source order.
#[derive(Debug, Clone, Default)]
pub struct Table {
    pub entries: Vec<Entry>,
}

impl Table {
    pub fn get(&self, key: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.key == key)
    }
    fn get_mut(&mut self, key: &str) -> Option<&mut Entry> {
        self.entries.iter_mut().find(|e| e.key == key)
    }
    fn remove(&mut self, key: &str) -> Option<Entry> {
        let i = self.entries.iter().position(|e| e.key == key)?;
        Some(self.entries.remove(i))
    }
}

impl Val {
    pub fn type_name(&self) -> &'static str {
        match self {
            Val::Str(_) => "a string",
            Val::Int(_) => "an integer",
            Val::Float(_) => "a float",
            Val::Bool(_) => "a boolean",
            Val::Datetime(_) => "a date-time",
            Val::Array(_) => "an array",
            Val::Table(_) => "a table",
        }
    }
}

fn convert(v: &toml::Spanned<DeValue<'_>>, file: usize, diags: &mut Vec<Diagnostic>) -> Node {
    let r = v.span();
    let span = Span {
        file,
        start: r.start,
        end: r.end,
    };
    let val = match v.get_ref() {
        DeValue::String(s) => Val::Str(s.to_string()),
        DeValue::Integer(i) => match i64::from_str_radix(&i.as_str().replace('_', ""), i.radix()) {
            Ok(x) => Val::Int(x),
            Err(_) => {
                diags.push(
                    Diagnostic::error("E0002", "integer out of range")
                        .label(span, "does not fit in a 64-bit integer")
                        .help("write it as a float (e.g. `1e20`) or use a smaller number"),
                );
                Val::Int(0)
            }
        },
        DeValue::Float(f) => Val::Float(
            f.as_str()
                .replace('_', "")
                .parse::<f64>()
                .unwrap_or(f64::NAN),
        ),
        DeValue::Boolean(b) => Val::Bool(*b),
        DeValue::Datetime(d) => Val::Datetime(d.to_string()),
        DeValue::Array(a) => Val::Array(a.iter().map(|x| convert(x, file, diags)).collect()),
        DeValue::Table(t) => Val::Table(convert_table(t, file, diags)),
    };
    Node { val, span }
}

fn convert_table(t: &DeTable<'_>, file: usize, diags: &mut Vec<Diagnostic>) -> Table {
    let mut entries: Vec<Entry> = t
        .iter()
        .map(|(k, v)| {
            let ks = k.span();
            Entry {
                key: k.get_ref().to_string(),
                key_span: Span {
                    file,
                    start: ks.start,
                    end: ks.end,
                },
                node: convert(v, file, diags),
            }
        })
        .collect();
    entries.sort_by_key(|e| (e.key_span.start, e.key_span.end));
    Table { entries }
}

/// Parse TOML text of file `file` into a table node. Syntax errors become diagnostics.
pub fn parse_text(text: &str, file: usize, diags: &mut Vec<Diagnostic>) -> Option<Node> {
    let (doc, errors) = DeTable::parse_recoverable(text);
    if !errors.is_empty() {
        for e in errors.iter().take(10) {
            let r = e.span().unwrap_or(0..0);
            let (start, end) = clamp_span(text, r.start, r.end);
            let msg = e.message().trim().to_string();
            let first = msg.lines().next().unwrap_or("invalid TOML").to_string();
            diags.push(
                Diagnostic::error("E0001", format!("TOML syntax error: {first}"))
                    .label(Span { file, start, end }, first)
                    .help(syntax_help(&msg)),
            );
        }
        return None;
    }
    let span = Span {
        file,
        start: 0,
        end: 0,
    };
    let mut d = Vec::new();
    let t = convert_table(doc.get_ref(), file, &mut d);
    diags.extend(d);
    Some(Node {
        val: Val::Table(t),
        span,
    })
}

fn clamp_span(text: &str, s: usize, e: usize) -> (usize, usize) {
    let mut s = s.min(text.len());
    while s > 0 && !text.is_char_boundary(s) {
        s -= 1;
    }
    let mut e = e.max(s).min(text.len());
    while e < text.len() && !text.is_char_boundary(e) {
        e += 1;
    }
    (s, e)
}

fn syntax_help(msg: &str) -> String {
    let m = msg.to_lowercase();
    if m.contains("duplicate") {
        "each key may appear only once per table; remove or rename one of them".into()
    } else if m.contains("string") || m.contains("quote") {
        "strings need double quotes on both ends, e.g. `thickness = \"10 mm\"`".into()
    } else {
        "see the TOML syntax at https://toml.io; values with units are strings: `depth = \"12 m\"`"
            .into()
    }
}

/// Whether `node` is the marker `{ unset = true }`, which removes the key it is written for
/// from what the included files set ([`merge`]).
pub fn is_unset(node: &Node) -> bool {
    matches!(&node.val, Val::Table(t)
        if t.entries.len() == 1 && t.entries[0].key == "unset"
            && matches!(t.entries[0].node.val, Val::Bool(true)))
}

/// Deep merge `over` onto `base`: tables merge key by key, everything else is replaced. A key
/// set to `{ unset = true }` in `over` removes the key from `base`; when `base` does not have
/// it the marker stays, for a later merge (a file included after the base) or for
/// [`unset_leftovers`] to report.
pub fn merge(base: &mut Node, over: Node) {
    match (&mut base.val, over.val) {
        (Val::Table(b), Val::Table(o)) => {
            for e in o.entries {
                if is_unset(&e.node) && b.get(&e.key).is_some_and(|be| !is_unset(&be.node)) {
                    b.remove(&e.key);
                    continue;
                }
                match b.get_mut(&e.key) {
                    Some(be) => {
                        be.key_span = e.key_span;
                        merge(&mut be.node, e.node);
                    }
                    None => b.entries.push(e),
                }
            }
        }
        (_, v) => {
            base.val = v;
            base.span = over.span;
        }
    }
}

/// Report every `{ unset = true }` left in the merged tree: it removed nothing, because no
/// included file sets that key (E0021, with the keys that table does have when one is close).
/// Also a table whose only key is `unset` with another value than `true`. The markers are
/// taken out of the tree, so the reader does not report them again.
pub fn unset_leftovers(node: &mut Node, path: &str, diags: &mut Vec<Diagnostic>) {
    let Val::Table(t) = &mut node.val else {
        if let Val::Array(a) = &mut node.val {
            for (i, x) in a.iter_mut().enumerate() {
                unset_leftovers(x, &format!("{path}[{i}]"), diags);
            }
        }
        return;
    };
    let siblings: Vec<String> = t
        .entries
        .iter()
        .filter(|e| !is_unset(&e.node))
        .map(|e| e.key.clone())
        .collect();
    let mut i = 0;
    while i < t.entries.len() {
        let e = &t.entries[i];
        let full = if path.is_empty() {
            e.key.clone()
        } else {
            format!("{path}.{}", e.key)
        };
        if is_unset(&e.node) {
            let mut d = Diagnostic::error(
                "E0021",
                format!("`{full}` is unset, but no included file sets it"),
            )
            .label(e.key_span, "nothing to remove here");
            d = match super::reader::did_you_mean(&e.key, siblings.iter().map(String::as_str)) {
                Some(s) => d.help(format!(
                    "did you mean `{s}`? `{{ unset = true }}` removes a key that an included file sets"
                )),
                None => d.help(
                    "`{ unset = true }` removes a key that an included file sets: check the key's \
                     spelling and table, or delete this line",
                ),
            };
            diags.push(d);
            t.entries.remove(i);
            continue;
        }
        if let Val::Table(inner) = &e.node.val
            && inner.entries.len() == 1
            && inner.entries[0].key == "unset"
        {
            let v = &inner.entries[0].node;
            diags.push(
                Diagnostic::error("E0021", format!("`{full}.unset` takes only `true`"))
                    .label(v.span, format!("found {}", v.val.type_name()))
                    .help(format!(
                        "write `{} = {{ unset = true }}` to remove the key an included file sets, or delete the line to keep it",
                        e.key
                    )),
            );
            t.entries.remove(i);
            continue;
        }
        unset_leftovers(&mut t.entries[i].node, &full, diags);
        i += 1;
    }
}

/// E0011 when `path` (canonical `canon`) is already being loaded (`stack`): the cycle, from
/// the file where it starts back to `path`.
fn include_cycle(
    path: &Path,
    canon: &Path,
    sources: &Sources,
    stack: &[PathBuf],
    included_from: Option<Span>,
) -> Option<Diagnostic> {
    let pos = stack.iter().position(|p| p.as_path() == canon)?;
    let chain: Vec<String> = sources
        .paths
        .iter()
        .flatten()
        .filter(|p| {
            p.canonicalize()
                .ok()
                .is_some_and(|c| stack[pos..].contains(&c))
        })
        .map(|p| display(p))
        .chain(std::iter::once(display(path)))
        .collect();
    let mut d = Diagnostic::error("E0011", "include cycle").help(
        "remove one of the includes in the cycle; an included file must not include its includer",
    );
    if let Some(s) = included_from {
        d = d.label(s, format!("includes `{}` again", display(path)));
    }
    Some(d.note(format!("cycle: {}", chain.join(" → "))))
}

/// E0010 for a scene file (or an include, named at `included_from`) that cannot be read.
fn unreadable(path: &Path, r: &Refusal, included_from: Option<Span>) -> Diagnostic {
    let mut d = Diagnostic::error(
        "E0010",
        format!("cannot read `{}`: {}", display(path), r.reason()),
    );
    let help = match r {
        Refusal::Unreadable(_) => None,
        Refusal::NotAFile(_) => Some(
            "a scene and its includes are TOML text files; folders, devices and named pipes are never read",
        ),
        Refusal::TooLarge { .. } => Some(
            "a scene file is text of at most 16 MiB: keep large data in the meshes and point lists it names",
        ),
    };
    d = match included_from {
        Some(s) => d.label(s, "included here").help(help.unwrap_or(
            "include paths are relative to the file that includes them; check the spelling",
        )),
        None => d.help(help.unwrap_or("check the path of the scene file")),
    };
    d
}

/// E0010 for a file that is not UTF-8 text (a bad byte `byte` at `at`): one diagnostic that
/// quotes none of the file's bytes but the harmless text before the bad one.
fn not_text_diag(
    path: &Path,
    bytes: &[u8],
    (at, byte): (usize, u8),
    sources: &mut Sources,
    included_from: Option<Span>,
) -> Diagnostic {
    // One diagnostic that quotes none of the file's bytes: only the text before the first
    // bad byte, made harmless, and a replacement character where it is.
    let mut shown = harmless_prefix(bytes, at);
    shown.push('\u{FFFD}');
    let file = sources.add(display(path), shown, Some(path.to_path_buf()));
    let bad = Span {
        file,
        start: at,
        end: at + '\u{FFFD}'.len_utf8(),
    };
    let what = if byte == 0 {
        "a NUL byte".to_string()
    } else {
        format!("byte 0x{byte:02x}, not UTF-8")
    };
    let mut d = Diagnostic::error("E0010", format!("`{}` is not a text file", display(path)))
        .label(bad, format!("{what} here"))
        .help("a scene is UTF-8 TOML text: check that the path names a scene and not an image or other binary file, or save the file as UTF-8");
    if let Some(s) = included_from {
        d = d.also(s, "included here");
    }
    d
}

/// Load `path` with its includes (recursively, relative to the including file), merged:
/// included files first in order, then the file itself on top.
pub fn load_file(
    path: &Path,
    sources: &mut Sources,
    diags: &mut Vec<Diagnostic>,
    stack: &mut Vec<PathBuf>,
    included_from: Option<Span>,
) -> Option<Node> {
    let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    if let Some(d) = include_cycle(path, &canon, sources, stack, included_from) {
        diags.push(d);
        return None;
    }
    if stack.len() > 32 {
        diags.push(Diagnostic::error(
            "E0011",
            "includes nested too deeply (more than 32 levels)",
        ));
        return None;
    }
    // Inside a pack, the scene file itself is in the pack's folder (its includes are checked
    // where they are named, below).
    if included_from.is_none()
        && let (Ok(c), Some(root)) = (path.canonicalize(), sources.root.as_ref())
        && !c.starts_with(root)
    {
        diags.push(
            Diagnostic::error("E0012", format!("`{}` is outside the pack", display(path)))
                .help("give the scene file inside the unpacked pack"),
        );
        return None;
    }
    let bytes = match read_capped(path, MAX_SCENE_BYTES) {
        Ok(b) => b,
        Err(r) => {
            diags.push(unreadable(path, &r, included_from));
            return None;
        }
    };
    if let Some((at, byte)) = not_text(&bytes) {
        diags.push(not_text_diag(
            path,
            &bytes,
            (at, byte),
            sources,
            included_from,
        ));
        return None;
    }
    let text = String::from_utf8(bytes).expect("checked by not_text");
    let file = sources.add_included(display(path), text, path, included_from);
    let text = sources.files[file].1.clone();
    let mut node = parse_text(&text, file, diags)?;
    // Includes.
    let Val::Table(t) = &mut node.val else {
        return Some(node);
    };
    let Some(inc) = t.remove(F::Scene::include) else {
        return Some(node);
    };
    let list: Vec<Node> = match inc.node.val {
        Val::Str(_) => vec![inc.node.clone()],
        Val::Array(a) => a,
        _ => {
            diags.push(
                Diagnostic::error("E0020", "`include` must be a list of file paths")
                    .label(inc.node.span, format!("found {}", inc.node.val.type_name()))
                    .help("write `include = [\"../shared/rig_stereo.toml\"]`"),
            );
            vec![]
        }
    };
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut merged: Option<Node> = None;
    stack.push(canon);
    for item in list {
        let Val::Str(rel) = &item.val else {
            diags.push(
                Diagnostic::error("E0020", "include entries must be strings")
                    .label(item.span, format!("found {}", item.val.type_name()))
                    .help("write the path in quotes: `include = [\"water.toml\"]`"),
            );
            continue;
        };
        let p = dir.join(rel);
        if let Some(why) = outside_root(sources, rel, &p) {
            diags.push(outside_diag(rel, &why, item.span));
            continue;
        }
        if let Some(n) = load_file(&p, sources, diags, stack, Some(item.span)) {
            match &mut merged {
                Some(m) => merge(m, n),
                None => merged = Some(n),
            }
        }
    }
    stack.pop();
    match merged {
        Some(mut m) => {
            let span = node.span;
            merge(&mut m, node);
            m.span = span;
            Some(m)
        }
        None => Some(node),
    }
}

/// Display a path with forward slashes as given (relative stays relative).
pub fn display(p: &Path) -> String {
    let s = p.to_string_lossy().to_string();
    s.strip_prefix("./").map(str::to_string).unwrap_or(s)
}

/// Apply `--set key.path=value` overrides onto `root`. Each override lives in the
/// [`COMMAND_LINE`] pseudo-file so that diagnostics can point at it.
pub fn apply_sets(
    root: &mut Node,
    sets: &[String],
    sources: &mut Sources,
    diags: &mut Vec<Diagnostic>,
) {
    if sets.is_empty() {
        return;
    }
    let mut text = String::new();
    let mut ranges = Vec::new();
    for s in sets {
        let start = text.len() + "--set ".len();
        text.push_str("--set ");
        text.push_str(s);
        ranges.push((start, text.len()));
        text.push('\n');
    }
    let file = sources.add(COMMAND_LINE.into(), text.clone(), None);
    for (s, (start, end)) in sets.iter().zip(ranges) {
        let whole = Span { file, start, end };
        let Some(eq) = s.find('=') else {
            diags.push(
                Diagnostic::error("E0030", "an override needs `KEY=VALUE`")
                    .label(whole, "no `=` here")
                    .help("write e.g. `--set water.temperature=12`"),
            );
            continue;
        };
        let key = &s[..eq];
        let raw = &s[eq + 1..];
        let vstart = start + eq + 1;
        // The value: TOML if it parses, else a plain string.
        let mut vd = Vec::new();
        let value = match DeValue::parse(raw) {
            Ok(v) => {
                let mut n = convert(&v, file, &mut vd);
                shift(&mut n, vstart);
                n
            }
            Err(_) => Node {
                val: Val::Str(raw.trim().to_string()),
                span: Span {
                    file,
                    start: vstart,
                    end,
                },
            },
        };
        diags.extend(vd);
        let mut segs = Vec::new();
        let mut off = start;
        for seg in key.split('.') {
            segs.push((
                seg.trim().to_string(),
                Span {
                    file,
                    start: off,
                    end: off + seg.len(),
                },
            ));
            off += seg.len() + 1;
        }
        if segs.iter().any(|(k, _)| k.is_empty()) {
            diags.push(
                Diagnostic::error("E0030", "empty key in override")
                    .label(
                        Span {
                            file,
                            start,
                            end: start + key.len(),
                        },
                        "a dotted path like `water.temperature` is expected",
                    )
                    .help("write e.g. `--set camera.port.thickness=\"12 mm\"`"),
            );
            continue;
        }
        set_path(root, &segs, value, diags);
    }
}

fn shift(n: &mut Node, by: usize) {
    n.span.start += by;
    n.span.end += by;
    match &mut n.val {
        Val::Array(a) => a.iter_mut().for_each(|x| shift(x, by)),
        Val::Table(t) => t.entries.iter_mut().for_each(|e| {
            e.key_span.start += by;
            e.key_span.end += by;
            shift(&mut e.node, by)
        }),
        _ => {}
    }
}

fn set_path(node: &mut Node, segs: &[(String, Span)], value: Node, diags: &mut Vec<Diagnostic>) {
    let (key, kspan) = &segs[0];
    match &mut node.val {
        Val::Table(t) => {
            if segs.len() == 1 && is_unset(&value) {
                // `--set a.b={ unset = true }` removes the key (nothing to remove: E0021).
                if t.remove(key).is_none() {
                    diags.push(
                        Diagnostic::error("E0021", format!("`{key}` is unset, but the scene does not set it"))
                            .label(*kspan, "nothing to remove here")
                            .help("`{ unset = true }` removes a key the scene or its includes set: check the key's spelling and table"),
                    );
                }
                return;
            }
            if segs.len() == 1 {
                // A new `type` changes what the table is: its other keys belonged to the old
                // kind, so the table is replaced by one holding only the new type.
                let retyped = key == "type"
                    && matches!(
                        (t.get(key).map(|e| &e.node.val), &value.val),
                        (Some(Val::Str(old)), Val::Str(new)) if old != new
                    );
                if retyped {
                    let dropped: Vec<String> = t
                        .entries
                        .iter()
                        .filter(|e| e.key != "type")
                        .map(|e| e.key.clone())
                        .collect();
                    t.entries.retain(|e| e.key == "type");
                    replaced(diags, *kspan, "a new `type` replaces its table", &dropped);
                }
                match t.get_mut(key) {
                    Some(e) => {
                        e.key_span = *kspan;
                        // A table replaces a table (it is not merged into it).
                        if let (Val::Table(old), Val::Table(new)) = (&e.node.val, &value.val) {
                            let dropped: Vec<String> = old
                                .entries
                                .iter()
                                .filter(|o| !new.entries.iter().any(|n| n.key == o.key))
                                .map(|o| o.key.clone())
                                .collect();
                            replaced(diags, *kspan, "a table replaces the table", &dropped);
                        }
                        e.node = value;
                    }
                    None => t.entries.push(Entry {
                        key: key.clone(),
                        key_span: *kspan,
                        node: value,
                    }),
                }
                return;
            }
            if t.get(key).is_none() {
                t.entries.push(Entry {
                    key: key.clone(),
                    key_span: *kspan,
                    node: Node {
                        val: Val::Table(Table::default()),
                        span: *kspan,
                    },
                });
            }
            let e = t.get_mut(key).expect("just inserted");
            set_path(&mut e.node, &segs[1..], value, diags);
        }
        Val::Array(a) => {
            let len = a.len();
            match key.parse::<usize>() {
                Ok(i) if i < len => {
                    if segs.len() == 1 {
                        a[i] = value;
                    } else {
                        set_path(&mut a[i], &segs[1..], value, diags);
                    }
                }
                _ => diags.push(
                    Diagnostic::error("E0031", format!("`{key}` is not an index of this list"))
                        .label(*kspan, format!("the list has {len} entries"))
                        .help(format!(
                            "use an index from 0 to {} to override one entry",
                            len.saturating_sub(1)
                        )),
                ),
            }
        }
        other => diags.push(
            Diagnostic::error(
                "E0031",
                format!("cannot set `{key}` inside {}", other.type_name()),
            )
            .label(*kspan, "this part of the path is not a table")
            .help("only tables (and list entries by index) contain keys"),
        ),
    }
}

/// Say which keys a `--set` that replaced a table dropped (nothing when none were).
fn replaced(diags: &mut Vec<Diagnostic>, span: Span, what: &str, dropped: &[String]) {
    if dropped.is_empty() {
        return;
    }
    let list = dropped
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ");
    diags.push(
        Diagnostic::warning(
            "W0032",
            format!("this override replaces the table: {list} dropped"),
        )
        .label(span, what.to_string())
        .help("set the keys the new table needs with further `--set KEY=VALUE` after this one"),
    );
}
