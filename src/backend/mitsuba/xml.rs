//! A tiny element tree for Mitsuba 3 scene files, serialised with quick-xml.
//!
//! Everything that reaches the file goes through quick-xml's attribute escaping; comments
//! (the only place where scene names appear) are sanitised so that they cannot close the
//! comment or break the document. Numbers are printed with [`num`], which is deterministic and
//! short (15 significant digits, so that `poser import` reads back the model to ~1e-15, and
//! no `-0`).

use glam::{DMat3, DVec3};
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};

/// One XML element.
#[derive(Debug, Clone, PartialEq)]
pub struct El {
    pub name: &'static str,
    pub attrs: Vec<(&'static str, String)>,
    pub children: Vec<Node>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    El(El),
    Comment(String),
}

impl El {
    pub fn new(name: &'static str) -> El {
        El {
            name,
            attrs: Vec::new(),
            children: Vec::new(),
        }
    }
    /// `<name type="…">`.
    pub fn typed(name: &'static str, ty: &str) -> El {
        El::new(name).attr("type", ty)
    }
    pub fn attr(mut self, key: &'static str, value: impl Into<String>) -> El {
        self.attrs.push((key, value.into()));
        self
    }
    /// The value of attribute `key`, if set.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.as_str())
    }
    pub fn child(mut self, c: El) -> El {
        self.children.push(Node::El(c));
        self
    }
    pub fn push(&mut self, c: El) {
        self.children.push(Node::El(c));
    }
    pub fn comment(mut self, text: impl Into<String>) -> El {
        self.children.push(Node::Comment(text.into()));
        self
    }
    pub fn push_comment(&mut self, text: impl Into<String>) {
        self.children.push(Node::Comment(text.into()));
    }
    /// `<float name="…" value="…"/>`.
    pub fn float(self, name: &str, v: f64) -> El {
        self.child(El::new("float").attr("name", name).attr("value", num(v)))
    }
    pub fn integer(self, name: &str, v: i64) -> El {
        self.child(
            El::new("integer")
                .attr("name", name)
                .attr("value", v.to_string()),
        )
    }
    pub fn string(self, name: &str, v: &str) -> El {
        self.child(El::new("string").attr("name", name).attr("value", v))
    }
    pub fn boolean(self, name: &str, v: bool) -> El {
        self.child(
            El::new("boolean")
                .attr("name", name)
                .attr("value", v.to_string()),
        )
    }
    /// `<rgb name="…" value="r, g, b"/>`.
    pub fn rgb(self, name: &str, v: [f64; 3]) -> El {
        self.child(El::new("rgb").attr("name", name).attr("value", triple(v)))
    }
    /// `<point name="…" value="x, y, z"/>`.
    pub fn point(self, name: &str, p: DVec3) -> El {
        self.child(
            El::new("point")
                .attr("name", name)
                .attr("value", triple(p.to_array())),
        )
    }
    /// `<ref name="…" id="…"/>`.
    pub fn reference(self, name: &str, id: &str) -> El {
        self.child(El::new("ref").attr("name", name).attr("id", id))
    }
    /// `<transform name="to_world"><matrix value="…"/></transform>` for `p ↦ m·p + t`.
    pub fn to_world(self, m: DMat3, t: DVec3) -> El {
        self.child(
            El::new("transform")
                .attr("name", "to_world")
                .child(matrix(m, t)),
        )
    }

    /// Every attribute value in this tree, depth first (for validation).
    pub fn walk_attrs<'a>(&'a self, f: &mut impl FnMut(&'a El, &'a str, &'a str)) {
        for (k, v) in &self.attrs {
            f(self, k, v);
        }
        for c in &self.children {
            if let Node::El(e) = c {
                e.walk_attrs(f);
            }
        }
    }

    /// Serialise as a complete document with an XML declaration, two-space indent, trailing
    /// newline.
    pub fn to_document(&self) -> Vec<u8> {
        let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
        // Writing into a Vec cannot fail.
        let _ = w.write_event(Event::Decl(BytesDecl::new("1.0", Some("utf-8"), None)));
        write_el(&mut w, self);
        let mut out = w.into_inner();
        out.push(b'\n');
        out
    }
}

fn write_el(w: &mut Writer<Vec<u8>>, e: &El) {
    let mut start = BytesStart::new(e.name);
    for (k, v) in &e.attrs {
        start.push_attribute((*k, xml_chars(v).as_str()));
    }
    if e.children.is_empty() {
        let _ = w.write_event(Event::Empty(start));
        return;
    }
    let _ = w.write_event(Event::Start(start));
    for c in &e.children {
        match c {
            Node::El(c) => write_el(w, c),
            Node::Comment(t) => {
                let _ = w.write_event(Event::Comment(BytesText::from_escaped(comment_text(t))));
            }
        }
    }
    let _ = w.write_event(Event::End(BytesEnd::new(e.name)));
}

