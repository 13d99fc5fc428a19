//! Diagnostics of the scene front end: errors and warnings with a code, spans into the scene
//! files (or the command line), a `help:` hint, rendered rustc-style by codespan-reporting.

use super::source::Sources;
use codespan_reporting::diagnostic::{Diagnostic as CsDiagnostic, Label};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term;

/// A byte range in one source file (index into [`Sources::files`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Span {
    pub file: usize,
    pub start: usize,
    pub end: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// One diagnostic. After [`Diagnostic::finish`], `location` and `rendered` are filled in.
#[derive(Debug, Clone)]
pub struct Diagnostic {
    pub severity: Severity,
    /// Stable code, e.g. `E0100` (unknown key) — see `docs/format.md`.
    pub code: &'static str,
    pub message: String,
    pub labels: Vec<(Span, String, bool)>,
    pub help: Option<String>,
    pub notes: Vec<String>,
    /// `file:line:column` of the primary label, when there is one.
    pub location: Option<String>,
    /// Full rendered text (source line, caret, help).
    pub rendered: String,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            code,
            message: message.into(),
            labels: vec![],
            help: None,
            notes: vec![],
            location: None,
            rendered: String::new(),
        }
    }
    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, message)
        }
    }
    /// Primary label (the first one is the location reported).
    pub fn label(mut self, span: Span, msg: impl Into<String>) -> Self {
        let primary = !self.labels.iter().any(|l| l.2);
        self.labels.push((span, msg.into(), primary));
        self
    }
    /// Secondary label.
    pub fn also(mut self, span: Span, msg: impl Into<String>) -> Self {
        self.labels.push((span, msg.into(), false));
        self
    }
    pub fn help(mut self, h: impl Into<String>) -> Self {
        self.help = Some(h.into());
        self
    }
    pub fn note(mut self, n: impl Into<String>) -> Self {
        self.notes.push(n.into());
        self
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// `(file, line, column)` of the primary label (1-based), split out of `location`.
    pub fn position(&self) -> Option<(&str, usize, usize)> {
        let loc = self.location.as_deref()?;
        let mut parts = loc.rsplitn(3, ':');
        let col = parts.next()?.parse().ok()?;
        let line = parts.next()?.parse().ok()?;
        Some((parts.next()?, line, col))
    }

    /// Render against the sources and fill `location` / `rendered`.
    pub fn finish(&mut self, sources: &Sources) {
        let mut files = SimpleFiles::new();
        for (name, text) in &sources.files {
            files.add(name.as_str(), text.as_str());
        }
        let mut d = match self.severity {
            Severity::Error => CsDiagnostic::error(),
            Severity::Warning => CsDiagnostic::warning(),
        }
        .with_code(self.code)
        .with_message(&self.message);
        let mut labels = Vec::new();
        for (span, msg, primary) in &self.labels {
            let Some((_, text)) = sources.files.get(span.file) else {
                continue;
            };
            let s = span.start.min(text.len());
            let e = span.end.clamp(s, text.len());
            if !text.is_char_boundary(s) || !text.is_char_boundary(e) {
                continue;
            }
            let l = if *primary {
                Label::primary(span.file, s..e)
            } else {
                Label::secondary(span.file, s..e)
            };
            labels.push(l.with_message(msg));
            if *primary && self.location.is_none() {
                let (line, col) = line_col(text, s);
                self.location = Some(format!("{}:{}:{}", sources.files[span.file].0, line, col));
            }
        }
        let mut notes: Vec<String> = self.notes.clone();
        if let Some(h) = &self.help {
            notes.push(format!("help: {h}"));
        }
        d = d.with_labels(labels).with_notes(notes);
        let config = term::Config::default();
        self.rendered = term::emit_into_string(&config, &files, &d)
            .unwrap_or_else(|_| format!("error[{}]: {}\n", self.code, self.message));
    }
}

/// 1-based line and column (in characters) of byte offset `at`.
pub fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rsplit('\n')
        .next()
        .map(|l| l.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}

/// A number for messages: at most 6 significant digits, no float noise (`0.7`, not
/// `0.7000000000000001`).
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let r: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    format!("{r}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_splits_the_location_from_the_right() {
        let mut d = Diagnostic::error("E0000", "x");
        assert_eq!(d.position(), None);
        d.location = Some("C:/scenes/a:b.toml:12:7".into());
        assert_eq!(d.position(), Some(("C:/scenes/a:b.toml", 12, 7)));
    }
}
