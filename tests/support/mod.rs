//! The one test-support module of the integration tests (`mod support;` in each test file).
//!
//! | module | what |
//! |---|---|
//! | [`model`] | the one model builder: cameras, ports, water, planes, lights, a minimal model |
//! | [`canonical`] | the canonical scenes of `tests/canonical/`, the analytic radiance oracle, and the geometry / radiometry checks every backend runs |
//! | [`lesson`] | running a lesson's quick form; its page in headless Chromium |
//! | [`mitsuba`], [`blender`], [`native`], [`plan`] | each suite's preset models, built with [`model`] |
#![allow(dead_code)]

pub mod blender;
pub mod canonical;
pub mod lesson;
pub mod mitsuba;
pub mod model;
pub mod native;
pub mod plan;
