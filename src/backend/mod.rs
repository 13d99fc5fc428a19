//! The back ends, as peers: each takes the resolved [`Model`] and renders it (or compiles it for
//! an outside renderer). None calls another; the commands, `compare` and `bench` reach them
//! through the one [`Backend`] enum here.
//!
//! | backend | module | compile | render | needs |
//! |---|---|---|---|---|
//! | [`Backend::Native`] | [`native`] | — (renders directly) | poser's CPU path tracer | nothing |
//! | [`Backend::Mitsuba`] | [`mitsuba`] | Mitsuba 3 XML + meshes | the real Mitsuba 3 (`scalar_rgb`) | Python with `mitsuba` ([`python`]) |
//! | [`Backend::Blender`] | [`blender`] | a self-contained bpy script | Blender/Cycles (`bpy`) | Python with `bpy` ([`python`]) |
//!
//! Both `compile` and `render` first validate the model ([`Model::validate`]: finite numbers,
//! rotations, positive sizes), so a model built in Rust (the bench's, the Python module's) is
//! checked as the front end checks a scene. Backends write images only; the ground truth beside them (`OUT/truth/`) is written once by
//! the `render` command, the same for every backend.

pub mod blender;
pub mod mitsuba;
pub mod native;
pub mod python;

use crate::model::Model;
use std::path::{Path, PathBuf};

/// One of the render backends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Backend {
    /// poser's own CPU path tracer (no Python).
    Native,
    /// Mitsuba 3 (XML scene; renders with the `mitsuba` Python package).
    Mitsuba,
    /// Blender/Cycles (bpy script; renders with the `bpy` Python package).
    Blender,
}

/// What a backend can do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    /// Writes a scene for an outside renderer (`poser compile`).
    pub compiles: bool,
    /// Needs the pinned Python environment ([`python`]).
    pub needs_python: bool,
}

impl Backend {
    /// Every backend, in the order reports list them.
    pub const ALL: [Backend; 3] = [Backend::Native, Backend::Mitsuba, Backend::Blender];

    /// The name users type (`native`, `mitsuba`, `blender`).
    pub fn name(self) -> &'static str {
        match self {
            Backend::Native => "native",
            Backend::Mitsuba => "mitsuba",
            Backend::Blender => "blender",
        }
    }

    /// The backend of a name, or an error listing the known names.
    pub fn parse(name: &str) -> Result<Backend, String> {
        Backend::ALL
            .into_iter()
            .find(|b| b.name() == name)
            .ok_or_else(|| {
                let known: Vec<&str> = Backend::ALL.iter().map(|b| b.name()).collect();
                format!("unknown backend `{name}` (known: {})", known.join(", "))
            })
    }

    pub fn capabilities(self) -> Capabilities {
        match self {
            Backend::Native => Capabilities {
                compiles: false,
                needs_python: false,
            },
            Backend::Mitsuba | Backend::Blender => Capabilities {
                compiles: true,
                needs_python: true,
            },
        }
    }

    /// What this backend cannot express in `model`, as the message a user reads; `Ok` when
    /// it can render the scene as modelled. (Refusals that need the backend's own geometry,
    /// such as Blender's caustics, stay in the backend.)
    pub fn refuse(self, model: &Model) -> Result<(), String> {
        if self == Backend::Native {
            return Ok(());
        }
        if model.any_above_surface() {
            return Err(format!(
                "the {} backend does not model a camera in the air looking through the sea \
                 surface (this network has images taken from above the water); render it with \
                 `--backend native`, whose camera rays refract at the flat or wavy surface",
                self.name()
            ));
        }
        for c in &model.cameras {
            if let crate::model::Port::Flat { outer_layers, .. } = &c.port
                && !outer_layers.is_empty()
            {
                return Err(format!(
                    "camera `{}`: the {} backend does not model multi-layer flat ports yet \
                     ({} glass layers); render it with `--backend native`, whose camera rays \
                     and ground truth refract through every layer",
                    c.name,
                    self.name(),
                    1 + outer_layers.len()
                ));
            }
        }
        Ok(())
    }

    /// Write the scene for the outside renderer into `out` (`poser compile`).
    pub fn compile(self, model: &Model, out: &Path) -> Result<(), String> {
        model.validate().map_err(|e| e.to_string())?;
        self.refuse(model)?;
        match self {
            Backend::Native => Err(
                "the native backend renders directly; use `poser render` (compile targets: mitsuba, blender)"
                    .into(),
            ),
            Backend::Mitsuba => mitsuba::compile(model, out),
            Backend::Blender => blender::compile(model, out),
        }
    }

    /// Render the selected poses of `model` into `out` (images only; see the module doc).
    pub fn render(
        self,
        model: &Model,
        out: &Path,
        opts: &RenderOptions,
    ) -> Result<RenderReport, String> {
        model.validate().map_err(|e| e.to_string())?;
        self.refuse(model)?;
        match self {
            Backend::Native => native::render(model, out, opts),
            Backend::Mitsuba => mitsuba::render(model, out, opts),
            Backend::Blender => blender::render(model, out, opts),
        }
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Backend, String> {
        Backend::parse(s)
    }
}

/// Options common to every backend's `render`.
#[derive(Debug, Clone, Default)]
pub struct RenderOptions {
    /// Override of the scene's samples per pixel.
    pub samples: Option<u32>,
    /// Render only these rig-pose indices (all when `None`).
    pub poses: Option<Vec<usize>>,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Native: skip the images that `OUT/render-manifest.json` records as finished with the
    /// same model and samples, and whose files still have the recorded hashes.
    pub resume: bool,
}

impl RenderOptions {
    /// The pose indices to render for a model with `n` poses.
    pub fn pose_indices(&self, n: usize) -> Vec<usize> {
        match &self.poses {
            Some(p) => p.iter().copied().filter(|&i| i < n).collect(),
            None => (0..n).collect(),
        }
    }
}

/// What a render produced.
#[derive(Debug, Clone, Default)]
pub struct RenderReport {
    /// Linear EXR images written, one per (pose, camera).
    pub images: Vec<PathBuf>,
    /// Wall-clock seconds of the whole render.
    pub seconds: f64,
}
