//! Resolution of the optional `[lesson]` table into [`crate::model::Lesson`] (documented in
//! [`crate::scene::format::LessonTable`]; what `poser lesson` does with it is in
//! `docs/lessons.md`).
//!
//! | key | resolved to | check |
//! |---|---|---|
//! | `title`, `question`, `setup`, `shows` | text of the page | `question` required |
//! | `kind` | [`LessonKind`] | `deformation`, `calibration`, `contrast`, `gsd`, `dive`, `survey`, `completeness`, `metrology` or `surface` |
//! | `gsd` | m/px (kinds `contrast`, `gsd`) | positive |
//! | `quick`, `full` | `--set` overrides of the quick and full forms | strings |
//! | `[[lesson.variants]]` `label`, `scene`, `set` | [`LessonVariant`]; `scene` made absolute, relative to the file that names it | the file exists |
//! | `[[lesson.try_next]]` `text`, `set` | [`TryNext`] | both given |

use crate::model::{Lesson, LessonKind, LessonVariant, TryNext};
use crate::scene::diag::{Diagnostic, Span};
use crate::scene::format::types as F;
use crate::scene::reader::{Cx, Tab, type_error};
use crate::scene::source::{Node, Sources, Val};

/// A list of strings (`set = ["a=1", "b=2"]`); a bad entry is reported and skipped.
fn strings(cx: &mut Cx, t: &mut Tab, key: &'static str) -> Vec<String> {
    let full = t.full(key);
    let Some(n) = t.get(key) else {
        return vec![];
    };
    match &n.val {
        Val::Array(a) => a
            .iter()
            .filter_map(|x| match &x.val {
                Val::Str(s) => Some(s.clone()),
                v => {
                    cx.push(type_error(x, &full, "a string", v));
                    None
                }
            })
            .collect(),
        v => {
            cx.push(type_error(n, &full, "a list of strings", v));
            vec![]
        }
    }
}

fn required(cx: &mut Cx, t: &mut Tab, key: &'static str, example: &str) -> String {
    match t.opt_str(cx, key) {
        Some(s) if !s.trim().is_empty() => s,
        _ => {
            cx.push(
                Diagnostic::error("E0500", format!("`{}` is required", t.full(key)))
                    .label(t.span_of(key), "missing or empty")
                    .help(format!("write e.g. `{key} = {example}`")),
            );
            String::new()
        }
    }
}

/// `[lesson]`, or `None` when the table is absent. `name` and `description` are the scene's
/// (the defaults of `title` and `setup`).
pub fn lesson(
    cx: &mut Cx,
    node: Option<&Node>,
    sources: &Sources,
    name: &str,
    description: &str,
    fallback: Span,
) -> Option<Lesson> {
    // Read even when absent, so that the key record that keeps reader and schema in step
    // sees every key.
    let present = node.is_some();
    let mut t = Tab::open(cx, node, F::Scene::lesson, fallback);
    let title = t
        .opt_str(cx, F::LessonTable::title)
        .unwrap_or_else(|| name.to_string());
    let question = if present {
        required(
            cx,
            &mut t,
            F::LessonTable::question,
            "\"Why does the reef come out bent?\"",
        )
    } else {
        t.opt_str(cx, F::LessonTable::question).unwrap_or_default()
    };
    let setup = t
        .opt_str(cx, F::LessonTable::setup)
        .unwrap_or_else(|| description.to_string());
    let shows = t.opt_str(cx, F::LessonTable::shows).unwrap_or_default();
    let kind = match t.choice(
        cx,
        F::LessonTable::kind,
        &[
            "deformation",
            "calibration",
            "contrast",
            "gsd",
            "dive",
            "survey",
            "completeness",
            "metrology",
            "surface",
        ],
    ) {
        Some("calibration") => LessonKind::Calibration,
        Some("contrast") => LessonKind::Contrast,
        Some("gsd") => LessonKind::Gsd,
        Some("dive") => LessonKind::Dive,
        Some("survey") => LessonKind::Survey,
        Some("completeness") => LessonKind::Completeness,
        Some("metrology") => LessonKind::Metrology,
        Some("surface") => LessonKind::Surface,
        _ => LessonKind::Deformation,
    };
    let gsd = t.opt_f64(cx, F::LessonTable::gsd, crate::units::Dim::Gsd);
    if let Some(g) = gsd {
        crate::scene::check::positive(cx, &t, F::LessonTable::gsd, g, "m/px");
    }
    let quick = strings(cx, &mut t, F::LessonTable::quick);
    let full = strings(cx, &mut t, F::LessonTable::full);
    let mut variants = Vec::new();
    for (i, n) in t
        .tables(cx, F::LessonTable::variants)
        .into_iter()
        .enumerate()
    {
        let mut v = Tab::open(cx, Some(n), &format!("lesson.variants[{i}]"), n.span);
        let label = v
            .opt_str(cx, F::LessonVariantTable::label)
            .unwrap_or_else(|| format!("variant {i}"));
        let scene = v.opt_str(cx, F::LessonVariantTable::scene).map(|rel| {
            let span = v.span_of(F::LessonVariantTable::scene);
            let dir = sources.dir_of(span.file).unwrap_or_default();
            let p = dir.join(&rel);
            if !p.is_file() {
                cx.push(
                    Diagnostic::error(
                        "E0501",
                        format!("lesson variant scene `{}` not found", p.display()),
                    )
                    .label(span, "no such file")
                    .help("variant scenes are relative to the file that names them"),
                );
            }
            p.to_string_lossy().to_string()
        });
        let set = strings(cx, &mut v, F::LessonVariantTable::set);
        v.finish(cx);
        variants.push(LessonVariant { label, scene, set });
    }
    let mut try_next = Vec::new();
    for (i, n) in t
        .tables(cx, F::LessonTable::try_next)
        .into_iter()
        .enumerate()
    {
        let mut v = Tab::open(cx, Some(n), &format!("lesson.try_next[{i}]"), n.span);
        let text = required(cx, &mut v, F::TryNextTable::text, "\"Fly higher\"");
        let set = required(
            cx,
            &mut v,
            F::TryNextTable::set,
            "\"network.altitude=\\\"2 m\\\"\"",
        );
        v.finish(cx);
        try_next.push(TryNext { text, set });
    }
    t.finish(cx);
    present.then_some(Lesson {
        title,
        question,
        setup,
        shows,
        kind,
        gsd,
        quick,
        full,
        variants,
        try_next,
    })
}

