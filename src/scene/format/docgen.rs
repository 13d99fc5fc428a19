//! Generation from the format types ([`super::types`]): the JSON Schema
//! (`schema/poser-scene.schema.json`, via schemars, every key admitting `{ unset = true }`),
//! the format reference (`docs/format.md`), the documented keys by table path, and the tests
//! that keep the generated files fresh and the reader and the schema agreeing key by key.

use super::types::*;

/// The JSON Schema of the scene format, pretty-printed with a trailing newline: the format
/// types' schema, in which every key also admits `{ unset = true }` (the removal of what an
/// included file sets, `source::merge`), so that an editor checking a scene with it accepts
/// what poser accepts.
pub fn schema_json() -> String {
    let mut v = format_schema();
    admit_unset(&mut v);
    if let Some(defs) = v.get_mut("$defs").and_then(|d| d.as_object_mut()) {
        defs.insert(UNSET_DEF.into(), unset_schema());
    }
    let mut s = serde_json::to_string_pretty(&v).expect("schema serialises");
    s.push('\n');
    s
}

/// The schema of the format types alone (no `{ unset = true }` alternatives): what the format
/// reference and the key lists are generated from.
fn format_schema() -> serde_json::Value {
    let schema = schemars::schema_for!(Scene);
    let mut v = serde_json::to_value(&schema).expect("schema serialises");
    if let Some(o) = v.as_object_mut() {
        o.insert(
            "$id".into(),
            serde_json::Value::String(
                "https://github.com/poser/poser/schema/poser-scene.schema.json".into(),
            ),
        );
    }
    v
}

/// Name of the `{ unset = true }` definition in the schema's `$defs`.
pub const UNSET_DEF: &str = "Unset";

fn unset_schema() -> serde_json::Value {
    serde_json::json!({
        "description": "Removes what an included file sets for this key (`key = { unset = true }`; docs/scenes.md).",
        "type": "object",
        "properties": { "unset": { "const": true } },
        "required": ["unset"],
        "additionalProperties": false
    })
}

