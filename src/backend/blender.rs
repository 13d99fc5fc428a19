//! Blender backend: compile the model to one self-contained bpy script and render with Cycles.
use super::{RenderOptions, RenderReport};
use crate::model::Model;
use std::path::Path;

pub fn compile(_model: &Model, _out: &Path) -> Result<(), String> {
    Err("the Blender backend is not implemented yet".into())
}

pub fn render(_model: &Model, _out: &Path, _opts: &RenderOptions) -> Result<RenderReport, String> {
    Err("the Blender backend is not implemented yet".into())
}
