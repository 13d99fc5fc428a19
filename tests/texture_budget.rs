//! The per-scene texel budget of baked textures (`poser::texture::bake::scene_plan`): a scene
//! whose wanted textures exceed it is coarsened by one factor to fit, objects with a set
//! `texel` keep it, and the plan is what the bake produces.

use crate::support;
use poser::texture::bake::{TEXEL_BUDGET, bake_object, scene_plan};

fn load(rel: &str) -> poser::model::Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    poser::scene::load(&path, &[])
        .unwrap_or_else(|f| panic!("{rel}: {}", f.render()))
        .model
}

fn total(plans: &[Option<poser::texture::bake::ObjectPlan>]) -> u64 {
    plans
        .iter()
        .flatten()
        .map(|p| p.width as u64 * p.height as u64)
        .sum()
}

#[test]
fn reef_strip_is_coarsened_by_one_factor_to_fit_the_budget() {
    let model = load("scenarios/reef_strip.toml");
    let plans = scene_plan(&model).unwrap();
    let n = total(&plans);
    assert!(n <= TEXEL_BUDGET, "{n} texels");
    // 1 % steps of the factor: the budget is nearly used up.
    assert!(n as f64 > 0.9 * TEXEL_BUDGET as f64, "{n} texels");
    let factors: Vec<f64> = plans.iter().flatten().map(|p| p.start / p.wanted).collect();
    assert_eq!(factors.len(), 2);
    assert!(factors[0] > 1.5, "{factors:?}");
    assert_eq!(factors[0], factors[1]);
    for p in plans.iter().flatten() {
        assert!(p.limit.contains("budget"), "{}", p.limit);
    }
}

#[test]
fn a_set_texel_is_kept_and_the_others_share_the_rest() {
    let mut model = load("scenarios/reef_strip.toml");
    let auto = scene_plan(&model).unwrap();
    // Boulders at a set 2.5 mm texel (about 9.6 M texels, more than the 6.2 M they had): kept;
    // the seabed gets what is left, so it is coarser than before.
    model.objects[1].material.texel = Some(0.0025);
    let plans = scene_plan(&model).unwrap();
    let boulders = plans[1].as_ref().unwrap();
    assert_eq!(boulders.texel, 0.0025);
    assert!(boulders.limit.is_empty(), "{}", boulders.limit);
    let seabed = plans[0].as_ref().unwrap();
    assert!(seabed.texel > auto[0].as_ref().unwrap().texel);
    assert!(total(&plans) <= TEXEL_BUDGET);
    // A set texel beyond the budget is still kept; the others keep a quarter of the budget.
    model.objects[1].material.texel = Some(0.001);
    let plans = scene_plan(&model).unwrap();
    // (Here only the 8192-a-side cap coarsens it, by 1 %.)
    let b = plans[1].as_ref().unwrap();
    assert_eq!(b.start, 0.001);
    assert!(b.texel < 0.00102, "{}", b.texel);
    assert!(
        b.limit.contains("a side") && !b.limit.contains("budget"),
        "{}",
        b.limit
    );
    let s = plans[0].as_ref().unwrap();
    let seabed = s.width as u64 * s.height as u64;
    assert!(
        seabed <= TEXEL_BUDGET / 4 && seabed > TEXEL_BUDGET / 5,
        "{seabed}"
    );
}

#[test]
fn the_bake_follows_the_plan() {
    let model = load("tests/textures/seabed.toml");
    let plans = scene_plan(&model).unwrap();
    assert!(total(&plans) <= TEXEL_BUDGET);
    for (i, p) in plans.iter().enumerate() {
        let Some(p) = p else { continue };
        let b = bake_object(&model, i).unwrap().unwrap();
        assert_eq!((b.texture.width, b.texture.height), (p.width, p.height));
        assert_eq!(b.texel, p.texel);
        assert_eq!(b.coarsened(), p.texel > p.wanted * 1.000_001);
    }
}

#[test]
fn a_coarsened_texture_is_warned_of_where_it_is_rendered_and_only_told_elsewhere() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let poser = |args: &[&str]| support::textured::poser_in(args, root);
    // reef_strip's textures are coarsened to fit the budget (the test above). Commands that
    // render nothing do not warn of it; `explain` tells it as information; a render warns (at
    // 0.35 of full size the texture is still coarsened ×1.24, at half size ×1.8; at a few per
    // cent of it, nothing is).
    let scene = "scenarios/reef_strip.toml";
    let (ok, text) = poser(&["validate", scene]);
    assert!(ok && !text.to_lowercase().contains("coarsened"), "{text}");
    let (ok, text) = poser(&["explain", scene]);
    assert!(ok && text.contains("coarsened ×"), "{text}");
    assert!(
        !text
            .lines()
            .any(|l| l.starts_with("warning") && l.to_lowercase().contains("coarsened")),
        "{text}"
    );
    let out = tempfile::tempdir().unwrap();
    let (ok, text) = poser(&[
        "render",
        scene,
        "-o",
        out.path().to_str().unwrap(),
        "--poses",
        "0",
        "--scale",
        "0.35",
        "--samples",
        "1",
        "--skip-truth",
    ]);
    assert!(ok, "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("warning:") && l.contains("COARSENED")),
        "{text}"
    );
}
