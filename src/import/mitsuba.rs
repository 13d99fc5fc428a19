//! Mitsuba 3 XML → a poser scene: the reader of `poser import` for `.xml` files.
//!
//! | Mitsuba 3 | poser | notes |
//! |---|---|---|
//! | `perspective`, `thinlens` sensor: `fov`, `fov_axis`, or `focal_length` (default `"50mm"`, on the diagonal), `principal_point_offset_x/y`, film `width`/`height` (default 768 × 576), `to_world` | `[camera]` `fx`, `principal_point`, size; one `[[network.poses]]` per sensor (in file order, then file by file) | Mitsuba's camera looks along +Z with +X left: `R_poser = R · diag(−1, −1, 1)`; `thinlens` gives `f_number`/`focus_distance`; a non-box `rfilter` (Mitsuba's default Gaussian) is noted |
//! | `rectangle`, `cube`, `sphere`, `cylinder` | `plane`, `box`, `sphere`, `cylinder` objects | `to_world` split into position, rotation (x, y, z angles) and size |
//! | `disk`, `obj`, `ply` | `mesh` objects, written as `.glb` assets | `to_world` baked into the vertices |
//! | `diffuse` BSDF (`rgb`, `spectrum`, `bitmap`, `checkerboard` reflectance), `twosided` | `albedo` | a bitmap on an `obj`/`ply` with texture coordinates or on a `rectangle` becomes the mesh's image texture, elsewhere its mean albedo; a checkerboard the mean of its colours (noted); other BSDFs their diffuse reflectance, noted |
//! | `spectrum` (one value, wavelength:value pairs, `.spd` file) | linear sRGB | as Mitsuba 3's RGB variants (`spectrum_list_to_srgb`): CIE 1931 2° observer, D65 for reflectances; noted |
//! | `dielectric` shapes and black walls around a sensor | dropped: a housing port is declared in poser | the note gives the `[camera.port]` to write; `int_ior`/`ext_ior` numbers or Mitsuba's names; per channel: their mean, noted. A `cube` or a `sphere` with a smooth `dielectric` 0.5 m or more from every sensor is a glass object (`glass = …`, the catalogue glass nearest its `int_ior`, within 0.02); a `cube` or `sphere` holding a homogeneous `interior` medium that no sensor is inside, with a `null` or smooth `dielectric` BSDF, is a filled object (`fill = { … }`: the medium's σa, σs, HG g, and `int_ior`, or 1 for `null`); other glass that far, or another shape holding such a medium, is refused at the shape |
//! | no glass at a sensor | `[camera.port] type = "none"` | |
//! | `point`, `spot`, `directional`, `constant`, `area` on a `rectangle` | `point`, `spot`, `[sun]`, `ambient`, `area` lights | lights of a per-image file (not of an included world) are rig-mounted |
//! | `homogeneous` medium (`sigma_t`, `albedo`, `scale`, `hg`/`isotropic`) | `[water]` `absorption`, `scattering`, `g` | the glass's `ext_ior` gives the water's index |
//! | a `null` `cube` holding the water, top at z = 0 | `site.surface = "flat"` | the sun is refracted back into the air |
//! | `integrator` `max_depth` (the file's, else an included file's) | `render.bounces` | a wrapper (`moment`) gives its inner integrator's; `direct` is depth 2 |
//! | `default`, `$name`, `include`, `<path>` | resolved while reading | files are found as Mitsuba's resolver finds them: the naming file's folder, the `<path>` folders (latest first), the main file's folder; `$poser_origin_x/y/z`, `$poser_unit` and `$poser_per_unit` (the per-view coordinates of poser's own views, in millimetres) are read as 0, 1 and 1: the world frame, in metres; a thin lens's lengths and point and spot intensities are divided by the unit a file declares (`Cx::units`) |
//! | `ref`/`id` | the element referenced, wherever an element is expected | an unknown id or a cycle is refused |
//!
//! Safety: a document type declaration (and with it every entity) is refused; `include`,
//! `filename` and `<path>` paths, resolved on disk (symbolic links included), must stay inside
//! the first file's folder (or the folder `--root` names); counts are bounded (elements, references copied, depth); lines
//! and columns are found in linear time; every file is
//! read as the scene front end reads one (regular files only — never a device or a named pipe —
//! of at most [`MAX_FILE`] bytes).

use super::{
    Imported, Note, arr, decompose, euler_xyz, explicit_network, finish, meshes, safe_file_name,
    sun_table, unrefract,
};
use crate::backend::mitsuba::xml::{ORIGIN_PARAMS, PER_UNIT_PARAM, UNIT_PARAM};
use crate::geometry::mesh::TriMesh;
use crate::scene::format::types as F;
use glam::{DMat3, DMat4, DVec3};
use quick_xml::events::Event;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use toml::{Table, Value};

/// Most XML elements read, over all files and includes.
pub const MAX_ELEMENTS: usize = 1_000_000;
/// Deepest nesting of elements, and of includes.
pub const MAX_DEPTH: usize = 64;
const MAX_INCLUDES: usize = 8;
/// Largest XML file read, bytes.
pub const MAX_FILE: u64 = 256 << 20;

/// One XML element with where it starts.
#[derive(Debug, Clone)]
struct X {
    tag: String,
    attrs: Vec<(String, String)>,
    kids: Vec<X>,
    /// The first comment inside the element (poser's files name things there).
    comment: Option<String>,
    loc: String,
    /// The element comes from an included file (the shared world of a set of views).
    included: bool,
    /// Folder of the file it is written in (the first place its `filename`s are looked for).
    dir: PathBuf,
    /// Which input file (of `import`'s list) it belongs to, includes included.
    doc: usize,
}

impl X {
    fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    fn ty(&self) -> &str {
        self.attr("type").unwrap_or("")
    }
    fn named(&self, name: &str) -> Option<&X> {
        self.kids.iter().find(|k| k.attr("name") == Some(name))
    }
}

/// Line and column of byte offsets in one file, in linear time over a parse: the line starts
/// are found once and binary-searched; the column is counted from the last position asked
/// for when it is on the same line (a parse asks in increasing order), else from the line's
/// start. (Recounting from the file's start for each element made parsing quadratic.)
struct Lines<'a> {
    text: &'a str,
    starts: Vec<usize>,
    /// The last answer: byte offset, its line index (0-based) and column (1-based, in chars).
    last: std::cell::Cell<(usize, usize, usize)>,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Lines<'a> {
        let mut starts = vec![0];
        starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        Lines {
            text,
            starts,
            last: std::cell::Cell::new((0, 0, 1)),
        }
    }

    /// 1-based line and column (in characters) of the first non-blank byte at or after `at`.
    fn line_col(&self, at: usize) -> (usize, usize) {
        let text = self.text;
        let mut at = at.min(text.len());
        while at < text.len() && text.as_bytes()[at].is_ascii_whitespace() {
            at += 1;
        }
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= at) - 1;
        let (l_at, l_line, l_col) = self.last.get();
        let col = if l_line == line && l_at <= at {
            l_col + text[l_at..at].chars().count()
        } else {
            1 + text[self.starts[line]..at].chars().count()
        };
        self.last.set((at, line, col));
        (line + 1, col)
    }
}

/// What a file that is not a regular file or folder is (a device, a pipe, a socket).
fn special_kind(path: &Path) -> Option<&'static str> {
    let t = std::fs::metadata(path).ok()?.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a named pipe (FIFO)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    let _ = t;
    None
}

/// Read a file the Mitsuba scene names as the scene front end reads one
/// ([`crate::scene::source::read_capped`]): regular files only, at most [`MAX_FILE`] bytes.
fn read_capped(path: &Path) -> Result<Vec<u8>, String> {
    crate::scene::source::read_capped(path, MAX_FILE).map_err(|r| {
        format!(
            "cannot read `{}`: {}\n  help: a Mitsuba scene names regular files (XML, meshes, images) of at most {} MiB",
            shown(path),
            r.reason(),
            MAX_FILE >> 20
        )
    })
}

/// A path named in the scene, resolved against `dir` and kept inside `root`.
#[cfg(test)]
fn inside(root: &Path, dir: &Path, name: &str, loc: &str) -> Result<PathBuf, String> {
    resolve(root, &[dir], name, loc)
}

/// `name` as Mitsuba's file resolver finds it: the first of `dirs` (in order) where it exists,
/// else the first one's (for the error of reading it). The path is resolved on disk (symbolic
/// links included) and must stay inside `root`, the first file's folder or `--root`
/// (canonical).
fn resolve(root: &Path, dirs: &[&Path], name: &str, loc: &str) -> Result<PathBuf, String> {
    let p = Path::new(name);
    if p.is_absolute() || p.components().any(|c| matches!(c, Component::Prefix(_))) {
        return Err(format!(
            "{loc}: `{name}` is an absolute path\n  help: imported scenes name their files \
             relative to the scene's folder"
        ));
    }
    let leaves = || {
        format!(
            "{loc}: `{name}` leaves the scene's folder ({})\n  help: copy the file into that \
             folder, or name a folder that holds both with `poser import --root`",
            root.display()
        )
    };
    // The path's text, `..` taken away (None: it leaves the root of the file system).
    let lexical = |dir: &Path| -> Option<PathBuf> {
        let mut norm = PathBuf::new();
        for c in dir.join(p).components() {
            match c {
                Component::ParentDir => {
                    if !norm.pop() {
                        return None;
                    }
                }
                Component::CurDir => {}
                c => norm.push(c),
            }
        }
        Some(norm)
    };
    let mut first: Option<Option<PathBuf>> = None;
    for d in dirs {
        let norm = lexical(d);
        if first.is_none() {
            first = Some(norm.clone());
        }
        let Some(norm) = norm else { continue };
        // A candidate that exists (a dangling link too) is the one Mitsuba takes.
        if norm.symlink_metadata().is_err() {
            continue;
        }
        if !norm.starts_with(root) {
            return Err(leaves());
        }
        return match std::fs::canonicalize(&norm) {
            Ok(real) if real.starts_with(root) => Ok(real),
            Ok(real) => Err(format!(
                "{loc}: `{name}` is a symbolic link (or passes through one) to `{}`{}, outside \
                 the scene's folder ({})\n  help: copy the file into that folder instead of \
                 linking to it",
                real.display(),
                special_kind(&real).map_or(String::new(), |k| format!(" ({k})")),
                root.display()
            )),
            Err(e) => Err(format!(
                "{loc}: `{name}` cannot be resolved: {e}\n  help: a dangling symbolic link? \
                 name a file inside the scene's folder"
            )),
        };
    }
    match first.flatten() {
        Some(norm) if norm.starts_with(root) => Ok(norm),
        _ => Err(leaves()),
    }
}

struct Reader {
    root: PathBuf,
    elements: usize,
    params: HashMap<String, String>,
    /// The input file's index.
    doc: usize,
    /// The input file's folder (canonical).
    main: PathBuf,
    /// `<path>` folders (canonical), the latest first: Mitsuba prepends each to its resolver.
    paths: Vec<PathBuf>,
    /// The length unit the input file declares (`$poser_unit`, units per metre; poser's views
    /// are in millimetres), read apart from the parameter, which placements read as 1.
    unit: Option<f64>,
}

impl Reader {
    fn parse_file(&mut self, path: &Path, depth: usize, included: bool) -> Result<X, String> {
        let shown = shown(path);
        // The scene front end's one way to read a named file: a regular file (never a device
        // or a named pipe, which would block), at most MAX_FILE bytes.
        let bytes = read_capped(path)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            format!(
                "{shown}: not a text file (byte {} is not UTF-8)\n  help: name the Mitsuba scene's `.xml` file",
                e.utf8_error().valid_up_to()
            )
        })?;
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let lines = Lines::new(&text);
        let mut r = quick_xml::Reader::from_str(&text);
        r.config_mut().trim_text(true);
        let mut stack: Vec<X> = vec![X {
            tag: "#document".into(),
            attrs: Vec::new(),
            kids: Vec::new(),
            comment: None,
            loc: shown.clone(),
            included,
            dir: dir.clone(),
            doc: self.doc,
        }];
        loop {
            let at = r.buffer_position() as usize;
            let ev = r.read_event().map_err(|e| {
                let (l, c) = lines.line_col(r.error_position() as usize);
                format!("{shown}:{l}:{c}: not well-formed XML: {e}")
            })?;
            let loc = || {
                let (l, c) = lines.line_col(at);
                format!("{shown}:{l}:{c}")
            };
            match ev {
                Event::DocType(_) => {
                    return Err(format!(
                        "{}: a document type declaration (<!DOCTYPE …>) is refused\n  help: \
                         Mitsuba scenes need none; entities could read other files",
                        loc()
                    ));
                }
                Event::Start(_) | Event::Empty(_) => {
                    let (e, empty) = match &ev {
                        Event::Start(e) => (e, false),
                        Event::Empty(e) => (e, true),
                        _ => unreachable!(),
                    };
                    self.elements += 1;
                    if self.elements > MAX_ELEMENTS {
                        return Err(format!("{}: more than {MAX_ELEMENTS} elements", loc()));
                    }
                    if stack.len() > MAX_DEPTH {
                        return Err(format!("{}: nested deeper than {MAX_DEPTH}", loc()));
                    }
                    let tag = e.name().0.to_string();
                    let mut attrs = Vec::new();
                    for a in e.attributes() {
                        let a = a.map_err(|err| format!("{}: {err}", loc()))?;
                        let k = a.key.0.to_string();
                        let v = a
                            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                            .map_err(|err| {
                                format!(
                                    "{}: attribute `{k}`: {err}\n  help: only XML's own entities \
                                 (&amp; &lt; &gt; &quot; &apos;) are read",
                                    loc()
                                )
                            })?;
                        attrs.push((k, self.substitute(&v)));
                    }
                    let x = X {
                        tag,
                        attrs,
                        kids: Vec::new(),
                        comment: None,
                        loc: loc(),
                        included,
                        dir: dir.clone(),
                        doc: self.doc,
                    };
                    if empty {
                        self.close(&mut stack, x, depth)?;
                    } else {
                        stack.push(x);
                    }
                }
                Event::End(_) => {
                    let x = stack
                        .pop()
                        .ok_or_else(|| format!("{}: unbalanced", loc()))?;
                    self.close(&mut stack, x, depth)?;
                }
                Event::Comment(c) => {
                    if let Some(top) = stack.last_mut()
                        && top.comment.is_none()
                    {
                        top.comment = Some(c[..].trim().to_string());
                    }
                }
                Event::GeneralRef(_) => {
                    return Err(format!("{}: an entity reference in text is refused", loc()));
                }
                Event::Eof => break,
                _ => {}
            }
        }
        let mut doc = stack.pop().ok_or("empty document")?;
        if !stack.is_empty() {
            return Err(format!("{shown}: unclosed elements at the end"));
        }
        match doc.kids.len() {
            1 => Ok(doc.kids.remove(0)),
            _ => Err(format!("{shown}: expected one root element <scene>")),
        }
    }

    /// An element is complete: handle `default` and `include`, else attach it to its parent.
    fn close(&mut self, stack: &mut [X], x: X, depth: usize) -> Result<(), String> {
        let parent = stack.last_mut().ok_or("unbalanced document")?;
        match x.tag.as_str() {
            "default" => {
                let (Some(n), Some(v)) = (x.attr("name"), x.attr("value")) else {
                    return Err(format!("{}: <default> needs `name` and `value`", x.loc));
                };
                if n == UNIT_PARAM && self.unit.is_none() {
                    let u = v
                        .trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|u| *u > 0.0 && u.is_finite());
                    self.unit = Some(u.ok_or_else(|| {
                        format!(
                            "{}: `{UNIT_PARAM}` is `{v}`, not a length unit\n  help: poser's \
                             views give the units per metre, such as 1000",
                            x.loc
                        )
                    })?);
                }
                self.params
                    .entry(n.to_string())
                    .or_insert_with(|| v.to_string());
            }
            "include" => {
                if depth >= MAX_INCLUDES {
                    return Err(format!(
                        "{}: includes nested deeper than {MAX_INCLUDES}",
                        x.loc
                    ));
                }
                let name = x
                    .attr("filename")
                    .ok_or_else(|| format!("{}: <include> needs `filename`", x.loc))?;
                let path = resolve(&self.root, &self.search(&x.dir), name, &x.loc)?;
                // A file that cannot be read is reported at the <include> that names it.
                let inc = self.parse_file(&path, depth + 1, true).map_err(|e| {
                    if e.starts_with("cannot read `") {
                        format!("{}: {e}", x.loc)
                    } else {
                        e
                    }
                })?;
                parent.kids.extend(inc.kids);
            }
            // A folder for Mitsuba's file resolver: relative to the file that names it.
            "path" => {
                if stack.len() != 2 {
                    return Err(format!(
                        "{}: <path> must be a child of <scene>\n  help: Mitsuba reads it there only",
                        x.loc
                    ));
                }
                let v = x
                    .attr("value")
                    .ok_or_else(|| format!("{}: <path> needs `value`", x.loc))?;
                let p = resolve(&self.root, &self.search(&x.dir), v, &x.loc)?;
                if !p.is_dir() {
                    return Err(format!(
                        "{}: <path> folder `{v}` not found\n  help: name a folder inside the \
                         scene's folder, relative to the file",
                        x.loc
                    ));
                }
                self.paths.retain(|q| q != &p);
                self.paths.insert(0, p);
            }
            _ => parent.kids.push(x),
        }
        Ok(())
    }

    /// Where Mitsuba looks for a file named in a file of folder `dir`: that folder, the
    /// `<path>` folders (the latest first), the input file's folder.
    fn search<'a>(&'a self, dir: &'a Path) -> Vec<&'a Path> {
        search_dirs(dir, &self.paths, &self.main)
    }

    fn substitute(&self, v: &str) -> String {
        if !v.contains('$') {
            return v.to_string();
        }
        let mut out = v.to_string();
        let mut keys: Vec<&String> = self.params.keys().collect();
        keys.sort_by_key(|k| std::cmp::Reverse(k.len()));
        for k in keys {
            out = out.replace(&format!("${k}"), &self.params[k]);
        }
        out
    }
}

