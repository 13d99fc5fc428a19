//! `poser lesson`: runs what a lesson scene's `[lesson]` table asks for, on each of its
//! variants, and measures the lesson's numbers for one self-contained HTML page.
//!
//! | item | meaning |
//! |---|---|
//! | [`Options`] | quick or full form, extra `--set` overrides |
//! | [`run`] | load every variant, run the lesson's kind, return a [`Report`] |
//! | [`deformation`] | kind `deformation`: `poser evaluate` (observations mode) per variant: RMS Z, the bowl |
//! | [`calibration`] | kind `calibration`: native renders of the board, OpenCV calibration per variant |
//! | [`contrast`] | kind `contrast`: native renders of a target at a GSD: Michelson contrast, colour cast, backscatter |
//! | [`gsd`] | kind `gsd`: camera height for a GSD through the port, smallest resolved Siemens-star element |
//! | [`dive`] | kinds `dive` and `survey`: survey and dive planner per variant (deco, gas, verdict, dives needed), `survey` adds `poser evaluate` with GCPs |
//! | [`completeness`] | kind `completeness`: share of the corals' surface seen by ≥ 3 images within 60° of its normal |
//! | [`surface`] | kind `surface`: a drone above the water: targets moved by the waves (px), caustic contrast against depth, the view |
//! | [`metrology`] | kind `metrology`: a stereo rig's backscatter and contrast (native renders), and its accuracy (`poser evaluate --rig --gcp`) |
//! | [`html`] | `index.html` (images inline, works offline) and `lesson.json` |
//!
//! Every page also shows one camera image of the scene: the first case's first image, rendered
//! by the native backend at most [`VIEW_WIDTH`] px wide and [`VIEW_SAMPLES`] samples per pixel
//! into `OUT/view/`.
//!
//! Overrides are applied in this order, the later winning: the form's (`lesson.quick`, or
//! `lesson.full` with `--full`), the variant's `set`, the command line's `--set`.

pub mod calibration;
pub mod completeness;
pub mod contrast;
pub mod deformation;
pub mod dive;
pub mod gsd;
pub mod html;
pub mod metrology;
pub mod surface;

use crate::model::{Lesson, LessonKind, Model};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Width of the page's camera image in the full form, px (smaller cameras keep their own).
pub const VIEW_WIDTH: u32 = 320;
/// Samples per pixel of the page's camera image in the full form: a preview, not a measurement.
pub const VIEW_SAMPLES: u32 = 8;
/// The quick form's camera image: half as wide, half the samples (an eighth of the cost; a
/// turbid survey's previews took three quarters of its quick lesson at the full form's size).
pub const VIEW_WIDTH_QUICK: u32 = 160;
pub const VIEW_SAMPLES_QUICK: u32 = 4;

/// One camera image of the scene for the page: `case`'s first image, rendered natively (through
/// [`crate::backend::Backend`]) into `out/view/`; an auto-exposed sRGB PNG of it. `full`: the
/// full form's size ([`VIEW_WIDTH`], [`VIEW_SAMPLES`]), else the quick form's.
pub fn view(case: &Case, out: &Path, full: bool) -> Result<Vec<u8>, String> {
    use crate::backend::{Backend, RenderOptions};
    let Some(cam) = case.model.cameras.first() else {
        return Err(format!("variant `{}` has no camera", case.label));
    };
    let (width, samples) = if full {
        (VIEW_WIDTH, VIEW_SAMPLES)
    } else {
        (VIEW_WIDTH_QUICK, VIEW_SAMPLES_QUICK)
    };
    let scale = (width as f64 / cam.width.max(1) as f64).min(1.0);
    let mut model = case.model.clone().with_resolution_scale(scale);
    // The solved water column where it applies: several times less noise at a preview's
    // samples in a deep, sky-lit scene (docs/column.md).
    model.render.daylight = crate::model::Daylight::Auto;
    let dir = out.join("view");
    let opts = RenderOptions {
        samples: Some(samples),
        poses: Some(vec![0]),
        progress: false,
        resume: false,
    };
    crate::pipeline::run(&model, Backend::Native, &dir, &opts, Default::default())
        .map_err(|e| format!("the page's camera image: {e}"))?;
    // Auto-exposed: a deep scene's radiance is far below the preview's fixed exposure.
    let exr = dir.join(format!("{}.exr", model.image_name(0, 0)));
    crate::image::preview_png(&crate::image::read_exr(&exr)?)
}

