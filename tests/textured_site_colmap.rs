//! COLMAP on the shipped textured model (issue 36's done-when row): the quick form of
//! `poser bench images` on `scenarios/sites/textured_bommie.toml` (the model's OBJ + MTL +
//! JPEG rendered by the native backend, 28 nadir images of 320 × 240 px over the bommie's
//! 1.6 × 1.6 m centre, through the default camera, then the real pycolmap's SIFT, matching,
//! mapping and a self-calibrating bundle adjustment; `src/bench/images.rs`). At least 95 % of
//! the images must be registered with a mean reprojection error under half a pixel. (A nadir
//! block does not determine the focal length, docs/bench/images.md; with a 30° oblique pass
//! two of the four oblique strips were dropped, 43 of 56 images, docs/lessons.md.)

use poser::bench::images::{CASES, run_case};
use std::path::Path;

#[test]
fn colmap_registers_the_survey_of_the_shipped_textured_model() {
    if let Err(e) = poser::backend::python::require_module("pycolmap") {
        panic!("this test runs the real COLMAP: {e}");
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let case = CASES
        .iter()
        .find(|c| c.scene.ends_with("textured_bommie.toml"))
        .expect("the textured model is a case of `poser bench images`");
    let out = tempfile::tempdir().unwrap();
    let row = run_case(root, case, true, true, out.path()).unwrap();
    eprintln!(
        "{}",
        poser::bench::images::table(std::slice::from_ref(&row))
    );
    assert!(row.failure.is_none(), "{:?}", row.failure);
    assert_eq!(row.images, 28);
    assert!(
        row.share >= 0.95,
        "{} of {} images registered",
        row.registered,
        row.images
    );
    assert!(row.reprojection_px < 0.5, "{} px", row.reprojection_px);
    // COLMAP as it ships, on the same JPEGs (`poser bench images --stock`): it runs, and reads
    // the focal length from their EXIF (the in-air value; docs/bench/images.md for its result).
    let stock = row.stock.as_ref().expect("the stock run");
    assert!(stock.failure.is_none(), "{:?}", stock.failure);
    let cam = &poser::scene::load(&root.join(case.scene), &[])
        .unwrap()
        .model
        .cameras[0];
    let f_air = cam.fx * case.scale;
    let exif = stock.exif_focal_px.expect("the EXIF focal length");
    assert!(
        (exif / f_air - 1.0).abs() < 0.01,
        "EXIF {exif} px, f_air {f_air} px"
    );
}
