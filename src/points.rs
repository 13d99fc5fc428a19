//! One point-list parser: `id x y z` per line, in metres. It reads `poser project --points`,
//! the `points_file` targets (a laboratory's test field or a GCP list, through
//! [`crate::scene::points_file`]) and the fuzz targets' input, so a file one of them takes
//! the others take too.
//!
//! | what | rule |
//! |---|---|
//! | separators | a line with a comma is split on commas (RFC 4180 quotes: `"a,1"`), else one with a semicolon on semicolons, else on runs of spaces and tabs; fields are trimmed; a line that mixes them (`A1 0.5,1,2`) is split on all of them when its own separator does not give the row |
//! | comments | `#` at the start of a line or after a separator or blank starts a comment (`GCP#7` is an id) |
//! | header | the first line whose fields after the first are not numbers; if it names the columns `id`, `x`, `y`, `z` (any order, any case, more columns allowed) rows are read by name, else by position `id x y z`; optional |
//! | rows | `id x y z` (by position: exactly 4 fields, trailing empty ones ignored), finite numbers |
//! | errors | 1-based line and column of the field at fault, and what is wrong |
//!
//! Duplicate ids and the size of a list are the caller's rules ([`crate::scene::points_file`]
//! refuses both; `poser project` keeps every row).
use glam::DVec3;

/// One point of a list, with the line and column of its id (1-based).
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub id: String,
    pub p: DVec3,
    pub line: usize,
    pub col: usize,
}

/// A problem in a point list: 1-based line and column (in characters), and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    pub line: usize,
    pub col: usize,
    pub message: String,
}

/// What every point list is, for the `help:` of an error.
pub const HELP: &str = "one point per line: `id x y z` in metres, separated by commas, \
     semicolons, spaces or tabs; `#` comments; an optional header line naming the columns \
     (`id,x,y,z`)";

/// One field of a line: its 1-based start column and its text (quotes removed).
type Field = (usize, String);

/// Where the columns of a row are.
enum Layout {
    /// `id x y z`, exactly four fields.
    Positional,
    /// Indices of `id`, `x`, `y`, `z` from the header.
    Named([usize; 4]),
}

/// Parse a point list's text. An empty list (no rows, or a header only) is `Ok(vec![])`.
pub fn parse(text: &str) -> Result<Vec<Point>, ParseError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut layout: Option<Layout> = None;
    let mut out = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let err = |col: usize, message: String| ParseError { line, col, message };
        let code = strip_comment(raw);
        let own = split(code, separator(code)).map_err(|(c, m)| err(c, m))?;
        if own.is_empty() {
            continue;
        }
        let Some(lay) = &layout else {
            if is_header(&own) {
                layout = Some(header_layout(&own).ok_or_else(|| {
                    err(
                        1,
                        format!(
                            "the header `{}` lacks one of the columns id, x, y, z",
                            code.trim()
                        ),
                    )
                })?);
                continue;
            }
            layout = Some(Layout::Positional);
            out.push(row(code, own, &Layout::Positional, line)?);
            continue;
        };
        out.push(row(code, own, lay, line)?);
    }
    Ok(out)
}

/// One data row: its fields read by `layout`, with the all-separators split as the fallback
/// for a line that mixes separators.
fn row(code: &str, own: Vec<Field>, layout: &Layout, line: usize) -> Result<Point, ParseError> {
    let fits = |f: &[Field]| match layout {
        Layout::Positional => trimmed_len(f) == 4,
        Layout::Named(ix) => ix.iter().all(|&i| i < f.len()),
    };
    let fields = if !fits(&own) {
        match split(code, Sep::Any) {
            Ok(all) if fits(&all) => all,
            _ => own,
        }
    } else {
        own
    };
    let err = |col: usize, message: String| ParseError { line, col, message };
    let ix = match layout {
        Layout::Positional => {
            let n = trimmed_len(&fields);
            if n != 4 {
                let c = fields.get(4).map_or(fields[0].0, |f| f.0);
                return Err(err(c, format!("expected 4 fields `id x y z`, found {n}")));
            }
            [0, 1, 2, 3]
        }
        Layout::Named(ix) => *ix,
    };
    let mut xyz = [0.0; 3];
    for (a, name) in ["x", "y", "z"].into_iter().enumerate() {
        let Some((c, f)) = fields.get(ix[a + 1]) else {
            let c = fields.last().map_or(1, |f| f.0);
            return Err(err(c, format!("missing column `{name}`")));
        };
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => xyz[a] = v,
            _ => {
                return Err(err(
                    *c,
                    format!("`{f}` is not a finite number (column `{name}`, in metres)"),
                ));
            }
        }
    }
    let Some((col, id)) = fields.get(ix[0]).cloned() else {
        return Err(err(1, "missing column `id`".into()));
    };
    Ok(Point {
        id,
        p: DVec3::from_array(xyz),
        line,
        col,
    })
}

/// The number of fields without the trailing empty ones (`A,1,2,3,`).
fn trimmed_len(f: &[Field]) -> usize {
    f.iter()
        .rposition(|(_, s)| !s.is_empty())
        .map_or(0, |i| i + 1)
}

