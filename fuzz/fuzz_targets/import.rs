//! libFuzzer target `import`: see `fuzz/checks.rs` for the property it checks, and
//! `docs/fuzzing.md` for what it found.
#![no_main]
#[path = "../checks.rs"]
mod checks;
libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::import(data));