fn search_dirs<'a>(dir: &'a Path, paths: &'a [PathBuf], main: &'a Path) -> Vec<&'a Path> {
    let mut v: Vec<&Path> = vec![dir];
    for p in paths.iter().map(PathBuf::as_path).chain([main]) {
        if !v.contains(&p) {
            v.push(p);
        }
    }
    v
}

// ---- values ---------------------------------------------------------------------------

fn nums(s: &str, loc: &str) -> Result<Vec<f64>, String> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{loc}: `{t}` is not a finite number"))
        })
        .collect()
}

struct Cx {
    notes: Vec<Note>,
    /// Targets already noted (poser's files name a target once per element group).
    targets: Vec<String>,
    ids: HashMap<String, X>,
    root: PathBuf,
    /// Per input file: its folder and its `<path>` folders (the resolver's state at the end).
    search: Vec<(PathBuf, Vec<PathBuf>)>,
    /// Per input file: its declared length unit, units per metre (`$poser_unit`; 1 when it
    /// declares none, as third-party files).
    units: Vec<f64>,
    /// Ids that a `<ref>` names.
    referenced: std::collections::HashSet<String>,
    /// Locations of the bitmaps the shape being read carries as its image texture (their
    /// mean colour is then not noted as what was imported).
    mapped: std::collections::HashSet<String>,
}

impl Cx {
    /// A file named by element `k` (a `filename`), found as Mitsuba's file resolver finds it.
    fn file(&self, k: &X, name: &str) -> Result<PathBuf, String> {
        let (main, paths) = &self.search[k.doc];
        resolve(&self.root, &search_dirs(&k.dir, paths, main), name, &k.loc)
    }

    fn note(&mut self, x: &X, msg: impl Into<String>, help: Option<&str>) {
        let mut n = Note::new(Some(x.loc.clone()), msg);
        if let Some(h) = help {
            n = n.help(h);
        }
        self.notes.push(n);
    }

    /// `x` itself, or the element its `<ref id>` names.
    fn deref<'a>(&'a self, x: &'a X) -> Result<&'a X, String> {
        if x.tag == "ref" {
            let id = x.attr("id").unwrap_or("");
            self.ids
                .get(id)
                .ok_or_else(|| format!("{}: no element has id `{id}`", x.loc))
        } else {
            Ok(x)
        }
    }

    fn float(&self, x: &X, name: &str, default: f64) -> Result<f64, String> {
        match x.named(name) {
            None => Ok(default),
            Some(k) => {
                let v = nums(k.attr("value").unwrap_or(""), &k.loc)?;
                v.first()
                    .copied()
                    .ok_or_else(|| format!("{}: `{name}` has no value", k.loc))
            }
        }
    }

    fn int(&self, x: &X, name: &str, default: i64) -> Result<i64, String> {
        Ok(self.float(x, name, default as f64)?.round() as i64)
    }

    /// A colour: `rgb`, `float`, uniform `spectrum`, or a `constvolume`/`uniform` wrapper.
    fn colour(&mut self, x: &X, name: &str) -> Result<Option<[f64; 3]>, String> {
        let Some(k) = x.named(name) else {
            return Ok(None);
        };
        let k = self.deref(k)?.clone();
        self.colour_of(&k)
    }

    fn colour_of(&mut self, k: &X) -> Result<Option<[f64; 3]>, String> {
        match k.tag.as_str() {
            "rgb" | "float" => {
                let v = nums(k.attr("value").unwrap_or(""), &k.loc)?;
                match v.len() {
                    1 => Ok(Some([v[0]; 3])),
                    3 => Ok(Some([v[0], v[1], v[2]])),
                    _ => Err(format!("{}: expected 1 or 3 numbers", k.loc)),
                }
            }
            "spectrum" => {
                // As Mitsuba 3's RGB variants read a spectrum (src/core/properties.cpp): an
                // emitter's is integrated without D65 and not bounded above, a reflectance's
                // under D65 and clipped to [0, 1], a medium's not bounded.
                let prop = k.attr("name").unwrap_or("");
                let emitter = matches!(prop, "radiance" | "intensity" | "irradiance");
                let unbounded = matches!(prop, "sigma_t" | "sigma_a" | "sigma_s" | "scale");
                let (wl, v) = match (k.attr("value"), k.attr("filename")) {
                    (Some(s), None) if s.contains(':') => spectrum_pairs(s, &k.loc)?,
                    (Some(s), None) => {
                        let v = nums(s, &k.loc)?;
                        let Some(&c) = v.first().filter(|_| v.len() == 1) else {
                            return Err(format!(
                                "{}: a spectrum of one value, or of wavelength:value pairs\n  \
                                 help: e.g. value=\"0.5\" or value=\"400:0.1, 700:0.8\"",
                                k.loc
                            ));
                        };
                        // A uniform spectrum; on an emitter Mitsuba's RGB variants give it
                        // the colour of equal energy in sRGB (slightly purple).
                        return Ok(Some(if emitter {
                            xyz_to_srgb([1.0; 3]).map(|x| x * c)
                        } else {
                            [c; 3]
                        }));
                    }
                    (None, Some(f)) => {
                        let path = self.file(k, f)?;
                        let bytes = read_capped(&path).map_err(|e| format!("{}: {e}", k.loc))?;
                        spectrum_pairs(
                            &String::from_utf8_lossy(&bytes),
                            &format!("{}: {f}", k.loc),
                        )?
                    }
                    _ => {
                        return Err(format!(
                            "{}: a <spectrum> needs either `value` or `filename`",
                            k.loc
                        ));
                    }
                };
                let rgb = spectrum_to_srgb(&wl, &v, !(emitter || unbounded), !emitter);
                self.note(
                    k,
                    format!(
                        "a sampled spectrum ({} samples) is imported as linear sRGB ({:.4}, \
                         {:.4}, {:.4}), as Mitsuba 3's RGB variants convert it",
                        wl.len(),
                        rgb[0],
                        rgb[1],
                        rgb[2]
                    ),
                    Some("CIE 1931 2° observer, D65 for reflectances (docs/import.md)"),
                );
                Ok(Some(rgb))
            }
            "volume" | "texture" => match k.ty() {
                "constvolume" | "uniform" => match k.named("value").or(k.kids.first()) {
                    Some(v) => {
                        let v = self.deref(v)?.clone();
                        self.colour_of(&v)
                    }
                    None => Ok(None),
                },
                "bitmap" => self.bitmap_mean(k).map(Some),
                "checkerboard" => {
                    // Mitsuba's defaults: color0 0.4, color1 0.2; half the texture is each.
                    let c0 = self.colour(k, "color0")?.unwrap_or([0.4; 3]);
                    let c1 = self.colour(k, "color1")?.unwrap_or([0.2; 3]);
                    let m = [0, 1, 2].map(|i| 0.5 * (c0[i] + c1[i]));
                    self.note(
                        k,
                        format!(
                            "a checkerboard texture is imported as the mean of its two colours \
                             ({:.3}, {:.3}, {:.3})",
                            m[0], m[1], m[2]
                        ),
                        Some("poser's own patterns include checkerboards (docs/textures.md)"),
                    );
                    Ok(Some(m))
                }
                t => {
                    self.note(
                        k,
                        format!("a `{t}` {} is not imported; 0.5 is used", k.tag),
                        Some("poser's albedos are constants or poser's own patterns"),
                    );
                    Ok(Some([0.5; 3]))
                }
            },
            _ => Ok(None),
        }
    }

    /// The mean colour of a `bitmap` texture (8-bit images decoded from sRGB).
    fn bitmap_mean(&mut self, k: &X) -> Result<[f64; 3], String> {
        let mapped = self.mapped.contains(&k.loc);
        let (fk, name) = k
            .named("filename")
            .and_then(|f| Some((f, f.attr("value")?)))
            .ok_or_else(|| format!("{}: a bitmap without `filename`", k.loc))?;
        let path = self.file(fk, name)?;
        let bytes = read_capped(&path).map_err(|e| format!("{}: {e}", k.loc))?;
        // The header first, with the textured-mesh code's limits: a damaged file or a
        // decompression bomb is refused before anything is decoded.
        crate::texture::mapped::probe(&bytes, &format!("`{}`", shown(&path)))
            .map_err(|e| format!("{}: {e}", k.loc))?;
        let img = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
            .and_then(|r| r.decode().map_err(|e| e.to_string()))
            .map_err(|e| format!("{}: {}: {e}", k.loc, path.display()))?;
        let srgb = !matches!(
            img,
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
        );
        let n = (img.width() as f64 * img.height() as f64).max(1.0);
        // 8-bit colour images (grey ones are widened to colour by a different conversion).
        let rgb8 = matches!(
            img,
            image::DynamicImage::ImageRgb8(_) | image::DynamicImage::ImageRgba8(_)
        );
        let sum = if srgb && rgb8 {
            sum_8bit_srgb(&img)
        } else {
            let rgb = img.to_rgb32f();
            let mut sum = [0.0f64; 3];
            for p in rgb.pixels() {
                for (acc, &v) in sum.iter_mut().zip(&p.0) {
                    let v = v as f64;
                    *acc += if srgb { srgb_to_linear(v) } else { v };
                }
            }
            sum
        };
        if mapped {
            return Ok(sum.map(|s| s / n));
        }
        self.note(
            k,
            format!(
                "texture `{name}` is imported as its mean albedo ({:.3}, {:.3}, {:.3})",
                sum[0] / n,
                sum[1] / n,
                sum[2] / n
            ),
            Some(
                "a bitmap on an `obj` or `ply` with texture coordinates, or on a `rectangle`, \
                 becomes the mesh's image texture (docs/import.md)",
            ),
        );
        Ok(sum.map(|s| s / n))
    }

    fn point(&self, x: &X, name: &str, default: DVec3) -> Result<DVec3, String> {
        match x.named(name) {
            None => Ok(default),
            Some(k) => vec3(k),
        }
    }

    /// The `to_world` of `x` (identity when absent).
    fn to_world(&self, x: &X) -> Result<DMat4, String> {
        match x.named("to_world") {
            None => Ok(DMat4::IDENTITY),
            Some(t) => transform(t),
        }
    }
}

