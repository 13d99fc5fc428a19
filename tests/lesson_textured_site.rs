//! The textured-model lesson (`scenarios/sites/textured_bommie.toml`, kind `completeness`) on
//! its quick form, and the shipped model it stands on (`scenarios/sites/assets/
//! textured_bommie/`: OBJ + MTL + JPEG written by `src/geometry/bommie.rs`, which checks the
//! files byte for byte). No Python: this runs in the fast tier; COLMAP on the model's rendered
//! images is `textured_site_colmap.rs` (full tier).
//!
//! Bands: the model is read with its texture (the OBJ's triangles, the MTL's `map_Kd` image);
//! its surface is the whole 4 × 4 m relief, more than its 16 m² footprint; shares lie in
//! [0, 1], completeness below "seen at all"; an oblique pass adds what the nadir strips miss
//! (the model's edges and the bommie's flanks), and a dome of rings around the bommie covers
//! less of the whole model than the lawnmower over it.

use crate::support::lesson::row;
use std::path::Path;
use std::process::Command;

const SCENE: &str = "scenarios/sites/textured_bommie.toml";

#[test]
fn the_lesson_reads_the_shipped_model_with_its_texture() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = poser::scene::load(&root.join(SCENE), &[])
        .unwrap_or_else(|f| panic!("{}", f.render()))
        .model;
    let k = model
        .objects
        .iter()
        .position(|o| o.name == "bommie")
        .unwrap();
    let prepared = poser::texture::mapped::prepare_object(&model, k)
        .unwrap()
        .expect("the bommie is a textured mesh");
    assert_eq!(
        prepared.mesh().triangles.len() as u64,
        poser::geometry::bommie::SHIPPED_TRIANGLES
    );
    let m = &prepared.plan.materials[0];
    let side = poser::geometry::bommie::SHIPPED_TEXTURE;
    assert_eq!(m.size, (side, side), "the MTL's map_Kd image");
    assert!(
        matches!(
            prepared.looks.first(),
            Some(poser::texture::mapped::Look::Image(_))
        ),
        "the model's albedo is its image"
    );
}

#[test]
fn completeness_of_the_textured_model_follows_the_networks() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bommie");
    let o = Command::new(env!("CARGO_BIN_EXE_poser"))
        .args(["lesson", SCENE, "-o", out.to_str().unwrap(), "--quiet"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run poser");
    assert!(
        o.status.success(),
        "poser lesson failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lesson.json")).unwrap()).unwrap();
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    for r in json["results"]["rows"].as_array().unwrap() {
        let (seen, comp) = (f(&r["seen"]), f(&r["completeness"]));
        assert!(
            (0.0..=1.0).contains(&seen) && (0.0..=1.0).contains(&comp),
            "{r}"
        );
        assert!(comp <= seen, "{r}");
        // The whole relief: more than its 4 × 4 m footprint, less than 1.2 times it.
        let area = f(&r["area_m2"]);
        assert!((16.0..19.2).contains(&area), "{r}");
    }
    let nadir = row(&json, "nadir lawnmower");
    let obl = row(&json, "lawnmower with 30° obliques");
    let rings = row(&json, "dome of rings");
    let c = |r: &serde_json::Value| f(&r["completeness"]);
    assert_eq!(f(&obl["images"]), 2.0 * f(&nadir["images"]), "{obl}");
    assert!(c(obl) > c(nadir) + 0.1, "{nadir}\n{obl}");
    assert!(c(nadir) > 0.6, "{nadir}");
    assert!(c(rings) < c(nadir) - 0.2, "{rings}\n{nadir}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for r in [nadir, obl, rings] {
        let k = poser::lesson::slug(r["label"].as_str().unwrap());
        let cell = format!("data-key=\"{k}.completeness\">{:.1}</td>", 100.0 * c(r));
        assert!(html.contains(&cell), "{cell}");
    }
}
