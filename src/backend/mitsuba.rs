//! Mitsuba 3 backend: compile the model to XML (quick-xml) and render with the `mitsuba` package.
use super::{RenderOptions, RenderReport};
use crate::model::Model;
use std::path::Path;

pub fn compile(_model: &Model, _out: &Path) -> Result<(), String> {
    Err("the Mitsuba backend is not implemented yet".into())
}

pub fn render(_model: &Model, _out: &Path, _opts: &RenderOptions) -> Result<RenderReport, String> {
    Err("the Mitsuba backend is not implemented yet".into())
}
