//! The fast tier of the integration tests, one binary (plain `cargo test`, no Python): each
//! module is one suite, a file of `tests/`. Run one with `cargo test --test suite NAME::`.
//! One binary is linked once, where one binary per file was linked fifty times (most of the
//! tier's build time).

#[allow(dead_code)]
mod support;

mod architecture;
mod bench_column;
mod bench_mesh;
mod bench_render;
mod blender_snapshots;
mod canonical_native;
mod compare_targets;
mod compile_out;
mod crop;
mod diagnostics;
mod dive_advice;
mod dive_cli;
mod dive_export;
mod dive_lost_gas;
mod dive_oxygen;
mod dive_planned;
mod dive_repetitive;
mod dive_roles;
mod dive_safety;
mod dive_trimix;
mod docs_numbers;
mod error_index;
mod evaluate_images_folder;
mod evaluate_precheck;
mod filled_objects;
mod fuzz_replay;
mod georef_mesh;
mod glass_objects;
mod gltf_export;
mod hostile_input;
mod hostile_names;
mod housing_shadow;
mod import_mitsuba;
mod import_mitsuba_files;
mod import_mitsuba_glass;
mod lesson_completeness;
mod lesson_textured_site;
mod mitsuba_compile;
mod model_valid;
mod native_amphora;
mod native_caustics;
mod native_column;
mod native_render;
mod optics_cli;
mod optics_fast_path;
mod optics_hard_cases;
mod optics_proptest;
mod optics_roundtrip;
mod pack;
mod plan_deco;
mod plan_dive;
mod plan_scenario;
mod plan_spacing;
mod plan_survey;
mod points_file;
mod port_layers;
mod render_resume;
mod scenarios;
mod seabed_relief;
mod sensor;
mod texture_budget;
mod textured_mesh;
mod truth;