/// Make arbitrary text safe inside `<!-- … -->`: XML-escaped, no `--`, no trailing `-`, no
/// control characters, padded with spaces.
pub fn comment_text(t: &str) -> String {
    let cleaned: String = t
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect::<String>();
    let cleaned = xml_chars(&cleaned);
    let mut s = quick_xml::escape::partial_escape(cleaned.as_str()).into_owned();
    while s.contains("--") {
        s = s.replace("--", "- -");
    }
    format!(" {s} ")
}

/// Whether XML 1.0 allows `c` in a document (`Char` production: tab, LF, CR, U+0020–U+D7FF,
/// U+E000–U+FFFD, U+10000 and up; Rust `char`s are never surrogates).
pub fn is_xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | ' '..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
}

/// `t` with every character XML 1.0 forbids (C0 controls but tab/LF/CR, U+FFFE, U+FFFF)
/// replaced by U+FFFD, so any text can be written into a well-formed document.
pub fn xml_chars(t: &str) -> String {
    t.chars()
        .map(|c| if is_xml_char(c) { c } else { '\u{FFFD}' })
        .collect()
}

/// The parameters that place the world's origin in a document's coordinates
/// (`$poser_origin_x`, `_y`, `_z`, in the document's length unit). Every placed element
/// (shape, sensor, point or spot emitter) ends its `to_world` with
/// `<scale value="$poser_unit"/>` and `<translate x="$poser_origin_x" …/>`
/// ([`place_at_origin`]). A view sets the unit to [`VIEW_UNIT`] (millimetres) and the origin
/// to minus its camera's centre, so that the camera and its port sit at Mitsuba's origin;
/// `world.xml` defaults them to metres and 0 (world coordinates). The similarity changes no
/// light path; it keeps Mitsuba's float32 ray offsets, (1 + max |coordinate|) × 8.94e-5
/// document units, at their smallest at the port's glass (docs/backends.md, "Per-view
/// coordinates").
pub const ORIGIN_PARAMS: [&str; 3] = ["poser_origin_x", "poser_origin_y", "poser_origin_z"];

/// Document length units per metre (`$poser_unit`): 1 in `world.xml`, [`VIEW_UNIT`] in a
/// view.
pub const UNIT_PARAM: &str = "poser_unit";

/// Its inverse, metres per document unit (`$poser_per_unit`): the water medium's `scale`
/// (σt is given per metre) and the first factor of a sensor's `to_world`.
pub const PER_UNIT_PARAM: &str = "poser_per_unit";

/// A view's length unit, units per metre: millimetres. The constant part of Mitsuba's ray
/// offset, 8.94e-5 units, is then 0.09 µm instead of 89 µm (docs/backends.md).
pub const VIEW_UNIT: f64 = 1000.0;

/// `<default …/>` for a document in `unit` (units per metre) whose world origin lies at
/// `origin` (in those units): the origin, the unit and its inverse.
pub fn placement_defaults(origin: DVec3, unit: f64) -> Vec<El> {
    let default = |name: &str, value: String| {
        El::new("default")
            .attr("name", name.to_string())
            .attr("value", value)
    };
    let mut d: Vec<El> = (0..3)
        .map(|i| default(ORIGIN_PARAMS[i], num(origin[i])))
        .collect();
    d.push(default(UNIT_PARAM, num(unit)));
    d.push(default(PER_UNIT_PARAM, num(1.0 / unit)));
    d
}

/// The parameter holding the intensity of world-mounted point or spot light `i` in
/// `world.xml` (W/sr in metres; a view overrides it with the value in its own unit, × unit²,
/// since a point light's irradiance falls as 1/distance²).
pub fn intensity_param(i: usize) -> String {
    format!("poser_intensity_{i}")
}

/// End the `to_world` of every placed top-level element of `doc` (shapes, sensors, point and
/// spot emitters; one without a `to_world` gets one) with the scale by [`UNIT_PARAM`] and
/// the translation by [`ORIGIN_PARAMS`]. A sensor's `to_world` may not scale, so it also
/// starts with the scale by [`PER_UNIT_PARAM`]: `T(o)·S(u)·T(C)·R·S(1/u) = T(o + u·C)·R`.
/// Directional and constant emitters have no place.
pub fn place_at_origin(doc: &mut El) {
    let scale = |p: &str| El::new("scale").attr("value", format!("${p}"));
    let shift = || {
        let [x, y, z] = ORIGIN_PARAMS.map(|n| format!("${n}"));
        El::new("translate").attr("x", x).attr("y", y).attr("z", z)
    };
    for c in &mut doc.children {
        let Node::El(e) = c else { continue };
        let placed = match e.name {
            "shape" | "sensor" => true,
            "emitter" => matches!(e.get("type"), Some("point" | "spot")),
            _ => false,
        };
        if !placed {
            continue;
        }
        let sensor = e.name == "sensor";
        let tw = e.children.iter_mut().find_map(|k| match k {
            Node::El(t) if t.name == "transform" && t.get("name") == Some("to_world") => Some(t),
            _ => None,
        });
        let t = match tw {
            Some(t) => t,
            None => {
                e.push(El::new("transform").attr("name", "to_world"));
                let Some(Node::El(t)) = e.children.last_mut() else {
                    unreachable!("just pushed")
                };
                t
            }
        };
        if sensor {
            t.children.insert(0, Node::El(scale(PER_UNIT_PARAM)));
        }
        t.push(scale(UNIT_PARAM));
        t.push(shift());
    }
}