/// The sRGB transfer function, inverted (8-bit textures are stored encoded).
fn srgb_to_linear(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn vec3(k: &X) -> Result<DVec3, String> {
    if let Some(v) = k.attr("value") {
        let v = nums(v, &k.loc)?;
        return match v.len() {
            1 => Ok(DVec3::splat(v[0])),
            3 => Ok(DVec3::new(v[0], v[1], v[2])),
            _ => Err(format!("{}: expected 3 numbers", k.loc)),
        };
    }
    let c = |a: &str| -> Result<f64, String> {
        match k.attr(a) {
            None => Ok(0.0),
            Some(s) => nums(s, &k.loc)?
                .first()
                .copied()
                .ok_or_else(|| format!("{}: `{a}` is empty", k.loc)),
        }
    };
    Ok(DVec3::new(c("x")?, c("y")?, c("z")?))
}

/// Mitsuba 3's `<rotate>` (Dr.Jit's `rotate`, Rodrigues' formula): the axis is used as
/// written, not normalised, so a non-unit axis also scales and shears (mitsuba-data's
/// `hello.xml` rotates its teapot about (0, 1, 1); normalising it moved the silhouette and cost
/// 7 % of its light).
fn mitsuba_rotate(a: DVec3, angle: f64) -> DMat3 {
    let (s, c) = angle.sin_cos();
    let cm = 1.0 - c;
    DMat3::from_cols(
        DVec3::new(
            c + a.x * a.x * cm,
            a.x * a.y * cm + a.z * s,
            a.x * a.z * cm - a.y * s,
        ),
        DVec3::new(
            a.x * a.y * cm - a.z * s,
            c + a.y * a.y * cm,
            a.y * a.z * cm + a.x * s,
        ),
        DVec3::new(
            a.x * a.z * cm + a.y * s,
            a.y * a.z * cm - a.x * s,
            c + a.z * a.z * cm,
        ),
    )
}

/// A `<transform>`: its operations applied in order (each one on the left).
fn transform(t: &X) -> Result<DMat4, String> {
    let mut m = DMat4::IDENTITY;
    for op in &t.kids {
        let step = match op.tag.as_str() {
            "translate" => DMat4::from_translation(vec3(op)?),
            "scale" => {
                let s = if op.attr("value").is_some() {
                    vec3(op)?
                } else {
                    let g = |a: &str| op.attr(a).and_then(|v| v.trim().parse::<f64>().ok());
                    DVec3::new(
                        g("x").unwrap_or(1.0),
                        g("y").unwrap_or(1.0),
                        g("z").unwrap_or(1.0),
                    )
                };
                DMat4::from_scale(s)
            }
            "rotate" => {
                let axis = vec3(op)?;
                let angle = op
                    .attr("angle")
                    .and_then(|a| a.trim().parse::<f64>().ok())
                    .ok_or_else(|| format!("{}: <rotate> needs `angle` (degrees)", op.loc))?;
                if axis.length() == 0.0 {
                    return Err(format!("{}: <rotate> needs a non-zero axis", op.loc));
                }
                DMat4::from_mat3(mitsuba_rotate(axis, angle.to_radians()))
            }
            "matrix" => {
                let v = nums(op.attr("value").unwrap_or(""), &op.loc)?;
                match v.len() {
                    16 => DMat4::from_cols_array(&[
                        v[0], v[4], v[8], v[12], v[1], v[5], v[9], v[13], v[2], v[6], v[10], v[14],
                        v[3], v[7], v[11], v[15],
                    ]),
                    9 => DMat4::from_mat3(DMat3::from_cols_array(&[
                        v[0], v[3], v[6], v[1], v[4], v[7], v[2], v[5], v[8],
                    ])),
                    n => return Err(format!("{}: a matrix of {n} numbers (16 or 9)", op.loc)),
                }
            }
            "lookat" => {
                let g = |a: &str| -> Result<DVec3, String> {
                    let v = nums(op.attr(a).unwrap_or(""), &op.loc)?;
                    if v.len() != 3 {
                        return Err(format!("{}: <lookat> `{a}` needs 3 numbers", op.loc));
                    }
                    Ok(DVec3::new(v[0], v[1], v[2]))
                };
                let (o, target) = (g("origin")?, g("target")?);
                let up = if op.attr("up").is_some() {
                    g("up")?
                } else {
                    DVec3::Y
                };
                let dir = (target - o).normalize_or_zero();
                let left = up.cross(dir).normalize_or_zero();
                if dir == DVec3::ZERO || left == DVec3::ZERO {
                    return Err(format!(
                        "{}: <lookat> with origin = target or up along the view",
                        op.loc
                    ));
                }
                let new_up = dir.cross(left);
                DMat4::from_cols(
                    left.extend(0.0),
                    new_up.extend(0.0),
                    dir.extend(0.0),
                    o.extend(1.0),
                )
            }
            other => return Err(format!("{}: unknown transform operation <{other}>", op.loc)),
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(format!("{}: the transform is not finite", t.loc));
    }
    Ok(m)
}

// ---- spectra ----------------------------------------------------------------------------

/// The CIE 1931 2° standard observer's colour matching functions x̄, ȳ, z̄ (95 samples each,
/// 360–830 nm every 5 nm), as Mitsuba 3 tabulates them (`cie1931_tbl`, src/core/spectrum.cpp;
/// from the CIE's tables).
#[rustfmt::skip]
const CIE1931: [f64; 285] = [
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236,
    0.004243, 0.00765, 0.01431, 0.02319, 0.04351, 0.07763,
    0.13438, 0.21477, 0.2839, 0.3285, 0.34828, 0.34806,
    0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024,
    0.0093, 0.0291, 0.06327, 0.1096, 0.1655, 0.2257499,
    0.2904, 0.3597, 0.4334499, 0.5120501, 0.5945, 0.6784,
    0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514,
    0.6424, 0.5419, 0.4479, 0.3608, 0.2835, 0.2187,
    0.1649, 0.1212, 0.0874, 0.0636, 0.04677, 0.0329,
    0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.0009999493, 0.0006900786, 0.0004760213,
    0.0003323011, 0.0002348261, 0.0001661505, 0.000117413, 0.00008307527, 0.00005870652,
    0.00004150994, 0.00002935326, 0.00002067383, 0.00001455977, 0.00001025398, 0.000007221456,
    0.000005085868, 0.000003581652, 0.000002522525, 0.000001776509, 0.000001251141, 0.000003917,
    0.000006965, 0.00001239, 0.00002202, 0.000039, 0.000064, 0.00012,
    0.000217, 0.000396, 0.00064, 0.00121, 0.00218, 0.004,
    0.0073, 0.0116, 0.01684, 0.023, 0.0298, 0.038,
    0.048, 0.06, 0.0739, 0.09098, 0.1126, 0.13902,
    0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503,
    0.6082, 0.71, 0.7932, 0.862, 0.9148501, 0.954,
    0.9803, 0.9949501, 1.0, 0.995, 0.9786, 0.952,
    0.9154, 0.87, 0.8163, 0.757, 0.6949, 0.631,
    0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265,
    0.217, 0.175, 0.1382, 0.107, 0.0816, 0.061,
    0.04458, 0.032, 0.0232, 0.017, 0.01192, 0.00821,
    0.005723, 0.004102, 0.002929, 0.002091, 0.001484, 0.001047,
    0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012,
    0.0000848, 0.00006, 0.0000424, 0.00003, 0.0000212, 0.00001499,
    0.0000106, 0.0000074657, 0.0000052578, 0.0000037029, 0.0000026078, 0.0000018366,
    0.0000012934, 0.00000091093, 0.00000064153, 0.00000045181, 0.0006061, 0.001086,
    0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.0390501,
    1.3856, 1.62296, 1.74706, 1.7826, 1.77211, 1.7441,
    1.6692, 1.5281, 1.28764, 1.0419, 0.8129501, 0.6162,
    0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134,
    0.008749999, 0.005749999, 0.0039, 0.002749999, 0.0021, 0.0018,
    0.001650001, 0.0014, 0.0011, 0.001, 0.0008, 0.0006,
    0.00034, 0.00024, 0.00019, 0.0001, 0.00004999999, 0.00003,
    0.00002, 0.00001, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0,
];

/// The CIE standard illuminant D65, relative to its power at 560 nm, on the same grid
/// (Mitsuba 3's `d65_table`, include/mitsuba/core/spectrum.h).
#[rustfmt::skip]
const D65: [f64; 95] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118,
    54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589,
    93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936,
    117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047,
    104.405, 104.225, 104.046, 102.023, 100.0, 98.1671,
    96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936,
    83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207,
    80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027,
    69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398,
    63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941,
    63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054,
    51.959, 54.6998, 57.4406, 58.8765, 60.3125,
];

/// Linear interpolation in a table on the 360–830 nm grid (0 outside), as Mitsuba's
/// `cie1931_xyz` and `cie_d65` do.
fn on_grid(table: &[f64], offset: usize, w: f64) -> f64 {
    if !(360.0..=830.0).contains(&w) {
        return 0.0;
    }
    let t = (w - 360.0) * (94.0 / 470.0);
    let i0 = (t as usize).min(93);
    let w1 = t - i0 as f64;
    (1.0 - w1) * table[offset + i0] + w1 * table[offset + i0 + 1]
}

/// linear sRGB (Rec. 709 primaries, D65 white) of a sampled spectrum, as Mitsuba 3's RGB
/// variants convert one (`spectrum_list_to_srgb`, src/core/spectrum.cpp): the spectrum, linear
/// between its samples and 0 outside them, is integrated against the CIE 1931 2° observer
/// (times D65 for a reflectance, `d65`) at 1000 points over 360–830 nm, normalised so that a
/// unit spectrum has luminance 1, and taken from XYZ to linear sRGB. A `bounded` value
/// (a reflectance) is clipped to [0, 1], another one at 0.
fn spectrum_to_srgb(wl: &[f64], v: &[f64], bounded: bool, d65: bool) -> [f64; 3] {
    let steps = 1000;
    let mut xyz = [0.0f64; 3];
    for i in 0..steps {
        let w = 360.0 + (i as f64 / (steps - 1) as f64) * (830.0 - 360.0);
        if w < wl[0] || w > wl[wl.len() - 1] {
            continue;
        }
        // The interval [wl[k], wl[k+1]] holding w.
        let k = wl[..wl.len() - 1]
            .partition_point(|&x| x <= w)
            .saturating_sub(1)
            .min(wl.len().saturating_sub(2));
        let val = if wl.len() == 1 {
            v[0]
        } else {
            let (w0, w1, v0, v1) = (wl[k], wl[k + 1], v[k], v[k + 1]);
            ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        };
        let light = if d65 {
            on_grid(&D65, 0, w) / 98.99741751876255
        } else {
            1.0
        };
        for (c, x) in xyz.iter_mut().enumerate() {
            *x += on_grid(&CIE1931, 95 * c, w) * val * light;
        }
    }
    let scale = (830.0 - 360.0) / 106.750_259_399_414_06 / steps as f64;
    let rgb = xyz_to_srgb(xyz.map(|x| x * scale));
    if bounded {
        rgb.map(|c| c.clamp(0.0, 1.0))
    } else {
        rgb.map(|c| c.max(0.0))
    }
}

/// CIE XYZ → linear sRGB (Mitsuba 3's `xyz_to_srgb`).
fn xyz_to_srgb(x: [f64; 3]) -> [f64; 3] {
    [
        3.240479 * x[0] - 1.537150 * x[1] - 0.498535 * x[2],
        -0.969256 * x[0] + 1.875991 * x[1] + 0.041556 * x[2],
        0.055648 * x[0] - 0.204043 * x[1] + 1.057311 * x[2],
    ]
}

/// Wavelength:value pairs (`"400:0.1, 500:0.3"`), or the lines of a `.spd` file
/// (`wavelength value`, `#` comments): wavelengths in nm, increasing.
fn spectrum_pairs(s: &str, loc: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    let mut wl = Vec::new();
    let mut v = Vec::new();
    let items: Vec<&str> = if s.contains(':') {
        s.split(',').collect()
    } else {
        s.lines()
            .map(|l| l.split('#').next().unwrap_or(""))
            .collect()
    };
    for item in items.iter().map(|i| i.trim()).filter(|i| !i.is_empty()) {
        let mut parts = item
            .split(|c: char| c == ':' || c.is_whitespace())
            .filter(|p| !p.is_empty());
        let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(format!(
                "{loc}: `{item}` is not a wavelength:value pair\n  help: write a sampled \
                 spectrum as \"400:0.1, 500:0.3, …\" (nm:value)"
            ));
        };
        let num = |t: &str| t.parse::<f64>().ok().filter(|x| x.is_finite());
        let (Some(a), Some(b)) = (num(a), num(b)) else {
            return Err(format!("{loc}: `{item}` is not a pair of finite numbers"));
        };
        if wl.last().is_some_and(|&l| a <= l) {
            return Err(format!(
                "{loc}: the spectrum's wavelengths must increase (`{item}`)\n  help: list the \
                 samples from short to long wavelengths"
            ));
        }
        wl.push(a);
        v.push(b);
    }
    if wl.is_empty() {
        return Err(format!("{loc}: an empty spectrum"));
    }
    Ok((wl, v))
}

// ---- the scene ------------------------------------------------------------------------

struct Sensor {
    x: X,
    width: i64,
    height: i64,
    fx: f64,
    cx: f64,
    cy: f64,
    thin: Option<(f64, f64)>,
    /// world_from_camera in poser's camera axes (x right, y down, z forward).
    rot: DMat3,
    pos: DVec3,
    samples: Option<i64>,
    /// Which input file it comes from.
    doc: usize,
    /// The (pose, camera) a poser view file names in its first comment.
    view: Option<(usize, String)>,
}

/// poser's view files name their image's rig pose and camera in their first comment:
/// "… image `left_img_0001` = pose 0 (`img_0001`), camera `left`; …".
fn view_of(doc: &X) -> Option<(usize, String)> {
    let c = doc.comment.as_deref()?;
    let i = c.find("= pose ")? + "= pose ".len();
    let pose: usize = c[i..].split_whitespace().next()?.parse().ok()?;
    let j = c.find("camera `")? + "camera `".len();
    let name = c[j..].split('`').next()?.to_string();
    Some((pose, name))
}

/// The film's size in pixels (Mitsuba's default 768 × 576); notes a reconstruction filter
/// other than a box.
fn film_size(cx: &mut Cx, x: &X) -> Result<(i64, i64), String> {
    let film = x.kids.iter().find(|k| k.tag == "film");
    // Mitsuba's film defaults: 768 × 576 pixels, a Gaussian reconstruction filter.
    let (width, height) = match film {
        Some(f) => (cx.int(f, "width", 768)?, cx.int(f, "height", 576)?),
        None => (768, 576),
    };
    let rfilter = film.and_then(|f| f.kids.iter().find(|k| k.tag == "rfilter"));
    let filter = rfilter.map_or("gaussian", |r| r.ty());
    if filter != "box" {
        let at = rfilter.or(film).unwrap_or(x).clone();
        cx.note(
            &at,
            format!(
                "the film's `{filter}` reconstruction filter{} is not imported: poser's pixels \
                 are one-pixel boxes (docs/render-conventions.md)",
                if rfilter.is_none() {
                    " (Mitsuba's default)"
                } else {
                    ""
                }
            ),
            Some("images come out a little sharper than Mitsuba's"),
        );
    }
    if !(1..=100_000).contains(&width) || !(1..=100_000).contains(&height) {
        return Err(format!("{}: film of {width}×{height} pixels", x.loc));
    }
    Ok((width, height))
}

/// The sensor's field of view in degrees and the axis it spans (`x`, `y`, `diagonal`, …).
fn field_of_view(cx: &mut Cx, x: &X) -> Result<(f64, String), String> {
    // Mitsuba 3's `parse_fov` (src/render/sensor.cpp): `fov` along `fov_axis` (default x),
    // or else `focal_length` (default "50mm"), a 35 mm-film equivalent on the diagonal
    // (fov_axis is then not read).
    Ok(match (x.named("fov"), x.named("focal_length")) {
        (Some(_), Some(f)) => {
            return Err(format!(
                "{}: the sensor gives both `fov` and `focal_length`\n  help: Mitsuba refuses \
                 this; keep one",
                f.loc
            ));
        }
        (Some(_), None) => (
            cx.float(x, "fov", f64::NAN)?,
            x.named("fov_axis")
                .and_then(|a| a.attr("value"))
                .unwrap_or("x")
                .to_ascii_lowercase(),
        ),
        (None, f) => {
            let s = f.and_then(|f| f.attr("value")).unwrap_or("50mm");
            let mm: f64 = s
                .trim()
                .strip_suffix("mm")
                .unwrap_or(s.trim())
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    format!(
                        "{}: focal_length `{s}` is not a length in millimetres\n  help: write it \
                         as Mitsuba does, e.g. \"50mm\"",
                        f.map_or(&x.loc, |f| &f.loc)
                    )
                })?;
            if f.is_none() {
                cx.note(
                    x,
                    "the sensor has neither `fov` nor `focal_length`: Mitsuba's default, a 50 mm \
                     lens on 35 mm film (a 46.8° diagonal field of view), is imported",
                    None,
                );
            }
            (
                2.0 * (36f64.hypot(24.0) / (2.0 * mm)).atan().to_degrees(),
                "diagonal".to_string(),
            )
        }
    })
}

fn sensor(cx: &mut Cx, x: &X) -> Result<Option<Sensor>, String> {
    let thin = match x.ty() {
        "perspective" => None,
        "thinlens" => Some((
            cx.float(x, "aperture_radius", 0.0)? / cx.units[x.doc],
            cx.float(x, "focus_distance", 0.0)? / cx.units[x.doc],
        )),
        t => {
            cx.note(
                x,
                format!("a `{t}` sensor is not imported"),
                Some("poser's cameras are perspective (with an optional thin lens)"),
            );
            return Ok(None);
        }
    };
    let (width, height) = film_size(cx, x)?;
    let (w, h) = (width as f64, height as f64);
    let (fov, axis) = field_of_view(cx, x)?;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(format!(
            "{}: the sensor's field of view is {fov}°, not in (0, 180)\n  help: give `fov` in \
             degrees, or `focal_length` such as \"50mm\"",
            x.loc
        ));
    }
    let axis_px = match axis.as_str() {
        "x" => w,
        "y" => h,
        "diagonal" => w.hypot(h),
        "smaller" => w.min(h),
        "larger" => w.max(h),
        other => {
            return Err(format!(
                "{}: unknown fov_axis `{other}`\n  help: x, y, diagonal, smaller or larger",
                x.loc
            ));
        }
    };
    let fx = axis_px / 2.0 / (fov.to_radians() / 2.0).tan();
    let cxp = w * (0.5 - cx.float(x, "principal_point_offset_x", 0.0)?);
    let cyp = h * (0.5 - cx.float(x, "principal_point_offset_y", 0.0)?);
    let m = cx.to_world(x)?;
    let (_, frame, mirror, sheared) = decompose(&m);
    if sheared {
        cx.note(
            x,
            "the sensor's to_world is sheared; its rotation is taken from the first two axes",
            None,
        );
    }
    let mut rot = frame * DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0));
    if mirror {
        rot = DMat3::from_cols(-rot.x_axis, rot.y_axis, rot.z_axis);
        cx.note(
            x,
            "the sensor's to_world mirrors the image (a negative scale); imported unmirrored",
            Some("the imported camera's images are the originals flipped left–right"),
        );
    }
    let samples = x
        .kids
        .iter()
        .find(|k| k.tag == "sampler")
        .map(|s| cx.int(s, "sample_count", 4))
        .transpose()?;
    Ok(Some(Sensor {
        x: x.clone(),
        width,
        height,
        fx,
        cx: cxp,
        cy: cyp,
        thin,
        rot,
        pos: m.w_axis.truncate(),
        samples,
        doc: 0,
        view: None,
    }))
}

