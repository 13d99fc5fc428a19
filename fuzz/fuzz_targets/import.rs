//! libFuzzer target `import`: see `fuzz/checks.rs` for the property it checks. Not in
//! `fuzz/run.sh`'s default list (CI time); run it with `fuzz/run.sh SECONDS import`.
#![no_main]
#[path = "../checks.rs"]
mod checks;
libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::import(data));
