//! libFuzzer target `project_csv`: see `fuzz/checks.rs` for the property it checks.
#![no_main]
#[path = "../checks.rs"]
mod checks;
libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::project_csv(data));
