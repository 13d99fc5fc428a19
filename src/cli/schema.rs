//! `poser schema`: write (or `--check`) the JSON Schema of the scene format
//! (`schema/poser-scene.schema.json`) and the generated format reference
//! (`docs/format.md`), both from the Rust types in `scene::format`.
use super::CliError;
use std::path::Path;

/// File name of the schema inside the schema directory.
pub const SCHEMA_FILE: &str = "poser-scene.schema.json";
/// File name of the reference inside the docs directory.
pub const DOCS_FILE: &str = "format.md";

pub fn run(out: &Path, docs: &Path, check: bool) -> Result<(), CliError> {
    let files = [
        (out.join(SCHEMA_FILE), crate::scene::format::schema_json()),
        (
            docs.join(DOCS_FILE),
            crate::scene::format::format_markdown(),
        ),
    ];
    if check {
        let mut stale = Vec::new();
        for (p, want) in &files {
            match std::fs::read_to_string(p) {
                Ok(have) if have == *want => {}
                _ => stale.push(p.display().to_string()),
            }
        }
        if stale.is_empty() {
            println!(
                "up to date: {}",
                files
                    .iter()
                    .map(|f| f.0.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            return Ok(());
        }
        return Err(CliError::Failed(format!(
            "stale: {} — run `poser schema` and commit the result",
            stale.join(", ")
        )));
    }
    for (p, text) in &files {
        if let Some(dir) = p.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|e| CliError::Failed(format!("{}: {e}", dir.display())))?;
        }
        crate::io::write_atomic(p, text.as_bytes())
            .map_err(|e| CliError::Failed(format!("{}: {e}", p.display())))?;
        println!("wrote {}", p.display());
    }
    Ok(())
}