/// The name poser's own files give an element in its first comment (`object `name``…).
fn comment_name(x: &X, kind: &str) -> Option<String> {
    let c = x.comment.as_deref()?;
    let rest = c.strip_prefix(kind)?.trim_start();
    let rest = rest.strip_prefix('`')?;
    let end = rest.find('`')?;
    Some(rest[..end].to_string()).filter(|s| !s.is_empty())
}

struct Water {
    sigma_a: [f64; 3],
    sigma_s: [f64; 3],
    g: f64,
}

fn medium(cx: &mut Cx, x: &X) -> Result<Option<Water>, String> {
    if x.ty() != "homogeneous" {
        cx.note(
            x,
            format!("a `{}` medium is not imported", x.ty()),
            Some("poser's water is homogeneous"),
        );
        return Ok(None);
    }
    let st = cx.colour(x, "sigma_t")?.unwrap_or([1.0; 3]);
    let al = cx.colour(x, "albedo")?.unwrap_or([0.75; 3]);
    let scale = cx.float(x, "scale", 1.0)?;
    let st = st.map(|v| v * scale);
    let sigma_s = [0, 1, 2].map(|c| al[c] * st[c]);
    let sigma_a = [0, 1, 2].map(|c| st[c] - sigma_s[c]);
    let g = match x.kids.iter().find(|k| k.tag == "phase") {
        None => 0.0,
        Some(p) => match p.ty() {
            "hg" => cx.float(p, "g", 0.8)?,
            "isotropic" => 0.0,
            t => {
                cx.note(
                    p,
                    format!("a `{t}` phase function is imported as isotropic"),
                    Some("poser's phase functions are Henyey–Greenstein and Fournier–Forand"),
                );
                0.0
            }
        },
    };
    Ok(Some(Water {
        sigma_a,
        sigma_s,
        g,
    }))
}

/// The albedo of a shape's BSDF (Mitsuba's default: diffuse 0.5), or `None` for a BSDF that
/// is not a surface poser can hold (null, dielectric).
/// The BSDF of a shape, references followed and `twosided`/`mask` wrappers opened.
fn shape_bsdf(cx: &Cx, shape: &X) -> Result<Option<X>, String> {
    let Some(b) = shape.kids.iter().find(|k| {
        k.tag == "bsdf" || (k.tag == "ref" && k.attr("name").is_none_or(|n| n == "bsdf"))
    }) else {
        return Ok(None);
    };
    let mut b = cx.deref(b)?.clone();
    while b.ty() == "twosided" || b.ty() == "mask" {
        match b.kids.iter().find(|k| k.tag == "bsdf" || k.tag == "ref") {
            Some(k) => b = cx.deref(k)?.clone(),
            None => break,
        }
    }
    Ok(Some(b))
}

/// The `bitmap` texture that gives a shape's diffuse colour (a diffuse `reflectance`, another
/// BSDF's `diffuse_reflectance`, a principled `base_color`), if any.
fn bitmap_of(cx: &Cx, shape: &X) -> Result<Option<X>, String> {
    let Some(b) = shape_bsdf(cx, shape)? else {
        return Ok(None);
    };
    let names: &[&str] = match b.ty() {
        "diffuse" => &["reflectance"],
        "null" | "dielectric" | "thindielectric" | "roughdielectric" => &[],
        _ => &["diffuse_reflectance", "base_color", "reflectance"],
    };
    for n in names {
        if let Some(t) = b.named(n) {
            let t = cx.deref(t)?;
            return Ok((t.tag == "texture" && t.ty() == "bitmap").then(|| t.clone()));
        }
    }
    Ok(None)
}

/// A bitmap texture as a file beside the imported mesh (`stem` + its extension): an 8-bit or
/// 16-bit sRGB PNG or JPEG is copied as it is; a float image (OpenEXR) or one Mitsuba reads
/// `raw` becomes a 16-bit sRGB PNG of the same linear values. The image is decoded first, with
/// the textured-mesh code's limits (a damaged file or a decompression bomb is refused).
fn bitmap_asset(
    cx: &mut Cx,
    b: &X,
    stem: &str,
) -> Result<(String, Vec<u8>, crate::geometry::meshfile::Wrap), String> {
    use crate::geometry::meshfile::Wrap;
    let (fk, name) = b
        .named("filename")
        .and_then(|f| Some((f, f.attr("value")?)))
        .ok_or_else(|| format!("{}: a bitmap without `filename`", b.loc))?;
    let path = cx.file(fk, name)?;
    let bytes = read_capped(&path).map_err(|e| format!("{}: {e}", b.loc))?;
    let shown = format!("`{}`", shown(&path));
    crate::texture::mapped::decode(&bytes, &shown, Wrap::Repeat)
        .map_err(|e| format!("{}: {e}", b.loc))?;
    let wrap = match b.named("wrap_mode").and_then(|w| w.attr("value")) {
        None | Some("repeat") => Wrap::Repeat,
        Some("clamp") => Wrap::Clamp,
        Some("mirror") => Wrap::Mirror,
        Some(other) => {
            return Err(format!(
                "{}: unknown wrap_mode `{other}` (Mitsuba's are repeat, mirror, clamp)",
                b.loc
            ));
        }
    };
    let raw = b
        .named("raw")
        .and_then(|r| r.attr("value"))
        .is_some_and(|v| v == "true");
    if b.named("to_uv").is_some() {
        cx.note(
            b,
            "the bitmap's `to_uv` transform is not imported: the image is laid on the mesh's own \
             texture coordinates",
            Some("bake the transform into the mesh's texture coordinates"),
        );
    }
    if b.named("filter_type").and_then(|f| f.attr("value")) == Some("nearest") {
        cx.note(
            b,
            "the bitmap's `nearest` filter becomes poser's bilinear lookup",
            None,
        );
    }
    let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| format!("{}: {e}", b.loc))?;
    let format = reader.format();
    let img = reader
        .decode()
        .map_err(|e| format!("{}: {shown}: {e}", b.loc))?;
    use image::DynamicImage as D;
    let float = matches!(img, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    let ext = match format {
        Some(image::ImageFormat::Png) => Some("png"),
        Some(image::ImageFormat::Jpeg) => Some("jpg"),
        _ => None,
    };
    if let (Some(ext), false, false) = (ext, float, raw) {
        return Ok((safe_file_name(&format!("{stem}.{ext}")), bytes, wrap));
    }
    // Linear values (as Mitsuba reads them) → 16-bit sRGB-encoded PNG.
    let lin = img.to_rgb32f();
    let mut out = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::new(lin.width(), lin.height());
    for (o, p) in out.pixels_mut().zip(lin.pixels()) {
        o.0 = p.0.map(|v| {
            let v = if v.is_finite() {
                v.clamp(0.0, 1.0) as f64
            } else {
                0.0
            };
            (linear_to_srgb(v) * 65535.0).round() as u16
        });
    }
    let mut png = Vec::new();
    out.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| format!("{}: re-encoding {shown}: {e}", b.loc))?;
    cx.note(
        b,
        format!(
            "texture `{name}` ({}) is written as a 16-bit sRGB PNG of its linear values",
            if float { "a float image" } else { "read `raw`" }
        ),
        None,
    );
    Ok((safe_file_name(&format!("{stem}.png")), png, wrap))
}

/// The sRGB transfer function (linear → encoded).
fn linear_to_srgb(v: f64) -> f64 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn albedo(cx: &mut Cx, shape: &X) -> Result<Result<[f64; 3], &'static str>, String> {
    let Some(b) = shape_bsdf(cx, shape)? else {
        return Ok(Ok([0.5; 3]));
    };
    match b.ty() {
        "null" => Ok(Err("null")),
        "dielectric" | "thindielectric" | "roughdielectric" => Ok(Err("dielectric")),
        "diffuse" => Ok(Ok(cx.colour(&b, "reflectance")?.unwrap_or([0.5; 3]))),
        t => {
            let c = match cx.colour(&b, "diffuse_reflectance")? {
                Some(c) => c,
                None => match cx.colour(&b, "base_color")? {
                    Some(c) => c,
                    None => cx.colour(&b, "reflectance")?.unwrap_or([0.5; 3]),
                },
            };
            cx.note(
                &b,
                format!(
                    "a `{t}` BSDF is imported as diffuse with albedo ({:.3}, {:.3}, {:.3})",
                    c[0], c[1], c[2]
                ),
                Some("poser's surfaces are Lambertian"),
            );
            Ok(Ok(c))
        }
    }
}

/// Mitsuba's named indices (include/mitsuba/render/ior.h), for `int_ior`/`ext_ior` strings.
const IOR_NAMES: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Mitsuba's named materials that are glasses of poser's catalogue (its names, lower case).
const MITSUBA_GLASSES: [(&str, &str); 3] = [
    ("bk7", "N-BK7"),
    ("acrylic glass", "PMMA"),
    ("fused quartz", "fused_silica"),
];

/// A dielectric's index `name`: a number, one of Mitsuba's named materials, or (not Mitsuba's,
/// but written by hand) a colour or spectrum per channel, imported as its mean with a note.
fn ior(cx: &mut Cx, b: &X, name: &str, default: f64) -> Result<f64, String> {
    let Some(k) = b.named(name) else {
        return Ok(default);
    };
    let k = k.clone();
    match k.tag.as_str() {
        "string" => {
            let v = k.attr("value").unwrap_or("").trim().to_ascii_lowercase();
            if let Some(&(_, n)) = IOR_NAMES.iter().find(|(m, _)| *m == v) {
                return Ok(n);
            }
            match v.parse::<f64>() {
                Ok(n) if n.is_finite() && n > 0.0 => Ok(n),
                _ => Err(format!(
                    "{}: `{name}` = `{v}` is not a number nor one of Mitsuba's named materials\n  \
                     help: give the index as a <float>, or a name such as \"water\" or \"bk7\"",
                    k.loc
                )),
            }
        }
        "rgb" | "spectrum" => {
            let c = cx.colour_of(&k)?.unwrap_or([default; 3]);
            let n = (c[0] + c[1] + c[2]) / 3.0;
            if (c[0] - c[2]).abs() > 1e-12 || (c[0] - c[1]).abs() > 1e-12 {
                cx.note(
                    &k,
                    format!(
                        "`{name}` per channel ({:.4}, {:.4}, {:.4}) is imported as one constant, \
                         their mean {n:.4}",
                        c[0], c[1], c[2]
                    ),
                    Some("the glass's and water's indices are read as one number here"),
                );
            }
            Ok(n)
        }
        _ => cx.float(b, name, default),
    }
}

/// The triangles of an `obj`/`ply` shape, in the world (`m` applied).
fn file_mesh(cx: &Cx, k: &X, m: &DMat4) -> Result<TriMesh, String> {
    Ok(file_mesh_uv(cx, k, m)?.0)
}

/// [`file_mesh`] with the file's per-vertex texture coordinates (empty when it has none; OBJ's
/// `vt` turned to v = 0 at the image's first row, as Mitsuba reads them).
fn file_mesh_uv(cx: &Cx, k: &X, m: &DMat4) -> Result<(TriMesh, Vec<[f32; 2]>), String> {
    let kind = k.ty();
    let (fk, f) = k
        .named("filename")
        .and_then(|f| Some((f, f.attr("value")?)))
        .ok_or_else(|| format!("{}: a `{kind}` shape without `filename`", k.loc))?;
    let path = cx.file(fk, f)?;
    let bytes = read_capped(&path).map_err(|e| format!("{}: {e}", k.loc))?;
    let shown = shown(&path);
    let (mut w, uv) = if kind == "obj" {
        crate::geometry::meshfile::parse_obj(&String::from_utf8_lossy(&bytes), &shown)
            .map(|o| (o.mesh, o.uv))
    } else {
        crate::geometry::meshfile::read_ply(&bytes, &shown).map(|f| (f.mesh, f.uv))
    }
    .map_err(|e| format!("{}: {e}", k.loc))?;
    for p in &mut w.positions {
        *p = m.transform_point3(*p);
    }
    if m.determinant() < 0.0 {
        for t in &mut w.triangles {
            t.swap(1, 2);
        }
    }
    Ok((w, uv))
}

/// A mesh that is one planar rectangle (four corners, two triangles): its centre, edge
/// vectors (`u`, `v`) and the unit normal its winding gives.
fn rectangle_of(mesh: &TriMesh) -> Option<(DVec3, DVec3, DVec3, DVec3)> {
    if mesh.triangles.len() != 2 {
        return None;
    }
    let t = mesh.triangles[0];
    let p = |i: u32| mesh.positions[i as usize];
    let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
    let n = (b - a).cross(c - a);
    if n.length() == 0.0 {
        return None;
    }
    let n = n.normalize();
    // The fourth corner: the one vertex of the second triangle not in the first.
    let d = mesh.triangles[1]
        .iter()
        .map(|&i| p(i))
        .find(|q| ![a, b, c].contains(q))?;
    // Corners in order around the rectangle: a, b, c, d with b − a ⟂ d − a.
    let (u, v) = (b - a, d - a);
    let tol = 1e-9 * (u.length() + v.length());
    if u.dot(v).abs() > tol * (u.length() + v.length()) || (a + u + v - c).length() > tol {
        return None;
    }
    Some((a + 0.5 * (u + v), u, v, n))
}

fn disk_mesh(m: &DMat4) -> TriMesh {
    let n = 64u32;
    let mut t = TriMesh::default();
    t.positions.push(m.transform_point3(DVec3::ZERO));
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        t.positions
            .push(m.transform_point3(DVec3::new(a.cos(), a.sin(), 0.0)));
    }
    for i in 0..n {
        t.triangles.push([0, 1 + i, 1 + (i + 1) % n]);
    }
    t
}

/// Import Mitsuba 3 scene files. The first file gives the world (its shapes, lights, water);
/// every file gives its sensors, in order, as the poses of the network. `assets` is how the
/// scene file names the assets folder (relative to the scene file).
pub fn import(files: &[PathBuf], assets: &str) -> Result<Imported, String> {
    import_within(files, assets, None)
}

