//! The scene format: its types (each table a struct, each key a field spelled once, the
//! constant every reader and importer names it by: [`types`]) and what is generated from them
//! (the JSON Schema and `docs/format.md`: [`docgen`]).

pub mod docgen;
pub mod types;

pub use docgen::{UNSET_DEF, format_markdown, keys_by_path, schema_json};