#[cfg(test)]
mod tests {
    use crate::model::LessonKind;
    use std::path::Path;

    fn load(sets: &[&str]) -> Result<crate::model::Model, String> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        crate::scene::load(Path::new("scenarios/reef_strip.toml"), &sets)
            .map(|l| l.model)
            .map_err(|f| f.render())
    }

    #[test]
    fn a_lesson_table_resolves_with_its_defaults() {
        let m = load(&["lesson={question = \"Why?\", kind = \"calibration\"}"]).unwrap();
        let l = m.lesson.unwrap();
        assert_eq!(l.kind, LessonKind::Calibration);
        assert_eq!(l.title, m.name);
        assert_eq!(l.setup, m.description);
        assert!(l.variants.is_empty() && l.try_next.is_empty());
        assert!(load(&[]).unwrap().lesson.is_none());
    }

    #[test]
    fn a_lesson_gsd_is_read_in_m_per_px_and_must_be_positive() {
        let m = load(&["lesson={question = \"q\", kind = \"gsd\", gsd = \"3 mm/px\"}"]).unwrap();
        let l = m.lesson.unwrap();
        assert_eq!(l.kind, LessonKind::Gsd);
        assert!((l.gsd.unwrap() - 3e-3).abs() < 1e-15);
        let e = load(&["lesson={question = \"q\", kind = \"contrast\", gsd = -1}"]).unwrap_err();
        assert!(e.contains("lesson.gsd") || e.contains("gsd"), "{e}");
    }

    #[test]
    fn bad_lesson_tables_are_located_errors_with_help() {
        let e = load(&["lesson={kind = \"deformation\"}"]).unwrap_err();
        assert!(
            e.contains("E0500") && e.contains("lesson.question") && e.contains("help"),
            "{e}"
        );
        let e = load(&["lesson={question = \"q\", kind = \"calibrate\"}"]).unwrap_err();
        assert!(e.contains("did you mean `calibration`"), "{e}");
        let e =
            load(&["lesson={question = \"q\", variants = [{scene = \"nope.toml\"}]}"]).unwrap_err();
        assert!(e.contains("E0501") && e.contains("nope.toml"), "{e}");
        let e = load(&["lesson={question = \"q\", try_next = [{text = \"t\"}]}"]).unwrap_err();
        assert!(e.contains("lesson.try_next[0].set"), "{e}");
        let e = load(&["lesson={question = \"q\", quick = \"a=1\"}"]).unwrap_err();
        assert!(e.contains("lesson.quick"), "{e}");
    }
}