/// [`import`], with every file the scene names kept inside folder `root` (resolved on disk)
/// instead of the first file's folder: for scenes whose `<path>` folders sit beside their
/// own, such as mitsuba-data's `common/`.
pub fn import_within(
    files: &[PathBuf],
    assets: &str,
    root: Option<&Path>,
) -> Result<Imported, String> {
    let first = files.first().ok_or("no input file")?;
    let root = match root {
        Some(r) => std::fs::canonicalize(r).map_err(|e| format!("{}: {e}", r.display()))?,
        None => std::fs::canonicalize(first.parent().unwrap_or(Path::new(".")).join("."))
            .map_err(|e| format!("{}: {e}", first.display()))?,
    };
    if !root.is_dir() {
        return Err(format!("{}: not a folder", root.display()));
    }
    let (mut docs, search, units) = read_docs(files, &root)?;
    let mut cx = Cx {
        notes: Vec::new(),
        targets: Vec::new(),
        ids: HashMap::new(),
        root: root.clone(),
        search,
        units,
        referenced: Default::default(),
        mapped: Default::default(),
    };
    for d in &docs {
        collect_ids(d, &mut cx.ids);
    }
    let mut budget = MAX_ELEMENTS;
    for d in &mut docs {
        expand_refs(d, &cx.ids, &mut cx.referenced, &mut budget, 0)?;
    }

    // Sensors → camera and poses.
    let sensors = sensors_of(&mut cx, &docs)?;
    let Some(s0) = sensors.first() else {
        return Err(format!(
            "{}: no sensor\n  help: a poser scene needs a camera; add a <sensor type=\"perspective\">",
            first.display()
        ));
    };
    let (names, rig) = rig_names(&sensors);
    if !rig {
        note_other_intrinsics(&mut cx, &sensors);
    }
    let sensor_at: Vec<DVec3> = sensors.iter().map(|s| s.pos).collect();
    let (water, surface) = water_of(&mut cx, &docs, &sensor_at)?;

    let mut t = Table::new();
    let name = comment_name(&docs[0], "poser scene")
        .or_else(|| first.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "imported".into());
    t.insert(F::Scene::name.into(), Value::String(name.clone()));
    t.insert(
        F::Scene::description.into(),
        Value::String(format!(
            "imported from Mitsuba 3 XML ({} file(s))",
            files.len()
        )),
    );

    let World {
        objects,
        lights,
        assets_out,
        port_faces,
        sun,
        max_depth,
    } = world_of(&mut cx, &docs, &sensors, assets)?;

    t.insert(
        F::Scene::camera.into(),
        camera_table(s0, port_faces.is_empty()),
    );
    if !port_faces.is_empty() {
        port_note(&mut cx, s0, &port_faces);
    }

    // The index outside the glass faces that border the water (an `exterior` medium).
    let n_water = port_faces
        .iter()
        .filter(|p| p.0.kids.iter().any(|c| c.attr("name") == Some("exterior")))
        .map(|p| p.3)
        .filter(|&n| n > 1.0)
        .reduce(f64::max);
    if let Some(w) = &water {
        insert_water(&mut cx, &mut t, w, n_water, surface, &sensors);
    }
    if let Some((k, dir, e)) = &sun {
        let (dir_air, e_air) = match (&water, surface) {
            (Some(_), true) => {
                let n = n_water.unwrap_or(1.334);
                unrefract(*dir, *e, [n; 3])
            }
            _ => (*dir, *e),
        };
        t.insert(F::Scene::sun.into(), sun_table(dir_air, e_air));
        if water.is_some() && surface {
            cx.note(k, "the directional light is read as the sun refracted at the flat sea surface: elevation and irradiance are those above the water", None);
        }
    }
    if !lights.is_empty() {
        t.insert(F::Scene::lights.into(), Value::Array(lights));
    }
    if !objects.is_empty() {
        t.insert(F::Scene::objects.into(), Value::Array(objects));
    }

    // Network: one explicit pose per sensor, or per rig pose (the rig frame is the first
    // camera's).
    let poses = if rig {
        rig_poses(&mut cx, &mut t, &sensors, &names)?
    } else {
        sensors.iter().map(|s| (s.rot, s.pos)).collect()
    };
    t.insert(F::Scene::network.into(), explicit_network(poses));
    let r = render_table(&mut cx, s0, max_depth.as_ref(), &port_faces);
    if !r.is_empty() {
        t.insert(F::Scene::render.into(), Value::Table(r));
    }

    let sources = files
        .iter()
        .map(|f| f.display().to_string())
        .collect::<Vec<_>>()
        .join(", ");
    finish(&t, &sources, cx.notes, assets_out)
}

/// What the world's elements give: objects, lights (the sun apart), mesh and texture assets,
/// the glass and housing faces of the port, and the integrator's `max_depth`.
struct World {
    objects: Vec<Value>,
    lights: Vec<Value>,
    assets_out: Vec<(String, Vec<u8>)>,
    port_faces: Vec<(X, DMat4, f64, f64)>,
    sun: Option<(X, DVec3, [f64; 3])>,
    max_depth: Option<(X, i64)>,
}

/// Read the shapes, lights and integrator of the world (the first file; its included world for
/// a poser view file) and the rig-mounted lights of the first view.
fn world_of(cx: &mut Cx, docs: &[X], sensors: &[Sensor], assets: &str) -> Result<World, String> {
    // Housing: dielectric and black shapes close to a sensor; the port's geometry. The
    // distance from the nearest sensor to a box (zero for a sensor inside it).
    let sensor_distance = |lo: DVec3, hi: DVec3| -> f64 {
        sensors
            .iter()
            .map(|s| (s.pos.clamp(lo, hi) - s.pos).length())
            .fold(f64::INFINITY, f64::min)
    };

    let mut objects: Vec<Value> = Vec::new();
    let mut lights: Vec<Value> = Vec::new();
    let mut assets_out: Vec<(String, Vec<u8>)> = Vec::new();
    let mut port_faces: Vec<(X, DMat4, f64, f64)> = Vec::new();
    let mut used_names: HashMap<String, usize> = HashMap::new();
    let mut unique = |n: String| -> String {
        let c = used_names.entry(n.clone()).or_insert(0);
        *c += 1;
        if *c == 1 { n } else { format!("{n}_{c}") }
    };
    let mut sun: Option<(X, DVec3, [f64; 3])> = None;

    // Shapes of the world (the first file; its included world for a poser view file) and the
    // rig-mounted lights of each view (elements of the view file itself, not included).
    let mut view_lights: Vec<(X, usize)> = Vec::new();
    let mut max_depth: Option<(X, i64)> = None;
    for (di, d) in docs.iter().enumerate() {
        for k in &d.kids {
            match k.tag.as_str() {
                "shape" if di == 0 => {
                    shape(
                        cx,
                        k,
                        &sensor_distance,
                        &mut objects,
                        &mut lights,
                        &mut assets_out,
                        &mut port_faces,
                        &mut unique,
                        assets,
                    )?;
                }
                // A view file that includes a shared world (poser's layout): its own lights
                // move with the camera. Otherwise lights are the first file's, in the world.
                "emitter" if !k.included && d.kids.iter().any(|x| x.included) => {
                    view_lights.push((k.clone(), di))
                }
                "emitter" if di == 0 => {
                    emitter(cx, k, None, &mut lights, &mut sun, &mut unique)?;
                }
                "shape" | "emitter" | "sensor" | "medium" | "bsdf" | "texture" => {}
                // The file's own integrator; else the one of a file it includes.
                "integrator" if di == 0 && (!k.included || max_depth.is_none()) => {
                    let own = max_depth.as_ref().is_some_and(|(x, _)| !x.included);
                    if !own {
                        let (x, depth) = integrator_depth(cx, k, 0)?;
                        note_direct_delta_weight(cx, &x)?;
                        max_depth = Some((x, depth));
                    }
                }
                other if di == 0 => cx.note(k, format!("<{other}> is not imported"), None),
                _ => {}
            }
        }
    }
    // Rig-mounted lights: those of the first view, in that view's camera frame.
    let first_view = view_lights.first().map(|(_, d)| *d);
    for (k, d) in &view_lights {
        if Some(*d) != first_view {
            continue;
        }
        let s = sensors.iter().find(|s| s.doc == *d).unwrap_or(&sensors[0]);
        emitter(
            cx,
            k,
            Some((s.rot, s.pos)),
            &mut lights,
            &mut sun,
            &mut unique,
        )?;
    }

    Ok(World {
        objects,
        lights,
        assets_out,
        port_faces,
        sun,
        max_depth,
    })
}

/// Integrator `k` and its path depth as Mitsuba's `max_depth` counts it (−1: unbounded): a
/// wrapper (`moment`, `aov`) gives its inner integrator's, `direct` (emitted and direct light
/// only) is a path of depth 2.
fn integrator_depth(cx: &Cx, k: &X, depth: usize) -> Result<(X, i64), String> {
    if let Some(inner) = k
        .kids
        .iter()
        .find(|c| c.tag == "integrator" || c.tag == "ref")
        && depth < MAX_DEPTH
    {
        let inner = cx.deref(inner)?;
        if inner.tag == "integrator" {
            return integrator_depth(cx, inner, depth + 1);
        }
    }
    match k.ty() {
        "direct" => Ok((k.clone(), 2)),
        _ => Ok((k.clone(), cx.int(k, "max_depth", -1)?)),
    }
}

/// Mitsuba's `direct` integrator adds each of its `emitter_samples` samples of a point, spot
/// or directional light at full weight (src/integrators/direct.cpp: `select(ds.delta, 1, …)`),
/// so with N of them it renders such lights N times as bright as their intensity. poser
/// imports the intensity as written; say so.
fn note_direct_delta_weight(cx: &mut Cx, k: &X) -> Result<(), String> {
    if k.ty() != "direct" {
        return Ok(());
    }
    let shading = cx.int(k, "shading_samples", 1)?;
    let n = cx.int(k, "emitter_samples", shading)?;
    if n > 1 {
        cx.note(
            k,
            format!(
                "Mitsuba's `direct` integrator adds each of its {n} emitter samples of a point, \
                 spot or directional light at full weight: it renders those lights {n}× as bright \
                 as their intensity, which is imported as written"
            ),
            Some("`--verify` against this file differs by that factor; with emitter_samples = 1 it does not"),
        );
    }
    Ok(())
}

/// Parse every input file (all inside `root`: the first file's folder, or `--root`), with the resolver
/// state each leaves: its folder and its `<path>` folders.
#[allow(clippy::type_complexity)]
/// The input files, parsed: their elements, their resolver's state and their declared length
/// units (units per metre).
type Docs = (Vec<X>, Vec<(PathBuf, Vec<PathBuf>)>, Vec<f64>);

fn read_docs(files: &[PathBuf], root: &Path) -> Result<Docs, String> {
    let mut docs = Vec::new();
    let mut search = Vec::new();
    let mut units = Vec::new();
    for (di, f) in files.iter().enumerate() {
        let abs = std::fs::canonicalize(f).map_err(|e| format!("{}: {e}", f.display()))?;
        if !abs.starts_with(root) {
            return Err(format!(
                "{}: every file of one import must be in the first file's folder, or in \
                 `--root` ({})",
                f.display(),
                root.display()
            ));
        }
        let main = abs.parent().unwrap_or(root).to_path_buf();
        // poser's own views move the world by `$poser_origin_*` and scale it by `$poser_unit`
        // (per-view coordinates in millimetres); read at 0 and 1, every file of a set comes
        // back in the one world frame, in metres. The few lengths a view writes as numbers
        // (a thin lens's) and its point lights' intensities are converted with the declared
        // unit (`Cx::units`).
        let params = ORIGIN_PARAMS
            .iter()
            .map(|n| (n.to_string(), "0".to_string()))
            .chain([UNIT_PARAM, PER_UNIT_PARAM].map(|n| (n.to_string(), "1".to_string())))
            .collect();
        let mut r = Reader {
            root: root.to_path_buf(),
            elements: 0,
            params,
            doc: di,
            main: main.clone(),
            paths: Vec::new(),
            unit: None,
        };
        let mut doc = r.parse_file(&abs, 0, false)?;
        // Keep the given spelling of the path in locations.
        let shown = f.display().to_string();
        relabel(&mut doc, &self::shown(&abs), &shown);
        if doc.tag != "scene" {
            return Err(format!(
                "{}: the root element is <{}>, not <scene>",
                doc.loc, doc.tag
            ));
        }
        docs.push(doc);
        search.push((main, r.paths));
        units.push(r.unit.unwrap_or(1.0));
    }
    Ok((docs, search, units))
}

/// Every sensor of every file, in file order; a file's only sensor takes the (pose, camera)
/// its poser view comment names.
fn sensors_of(cx: &mut Cx, docs: &[X]) -> Result<Vec<Sensor>, String> {
    let mut sensors = Vec::new();
    for (di, d) in docs.iter().enumerate() {
        for k in d.kids.iter().filter(|k| k.tag == "sensor") {
            if let Some(mut s) = sensor(cx, k)? {
                s.doc = di;
                if d.kids.iter().filter(|k| k.tag == "sensor").count() == 1 {
                    s.view = view_of(d);
                }
                sensors.push(s);
            }
        }
    }
    Ok(sensors)
}

/// The camera names of poser's view files, in first-seen order, and whether they make a rig
/// (several cameras, every sensor from a view file).
fn rig_names(sensors: &[Sensor]) -> (Vec<String>, bool) {
    let mut names: Vec<String> = Vec::new();
    for s in sensors {
        if let Some((_, n)) = &s.view
            && !names.contains(n)
        {
            names.push(n.clone());
        }
    }
    let rig = names.len() > 1 && sensors.iter().all(|s| s.view.is_some());
    (names, rig)
}

/// Note each sensor whose intrinsics differ from the first's (poser's network shares one
/// camera).
fn note_other_intrinsics(cx: &mut Cx, sensors: &[Sensor]) {
    let s0 = &sensors[0];
    for s in &sensors[1..] {
        if (s.width, s.height) != (s0.width, s0.height)
            || (s.fx / s0.fx - 1.0).abs() > 1e-9
            || (s.cx - s0.cx).abs() > 1e-6
            || (s.cy - s0.cy).abs() > 1e-6
        {
            cx.note(
                &s.x,
                "this sensor's intrinsics differ from the first's; it is imported with the first's",
                Some("poser's network shares one camera; import the sensors separately"),
            );
        }
    }
}

