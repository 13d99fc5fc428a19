//! Typed, error-collecting access to scene tables: every getter records the key as known
//! (for "unknown key, did you mean …" at [`Tab::finish`]), converts units, and on a bad value
//! records a diagnostic and returns the default so that checking continues.

use super::diag::{Diagnostic, Span};
use super::source::{Node, Table, Val};
use crate::model::Rgb;
use crate::units::{Dim, UnitError, parse_quantity, parse_vector};
use glam::DVec3;

/// Collected diagnostics.
#[derive(Default)]
pub struct Cx {
    pub diags: Vec<Diagnostic>,
    /// Asset files read while resolving (meshes, point lists), for [`super::Loaded::files`].
    pub files: Vec<std::path::PathBuf>,
    /// Per source file read through an include: the span of the `include` entry that read it
    /// and the file's name (None for the scene file and the command line). An unknown key
    /// such a file sets is reported as inherited ([`Tab::finish_as`]).
    pub included: Vec<Option<(Span, String)>>,
}

impl Cx {
    pub fn push(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }
    pub fn has_errors(&self) -> bool {
        self.diags.iter().any(|d| d.is_error())
    }
}

/// Closest candidate to `word` among `options`, if reasonably close.
pub fn did_you_mean<'o>(word: &str, options: impl IntoIterator<Item = &'o str>) -> Option<&'o str> {
    let w = word.to_lowercase();
    options
        .into_iter()
        .map(|o| (strsim::jaro_winkler(&w, &o.to_lowercase()), o))
        .filter(|(s, _)| *s >= 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|x| x.1)
}

thread_local! {
    /// When set, every table read records its known keys here (normalised path → keys); the
    /// tests use it to keep the reader and `scene::format` (schema, docs) in step.
    static RECORD: std::cell::RefCell<Option<std::collections::BTreeMap<String, std::collections::BTreeSet<String>>>> =
        const { std::cell::RefCell::new(None) };
}

/// Run `f` while recording the keys every table reader knows; returns them by normalised
/// path (`lights`, `camera.port`, … — list indices removed, `rig.cameras` folded into
/// `camera`).
pub fn record_known_keys<R>(
    f: impl FnOnce() -> R,
) -> (
    R,
    std::collections::BTreeMap<String, std::collections::BTreeSet<String>>,
) {
    RECORD.with(|r| *r.borrow_mut() = Some(Default::default()));
    let out = f();
    let map = RECORD.with(|r| r.borrow_mut().take()).unwrap_or_default();
    (out, map)
}

fn normalise_path(p: &str) -> String {
    let mut s = String::new();
    let mut skip = false;
    for c in p.chars() {
        match c {
            '[' => skip = true,
            ']' => skip = false,
            _ if !skip => s.push(c),
            _ => {}
        }
    }
    if let Some(rest) = s.strip_prefix("rig.cameras") {
        s = format!("camera{rest}");
    }
    s
}

/// One table being read.
pub struct Tab<'a> {
    pub table: Option<&'a Table>,
    /// Span of the table (its header / value), for errors about the table as a whole.
    pub span: Span,
    /// Dotted path, e.g. `camera.port`, for messages.
    pub path: String,
    known: Vec<&'static str>,
}

/// An unknown key that an included file set (at `span`, in `file`, read by the include entry
/// at `at`): it may be right for that file's own table (a flat port's key under a dome that
/// includes a flat-port base), so the hint names the way to remove it.
fn inherited_unknown(
    key: &str,
    whose: &str,
    span: Span,
    at: Span,
    file: &str,
    t: &Tab,
) -> Diagnostic {
    let d = Diagnostic::error(
        "E0100",
        format!("unknown key `{key}`{whose}, inherited from `{file}`"),
    )
    .label(span, format!("unknown key, set by the included `{file}`"))
    .also(at, "included here");
    let unset = format!(
        "remove the inherited key: write `{key} = {{ unset = true }}` {} of the scene that includes `{file}`",
        t.header()
    );
    match did_you_mean(key, t.known.iter().copied()) {
        Some(s) => d.help(format!("did you mean `{s}`? Fix it in `{file}`; or, if the key is right there but not here, {unset}")),
        None => d.help(unset),
    }
}