/// The knobs of one `poser lesson` run.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Run the full form instead of the quick one.
    pub full: bool,
    /// Command-line `--set` overrides, applied to every variant last.
    pub sets: Vec<String>,
}

/// One compared case, loaded.
#[derive(Debug, Clone)]
pub struct Case {
    pub label: String,
    /// Directory-name-safe label.
    pub slug: String,
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub model: Model,
}

impl Case {
    /// The `poser evaluate` / `poser render` command line a user types to run this case alone.
    pub fn command(&self, verb: &str) -> String {
        let mut s = format!("poser {verb} {}", self.scene.display());
        s.push_str(&format!(" -o out/{}", self.slug));
        for set in &self.sets {
            s.push_str(&format!(" --set '{set}'"));
        }
        s
    }
}

/// What the lesson measured, per kind.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Results {
    Deformation { rows: Vec<deformation::Row> },
    Calibration { rows: Vec<calibration::Row> },
    Contrast { rows: Vec<contrast::Row> },
    Gsd { rows: Vec<gsd::Row> },
    Dive(dive::Results),
    Survey(dive::Results),
    Completeness { rows: Vec<completeness::Row> },
    Metrology { rows: Vec<metrology::Row> },
    Surface { rows: Vec<surface::Row> },
}

/// A "try next" line with the command that does it.
#[derive(Debug, Clone, Serialize)]
pub struct Next {
    pub text: String,
    pub command: String,
}

/// Everything the page shows.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub scene: String,
    pub title: String,
    pub question: String,
    pub setup: String,
    /// "What this shows" (`lesson.shows`).
    pub shows: String,
    /// One camera image of the scene ([`view`]): the label of its case and the PNG.
    pub view_label: String,
    #[serde(skip)]
    pub view_png: Vec<u8>,
    /// `"quick"` or `"full"`.
    pub form: &'static str,
    /// The form's `--set` overrides (`lesson.quick` or `lesson.full`).
    pub form_sets: Vec<String>,
    pub command: String,
    /// The quick form's run: the command of the full form, for the page to say how to get it.
    pub full_command: Option<String>,
    pub results: Results,
    pub try_next: Vec<Next>,
    pub seconds: f64,
}

/// A label as a file name: lowercase ASCII letters, digits and `_` only.
pub fn slug(label: &str) -> String {
    let mut s = String::new();
    for c in label.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.ends_with('_') {
            s.push('_');
        }
    }
    let s = s.trim_matches('_').to_string();
    if s.is_empty() { "variant".into() } else { s }
}

fn load(path: &Path, sets: &[String]) -> Result<Model, String> {
    crate::scene::load(path, sets)
        .map(|l| l.model)
        .map_err(|f| f.render())
}

/// Load the lesson scene and every variant with its overrides.
pub fn cases(scene: &Path, opts: &Options) -> Result<(Lesson, Vec<Case>), String> {
    let base = load(scene, &opts.sets)?;
    let Some(lesson) = base.lesson.clone() else {
        return Err(format!(
            "{} has no [lesson] table\n  help: `poser lesson` runs the scenes of \
             scenarios/lessons/ (see docs/lessons.md); use `poser evaluate` or `poser render` \
             for other scenes",
            scene.display()
        ));
    };
    let form = if opts.full {
        &lesson.full
    } else {
        &lesson.quick
    };
    let variants = if lesson.variants.is_empty() {
        vec![crate::model::LessonVariant {
            label: base.name.clone(),
            scene: None,
            set: vec![],
        }]
    } else {
        lesson.variants.clone()
    };
    let mut out: Vec<Case> = Vec::new();
    for v in variants {
        let path = v
            .scene
            .as_ref()
            .map(PathBuf::from)
            .unwrap_or_else(|| scene.to_path_buf());
        let sets: Vec<String> = form
            .iter()
            .chain(&v.set)
            .chain(&opts.sets)
            .cloned()
            .collect();
        let model = load(&path, &sets).map_err(|e| format!("variant `{}`:\n{e}", v.label))?;
        let mut slug = slug(&v.label);
        while out.iter().any(|c| c.slug == slug) {
            slug.push('_');
        }
        out.push(Case {
            label: v.label,
            slug,
            scene: path,
            sets,
            model,
        });
    }
    Ok((lesson, out))
}

/// One row per case, in the cases' order, stopping at the first error: how a kind whose cases
/// are independent (all but `deformation`, `dive` and `survey`) runs its `run_case`.
fn each_case<R>(
    cases: &[Case],
    run_case: impl Fn(&Case) -> Result<R, String>,
) -> Result<Vec<R>, String> {
    cases.iter().map(run_case).collect()
}