/// The water: the medium inside a `null` shape (poser's sea box), else the first medium; and
/// whether a sea box has its top at z = 0 (a flat surface).
fn water_of(cx: &mut Cx, docs: &[X], sensors: &[DVec3]) -> Result<(Option<Water>, bool), String> {
    let world = &docs[0];
    let mut water = None;
    let mut surface = false;
    // A `cube` or `sphere` holding a medium that no sensor is inside is a filled object
    // (`filled_object`): its medium is not the scene's water.
    let mut filled: Vec<String> = Vec::new();
    for d in docs {
        for k in d.kids.iter().filter(|k| {
            k.tag == "shape"
                && matches!(k.ty(), "cube" | "sphere")
                && k.kids.iter().any(|c| c.attr("name") == Some("interior"))
        }) {
            let m = cx.to_world(k)?;
            let (lo, hi) = world_bounds(cx, k, &m)?;
            if !sensors
                .iter()
                .any(|p| p.cmpge(lo).all() && p.cmple(hi).all())
                && let Some(r) = k.kids.iter().find(|c| c.attr("name") == Some("interior"))
                && let Some(id) = r.attr("id")
            {
                filled.push(id.to_string());
            }
        }
    }
    let is_fill = |k: &X| {
        k.attr("id")
            .is_some_and(|id| filled.iter().any(|f| f == id))
    };
    for k in world
        .kids
        .iter()
        .filter(|k| k.tag == "medium" && !is_fill(k))
    {
        if water.is_none() {
            water = medium(cx, k)?;
        }
    }
    for d in docs {
        for k in d
            .kids
            .iter()
            .filter(|k| k.tag == "shape" && k.ty() == "cube")
        {
            let interior = k.kids.iter().any(|c| c.attr("name") == Some("interior"));
            let sensor_inside = {
                let m = cx.to_world(k)?;
                let (lo, hi) = world_bounds(cx, k, &m)?;
                sensors
                    .iter()
                    .any(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            };
            if interior && sensor_inside {
                if water.is_none()
                    && let Some(r) = k.kids.iter().find(|c| c.attr("name") == Some("interior"))
                {
                    let m = cx.deref(r)?.clone();
                    water = medium(cx, &m)?;
                }
                let m = cx.to_world(k)?;
                let top = m
                    .transform_point3(DVec3::ONE)
                    .z
                    .max(m.transform_point3(-DVec3::ONE).z);
                surface |= top.abs() < 1e-6;
            }
        }
        for k in d.kids.iter().filter(|k| k.tag == "medium" && !is_fill(k)) {
            if water.is_none() {
                water = medium(cx, k)?;
            }
        }
    }
    Ok((water, surface))
}

/// The `[camera]` table of the first sensor; `no_port`: no glass at the camera.
fn camera_table(s0: &Sensor, no_port: bool) -> Value {
    let mut cam = Table::new();
    cam.insert(F::Camera::width.into(), Value::Integer(s0.width));
    cam.insert(F::Camera::height.into(), Value::Integer(s0.height));
    cam.insert(F::Camera::fx.into(), Value::Float(s0.fx));
    cam.insert(F::Camera::principal_point.into(), arr([s0.cx, s0.cy]));
    if let Some((aperture, focus)) = s0.thin {
        // f-number for poser's default pixel pitch: the aperture radius (in metres) is what
        // the blur depends on, and it comes back unchanged.
        let pitch = 3.76e-6;
        cam.insert(F::Camera::pixel_pitch.into(), Value::Float(pitch));
        if aperture > 0.0 {
            cam.insert(
                F::Camera::f_number.into(),
                Value::Float(s0.fx * pitch / (2.0 * aperture)),
            );
        }
        if focus > 0.0 {
            cam.insert(F::Camera::focus_distance.into(), Value::Float(focus));
        }
        cam.remove(F::Camera::fx);
        cam.insert(F::Camera::focal_length.into(), Value::Float(s0.fx * pitch));
    }
    if no_port {
        // No glass at the camera: no housing, said explicitly (poser's default in water is
        // a 10 mm flat port).
        let mut port = Table::new();
        port.insert(F::PortTable::kind.into(), Value::String("none".into()));
        cam.insert(F::Camera::port.into(), Value::Table(port));
    }
    Value::Table(cam)
}

/// The `[water]` and `[site]` tables of the water medium `w`; `n_water`: the index outside the
/// port's glass. Notes a camera above the water.
fn insert_water(
    cx: &mut Cx,
    t: &mut Table,
    w: &Water,
    n_water: Option<f64>,
    surface: bool,
    sensors: &[Sensor],
) {
    let mut wt = Table::new();
    wt.insert(F::Water::absorption.into(), arr(w.sigma_a));
    wt.insert(F::Water::scattering.into(), arr(w.sigma_s));
    wt.insert(F::Water::g.into(), Value::Float(w.g));
    if let Some(n) = n_water {
        wt.insert(F::Water::ior.into(), Value::Float(n));
    }
    t.insert(F::Scene::water.into(), Value::Table(wt));
    if !surface && sensors.iter().any(|s| s.pos.z >= 0.0) {
        cx.notes.push(
            Note::new(
                Some(sensors[0].x.loc.clone()),
                "a camera is at z ≥ 0 in water: poser's water lies below z = 0",
            )
            .help("move the scene down (every to_world) so that the cameras are at z < 0"),
        );
    }
    // poser's sea has a flat surface at z = 0 unless told otherwise; a Mitsuba medium
    // without poser's sea box fills the scene.
    let mut site = Table::new();
    site.insert(
        F::Site::surface.into(),
        Value::String(if surface { "flat" } else { "none" }.into()),
    );
    t.insert(F::Scene::site.into(), Value::Table(site));
}

/// A rig of poser's view files: the `[rig]` table (each camera relative to the first camera
/// `names[0]`) and one pose per rig pose that has an image of the first camera.
fn rig_poses(
    cx: &mut Cx,
    t: &mut Table,
    sensors: &[Sensor],
    names: &[String],
) -> Result<Vec<(DMat3, DVec3)>, String> {
    let mut poses = Vec::new();
    let find = |p: usize, n: &str| {
        sensors
            .iter()
            .find(|s| s.view.as_ref().is_some_and(|v| v.0 == p && v.1 == n))
    };
    let mut ids: Vec<usize> = Vec::new();
    for s in sensors {
        let p = s.view.as_ref().map_or(0, |v| v.0);
        if !ids.contains(&p) {
            ids.push(p);
        }
    }
    let mut cams = Vec::new();
    for n in names {
        let Some((a, b)) = ids
            .iter()
            .find_map(|&p| Some((find(p, &names[0])?, find(p, n)?)))
        else {
            return Err(format!(
                "camera `{n}` is never imaged at a pose of camera `{}`: its place in the rig is unknown",
                names[0]
            ));
        };
        let inv = a.rot.transpose();
        let mut c = Table::new();
        c.insert(F::Camera::name.into(), Value::String(n.clone()));
        c.insert(
            F::Camera::position.into(),
            arr((inv * (b.pos - a.pos)).to_array()),
        );
        c.insert(F::Camera::rotation.into(), arr(euler_xyz(inv * b.rot)));
        c.insert(F::Camera::width.into(), Value::Integer(b.width));
        c.insert(F::Camera::height.into(), Value::Integer(b.height));
        c.insert(F::Camera::fx.into(), Value::Float(b.fx));
        c.insert(F::Camera::principal_point.into(), arr([b.cx, b.cy]));
        cams.push(Value::Table(c));
    }
    let mut rt = Table::new();
    rt.insert(F::Rig::kind.into(), Value::String("multi".into()));
    rt.insert(F::Rig::cameras.into(), Value::Array(cams));
    t.insert(F::Scene::rig.into(), Value::Table(rt));
    for &p in &ids {
        let Some(s) = find(p, &names[0]) else {
            cx.notes.push(Note::new(
                None,
                format!(
                    "rig pose {p} has no image of camera `{}`: it is not imported",
                    names[0]
                ),
            ));
            continue;
        };
        poses.push((s.rot, s.pos));
    }
    Ok(poses)
}

/// The `[render]` table: the first sensor's samples and the integrator's `max_depth` as
/// poser's bounces (noted when it cannot be).
fn render_table(
    cx: &mut Cx,
    s0: &Sensor,
    max_depth: Option<&(X, i64)>,
    port_faces: &[(X, DMat4, f64, f64)],
) -> Table {
    let mut r = Table::new();
    if let Some(spp) = s0.samples {
        r.insert(
            F::Render::samples.into(),
            Value::Integer(spp.clamp(1, 1 << 20)),
        );
    }
    if let Some((k, depth)) = max_depth {
        // Mitsuba counts path vertices from the camera and every glass face (poser's port:
        // 2); poser counts scattering vertices (docs/render-conventions.md §3.5).
        let glass = if port_faces.iter().any(|p| p.2 > 1.0) {
            2
        } else {
            0
        };
        if *depth > 1 + glass {
            r.insert(F::Render::bounces.into(), Value::Integer(depth - 1 - glass));
        } else {
            cx.note(
                k,
                format!("integrator max_depth {depth} is not imported"),
                Some("poser's render.bounces counts scattering vertices; its default is used"),
            );
        }
    }
    r
}

/// How locations name a file: relative to the working folder when it is inside it.
fn shown(path: &Path) -> String {
    std::env::current_dir()
        .ok()
        .and_then(|cwd| path.strip_prefix(cwd).ok().map(|p| p.display().to_string()))
        .unwrap_or_else(|| path.display().to_string())
}

fn relabel(x: &mut X, from: &str, to: &str) {
    if let Some(rest) = x.loc.strip_prefix(from) {
        x.loc = format!("{to}{rest}");
    }
    for k in &mut x.kids {
        relabel(k, from, to);
    }
}

fn collect_ids(x: &X, ids: &mut HashMap<String, X>) {
    for k in &x.kids {
        if k.tag != "ref"
            && let Some(id) = k.attr("id")
        {
            ids.entry(id.to_string()).or_insert_with(|| k.clone());
        }
        collect_ids(k, ids);
    }
}

/// Every `<ref id>` replaced by (a copy of) the element it names, with the ref's `name`:
/// Mitsuba lets a reference stand wherever an element is expected (a BSDF, an emitter on a
/// shape, a medium, a texture, a top-level emitter). A top-level reference to an element that
/// is itself at the top level is dropped (the element is read once). `budget` bounds the
/// elements copied (with the parse's, [`MAX_ELEMENTS`]); `depth` the nesting (a reference
/// cycle).
fn expand_refs(
    x: &mut X,
    ids: &HashMap<String, X>,
    referenced: &mut std::collections::HashSet<String>,
    budget: &mut usize,
    depth: usize,
) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err(format!(
            "{}: references nested deeper than {MAX_DEPTH}\n  help: a reference cycle? an \
             element cannot contain a reference to itself",
            x.loc
        ));
    }
    let top = x.tag == "scene";
    let top_ids: Vec<String> = if top {
        x.kids
            .iter()
            .filter(|k| k.tag != "ref")
            .filter_map(|k| k.attr("id").map(str::to_string))
            .collect()
    } else {
        Vec::new()
    };
    let mut kids = Vec::with_capacity(x.kids.len());
    for mut k in std::mem::take(&mut x.kids) {
        if k.tag == "ref" {
            let id = k.attr("id").unwrap_or("").to_string();
            referenced.insert(id.clone());
            if top && top_ids.contains(&id) {
                continue;
            }
            let target = ids.get(&id).ok_or_else(|| {
                format!(
                    "{}: no element has id `{id}`\n  help: define the element with `id=\"{id}\"` \
                     (in this file or one it includes)",
                    k.loc
                )
            })?;
            let size = count(target);
            if size > *budget {
                return Err(format!(
                    "{}: references copy more than {MAX_ELEMENTS} elements in all",
                    k.loc
                ));
            }
            *budget -= size;
            let mut c = target.clone();
            c.attrs.retain(|(a, _)| a != "name");
            if let Some(n) = k.attr("name") {
                c.attrs.push(("name".into(), n.to_string()));
            }
            k = c;
        }
        expand_refs(&mut k, ids, referenced, budget, depth + 1)?;
        kids.push(k);
    }
    x.kids = kids;
    Ok(())
}

/// Elements in `x`, itself included.
fn count(x: &X) -> usize {
    1 + x.kids.iter().map(count).sum::<usize>()
}

fn port_note(cx: &mut Cx, s: &Sensor, faces: &[(X, DMat4, f64, f64)]) {
    // Flat port: rectangles facing the camera; distances along the optical axis.
    let axis = s.rot.z_axis;
    let mut d: Vec<(f64, f64, f64)> = faces
        .iter()
        .filter(|(x, _, ni, _)| x.ty() == "rectangle" && *ni > 1.0)
        .filter_map(|(_, m, ni, ne)| {
            let nrm = m.z_axis.truncate().normalize_or_zero();
            (nrm.dot(axis).abs() > 1.0 - 1e-9)
                .then(|| ((m.w_axis.truncate() - s.pos).dot(axis), *ni, *ne))
        })
        .collect();
    d.sort_by(|a, b| a.0.total_cmp(&b.0));
    let x = faces[0].0.clone();
    let help = if d.len() >= 2 && d[0].0 > 0.0 {
        format!(
            "this is a flat port: declare it as [camera.port] type = \"flat\", pupil_distance = {:.6}, thickness = {:.6}, and its glass's index {:.6} (docs/format.md, camera.port)",
            d[0].0,
            d[d.len() - 1].0 - d[0].0,
            d[0].1
        )
    } else {
        "declare the camera's housing port as [camera.port] (flat, dome or cylinder; docs/format.md)".to_string()
    };
    cx.notes.push(
        Note::new(
            Some(x.loc),
            format!(
                "{} glass and housing shape(s) around the camera are not imported as geometry",
                faces.len()
            ),
        )
        .help(help),
    );
}

#[allow(clippy::too_many_arguments)]
fn shape(
    cx: &mut Cx,
    k: &X,
    sensor_distance: &dyn Fn(DVec3, DVec3) -> f64,
    objects: &mut Vec<Value>,
    lights: &mut Vec<Value>,
    assets_out: &mut Vec<(String, Vec<u8>)>,
    port_faces: &mut Vec<(X, DMat4, f64, f64)>,
    unique: &mut dyn FnMut(String) -> String,
    assets: &str,
) -> Result<(), String> {
    let m = cx.to_world(k)?;
    let kind = k.ty().to_string();
    // An area emitter on the shape.
    if let Some(e) = k.kids.iter().find(|c| c.tag == "emitter")
        && let Some(l) = area_light(cx, k, e, &m, &kind, unique)?
    {
        lights.push(l);
        return Ok(());
    }
    // A bitmap that becomes the mesh's image texture: on an `obj`/`ply` with texture
    // coordinates, or on a `rectangle` (Mitsuba's uv: (x + 1)/2, (y + 1)/2 of its local square).
    let bitmap = if matches!(kind.as_str(), "obj" | "ply" | "rectangle") {
        bitmap_of(cx, k)?
    } else {
        None
    };
    let uv_mesh = match &bitmap {
        Some(b) => mapped_mesh(cx, k, b, &m, &kind)?,
        None => None,
    };
    if let (Some(b), Some(_)) = (&bitmap, &uv_mesh) {
        cx.mapped.insert(b.loc.clone());
    }
    let alb = albedo(cx, k);
    cx.mapped.clear();
    let alb = match alb? {
        Ok(a) => a,
        Err(what) => {
            // A medium boundary (the sea box) or glass: only around the camera. A `null`
            // shape without a medium is invisible in Mitsuba too: its file is not read.
            let medium = k.kids.iter().any(|c| c.attr("name") == Some("interior"));
            if what == "null" && !medium {
                return Ok(());
            }
            let (lo, hi) = world_bounds(cx, k, &m)?;
            let distance = sensor_distance(lo, hi);
            let solid = kind == "cube" || kind == "sphere";
            let filled = medium && distance > 0.0 && (what == "dielectric" || what == "null");
            let glass = what == "dielectric" && distance >= PORT_REACH && !medium;
            if solid && (filled || glass) {
                let name = unique(
                    comment_name(k, "object")
                        .or_else(|| k.attr("id").map(str::to_string))
                        .unwrap_or_else(|| kind.clone()),
                );
                return if filled {
                    filled_object(cx, k, &m, &kind, &name, objects, assets_out, assets)
                } else {
                    glass_object(cx, k, &m, &kind, &name, objects, assets_out, assets)
                };
            }
            refuse_away_from_camera(cx, k, what, distance)?;
            if what == "null" {
                return Ok(());
            }
            let bsdf = k.kids.iter().find(|c| c.tag == "bsdf").cloned();
            let (ni, ne) = match bsdf {
                Some(b) => (ior(cx, &b, "int_ior", 1.5)?, ior(cx, &b, "ext_ior", 1.0)?),
                None => (1.5, 1.0),
            };
            // Glass is the camera's housing port, near the camera or (a mesh in world
            // coordinates) anywhere: poser declares ports, it does not model them.
            port_faces.push((k.clone(), m, ni, ne));
            return Ok(());
        }
    };
    let origin = m.transform_point3(DVec3::ZERO);
    if alb == [0.0; 3] && sensor_distance(origin, origin) < PORT_REACH {
        port_faces.push((k.clone(), m, 1.0, 1.0));
        return Ok(());
    }
    if alb.iter().any(|&a| !(0.0..=1.0).contains(&a)) {
        cx.note(
            k,
            format!(
                "albedo ({:.3}, {:.3}, {:.3}) clamped to [0, 1]",
                alb[0], alb[1], alb[2]
            ),
            None,
        );
    }
    let alb = alb.map(|a| a.clamp(0.0, 1.0));
    if let Some(t) = comment_name(k, "target").filter(|t| !cx.targets.contains(t)) {
        cx.targets.push(t.clone());
        cx.note(k, format!("target `{t}` is imported as plain geometry: its known 3D points (the ground truth) are not"), Some("declare it as [[targets]] to get its points in `poser truth`"));
    }
    let name = unique(
        comment_name(k, "object")
            .or_else(|| k.attr("id").map(str::to_string))
            .unwrap_or_else(|| kind.clone()),
    );
    let mut o = Table::new();
    o.insert(F::Object::name.into(), Value::String(name.clone()));
    if let (Some(b), Some((mesh, uv))) = (&bitmap, &uv_mesh) {
        let (image, bytes, wrap) = bitmap_asset(cx, b, &format!("{name}-texture"))?;
        let file = safe_file_name(&format!("{}.glb", name));
        let tex = meshes::MeshTexture {
            uv,
            image: &image,
            wrap,
        };
        assets_out.push((file.clone(), meshes::glb_textured(mesh, Some(&tex), &name)));
        assets_out.push((image.clone(), bytes));
        o.insert(F::Object::shape.into(), Value::String("mesh".into()));
        o.insert(
            F::Object::path.into(),
            Value::String(format!("{assets}/{file}")),
        );
        o.insert(F::Object::albedo.into(), arr(alb));
        objects.push(Value::Table(o));
        let src = b
            .named("filename")
            .and_then(|f| f.attr("value"))
            .unwrap_or("");
        cx.note(
            b,
            format!(
                "texture `{src}` is imported as the image texture of `{name}` \
                 ({assets}/{image}, sampled bilinearly at the mipmap level the cameras' GSD asks for)"
            ),
            Some("docs/textures.md, \"Textured meshes\""),
        );
        return Ok(());
    }
    if !shape_geometry(cx, k, &m, &kind, &name, &mut o, assets_out, assets)? {
        return Ok(());
    }
    o.insert(F::Object::albedo.into(), arr(alb));
    objects.push(Value::Table(o));
    Ok(())
}

