//! poser — simulate underwater photogrammetry surveys.
//!
//! Structured like a compiler: a front end ([`scene`]: TOML scene format → diagnostics),
//! one resolved [`model`], and several back ends ([`render`] native, [`backend::mitsuba`],
//! [`backend::blender`]), with the optics core ([`optics`]) as the geometric truth that
//! [`truth`] and every back end are checked against, and [`plan`] for survey and dive planning.

pub mod backend;
pub mod cli;
pub mod compare;
pub mod io;
pub mod mesh;
pub mod model;
pub mod optics;
pub mod plan;
pub mod render;
pub mod rng;
pub mod scene;
pub mod targets;
pub mod texture;
pub mod truth;
pub mod units;