/// Every property of every table in `v` (the scene's and each `$defs` entry's) becomes
/// "its own schema, or `{ unset = true }`".
fn admit_unset(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(o) => {
            for x in o.values_mut() {
                admit_unset(x);
            }
            if let Some(serde_json::Value::Object(props)) = o.get_mut("properties") {
                let unset = serde_json::json!({ "$ref": format!("#/$defs/{UNSET_DEF}") });
                for p in props.values_mut() {
                    let own = std::mem::take(p);
                    *p = serde_json::json!({ "anyOf": [own, unset.clone()] });
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(admit_unset),
        _ => {}
    }
}

/// Keys accepted per table path (`""` = top level, `"camera.port"`, `"lights"`, …), from
/// the schema. Used by the tests that keep the reader and the documentation in step.
pub fn keys_by_path() -> std::collections::BTreeMap<String, Vec<String>> {
    let v = format_schema();
    let mut out = std::collections::BTreeMap::new();
    walk_keys(&v, &v, "", &mut out, 0);
    out
}

fn resolve_ref<'a>(root: &'a serde_json::Value, v: &'a serde_json::Value) -> &'a serde_json::Value {
    if let Some(r) = v.get("$ref").and_then(|r| r.as_str()) {
        let name = r.rsplit('/').next().unwrap_or("");
        if let Some(d) = root.get("$defs").and_then(|d| d.get(name)) {
            return d;
        }
    }
    v
}

/// The object schema inside `v` (following `$ref`, `anyOf` with null, arrays of tables).
fn table_of<'a>(
    root: &'a serde_json::Value,
    v: &'a serde_json::Value,
) -> Option<(&'a serde_json::Value, bool)> {
    let v = resolve_ref(root, v);
    if v.get("properties").is_some() {
        return Some((v, false));
    }
    if let Some(items) = v.get("items") {
        return table_of(root, items).map(|(t, _)| (t, true));
    }
    for k in ["anyOf", "oneOf"] {
        if let Some(a) = v.get(k).and_then(|a| a.as_array()) {
            for x in a {
                if let Some(t) = table_of(root, x) {
                    return Some(t);
                }
            }
        }
    }
    if let Some(t) = v.get("type").and_then(|t| t.as_array())
        && t.iter().any(|x| x == "array")
        && let Some(items) = v.get("items")
    {
        return table_of(root, items).map(|(t, _)| (t, true));
    }
    None
}

fn walk_keys(
    root: &serde_json::Value,
    v: &serde_json::Value,
    path: &str,
    out: &mut std::collections::BTreeMap<String, Vec<String>>,
    depth: usize,
) {
    let Some(props) = v.get("properties").and_then(|p| p.as_object()) else {
        return;
    };
    out.insert(path.to_string(), props.keys().cloned().collect());
    if depth > 4 {
        return;
    }
    for (k, p) in props {
        if let Some((t, _)) = table_of(root, p) {
            let sub = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            walk_keys(root, t, &sub, out, depth + 1);
        }
    }
}

/// The format reference (`docs/format.md`), generated from the schema.
pub fn format_markdown() -> String {
    let v = format_schema();
    let mut s = String::new();
    s.push_str(
        "<!-- Generated by `poser schema` from src/scene/format/types.rs. Do not edit by hand. -->\n",
    );
    s.push_str("# poser scene format reference\n\n");
    s.push_str(
        "A scene is one TOML file. Values with a physical dimension take a plain number in the SI \
         unit listed, or a string with a unit: `\"18 mm\"`, `\"15 m\"`, `\"0.2 m/s\"`, `\"20 l/min\"`, \
         `\"532 nm\"`, `\"30 deg\"`, `\"232 bar\"`, `\"12 l\"`, `\"50 W\"`, `\"4.5 µm\"`, `\"60 %\"`. \
         Vectors are `[x, y, z]` or one string with a trailing unit (`\"0, 0.1, 2 m\"`). \
         Per-channel values are one number for R, G and B or `[r, g, b]` (650/550/450 nm).\n\n",
    );
    s.push_str(
        "World frame: metres, z up, x east, y north, sea surface z = 0, seabed z = −`site.depth`. \
         Camera and rig frames: x right, y down, z forward (OpenCV), origin at the entrance pupil.\n\n",
    );
    s.push_str(
        "Composition: `include = [\"../shared/rig.toml\"]` merges files under this one (deep merge \
         of tables); `poser … --set a.b.c=value` overrides any value after includes (the value is \
         read as TOML, else as a string; list entries by index: `--set network.poses.0.position=[0,0,-2]`). \
         A key written `key = { unset = true }` removes what the included files set for it (a \
         dome variant of a flat-port base: `pupil_distance = { unset = true }` under \
         `[camera.port]`; a whole table: `port = { unset = true }` under `[camera]`); unsetting a \
         key no included file sets is error E0021, and `--set camera.port.tilt='{ unset = true }'` \
         removes a key from the command line. An unknown key an included file sets is reported \
         in that file, as inherited, with the include line.\n\n",
    );
    s.push_str(
        "Editor support: the JSON Schema is `schema/poser-scene.schema.json`. With the Even Better \
         TOML extension (taplo), put `#:schema ../schema/poser-scene.schema.json` as the first \
         line of a scene (path relative to the scene), or map `scenarios/*.toml` to the schema in \
         `.taplo.toml`:\n\n```toml\n[[rule]]\ninclude = [\"scenarios/**/*.toml\"]\n[rule.schema]\npath = \"./schema/poser-scene.schema.json\"\n```\n\n\
         The schema accepts `{ unset = true }` for every key, as poser does, and refuses any other \
         value of that shape. Every shipped scene validates against it with a real validator \
         (`jsonschema`, in the full test tier: backends/schema).\n\n",
    );
    s.push_str("Check a scene with `poser validate SCENE`; see what it resolves to with `poser explain SCENE`.\n\n");
    s.push_str("## Contents\n\n");
    let mut sections = Vec::new();
    collect_sections(&v, &v, "", &mut sections, 0);
    for (path, _, _) in &sections {
        let title = if path.is_empty() {
            "top level".to_string()
        } else {
            path.clone()
        };
        s.push_str(&format!("- [{title}](#{})\n", anchor(&title)));
    }
    s.push('\n');
    for (path, table, is_array) in &sections {
        let title = if path.is_empty() {
            "top level".to_string()
        } else {
            path.clone()
        };
        s.push_str(&format!("## {title}\n\n"));
        if !path.is_empty() {
            s.push_str(&format!(
                "Written as `{}`.\n\n",
                if *is_array {
                    format!("[[{path}]]")
                } else {
                    format!("[{path}]")
                }
            ));
        }
        if let Some(d) = table.get("description").and_then(|d| d.as_str()) {
            s.push_str(&one_line(d));
            s.push_str("\n\n");
        }
        s.push_str("| key | value | meaning, unit, default |\n|---|---|---|\n");
        let props = table
            .get("properties")
            .and_then(|p| p.as_object())
            .cloned()
            .unwrap_or_default();
        for (k, p) in &props {
            let (kind, mut sub) = describe(&v, p);
            let mut desc = p
                .get("description")
                .and_then(|d| d.as_str())
                .map(one_line)
                .unwrap_or_default();
            if let Some((t, _)) = table_of(&v, p) {
                let full = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                sub = Some(if full == "rig.cameras" {
                    "camera".to_string()
                } else {
                    full
                });
                if desc.is_empty()
                    && let Some(d) = t.get("description").and_then(|d| d.as_str())
                {
                    desc = one_line(d.split("\n\n").next().unwrap_or(d));
                }
            }
            if let Some(sp) = sub {
                desc = format!("{desc} See [{sp}](#{}).", anchor(&sp))
                    .trim()
                    .to_string();
            }
            s.push_str(&format!(
                "| `{k}` | {kind} | {} |\n",
                desc.replace('|', "\\|")
            ));
        }
        s.push('\n');
    }
    s.push_str(UNITS_TABLE);
    s
}

const UNITS_TABLE: &str = "## Units\n\n\
| dimension | plain numbers | units in strings |\n|---|---|---|\n\
| length | m | m, cm, mm, µm (um), nm, km, ft, in |\n\
| angle | rad | rad, mrad, deg, ° |\n\
| speed | m/s | m/s, cm/s, m/min, ft/min, km/h, kn |\n\
| gas flow | m³/s | l/min, L/min, m3/s, cuft/min |\n\
| pressure | Pa | Pa, kPa, MPa, bar, mbar, psi, atm |\n\
| volume | m³ | m3, l, L, ml, cuft |\n\
| time | s | s, ms, min, h |\n\
| power | W | W, mW, kW |\n\
| radiant intensity | W/sr | W/sr, mW/sr |\n\
| radiance | W/(m²·sr) | W/m2/sr |\n\
| irradiance | W/m² | W/m2 |\n\
| temperature | °C | °C, C, degC, K, F |\n\
| fraction | 1 | % |\n\
| ground sampling distance | m/px | m/px, cm/px, mm/px |\n\n\
Units are case-exact, as SI writes them: `mW` is a milliwatt and `MW` a megawatt, so `\"50 MW\"` \
is an error (with a hint), never 50 mW. Spellings without an SI prefix (bar, psi, atm, deg, rad, \
ft, in, min, kn, cuft, degC) are also accepted in any case (`\"232 Bar\"`).\n";

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn anchor(title: &str) -> String {
    title
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == ' ' || *c == '_')
        .collect::<String>()
        .replace(' ', "-")
}