/// A smooth `dielectric` `cube` or `sphere` (`kind`) away from every sensor: a glass object
/// (`glass = …`, a box or a sphere) of the catalogue glass Mitsuba names ([`MITSUBA_GLASSES`])
/// or else whose green index is nearest its `int_ior` (within [`super::GLASS_MATCH`]); noted
/// when the indices differ by more than 0.001. Its
/// `ext_ior` is the water's or air's, which the scene declares. A rough or thin dielectric, an
/// index no catalogue glass has, or a sphere scaled unevenly, is refused with the reason.
#[allow(clippy::too_many_arguments)]
fn glass_object(
    cx: &mut Cx,
    k: &X,
    m: &DMat4,
    kind: &str,
    name: &str,
    objects: &mut Vec<Value>,
    assets_out: &mut Vec<(String, Vec<u8>)>,
    assets: &str,
) -> Result<(), String> {
    let Some(b) = shape_bsdf(cx, k)? else {
        return Err(format!("{}: a dielectric {kind} without its BSDF", k.loc));
    };
    if b.ty() != "dielectric" {
        return Err(format!(
            "{}: this `{kind}` has a `{}` BSDF: poser's glass objects are smooth, thick glass\n  \
             help: make it a smooth `dielectric`, or give it a diffuse BSDF",
            k.loc,
            b.ty()
        ));
    }
    let n = ior(cx, &b, "int_ior", 1.5046)?;
    // Mitsuba's named glasses that are catalogue glasses are those, whatever their one index
    // says (`bk7`'s 1.5046 is nearer PMMA's index than N-BK7's in green); no `int_ior` is `bk7`.
    let named = match b.named("int_ior") {
        Some(v) if v.tag == "string" => v.attr("value").map(|v| v.trim().to_ascii_lowercase()),
        Some(_) => None,
        None => Some("bk7".to_string()),
    };
    let by_name = named
        .and_then(|v| MITSUBA_GLASSES.iter().find(|(m, _)| *m == v))
        .and_then(|&(_, g)| {
            crate::optics::glass::catalogue_ior(g, crate::model::CHANNEL_WAVELENGTHS_NM[1])
                .map(|n_g| (g, n_g))
        });
    let Some((glass, n_g)) = by_name.or_else(|| super::catalogue_glass_near(n)) else {
        return Err(format!(
            "{}: glass of index {n:.4}: poser's glass objects are made of a catalogue glass \
             ({})\n  help: set `int_ior` to one of them, or give the shape a diffuse BSDF",
            b.loc,
            crate::optics::glass::CATALOGUE.join(", ")
        ));
    };
    if (n_g - n).abs() > 1e-3 {
        cx.note(
            &b,
            format!(
                "int_ior {n:.4} is imported as the catalogue glass {glass} ({n_g:.4} in green)"
            ),
            Some(
                "poser's glass objects take a catalogue glass (docs/scenes.md, \"Glass objects\")",
            ),
        );
    }
    let Some(mut o) = solid_table(cx, k, m, kind, name, "glass", assets_out, assets)? else {
        return Ok(());
    };
    o.insert(F::Object::glass.into(), Value::String(glass.to_string()));
    objects.push(Value::Table(o));
    Ok(())
}

/// A `cube` or `sphere` holding an `interior` medium that no sensor is inside: a filled
/// object (`fill = { … }`, docs/scenes.md "Filled objects") of the medium's coefficients and
/// phase, its faces of the smooth `dielectric`'s `int_ior` (a `null` BSDF: index 1, a boundary
/// that neither reflects nor bends).
#[allow(clippy::too_many_arguments)]
fn filled_object(
    cx: &mut Cx,
    k: &X,
    m: &DMat4,
    kind: &str,
    name: &str,
    objects: &mut Vec<Value>,
    assets_out: &mut Vec<(String, Vec<u8>)>,
    assets: &str,
) -> Result<(), String> {
    let Some(r) = k.kids.iter().find(|c| c.attr("name") == Some("interior")) else {
        return Err(format!("{}: a filled {kind} without its medium", k.loc));
    };
    let medium_x = cx.deref(r)?.clone();
    let Some(w) = medium(cx, &medium_x)? else {
        return Err(format!(
            "{}: this `{kind}` holds a `{}` medium: poser's filled objects hold homogeneous \
             water\n  help: make the medium `homogeneous`, or remove the shape",
            k.loc,
            medium_x.ty()
        ));
    };
    let n = match shape_bsdf(cx, k)? {
        Some(b) if b.ty() == "dielectric" => {
            let ne = ior(cx, &b, "ext_ior", 1.000277)?;
            if (ne - 1.0).abs() > 1e-3 {
                cx.note(
                    &b,
                    format!("ext_ior {ne:.4} is imported as what is around the object in poser"),
                    Some("a filled object's faces divide its water from the scene's water or air"),
                );
            }
            ior(cx, &b, "int_ior", 1.5046)?
        }
        _ => 1.0,
    };
    let Some(mut o) = solid_table(cx, k, m, kind, name, "filled", assets_out, assets)? else {
        return Ok(());
    };
    let mut f = Table::new();
    f.insert(F::FillTable::absorption.into(), arr(w.sigma_a));
    f.insert(F::FillTable::scattering.into(), arr(w.sigma_s));
    f.insert(F::FillTable::phase.into(), Value::String("hg".into()));
    f.insert(F::FillTable::g.into(), Value::Float(w.g));
    f.insert(F::FillTable::ior.into(), Value::Float(n));
    o.insert(F::Object::fill.into(), Value::Table(f));
    objects.push(Value::Table(o));
    Ok(())
}

/// The object table of a glass or filled (`what`) `cube` or `sphere`: its name and geometry
/// as a box or a round sphere (`None`: the geometry was noted and left out), or an error for a
/// sheared, mirrored or unevenly scaled one.
#[allow(clippy::too_many_arguments)]
fn solid_table(
    cx: &mut Cx,
    k: &X,
    m: &DMat4,
    kind: &str,
    name: &str,
    what: &str,
    assets_out: &mut Vec<(String, Vec<u8>)>,
    assets: &str,
) -> Result<Option<Table>, String> {
    let mut o = Table::new();
    o.insert(F::Object::name.into(), Value::String(name.to_string()));
    if !shape_geometry(cx, k, m, kind, name, &mut o, assets_out, assets)? {
        return Ok(None);
    }
    let want = if kind == "cube" { "box" } else { "sphere" };
    if o.get(F::Object::shape).and_then(Value::as_str) != Some(want) {
        return Err(format!(
            "{}: this {what} `{kind}` is sheared, mirrored or (a sphere) scaled unevenly: \
             poser's {what} objects are boxes and round spheres\n  help: give the shape a \
             rotation, a translation and one scale only",
            k.loc
        ));
    }
    Ok(Some(o))
}

/// How far from a sensor glass and black walls are read as its housing, metres.
const PORT_REACH: f64 = 0.5;

/// Refuse a `null` or dielectric shape (`what`) that poser cannot hold: glass `distance` m or
/// more from every sensor (poser's only glass is the camera's port), or the boundary of an
/// `interior` medium whose box no sensor is inside (poser's water fills the scene below z = 0).
fn refuse_away_from_camera(cx: &Cx, k: &X, what: &str, distance: f64) -> Result<(), String> {
    let medium = k.kids.iter().find(|c| c.attr("name") == Some("interior"));
    let bsdf = shape_bsdf(cx, k)?
        .map(|b| b.ty().to_string())
        .unwrap_or_default();
    let medium_id = medium.map(|r| match r.attr("id") {
        Some(id) => format!("medium `{id}`"),
        None => "a medium".to_string(),
    });
    match (what, medium_id) {
        ("null", None) => Ok(()), // invisible in Mitsuba too
        (_, Some(mid)) if distance > 0.0 => Err(format!(
            "{}: this `{}` shape with a `{bsdf}` BSDF bounds {mid}, and the camera is outside \
             it ({distance:.3} m away): the medium fills only the shape in Mitsuba, but poser's \
             water fills the whole scene below z = 0\n  help: poser holds no volume of medium \
             inside a shape; import a scene whose camera is inside the medium (a sea box around \
             it), or remove the medium and the shape",
            k.loc,
            k.ty()
        )),
        ("null", Some(_)) => Ok(()),
        (_, _) if distance >= PORT_REACH => Err(format!(
            "{}: this `{}` shape with a `{bsdf}` BSDF is a glass object {distance:.3} m from \
             the camera: poser imports a `cube` or a `sphere` of smooth `dielectric` as a \
             glass object (Mitsuba's `cylinder` is open: no solid), and glass within \
             {PORT_REACH} m of the camera is its housing port\n  help: make it a `cube` or a \
             `sphere` with a `dielectric` BSDF, or give the shape a diffuse BSDF, or remove \
             it, to import the rest of the scene",
            k.loc,
            k.ty()
        )),
        _ => Ok(()),
    }
}

/// The box around shape `k` in the world (`m` its `to_world`): its vertices for a mesh, its
/// local bounds transformed for Mitsuba's built-in shapes (`sphere`: `center`, `radius`;
/// `cylinder`: `p0`, `p1`, `radius`), `to_world`'s origin for any other.
fn world_bounds(cx: &Cx, k: &X, m: &DMat4) -> Result<(DVec3, DVec3), String> {
    let corners = |lo: DVec3, hi: DVec3| -> Vec<DVec3> {
        (0..8)
            .map(|i| {
                let pick = |b: usize, a: f64, z: f64| if i & b == 0 { a } else { z };
                m.transform_point3(DVec3::new(
                    pick(1, lo.x, hi.x),
                    pick(2, lo.y, hi.y),
                    pick(4, lo.z, hi.z),
                ))
            })
            .collect()
    };
    let points = match k.ty() {
        "obj" | "ply" => file_mesh(cx, k, m)?.positions,
        "rectangle" | "disk" => corners(DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.0)),
        "cube" => corners(-DVec3::ONE, DVec3::ONE),
        "sphere" => {
            let c = cx.point(k, "center", DVec3::ZERO)?;
            let r = cx.float(k, "radius", 1.0)?.abs();
            corners(c - DVec3::splat(r), c + DVec3::splat(r))
        }
        "cylinder" => {
            let p0 = cx.point(k, "p0", DVec3::ZERO)?;
            let p1 = cx.point(k, "p1", DVec3::Z)?;
            let r = DVec3::splat(cx.float(k, "radius", 1.0)?.abs());
            corners(p0.min(p1) - r, p0.max(p1) + r)
        }
        _ => vec![m.transform_point3(DVec3::ZERO)],
    };
    let lo = points.iter().copied().fold(DVec3::INFINITY, DVec3::min);
    let hi = points.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
    if !(lo.is_finite() && hi.is_finite()) {
        let o = m.transform_point3(DVec3::ZERO);
        return Ok((o, o));
    }
    Ok((lo, hi))
}

/// The area light of emitter `e` on shape `k` (a `rectangle`, or an `obj`/`ply` mesh of one
/// rectangle); `None`, noted, for an emitter poser cannot take.
fn area_light(
    cx: &mut Cx,
    k: &X,
    e: &X,
    m: &DMat4,
    kind: &str,
    unique: &mut dyn FnMut(String) -> String,
) -> Result<Option<Value>, String> {
    if e.ty() == "area" && kind == "rectangle" {
        let radiance = cx.colour(e, "radiance")?.unwrap_or([1.0; 3]);
        let (len, frame, ..) = decompose(m);
        let mut l = Table::new();
        l.insert(
            F::Light::name.into(),
            Value::String(unique(
                comment_name(k, "light").unwrap_or_else(|| "area".into()),
            )),
        );
        l.insert(F::Light::kind.into(), Value::String("area".into()));
        l.insert(F::Light::mount.into(), Value::String("world".into()));
        l.insert(
            F::Light::position.into(),
            arr(m.w_axis.truncate().to_array()),
        );
        l.insert(F::Light::aim.into(), arr(frame.z_axis.to_array()));
        l.insert(F::Light::width.into(), Value::Float(2.0 * len.x));
        l.insert(F::Light::height.into(), Value::Float(2.0 * len.y));
        l.insert(F::Light::radiance.into(), arr(radiance));
        return Ok(Some(Value::Table(l)));
    }
    if e.ty() == "area"
        && (kind == "obj" || kind == "ply")
        && let Some((centre, u, v, n)) = rectangle_of(&file_mesh(cx, k, m)?)
    {
        let radiance = cx.colour(e, "radiance")?.unwrap_or([1.0; 3]);
        let mut l = Table::new();
        l.insert(
            F::Light::name.into(),
            Value::String(unique(
                k.attr("id")
                    .map(str::to_string)
                    .unwrap_or_else(|| "area".into()),
            )),
        );
        l.insert(F::Light::kind.into(), Value::String("area".into()));
        l.insert(F::Light::mount.into(), Value::String("world".into()));
        l.insert(F::Light::position.into(), arr(centre.to_array()));
        l.insert(F::Light::aim.into(), arr(n.to_array()));
        l.insert(F::Light::width.into(), Value::Float(u.length()));
        l.insert(F::Light::height.into(), Value::Float(v.length()));
        l.insert(F::Light::radiance.into(), arr(radiance));
        if (u.length() - v.length()).abs() > 1e-9 * u.length() {
            cx.note(
                e,
                "a rectangular mesh emitter becomes an area light; its turn about its \
                     normal follows poser's convention for `aim`",
                None,
            );
        }
        return Ok(Some(Value::Table(l)));
    }
    cx.note(
        e,
        format!("an area emitter on a `{kind}` is not imported"),
        Some("poser's area lights are rectangles (a `rectangle`, or a mesh of one)"),
    );
    Ok(None)
}