/// Run the lesson of `scene`, writing each variant's own outputs under `out`, and return
/// the report (the caller writes the page with [`html::write`]).
pub fn run(
    scene: &Path,
    out: &Path,
    opts: &Options,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Report, String> {
    let t0 = std::time::Instant::now();
    let (lesson, cases) = cases(scene, opts)?;
    progress("rendering the page's camera image");
    let view_png = match cases.first() {
        Some(c) => view(c, out, opts.full)?,
        None => Vec::new(),
    };
    let view_label = cases.first().map(|c| c.label.clone()).unwrap_or_default();
    let results = match lesson.kind {
        LessonKind::Deformation => Results::Deformation {
            rows: deformation::run(&cases, out, progress)?,
        },
        LessonKind::Calibration => Results::Calibration {
            rows: each_case(&cases, |c| calibration::run_case(c, out, progress))?,
        },
        LessonKind::Contrast => Results::Contrast {
            rows: each_case(&cases, |c| contrast::run_case(c, out, progress))?,
        },
        LessonKind::Gsd => Results::Gsd {
            rows: each_case(&cases, |c| gsd::run_case(c, out, progress))?,
        },
        LessonKind::Dive => Results::Dive(dive::run(&cases, out, false, opts.full, progress)?),
        LessonKind::Survey => Results::Survey(dive::run(&cases, out, true, opts.full, progress)?),
        LessonKind::Completeness => Results::Completeness {
            rows: each_case(&cases, |c| completeness::run_case(c, opts.full, progress))?,
        },
        LessonKind::Metrology => Results::Metrology {
            rows: each_case(&cases, |c| metrology::run_case(c, out, progress))?,
        },
        LessonKind::Surface => Results::Surface {
            rows: each_case(&cases, |c| surface::run_case(c, out, progress))?,
        },
    };
    let command_of = |full: bool| {
        let mut command = format!("poser lesson {} -o {}", scene.display(), out.display());
        if full {
            command.push_str(" --full");
        }
        for s in &opts.sets {
            command.push_str(&format!(" --set '{s}'"));
        }
        command
    };
    let command = command_of(opts.full);
    let try_next = lesson
        .try_next
        .iter()
        .map(|t| Next {
            text: t.text.clone(),
            command: format!(
                "poser lesson {} -o {}_next{} --set '{}'",
                scene.display(),
                out.display(),
                if opts.full { " --full" } else { "" },
                t.set
            ),
        })
        .collect();
    Ok(Report {
        scene: scene.display().to_string(),
        title: lesson.title,
        question: lesson.question,
        setup: lesson.setup,
        shows: lesson.shows,
        view_label,
        view_png,
        form: if opts.full { "full" } else { "quick" },
        form_sets: if opts.full {
            lesson.full.clone()
        } else {
            lesson.quick.clone()
        },
        command,
        full_command: (!opts.full).then(|| command_of(true)),
        results,
        try_next,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_file_names() {
        assert_eq!(slug("flat, pupil 3 cm"), "flat_pupil_3_cm");
        assert_eq!(slug("../../etc"), "etc");
        assert_eq!(slug("—"), "variant");
    }

    #[test]
    fn the_deformation_lesson_loads_its_variants_with_the_quick_form() {
        let (lesson, cases) = cases(
            Path::new("scenarios/lessons/flat_port_deformation.toml"),
            &Options::default(),
        )
        .unwrap();
        assert_eq!(lesson.kind, LessonKind::Deformation);
        assert!(cases.len() >= 3);
        for c in &cases {
            assert!(
                c.sets.iter().any(|s| s == "network.length=10"),
                "{:?}",
                c.sets
            );
            // The quick form stays small (observations mode costs ≈ 25 ms per image). With the
            // images spaced by the exact footprint through the flat port (more images than the
            // paraxial spacing gave), the obliques case has 1232 poses.
            assert!(
                c.model.poses.len() < 2000,
                "{}: {} poses",
                c.label,
                c.model.poses.len()
            );
        }
    }

    #[test]
    fn a_scene_without_a_lesson_is_refused_with_a_hint() {
        let e = cases(Path::new("scenarios/reef_strip.toml"), &Options::default()).unwrap_err();
        assert!(
            e.contains("no [lesson] table") && e.contains("help:"),
            "{e}"
        );
    }
}
