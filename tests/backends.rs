//! The full tier's own suites, one binary (`cargo test --test backends`): the ones that run
//! the real Mitsuba 3, Blender/Cycles, COLMAP, OpenCV and headless Chromium (`./test.sh` sets
//! them up), and the native renderer's slow checks, which need no Python but minutes of CPU
//! that would make the fast tier a minute slower: its statistics against itself and its
//! brute-force transport (`native_column_convergence`, `native_convergence`) and `poser bench
//! sensor` (`bench_sensor`). Each module is one file of `tests/`; run one with
//! `cargo test --test backends NAME::`.

#[allow(dead_code)]
mod support;

mod bench_render_backends;
mod bench_sensor;
mod blender;
mod compare_cli;
mod cross_backend;
mod evaluate;
mod exif_pycolmap;
mod filled_backends;
mod glass_backends;
mod gltf_view;
mod import_blender;
mod import_cbox;
mod import_mitsuba_data;
mod import_verify;
mod lesson;
mod lesson_completeness_page;
mod lesson_contrast;
mod lesson_dive;
mod lesson_metrology;
mod lesson_surface;
mod mitsuba_render;
mod native_column_convergence;
mod native_convergence;
mod opencv_export;
mod pack_python;
mod scenario_parity;
mod slurm;
mod surface_view;
mod target_parity;
mod textured_mesh_backends;
mod textured_site_colmap;
mod textures_cross_backend;
mod truth_pycolmap;