/// A first line is a header when its fields after the first are not numbers.
fn is_header(f: &[Field]) -> bool {
    f.len() >= 2
        && f[1..f.len().min(4)]
            .iter()
            .all(|(_, s)| s.parse::<f64>().is_err())
}

/// Rows by name when the header names `id`, `x`, `y`, `z`; by position when it has four or
/// more other columns (a published list's `name east north up`); else `None`.
fn header_layout(f: &[Field]) -> Option<Layout> {
    let find = |name: &str| f.iter().position(|(_, s)| s.eq_ignore_ascii_case(name));
    match (find("id"), find("x"), find("y"), find("z")) {
        (Some(i), Some(x), Some(y), Some(z)) => Some(Layout::Named([i, x, y, z])),
        _ if f.len() >= 4 => Some(Layout::Positional),
        _ => None,
    }
}

/// How a line's fields are separated.
#[derive(Clone, Copy, PartialEq)]
enum Sep {
    Comma,
    Semicolon,
    Blank,
    /// Commas, semicolons and blanks alike (runs collapse).
    Any,
}

/// The separator of a line: a comma outside quotes, else a semicolon, else blanks.
fn separator(code: &str) -> Sep {
    let mut quoted = false;
    let mut semi = false;
    for c in code.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => return Sep::Comma,
            ';' if !quoted => semi = true,
            _ => {}
        }
    }
    if semi { Sep::Semicolon } else { Sep::Blank }
}

/// The line without its comment: from a `#` (outside quotes) at the start of the line or
/// after a separator or blank.
fn strip_comment(line: &str) -> &str {
    let mut quoted = false;
    let mut prev_sep = true;
    for (b, c) in line.char_indices() {
        if c == '"' {
            quoted = !quoted;
        } else if c == '#' && !quoted && prev_sep {
            return &line[..b];
        }
        prev_sep = !quoted && (c.is_whitespace() || c == ',' || c == ';');
    }
    line
}

/// Split a line (comment removed) into fields with their start columns. `"…"` quotes a field
/// (`""` is one quote); an unterminated quote is an error at its column.
fn split(code: &str, sep: Sep) -> Result<Vec<Field>, (usize, String)> {
    let is_sep = |c: char| match sep {
        Sep::Comma => c == ',',
        Sep::Semicolon => c == ';',
        Sep::Blank => c.is_whitespace(),
        Sep::Any => c.is_whitespace() || c == ',' || c == ';',
    };
    let collapse = matches!(sep, Sep::Blank | Sep::Any);
    let mut out: Vec<Field> = Vec::new();
    let mut cur = String::new();
    let mut start: Option<usize> = None; // column of the field's first non-blank character
    let mut quote: Option<usize> = None; // column of an open quote
    let mut was_quoted = false;
    let mut chars = code.chars().enumerate().peekable();
    let mut push = |cur: &mut String, start: &mut Option<usize>, col: usize, quoted: bool| {
        let text = if quoted {
            std::mem::take(cur)
        } else {
            std::mem::take(cur).trim().to_string()
        };
        if !(collapse && text.is_empty() && !quoted) {
            out.push((start.take().unwrap_or(col), text));
        }
        *start = None;
    };
    while let Some((i, c)) = chars.next() {
        let col = i + 1;
        if quote.is_some() {
            if c == '"' {
                if chars.peek().is_some_and(|&(_, n)| n == '"') {
                    cur.push('"');
                    chars.next();
                } else {
                    quote = None;
                }
            } else {
                cur.push(c);
            }
        } else if c == '"' && cur.trim().is_empty() && !was_quoted {
            quote = Some(col);
            was_quoted = true;
            start.get_or_insert(col);
            cur.clear();
        } else if is_sep(c) {
            push(&mut cur, &mut start, col, was_quoted);
            was_quoted = false;
        } else {
            if !c.is_whitespace() {
                start.get_or_insert(col);
            }
            cur.push(c);
        }
    }
    if let Some(c) = quote {
        return Err((c, "unterminated quoted field".into()));
    }
    let end = code.chars().count() + 1;
    push(&mut cur, &mut start, end, was_quoted);
    if !collapse && out.iter().all(|(_, s)| s.is_empty()) {
        out.clear(); // a blank line
    }
    Ok(out)
}

/// The point list of `poser project --points` (and the fuzz target): `(id, point)` per row.
/// Errors read `file:line:column: what` with the `help:` of every point list.
pub fn parse_points(text: &str, file: &str) -> Result<Vec<(String, DVec3)>, String> {
    if text.trim_start_matches('\u{feff}').trim().is_empty() {
        return Err(format!("{file}: empty file\nhelp: {HELP}"));
    }
    match parse(text) {
        Ok(v) => Ok(v.into_iter().map(|q| (q.id, q.p)).collect()),
        Err(e) => Err(format!(
            "{file}:{}:{}: {}\nhelp: {HELP}",
            e.line, e.col, e.message
        )),
    }
}
