//! The scene format front end: TOML scene files (with includes and `--set` overrides) →
//! diagnostics → the resolved [`Model`](crate::model::Model).
use crate::model::Model;
use std::path::Path;

/// A successfully loaded scene, with its warnings.
pub struct Loaded {
    pub model: Model,
    pub warnings: Vec<String>,
}

impl Loaded {
    pub fn render_warnings(&self) -> String {
        self.warnings.join("")
    }
}

/// A scene that failed to load; `render` gives the full diagnostic text.
pub struct Failure {
    pub diagnostics: Vec<String>,
}

impl Failure {
    pub fn render(&self) -> String {
        self.diagnostics.join("")
    }
}

pub fn load(_path: &Path, _sets: &[String]) -> Result<Loaded, Failure> {
    Err(Failure {
        diagnostics: vec!["error: scene loading is not implemented yet\n".into()],
    })
}