fn expect_dim(dim: Dim) -> String {
    match dim {
        Dim::Number => "a number".into(),
        Dim::Fraction => "a fraction (a number like 0.6, or a string like \"60 %\")".into(),
        Dim::Temperature => "a temperature (a number in °C, or a string like \"12 °C\")".into(),
        d => format!(
            "a {} (a number in {}, or a string like \"{}\")",
            d.name(),
            d.si_unit(),
            example(d)
        ),
    }
}

fn example(d: Dim) -> &'static str {
    match d {
        Dim::Length => "18 mm",
        Dim::Angle => "30 deg",
        Dim::Speed => "0.2 m/s",
        Dim::Flow => "20 l/min",
        Dim::Pressure => "232 bar",
        Dim::Volume => "12 l",
        Dim::Time => "2 s",
        Dim::Power => "50 W",
        Dim::Intensity => "4 W/sr",
        Dim::Radiance => "1 W/m2/sr",
        Dim::Irradiance => "800 W/m2",
        Dim::Temperature => "12 °C",
        Dim::Fraction => "60 %",
        Dim::Gsd => "2 mm/px",
        Dim::Number => "1",
    }
}

fn path_join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

impl<'a> Tab<'a> {
    /// Open `node` as a table (None: the table is absent, every getter returns defaults).
    pub fn open(cx: &mut Cx, node: Option<&'a Node>, path: &str, fallback: Span) -> Tab<'a> {
        let (table, span) = match node {
            Some(Node {
                val: Val::Table(t),
                span,
            }) => (Some(t), *span),
            Some(n) => {
                cx.push(
                    Diagnostic::error("E0101", format!("`{path}` must be a table"))
                        .label(n.span, format!("found {}", n.val.type_name()))
                        .help(format!(
                            "write it as a table: `[{path}]` followed by `key = value` lines"
                        )),
                );
                (None, n.span)
            }
            None => (None, fallback),
        };
        Tab {
            table,
            span,
            path: path.to_string(),
            known: vec![],
        }
    }

    pub fn present(&self) -> bool {
        self.table.is_some()
    }
    pub fn full(&self, key: &str) -> String {
        path_join(&self.path, key)
    }
    /// The node of `key`, marking it known.
    pub fn get(&mut self, key: &'static str) -> Option<&'a Node> {
        if !self.known.contains(&key) {
            self.known.push(key);
        }
        self.table.and_then(|t| t.get(key)).map(|e| &e.node)
    }
    /// Whether `key` is present (does not mark it known).
    pub fn has(&self, key: &str) -> bool {
        self.table.is_some_and(|t| t.get(key).is_some())
    }
    /// Span of `key`'s value, or of the table when absent.
    pub fn span_of(&self, key: &str) -> Span {
        self.table
            .and_then(|t| t.get(key))
            .map(|e| e.node.span)
            .unwrap_or(self.span)
    }
    /// Span of the key itself, or of the table when absent.
    pub fn key_span(&self, key: &str) -> Span {
        self.table
            .and_then(|t| t.get(key))
            .map(|e| e.key_span)
            .unwrap_or(self.span)
    }
    /// Span covering `key = value`.
    pub fn entry_span(&self, key: &str) -> Span {
        match self.table.and_then(|t| t.get(key)) {
            Some(e)
                if e.key_span.file == e.node.span.file && e.node.span.end >= e.key_span.start =>
            {
                Span {
                    file: e.key_span.file,
                    start: e.key_span.start,
                    end: e.node.span.end,
                }
            }
            Some(e) => e.node.span,
            None => self.span,
        }
    }

    /// Report keys nobody asked for, with "did you mean".
    pub fn finish(self, cx: &mut Cx) {
        self.finish_as(cx, None)
    }
    /// Same, naming the kind of table (e.g. "a flat port") in the message.
    pub fn finish_as(self, cx: &mut Cx, what: Option<&str>) {
        RECORD.with(|r| {
            if let Some(m) = r.borrow_mut().as_mut() {
                m.entry(normalise_path(&self.path))
                    .or_default()
                    .extend(self.known.iter().map(|k| k.to_string()));
            }
        });
        let Some(t) = self.table else { return };
        for e in &t.entries {
            if self.known.contains(&e.key.as_str()) {
                continue;
            }
            let whose = match what {
                Some(w) => format!(" for {w}"),
                None if self.path.is_empty() => " at the top level".to_string(),
                None => format!(" in `[{}]`", self.path),
            };
            if let Some(Some((at, file))) = cx.included.get(e.key_span.file) {
                let d = inherited_unknown(&e.key, &whose, e.key_span, *at, file, &self);
                cx.push(d);
                continue;
            }
            let mut d = Diagnostic::error("E0100", format!("unknown key `{}`{whose}", e.key))
                .label(e.key_span, "unknown key");
            match did_you_mean(&e.key, self.known.iter().copied()) {
                Some(s) => d = d.help(format!("did you mean `{s}`?")),
                None => {
                    let mut k: Vec<&str> = self.known.clone();
                    k.sort();
                    d = d.help(format!("known keys here: {}", k.join(", ")));
                }
            }
            cx.push(d);
        }
    }

    /// `[camera.port]`-style header of this table, for hints (`the top level` for the root).
    fn header(&self) -> String {
        if self.path.is_empty() {
            "at the top level".into()
        } else {
            format!("in `[{}]`", normalise_path(&self.path))
        }
    }

    // ---- typed getters ------------------------------------------------------------------

    pub fn opt_f64(&mut self, cx: &mut Cx, key: &'static str, dim: Dim) -> Option<f64> {
        let n = self.get(key)?;
        number(cx, n, dim, &self.full(key))
    }
    pub fn f64(&mut self, cx: &mut Cx, key: &'static str, dim: Dim, default: f64) -> f64 {
        self.opt_f64(cx, key, dim).unwrap_or(default)
    }
    /// Angles where plain numbers mean degrees (latitude/longitude).
    pub fn opt_degrees(&mut self, cx: &mut Cx, key: &'static str) -> Option<f64> {
        let n = self.get(key)?;
        match &n.val {
            Val::Int(i) => Some(*i as f64),
            Val::Float(_) => number(cx, n, Dim::Number, &self.full(key)),
            _ => number(cx, n, Dim::Angle, &self.full(key)).map(f64::to_degrees),
        }
    }
    pub fn opt_u64(&mut self, cx: &mut Cx, key: &'static str) -> Option<u64> {
        let n = self.get(key)?;
        match &n.val {
            Val::Int(i) if *i >= 0 => Some(*i as u64),
            Val::Int(i) => {
                cx.push(
                    Diagnostic::error(
                        "E0043",
                        format!("`{}` must not be negative", self.full(key)),
                    )
                    .label(n.span, format!("{i} is negative"))
                    .help("use a whole number ≥ 0"),
                );
                None
            }
            v => {
                cx.push(type_error(n, &self.full(key), "a whole number", v));
                None
            }
        }
    }
    pub fn u32(&mut self, cx: &mut Cx, key: &'static str, default: u32) -> u32 {
        let span = self.span_of(key);
        match self.opt_u64(cx, key) {
            Some(v) if v <= u32::MAX as u64 => v as u32,
            Some(v) => {
                cx.push(
                    Diagnostic::error("E0043", format!("`{}` is too large", self.full(key)))
                        .label(span, format!("{v} does not fit in 32 bits"))
                        .help("use a smaller number"),
                );
                default
            }
            None => default,
        }
    }
    pub fn opt_u32(&mut self, cx: &mut Cx, key: &'static str) -> Option<u32> {
        if self.has(key) {
            Some(self.u32(cx, key, 0))
        } else {
            self.get(key);
            None
        }
    }
    pub fn bool(&mut self, cx: &mut Cx, key: &'static str, default: bool) -> bool {
        let Some(n) = self.get(key) else {
            return default;
        };
        match &n.val {
            Val::Bool(b) => *b,
            v => {
                cx.push(type_error(n, &self.full(key), "true or false", v));
                default
            }
        }
    }
    pub fn opt_str(&mut self, cx: &mut Cx, key: &'static str) -> Option<String> {
        let n = self.get(key)?;
        match &n.val {
            Val::Str(s) => Some(s.clone()),
            v => {
                cx.push(type_error(n, &self.full(key), "a string", v));
                None
            }
        }
    }
    /// One of `options` (case-sensitive, did-you-mean on mismatch).
    pub fn choice(
        &mut self,
        cx: &mut Cx,
        key: &'static str,
        options: &[&'static str],
    ) -> Option<&'static str> {
        let span = self.span_of(key);
        let s = self.opt_str(cx, key)?;
        if let Some(o) = options.iter().find(|o| **o == s) {
            return Some(o);
        }
        let mut d = Diagnostic::error(
            "E0102",
            format!("unknown value `{s}` for `{}`", self.full(key)),
        )
        .label(span, format!("expected one of: {}", options.join(", ")));
        if let Some(m) = did_you_mean(&s, options.iter().copied()) {
            d = d.help(format!("did you mean `{m}`?"));
        } else {
            d = d.help(format!("use one of: {}", options.join(", ")));
        }
        cx.push(d);
        None
    }
    pub fn opt_vec3(&mut self, cx: &mut Cx, key: &'static str, dim: Dim) -> Option<DVec3> {
        let n = self.get(key)?;
        let v = vector(cx, n, dim, &self.full(key), Some(3))?;
        Some(DVec3::new(v[0], v[1], v[2]))
    }
    pub fn vec3(&mut self, cx: &mut Cx, key: &'static str, dim: Dim, default: DVec3) -> DVec3 {
        self.opt_vec3(cx, key, dim).unwrap_or(default)
    }
    /// A vector of 2 or 3 values (a 2-vector gets z = `z`).
    pub fn opt_vec23(&mut self, cx: &mut Cx, key: &'static str, dim: Dim, z: f64) -> Option<DVec3> {
        let n = self.get(key)?;
        let v = vector(cx, n, dim, &self.full(key), None)?;
        match v.len() {
            2 => Some(DVec3::new(v[0], v[1], z)),
            3 => Some(DVec3::new(v[0], v[1], v[2])),
            k => {
                cx.push(
                    Diagnostic::error("E0044", format!("`{}` needs 2 or 3 values", self.full(key)))
                        .label(n.span, format!("{k} values given"))
                        .help("write `[x, y]` or `[x, y, z]`"),
                );
                None
            }
        }
    }
    /// A list of values of any length.
    pub fn opt_list(&mut self, cx: &mut Cx, key: &'static str, dim: Dim) -> Option<Vec<f64>> {
        let n = self.get(key)?;
        vector(cx, n, dim, &self.full(key), None)
    }
    /// Per-channel value: a scalar (same for R, G, B) or `[r, g, b]`.
    pub fn opt_rgb(&mut self, cx: &mut Cx, key: &'static str, dim: Dim) -> Option<Rgb> {
        let n = self.get(key)?;
        match &n.val {
            Val::Array(_) => {
                let v = vector(cx, n, dim, &self.full(key), Some(3))?;
                Some([v[0], v[1], v[2]])
            }
            _ => number(cx, n, dim, &self.full(key)).map(|x| [x; 3]),
        }
    }
    pub fn rgb(&mut self, cx: &mut Cx, key: &'static str, dim: Dim, default: Rgb) -> Rgb {
        self.opt_rgb(cx, key, dim).unwrap_or(default)
    }
    /// An array of tables (`[[key]]`); entries that are not tables are reported.
    pub fn tables(&mut self, cx: &mut Cx, key: &'static str) -> Vec<&'a Node> {
        let full = self.full(key);
        let Some(n) = self.get(key) else {
            return vec![];
        };
        match &n.val {
            Val::Array(a) => a
                .iter()
                .filter(|x| {
                    let ok = matches!(x.val, Val::Table(_));
                    if !ok {
                        cx.push(
                            Diagnostic::error(
                                "E0101",
                                format!("entries of `{full}` must be tables"),
                            )
                            .label(x.span, format!("found {}", x.val.type_name()))
                            .help(format!(
                                "write each entry as `[[{full}]]` followed by its keys"
                            )),
                        );
                    }
                    ok
                })
                .collect(),
            Val::Table(_) => vec![n],
            v => {
                cx.push(type_error(n, &full, "a list of tables", v));
                vec![]
            }
        }
    }
}

pub fn type_error(n: &Node, full: &str, expected: &str, found: &Val) -> Diagnostic {
    Diagnostic::error("E0040", format!("wrong type for `{full}`"))
        .label(
            n.span,
            format!("expected {expected}, found {}", found.type_name()),
        )
        .help(format!("`{full}` takes {expected}"))
}

fn not_finite(n: &Node, full: &str) -> Diagnostic {
    Diagnostic::error("E0041", format!("`{full}` is not a finite number"))
        .label(n.span, "NaN and infinity are not allowed")
        .help("give a finite value")
}

/// A scalar quantity from a number or a unit string.
pub fn number(cx: &mut Cx, n: &Node, dim: Dim, full: &str) -> Option<f64> {
    match &n.val {
        Val::Int(i) => Some(*i as f64),
        Val::Float(f) if f.is_finite() => Some(*f),
        Val::Float(_) => {
            cx.push(not_finite(n, full));
            None
        }
        Val::Str(s) => match parse_quantity(s, dim) {
            Ok(v) => Some(v),
            Err(e) => {
                cx.push(unit_error(n, full, dim, &e));
                None
            }
        },
        v => {
            cx.push(type_error(n, full, &expect_dim(dim), v));
            None
        }
    }
}

pub fn unit_error(n: &Node, full: &str, dim: Dim, e: &UnitError) -> Diagnostic {
    let help = match e {
        UnitError::BadUnit {
            suggestion: Some(s),
            ..
        } => format!("did you mean `{s}`?"),
        UnitError::BadUnit { .. } if dim == Dim::Number => {
            "this value is a plain number; remove the unit".into()
        }
        UnitError::BadUnit { .. } => format!("units for a {}: {}", dim.name(), dim.unit_list()),
        UnitError::NotFinite => "give a finite value".into(),
        UnitError::BadNumber(_) => format!("`{full}` takes {}", expect_dim(dim)),
    };
    let code = if matches!(e, UnitError::NotFinite) {
        "E0041"
    } else {
        "E0042"
    };
    Diagnostic::error(code, format!("invalid value for `{full}`"))
        .label(n.span, e.to_string())
        .help(help)
}

/// A vector from an array of numbers/unit strings, or one string with a trailing unit.
pub fn vector(cx: &mut Cx, n: &Node, dim: Dim, full: &str, len: Option<usize>) -> Option<Vec<f64>> {
    let v = match &n.val {
        Val::Array(a) => {
            let mut out = Vec::new();
            let mut ok = true;
            for x in a {
                match number(cx, x, dim, full) {
                    Some(v) => out.push(v),
                    None => ok = false,
                }
            }
            if !ok {
                return None;
            }
            out
        }
        Val::Str(s) => match parse_vector(s, dim) {
            Ok(v) => v,
            Err(e) => {
                cx.push(unit_error(n, full, dim, &e));
                return None;
            }
        },
        v => {
            let what = match len {
                Some(3) => format!(
                    "a list of 3 numbers like `[0, 0, 1]` or a string like \"0, 0, 10 {}\"",
                    example_unit(dim)
                ),
                _ => "a list of numbers".to_string(),
            };
            cx.push(type_error(n, full, &what, v));
            return None;
        }
    };
    if let Some(l) = len
        && v.len() != l
    {
        cx.push(
            Diagnostic::error("E0044", format!("`{full}` needs {l} values"))
                .label(
                    n.span,
                    format!(
                        "{} value{} given",
                        v.len(),
                        if v.len() == 1 { "" } else { "s" }
                    ),
                )
                .help(if l == 3 {
                    "write `[x, y, z]`".to_string()
                } else {
                    format!("give exactly {l} values")
                }),
        );
        return None;
    }
    Some(v)
}

fn example_unit(dim: Dim) -> &'static str {
    match dim {
        Dim::Angle => "deg",
        Dim::Length => "m",
        _ => "",
    }
}