/// Deterministic short decimal for a float: 15 significant digits (every f64 is read back
/// within 5e-15 relative; a decimal like 0.3 stays `0.3`), `-0` printed as `0`.
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        // Caught by `validate_finite` before anything is written.
        return format!("{x}");
    }
    let r: f64 = format!("{x:.14e}").parse().unwrap_or(x);
    if r.abs() < 1e-12 {
        "0".to_string()
    } else {
        format!("{r}")
    }
}

pub fn triple(v: [f64; 3]) -> String {
    format!("{}, {}, {}", num(v[0]), num(v[1]), num(v[2]))
}

/// `<matrix value="…"/>`: 4×4 row-major of the affine map `p ↦ m·p + t`.
pub fn matrix(m: DMat3, t: DVec3) -> El {
    let r = |i: usize| m.row(i);
    let mut vals = Vec::with_capacity(16);
    for i in 0..3 {
        let row = r(i);
        vals.extend([row.x, row.y, row.z, t[i]]);
    }
    vals.extend([0.0, 0.0, 0.0, 1.0]);
    let s: Vec<String> = vals.into_iter().map(num).collect();
    El::new("matrix").attr("value", s.join(" "))
}

/// Error if any attribute holds a non-finite number (`NaN`, `inf`).
pub fn validate_finite(root: &El) -> Result<(), String> {
    let mut bad = None;
    root.walk_attrs(&mut |el, k, v| {
        if bad.is_none()
            && k == "value"
            && el.name != "string"
            && v.split([',', ' ']).any(|t| {
                let t = t.trim();
                t.eq_ignore_ascii_case("nan") || t.eq_ignore_ascii_case("inf") || t == "-inf"
            })
        {
            let name = el.get("name");
            bad = Some(format!(
                "the Mitsuba scene would contain a non-finite number in <{}{}>: {v}",
                el.name,
                name.map(|n| format!(" name=\"{n}\"")).unwrap_or_default()
            ));
        }
    });
    match bad {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_stable() {
        assert_eq!(num(0.1 + 0.2), "0.3");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-2.5e-7), "-0.00000025");
        assert_eq!(num(1.0 / 3.0), "0.333333333333333");
        let x = 38.068868712345678_f64;
        assert!((num(x).parse::<f64>().unwrap() / x - 1.0).abs() < 5e-15);
    }

    #[test]
    fn comments_cannot_escape() {
        let c = comment_text("a-->b<c>&--d-");
        assert!(!c.contains("--"), "{c}");
        assert!(!c.trim_end().ends_with('-') || c.ends_with(' '));
        let doc = El::new("scene")
            .comment("x --> <shape type=\"evil\"/> <!--")
            .to_document();
        let s = String::from_utf8(doc).unwrap();
        assert!(!s.contains("<shape"), "{s}");
    }

    #[test]
    fn xml_illegal_characters_are_replaced() {
        let hostile = "a\u{FFFE}b\u{FFFF}c\u{1}d\u{1F}e\u{7}";
        let doc = El::new("scene")
            .comment(hostile)
            .string("s", hostile)
            .to_document();
        let s = String::from_utf8(doc).unwrap();
        assert!(s.chars().all(is_xml_char), "{s:?}");
        assert!(s.contains("a\u{FFFD}b\u{FFFD}c"), "{s:?}");
    }

    #[test]
    fn attributes_are_escaped() {
        let doc = El::new("scene")
            .string("a", "\"/><evil x=\"&")
            .to_document();
        let s = String::from_utf8(doc).unwrap();
        assert!(s.contains("&quot;/&gt;&lt;evil x=&quot;&amp;"), "{s}");
    }

    #[test]
    fn non_finite_is_rejected() {
        let e = El::new("scene").float("x", f64::NAN);
        assert!(validate_finite(&e).is_err());
        let e = El::new("scene").rgb("x", [1.0, f64::INFINITY, 0.0]);
        assert!(validate_finite(&e).is_err());
        assert!(validate_finite(&El::new("scene").float("x", 1.5)).is_ok());
    }
}
