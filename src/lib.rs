//! poser — simulate underwater photogrammetry surveys.
//!
//! Structured like a compiler: a front end ([`scene`]: TOML scene format → diagnostics), one
//! resolved [`model`], and peer back ends ([`backend`]: native, Mitsuba, Blender, behind one
//! [`backend::Backend`]), with the optics core ([`optics`], pure math, the `poser-optics`
//! crate) as the geometric truth that [`truth`] and every back end are checked against, the
//! [`geometry`] service (meshes, targets, BVH) shared by the truth, the planner and the native
//! renderer, [`plan`] for survey and dive planning, [`compare`] / [`bench`] driving the back
//! ends from outside, and [`export`] writing the model for other tools (a glTF preview of the
//! whole scene); [`pipeline`] runs render → truth → camera for every command that makes
//! images. The [`cli`] sits on top and nothing in the library imports it: [`explain`]
//! (the model for a person), [`points`] (the one point-list parser) and [`image`] (linear
//! images, the EXR reader) serve the CLI, the Python module and the fuzz targets alike;
//! [`progress`] reports long jobs on stderr, with or without a terminal.

// `!(x > 0.0)` is how poser rejects NaN together with the values out of range.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod backend;
pub mod bench;
pub mod cli;
pub mod column;
pub mod compare;
pub mod evaluate;
pub mod explain;
pub mod export;
pub mod geometry;
pub mod image;
pub mod import;
pub mod io;
pub mod lesson;
pub mod noise;
pub mod pack;
pub mod pipeline;
pub mod plan;
pub mod points;
pub mod progress;
pub mod scene;
pub mod sensor;
pub mod slurm;
pub mod texture;
pub mod truth;
pub mod units;

/// The resolved model, its own crate (`crates/poser-model`) on the optics only: the
/// compiler keeps it free of the scene format, the back ends and the CLI.
pub use poser_model as model;
/// The optics core, its own crate (`crates/poser-optics`): pure math on its own value types,
/// which the compiler keeps free of the scene, the model and the back ends.
pub use poser_optics as optics;
/// SplitMix64, the one random stream (it lives in the optics crate, which uses it too).
pub use poser_optics::rng;