fn collect_sections(
    root: &serde_json::Value,
    v: &serde_json::Value,
    path: &str,
    out: &mut Vec<(String, serde_json::Value, bool)>,
    depth: usize,
) {
    let Some(props) = v.get("properties").and_then(|p| p.as_object()) else {
        return;
    };
    if !out.iter().any(|(p, _, _)| p == path) {
        out.push((path.to_string(), v.clone(), false));
    }
    if depth > 3 {
        return;
    }
    for (k, p) in props {
        if let Some((t, arr)) = table_of(root, p) {
            let sub = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            // rig.cameras repeats [camera]: document it once.
            if sub == "rig.cameras" {
                continue;
            }
            let before = out.len();
            collect_sections(root, t, &sub, out, depth + 1);
            if out.len() > before {
                out[before].2 = arr;
            }
        }
    }
}

/// (value description, sub-section path if the value is a table).
fn describe(root: &serde_json::Value, p: &serde_json::Value) -> (String, Option<String>) {
    let r = resolve_ref(root, p);
    if let Some(kind) = find_kind(r) {
        let unit = find_unit(r).filter(|u| !u.is_empty() && *u != "1");
        return (
            match unit {
                Some(u) => format!("{kind} ({u})"),
                None => kind,
            },
            None,
        );
    }
    if let Some(e) = enum_values(root, r) {
        return (
            format!(
                "one of {}",
                e.iter()
                    .map(|x| format!("`\"{x}\"`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None,
        );
    }
    if table_of(root, p).is_some() {
        let arr = table_of(root, p).is_some_and(|t| t.1);
        return (
            if arr {
                "list of tables".into()
            } else {
                "table".into()
            },
            None,
        );
    }
    let t = type_name(r);
    (t, None)
}

fn find_kind(v: &serde_json::Value) -> Option<String> {
    if let Some(k) = v.get("x-poser-kind").and_then(|k| k.as_str()) {
        return Some(k.to_string());
    }
    for k in ["anyOf", "oneOf"] {
        if let Some(a) = v.get(k).and_then(|a| a.as_array()) {
            for x in a {
                if let Some(r) = find_kind(x) {
                    return Some(r);
                }
            }
        }
    }
    None
}

fn find_unit(v: &serde_json::Value) -> Option<&str> {
    if let Some(k) = v.get("x-poser-unit").and_then(|k| k.as_str()) {
        return Some(k);
    }
    for k in ["anyOf", "oneOf"] {
        if let Some(a) = v.get(k).and_then(|a| a.as_array()) {
            for x in a {
                if let Some(r) = find_unit(x) {
                    return Some(r);
                }
            }
        }
    }
    None
}

fn enum_values(root: &serde_json::Value, v: &serde_json::Value) -> Option<Vec<String>> {
    let v = resolve_ref(root, v);
    if let Some(e) = v.get("enum").and_then(|e| e.as_array()) {
        return Some(
            e.iter()
                .filter_map(|x| x.as_str().map(str::to_string))
                .collect(),
        );
    }
    if let Some(a) = v.get("oneOf").and_then(|a| a.as_array()) {
        let mut out = Vec::new();
        for x in a {
            if let Some(c) = x.get("const").and_then(|c| c.as_str()) {
                out.push(c.to_string());
            } else if let Some(e) = x.get("enum").and_then(|e| e.as_array()) {
                out.extend(e.iter().filter_map(|x| x.as_str().map(str::to_string)));
            } else {
                return None;
            }
        }
        return Some(out);
    }
    if let Some(a) = v.get("anyOf").and_then(|a| a.as_array()) {
        for x in a {
            if x.get("type").and_then(|t| t.as_str()) == Some("null") {
                continue;
            }
            if let Some(e) = enum_values(root, x) {
                return Some(e);
            }
        }
    }
    None
}

fn type_name(v: &serde_json::Value) -> String {
    let t = match v.get("type") {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(serde_json::Value::Array(a)) => a
            .iter()
            .filter_map(|x| x.as_str())
            .filter(|x| *x != "null")
            .collect::<Vec<_>>()
            .join(" or "),
        _ => "value".into(),
    };
    match t.as_str() {
        "integer" => "integer".into(),
        "boolean" => "true / false".into(),
        "array" => match v.get("items").map(type_name).as_deref() {
            Some("string") => "list of strings".into(),
            Some(x) => format!("list of {x}"),
            None => "list".into(),
        },
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::{BTreeMap, BTreeSet};

    /// Every key the reader accepts is documented in the schema, and every documented key is
    /// read by some variant: load the examples with overrides that switch every `type`.
    #[test]
    fn reader_and_schema_agree_key_by_key() {
        let variants: &[&[&str]] = &[
            &[],
            &["camera.port.type=\"dome\""],
            &["camera.port.type=\"cylinder\""],
            &["camera.port.type=\"none\"", "camera.distortion.k1=0.01"],
            &["rig.type=\"stereo\""],
            &[
                "rig.type=\"multi\"",
                "rig.cameras=[{name = \"a\"}, {name = \"b\", position = [0.3, 0, 0]}]",
            ],
            &["lights.0.type=\"point\"", "lights.1.type=\"area\""],
            &["lights.0.type=\"ambient\""],
            &[
                "objects.0.shape=\"mesh\"",
                "objects.0.texture=false",
                "objects.1.shape=\"plane\"",
            ],
            &["objects.0.shape=\"box\"", "objects.1.shape=\"sphere\""],
            &[
                "objects.0.shape=\"cylinder\"",
                "objects.0.pattern={type = \"checker\"}",
            ],
            &[
                "objects.0.pattern={type = \"fbm\"}",
                "objects.1.pattern={type = \"noise\"}",
            ],
            &["objects.0.pattern={type = \"rock\"}"],
            &[
                "objects.0.pattern={type = \"sand\", grid = 1, grid_width = 0.01, grid_albedo = [0.8, 0.8, 0.6]}",
            ],
            &["objects.0.pattern={type = \"coral\", colors = [[0.5, 0.2, 0.3]]}"],
            &["targets.0.type=\"checkerboard\""],
            &["targets.0.type=\"circle_grid\""],
            &["targets.0.type=\"coded\""],
            &["targets.0.type=\"siemens_star\""],
            &["targets.0.type=\"test_object\""],
            &["network.type=\"spiral\""],
            &["network.type=\"orbit\""],
            &[
                "network.type=\"explicit\"",
                "network.poses=[{position = [0, 0, -10]}]",
            ],
            &["diver.cylinders.0.o2=0.32"],
            &["sun.elevation=0.5"],
            &["objects.0.shape=\"coral\"", "objects.0.growth=\"massive\""],
            &[
                "objects.0.relief_file=\"none.txt\"",
                "objects.0.relief_origin=[0, 0, 0]",
            ],
            &[
                "objects.0.shape=\"box\"",
                "objects.0.fill={ior = 1.33, temperature = 20, salinity = 35, ior_depth = 1, jerlov = \"3C\", absorption = 0.1, scattering = 0.2, phase = \"fournier_forand\", g = 0.8, particle_index = 1.1, junge_slope = 3.6}",
            ],
            &[
                "targets=[{type = \"points_file\", file = \"none.txt\", surface = \"seabed\", diameter = 0.1}]",
            ],
            &[
                "camera.port={type = \"flat\", layers = [{thickness = \"6 mm\", material = \"PMMA\"}, {thickness = \"2 mm\", ior = 1.77}]}",
            ],
            &[
                "lesson={question = \"q\", quick = [], full = [], variants = [{label = \"a\", set = []}], try_next = [{text = \"t\", set = \"a=1\"}]}",
            ],
        ];
        let mut known: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for v in variants {
            let sets: Vec<String> = v.iter().map(|s| s.to_string()).collect();
            let (_, m) = crate::scene::reader::record_known_keys(|| {
                let _ =
                    crate::scene::load(std::path::Path::new("scenarios/reef_strip.toml"), &sets);
            });
            for (k, s) in m {
                known.entry(k).or_default().extend(s);
            }
        }
        let schema = keys_by_path();
        let mut problems = Vec::new();
        for (path, keys) in &known {
            let Some(doc) = schema.get(path) else {
                problems.push(format!("table `{path}` is read but not in the schema"));
                continue;
            };
            for k in keys {
                if !doc.contains(k) {
                    problems.push(format!("`{path}.{k}` is read but not documented"));
                }
            }
            for k in doc {
                if !(keys.contains(k) || path.is_empty() && k == "include") {
                    problems.push(format!("`{path}.{k}` is documented but never read"));
                }
            }
        }
        for path in schema.keys() {
            if !known.contains_key(path)
                && path != "rig.cameras"
                && !path.starts_with("rig.cameras.")
            {
                problems.push(format!("table `{path}` is documented but never read"));
            }
        }
        assert!(
            problems.is_empty(),
            "reader and schema disagree:\n{}",
            problems.join("\n")
        );
    }

    /// The string literals of `code` in the key argument of a reader's getter (`cx, "…"`,
    /// `cx, t, "…"`, `.span_of("…")`, `.has("…")`, …) or of an importer's `.insert("…"`,
    /// with their line numbers; `//` lines are skipped.
    fn key_arguments(code: &str) -> Vec<(usize, String)> {
        const CALLS: [&str; 11] = [
            "(cx,",
            ".span_of(",
            ".has(",
            ".key_span(",
            ".entry_span(",
            ".full(",
            ".get(",
            ".get_mut(",
            ".remove(",
            ".insert(",
            ".contains_key(",
        ];
        let code: String = code
            .lines()
            .map(|l| {
                if l.trim_start().starts_with("//") {
                    ""
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let mut out = Vec::new();
        for call in CALLS {
            for (at, _) in code.match_indices(call) {
                let mut rest = code[at + call.len()..].trim_start();
                if call == "(cx," && !rest.starts_with('"') {
                    // One more argument first (`cx, &mut t, "key"`): a variable.
                    let arg = rest.trim_start_matches('&').trim_start_matches("mut ");
                    let n = arg
                        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                        .unwrap_or(arg.len());
                    if n > 0 && arg[n..].starts_with(',') {
                        rest = arg[n + 1..].trim_start();
                    }
                }
                if let Some(lit) = rest.strip_prefix('"').and_then(|r| r.split('"').next()) {
                    out.push((code[..at].lines().count().max(1), lit.to_string()));
                }
            }
        }
        out
    }

    /// The resolvers and the importers name every documented key through its format type's
    /// constant (`F::Light::beam_angle`), never as a string: a documented key written as a
    /// literal in a getter's or an insert's key argument fails here.
    #[test]
    fn resolvers_and_importers_name_keys_by_constant() {
        let keys: BTreeSet<String> = keys_by_path().into_values().flatten().collect();
        let key_literals = |code: &str| -> Vec<(usize, String)> {
            let mut v = key_arguments(code);
            v.retain(|(_, k)| keys.contains(k));
            v
        };
        // The scan sees what it must (so it cannot pass by finding nothing).
        let planted = "let a = l.f64(cx, \"beam_angle\", Dim::Angle, 1.0);\n\
            check::positive(cx, &mut o, \"radius\", r, \"m\");\n\
            // t.span_of(\"aim\") in a comment is fine\n\
            let s = l.span_of(if l.has(\"aim\") { x } else { y });\n\
            t.insert(\n    \"name\".into(), v);\n\
            let d = l.f64(cx, F::Light::beam_angle, Dim::Angle, 1.0);\n\
            let m = l.opt_str(cx, \"not_a_key\");";
        let found: BTreeSet<(usize, String)> = key_literals(planted).into_iter().collect();
        let want: BTreeSet<(usize, String)> =
            [(1, "beam_angle"), (2, "radius"), (4, "aim"), (5, "name")]
                .map(|(l, k)| (l, k.to_string()))
                .into();
        assert_eq!(found, want);
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = vec![src.join("scene/check.rs"), src.join("scene/source.rs")];
        for dir in ["scene/resolve", "import"] {
            for e in std::fs::read_dir(src.join(dir)).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "rs") {
                    files.push(p);
                }
            }
        }
        assert!(files.len() > 15, "only {} files", files.len());
        let mut bad = Vec::new();
        for f in &files {
            let code = std::fs::read_to_string(f).unwrap();
            for (line, k) in key_literals(&code) {
                bad.push(format!(
                    "{}:{line}: \"{k}\"",
                    f.strip_prefix(&src).unwrap().display()
                ));
            }
        }
        assert!(
            bad.is_empty(),
            "a documented key written as a string; name it `F::<Table>::<field>` (use crate::scene::format::types as F):\n{}",
            bad.join("\n")
        );
    }

    /// `schema/` and `docs/format.md` are regenerated by `poser schema`; stale files fail.
    #[test]
    fn generated_files_are_fresh() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let schema = std::fs::read_to_string(root.join("schema/poser-scene.schema.json"))
            .unwrap_or_default();
        let docs = std::fs::read_to_string(root.join("docs/format.md")).unwrap_or_default();
        assert!(
            schema == schema_json(),
            "schema/poser-scene.schema.json is stale: run `cargo run -- schema`"
        );
        assert!(
            docs == format_markdown(),
            "docs/format.md is stale: run `cargo run -- schema`"
        );
    }

    /// Every key of every table in the published schema admits `{ unset = true }`, and only
    /// that spelling (a real validator checks scenes with it: backends/schema).
    #[test]
    fn every_key_of_the_schema_admits_unset() {
        let v: serde_json::Value = serde_json::from_str(&schema_json()).unwrap();
        let unset = serde_json::json!({ "$ref": format!("#/$defs/{UNSET_DEF}") });
        let mut keys = 0;
        fn each<'a>(v: &'a serde_json::Value, f: &mut dyn FnMut(&'a serde_json::Value)) {
            match v {
                serde_json::Value::Object(o) => {
                    if let Some(serde_json::Value::Object(p)) = o.get("properties") {
                        p.values().for_each(&mut *f);
                    }
                    o.values().for_each(|x| each(x, f));
                }
                serde_json::Value::Array(a) => a.iter().for_each(|x| each(x, f)),
                _ => {}
            }
        }
        each(&v, &mut |p| {
            if p.get("const").is_none() {
                keys += 1;
                let alts = p["anyOf"].as_array().expect("a key is its schema or unset");
                assert_eq!(alts.len(), 2, "{p}");
                assert_eq!(alts[1], unset, "{p}");
            }
        });
        assert!(keys > 200, "only {keys} keys");
        let def = &v["$defs"][UNSET_DEF];
        assert_eq!(
            def["properties"]["unset"]["const"],
            serde_json::Value::Bool(true)
        );
        assert_eq!(def["required"][0], "unset");
    }

    #[test]
    fn schema_is_valid_json_with_every_table() {
        let v: serde_json::Value = serde_json::from_str(&schema_json()).unwrap();
        assert_eq!(v["additionalProperties"], serde_json::Value::Bool(false));
        let k = keys_by_path();
        for t in [
            "water",
            "site",
            "sun",
            "camera",
            "camera.port",
            "rig",
            "lights",
            "objects",
            "targets",
            "network",
            "network.poses",
            "diver",
            "diver.cylinders",
            "render",
        ] {
            assert!(k.contains_key(t), "schema lacks `{t}`");
        }
    }
}
