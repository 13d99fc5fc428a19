//! The native renderer: poser's own CPU path tracer (default backend, no Python).
pub mod scene;

use crate::backend::{RenderOptions, RenderReport};
use crate::model::Model;
use std::path::Path;

pub fn render(_model: &Model, _out: &Path, _opts: &RenderOptions) -> Result<RenderReport, String> {
    Err("the native renderer is not implemented yet".into())
}
