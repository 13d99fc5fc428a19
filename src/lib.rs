//! poser — simulate underwater photogrammetry surveys.
//!
//! Structured like a compiler: a front end ([`scene`]: TOML scene format → diagnostics),
//! one resolved [`model`], and several back ends ([`render`] native, [`backend::mitsuba`],
//! [`backend::blender`]), with the optics core ([`optics`]) as the geometric truth that
//! [`truth`] and every back end are checked against, and [`plan`] for survey and dive planning.

pub mod backend;
pub mod bench;
pub mod cli;
pub mod compare;
pub mod geometry;
pub mod io;
pub mod model;
pub mod optics;
pub mod plan;
pub mod rng;
pub mod scene;
pub mod truth;
pub mod units;