/// The mesh in world coordinates and its texture coordinates for bitmap `b` on shape `k`;
/// `None` (noted for a mesh without texture coordinates) when the bitmap cannot be mapped.
#[allow(clippy::type_complexity)]
fn mapped_mesh(
    cx: &mut Cx,
    k: &X,
    b: &X,
    m: &DMat4,
    kind: &str,
) -> Result<Option<(TriMesh, Vec<[f32; 2]>)>, String> {
    Ok(match kind {
        "obj" | "ply" => {
            let (mesh, uv) = file_mesh_uv(cx, k, m)?;
            if uv.is_empty() {
                cx.note(
                    b,
                    format!("the `{kind}` has no texture coordinates for its bitmap"),
                    Some("the bitmap's mean colour is used (noted below)"),
                );
                None
            } else {
                Some((mesh, uv))
            }
        }
        "rectangle" => {
            let mut w = TriMesh {
                positions: [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(x, y)| m.transform_point3(DVec3::new(x, y, 0.0)))
                    .to_vec(),
                triangles: vec![[0, 1, 2], [0, 2, 3]],
            };
            if m.determinant() < 0.0 {
                for t in &mut w.triangles {
                    t.swap(1, 2);
                }
            }
            Some((w, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
        }
        _ => None,
    })
}

/// The geometry keys of object `o` for shape `k` (world matrix `m`): an analytic shape when
/// `m` neither shears nor mirrors it, else a mesh asset. `false`, noted, for a kind poser
/// does not read.
#[allow(clippy::too_many_arguments)]
fn shape_geometry(
    cx: &mut Cx,
    k: &X,
    m: &DMat4,
    kind: &str,
    name: &str,
    o: &mut Table,
    assets_out: &mut Vec<(String, Vec<u8>)>,
    assets: &str,
) -> Result<bool, String> {
    let (len, frame, mirror, sheared) = decompose(m);
    let placed = |o: &mut Table| {
        o.insert(
            F::Object::position.into(),
            arr(m.w_axis.truncate().to_array()),
        );
        o.insert(F::Object::rotation.into(), arr(euler_xyz(frame)));
    };
    let analytic = !sheared && !mirror;
    match kind {
        "rectangle" if analytic => {
            o.insert(F::Object::shape.into(), Value::String("plane".into()));
            o.insert(F::Object::width.into(), Value::Float(2.0 * len.x));
            o.insert(F::Object::height.into(), Value::Float(2.0 * len.y));
            placed(o);
        }
        "cube" if analytic => {
            o.insert(F::Object::shape.into(), Value::String("box".into()));
            o.insert(F::Object::size.into(), arr((2.0 * len).to_array()));
            placed(o);
        }
        "sphere"
            if analytic
                && (len.x - len.y).abs() < 1e-9 * len.x
                && (len.x - len.z).abs() < 1e-9 * len.x =>
        {
            let r = cx.float(k, "radius", 1.0)? * len.x;
            let c = m.transform_point3(cx.point(k, "center", DVec3::ZERO)?);
            o.insert(F::Object::shape.into(), Value::String("sphere".into()));
            o.insert(F::Object::radius.into(), Value::Float(r));
            o.insert(F::Object::position.into(), arr(c.to_array()));
        }
        "cylinder"
            if analytic
                && (len.x - len.y).abs() < 1e-9 * len.x
                && (len.x - len.z).abs() < 1e-9 * len.x =>
        {
            let p0 = m.transform_point3(cx.point(k, "p0", DVec3::ZERO)?);
            let p1 = m.transform_point3(cx.point(k, "p1", DVec3::Z)?);
            let r = cx.float(k, "radius", 1.0)? * len.x;
            let axis = (p1 - p0).normalize_or_zero();
            if axis == DVec3::ZERO {
                return Err(format!("{}: a cylinder with p0 = p1", k.loc));
            }
            let rot = DMat3::from_quat(glam::DQuat::from_rotation_arc(DVec3::Z, axis));
            o.insert(F::Object::shape.into(), Value::String("cylinder".into()));
            o.insert(F::Object::radius.into(), Value::Float(r));
            o.insert(F::Object::height.into(), Value::Float((p1 - p0).length()));
            o.insert(
                F::Object::position.into(),
                arr((0.5 * (p0 + p1)).to_array()),
            );
            o.insert(F::Object::rotation.into(), arr(euler_xyz(rot)));
            cx.note(k, "Mitsuba's cylinder is open; poser's has caps", None);
        }
        "rectangle" | "cube" | "sphere" | "cylinder" | "disk" | "obj" | "ply" => {
            let mesh = match kind {
                "obj" | "ply" => file_mesh(cx, k, m)?,
                "disk" => disk_mesh(m),
                _ => {
                    // Sheared or mirrored analytic shapes: tessellate them.
                    use crate::geometry::mesh as gm;
                    let mut w = match kind {
                        "rectangle" => gm::plane(2.0, 2.0),
                        "cube" => gm::cuboid(DVec3::splat(2.0)),
                        "sphere" => gm::sphere(1.0, gm::SPHERE_SEGMENTS),
                        _ => gm::cylinder(1.0, 1.0, gm::CYLINDER_SEGMENTS),
                    };
                    for p in &mut w.positions {
                        *p = m.transform_point3(*p);
                    }
                    w
                }
            };
            let file = safe_file_name(&format!("{}.glb", name));
            assets_out.push((file.clone(), meshes::glb(&mesh, name)));
            o.insert(F::Object::shape.into(), Value::String("mesh".into()));
            o.insert(
                F::Object::path.into(),
                Value::String(format!("{assets}/{file}")),
            );
        }
        other => {
            cx.note(
                k,
                format!("a `{other}` shape is not imported"),
                Some("poser reads rectangle, cube, sphere, cylinder, disk, obj and ply"),
            );
            return Ok(false);
        }
    }
    Ok(true)
}

/// A light (not an area emitter). `view`: the camera (rotation, centre) of the view file the
/// light comes from, for a rig-mounted light.
/// A point or spot light's intensity (W/sr) in metres: a document in `u` units per metre
/// gives it × u² (the irradiance falls as 1/distance²).
fn point_intensity(cx: &mut Cx, k: &X) -> Result<[f64; 3], String> {
    let u = cx.units[k.doc];
    Ok(cx
        .colour(k, "intensity")?
        .unwrap_or([1.0; 3])
        .map(|c| c / (u * u)))
}

fn emitter(
    cx: &mut Cx,
    k: &X,
    view: Option<(DMat3, DVec3)>,
    lights: &mut Vec<Value>,
    sun: &mut Option<(X, DVec3, [f64; 3])>,
    unique: &mut dyn FnMut(String) -> String,
) -> Result<(), String> {
    if k.ty() == "area" {
        // An area emitter defined apart, for the shapes that reference it.
        if !k.attr("id").is_some_and(|id| cx.referenced.contains(id)) {
            cx.note(
                k,
                "an `area` emitter outside a shape is not imported",
                Some("an area emitter lights the shape it is in (or that references it)"),
            );
        }
        return Ok(());
    }
    let m = cx.to_world(k)?;
    let name = comment_name(k, "light").or_else(|| k.attr("id").map(str::to_string));
    let mut l = Table::new();
    let place = |l: &mut Table, pos: DVec3, aim: Option<DVec3>| match view {
        Some((r, c)) => {
            let inv = r.transpose();
            l.insert(F::Light::mount.into(), Value::String("rig".into()));
            l.insert(F::Light::position.into(), arr((inv * (pos - c)).to_array()));
            if let Some(a) = aim {
                l.insert(F::Light::aim.into(), arr((inv * a).to_array()));
            }
        }
        None => {
            l.insert(F::Light::mount.into(), Value::String("world".into()));
            l.insert(F::Light::position.into(), arr(pos.to_array()));
            if let Some(a) = aim {
                l.insert(F::Light::aim.into(), arr(a.to_array()));
            }
        }
    };
    match k.ty() {
        "point" => {
            let pos = if k.named("position").is_some() {
                cx.point(k, "position", DVec3::ZERO)?
            } else {
                m.w_axis.truncate()
            };
            l.insert(
                F::Light::name.into(),
                Value::String(unique(name.unwrap_or_else(|| "point".into()))),
            );
            l.insert(F::Light::kind.into(), Value::String("point".into()));
            place(&mut l, pos, None);
            l.insert(F::Light::intensity.into(), arr(point_intensity(cx, k)?));
        }
        "spot" => {
            let cutoff = cx.float(k, "cutoff_angle", 20.0)?;
            let beam = cx.float(k, "beam_width", cutoff * 0.75)?;
            if beam < cutoff * (1.0 - 1e-3) {
                cx.note(k, format!("the spot's soft edge (beam_width {beam}° inside cutoff_angle {cutoff}°) is imported sharp at the cutoff"), Some("poser's spots have a sharp edge"));
            }
            l.insert(
                F::Light::name.into(),
                Value::String(unique(name.unwrap_or_else(|| "spot".into()))),
            );
            l.insert(F::Light::kind.into(), Value::String("spot".into()));
            place(
                &mut l,
                m.w_axis.truncate(),
                Some(m.z_axis.truncate().normalize()),
            );
            l.insert(
                F::Light::beam_angle.into(),
                Value::Float((2.0 * cutoff).to_radians()),
            );
            l.insert(F::Light::intensity.into(), arr(point_intensity(cx, k)?));
        }
        "directional" => {
            let dir = if k.named("direction").is_some() {
                cx.point(k, "direction", -DVec3::Z)?
            } else {
                m.z_axis.truncate()
            };
            let e = cx.colour(k, "irradiance")?.unwrap_or([1.0; 3]);
            if sun.is_some() {
                cx.note(
                    k,
                    "a second directional light is not imported",
                    Some("poser has one sun"),
                );
            } else if dir.z >= 0.0 {
                cx.note(
                    k,
                    "a directional light shining upwards is not imported",
                    Some("poser's sun shines down"),
                );
            } else {
                *sun = Some((k.clone(), dir.normalize(), e));
            }
            return Ok(());
        }
        "constant" => {
            l.insert(
                F::Light::name.into(),
                Value::String(unique(name.unwrap_or_else(|| "ambient".into()))),
            );
            l.insert(F::Light::kind.into(), Value::String("ambient".into()));
            l.insert(
                F::Light::radiance.into(),
                arr(cx.colour(k, "radiance")?.unwrap_or([1.0; 3])),
            );
        }
        t => {
            cx.note(
                k,
                format!("a `{t}` emitter is not imported"),
                Some("poser's lights are point, spot, area, ambient and the sun"),
            );
            return Ok(());
        }
    }
    lights.push(Value::Table(l));
    Ok(())
}

/// Per channel, the sum over an 8-bit image's pixels of their linear values (sRGB decoded):
/// each of the 256 codes decoded once, through the very conversion (`to_rgb32f`) and decoding
/// the general path applies per pixel, so the sums are the same numbers, without a `powf` per
/// channel and pixel (a photogrammetric texture holds tens of millions).
fn sum_8bit_srgb(img: &image::DynamicImage) -> [f64; 3] {
    let codes = image::RgbImage::from_fn(256, 1, |i, _| image::Rgb([i as u8; 3]));
    let as_f32 = image::DynamicImage::ImageRgb8(codes).to_rgb32f();
    let lut: Vec<f64> = as_f32
        .pixels()
        .map(|p| srgb_to_linear(p.0[0] as f64))
        .collect();
    let mut sum = [0.0f64; 3];
    for p in img.to_rgb8().pixels() {
        for (acc, &v) in sum.iter_mut().zip(&p.0) {
            *acc += lut[v as usize];
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::EulerRot;

    fn x(tag: &str, attrs: &[(&str, &str)], kids: Vec<X>) -> X {
        X {
            tag: tag.into(),
            attrs: attrs
                .iter()
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect(),
            kids,
            comment: None,
            loc: "t.xml:1:1".into(),
            included: false,
            dir: PathBuf::from("."),
            doc: 0,
        }
    }

    /// The 8-bit path's sums are the general path's, to the bit, for RGB and RGBA images.
    #[test]
    fn eight_bit_sums_are_the_general_paths() {
        let mut h = 5u64;
        let mut next = || {
            h = h
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (h >> 56) as u8
        };
        let rgba =
            image::RgbaImage::from_fn(37, 23, |_, _| image::Rgba([next(), next(), next(), next()]));
        for img in [
            image::DynamicImage::ImageRgba8(rgba.clone()),
            image::DynamicImage::ImageRgb8(image::DynamicImage::ImageRgba8(rgba).to_rgb8()),
        ] {
            let mut general = [0.0f64; 3];
            for p in img.to_rgb32f().pixels() {
                for (acc, &v) in general.iter_mut().zip(&p.0) {
                    *acc += srgb_to_linear(v as f64);
                }
            }
            assert_eq!(sum_8bit_srgb(&img), general);
        }
    }

    #[test]
    fn a_rotation_axis_is_used_as_written_as_mitsuba_3_does() {
        let rot = |(ax, ay, az): (&str, &str, &str), angle: &str| {
            let op = x(
                "rotate",
                &[("x", ax), ("y", ay), ("z", az), ("angle", angle)],
                vec![],
            );
            transform(&x("transform", &[("name", "to_world")], vec![op])).unwrap()
        };
        // A unit axis: the rotation (90° about z takes x to y).
        let m = rot(("0", "0", "1"), "90");
        assert!((m.transform_vector3(DVec3::X) - DVec3::Y).length() < 1e-12);
        // Axis (0, 2, 0), 90°: Rodrigues with the axis as written gives, by hand,
        // [[0, 0, 2], [0, 4, 0], [-2, 0, 0]] (rows); a normalised axis would give a rotation.
        let m = rot(("0", "2", "0"), "90");
        let want = DMat3::from_cols(
            DVec3::new(0.0, 0.0, -2.0),
            DVec3::new(0.0, 4.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        );
        let got = DMat3::from_mat4(m);
        assert!(
            (got - want).to_cols_array().iter().all(|d| d.abs() < 1e-12),
            "{got}"
        );
    }

    #[test]
    fn transforms_compose_in_order() {
        let t = x(
            "transform",
            &[("name", "to_world")],
            vec![
                x("scale", &[("value", "2")], vec![]),
                x("rotate", &[("z", "1"), ("angle", "90")], vec![]),
                x("translate", &[("x", "1"), ("y", "2"), ("z", "3")], vec![]),
            ],
        );
        let m = transform(&t).unwrap();
        let p = m.transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-12, "{p}");
        let la = x(
            "transform",
            &[],
            vec![x(
                "lookat",
                &[
                    ("origin", "0, 0, 1"),
                    ("target", "0, 0, 0"),
                    ("up", "0, 1, 0"),
                ],
                vec![],
            )],
        );
        let m = transform(&la).unwrap();
        assert!((m.z_axis.truncate() - DVec3::NEG_Z).length() < 1e-12);
        assert!((m.w_axis.truncate() - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn euler_angles_invert_the_scene_format_s() {
        let v = DVec3::new(0.3, -1.1, 2.5);
        let r = DMat3::from_euler(EulerRot::ZYX, v.z, v.y, v.x);
        let e = euler_xyz(r);
        assert!((DVec3::from_array(e) - v).length() < 1e-12);
    }

    #[test]
    fn paths_stay_inside_the_root() {
        let root = Path::new("/a/b");
        assert!(inside(root, root, "m.ply", "l").is_ok());
        assert!(
            inside(root, root, "../c.ply", "l")
                .unwrap_err()
                .contains("leaves")
        );
        assert!(
            inside(root, root, "/etc/passwd", "l")
                .unwrap_err()
                .contains("absolute")
        );
        assert!(inside(root, &root.join("sub"), "../x.ply", "l").is_ok());
    }

    #[test]
    fn spectra_become_srgb_as_in_mitsubas_rgb_variants() {
        // A flat reflectance of 0.5 under D65 is grey 0.5 (sRGB's white is D65's).
        let (wl, v) = spectrum_pairs("360:0.5, 830:0.5", "l").unwrap();
        let rgb = spectrum_to_srgb(&wl, &v, true, true);
        for c in rgb {
            assert!((c - 0.5).abs() < 1e-3, "{rgb:?}");
        }
        // Mitsuba's sampled spectra: values over a part of the range only count there.
        let (wl, v) = spectrum_pairs("400:0.05, 500:0.05, 560:0.1, 600:0.6, 700:0.7", "l").unwrap();
        let rgb = spectrum_to_srgb(&wl, &v, true, true);
        assert!(rgb[0] > rgb[1] && rgb[0] > rgb[2], "{rgb:?}");
        assert!(rgb[0] > 0.3 && rgb[1] < 0.15, "{rgb:?}");
        // An emitter's uniform spectrum is equal energy in sRGB: slightly purple.
        let e = xyz_to_srgb([1.0; 3]);
        assert!(e[0] > 1.2 && e[1] < 0.95 && e[2] < 0.95, "{e:?}");
        // A unit spectrum has luminance 1 without D65.
        let (wl, v) = spectrum_pairs("360:1, 830:1", "l").unwrap();
        let rgb = spectrum_to_srgb(&wl, &v, false, false);
        let y = 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
        assert!((y - 1.0).abs() < 2e-3, "{y}");
        // Malformed spectra are refused with their place.
        assert!(
            spectrum_pairs("500:0.1, 400:0.2", "f.xml:3:4")
                .unwrap_err()
                .contains("f.xml:3:4")
        );
        assert!(spectrum_pairs("500-0.1", "l").is_err());
    }

    #[test]
    fn line_and_column_are_found_once_per_position() {
        let text = "ab\ncdé f\n\n  x";
        let l = Lines::new(text);
        assert_eq!(l.line_col(0), (1, 1));
        assert_eq!(l.line_col(3), (2, 1));
        assert_eq!(l.line_col(text.find('f').unwrap()), (2, 5));
        assert_eq!(l.line_col(text.find('x').unwrap() - 2), (4, 3));
        // Backwards (an error position) is found from the line's start.
        assert_eq!(l.line_col(1), (1, 2));
    }

    #[test]
    fn the_sun_goes_back_through_the_surface() {
        let dir_a = crate::optics::sun::direction_from(0.9, 2.0);
        let (dir_w, f) = crate::optics::sun::refract_into_water(dir_a, 1.34);
        let (back, e) = unrefract(dir_w, [f * 800.0; 3], [1.34; 3]);
        assert!((back - dir_a).length() < 1e-12, "{back} {dir_a}");
        assert!((e[0] / 800.0 - 1.0).abs() < 1e-12);
    }
}
