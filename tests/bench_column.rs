//! `poser bench column` on a tiny reef_strip (24 × 16 px): the column lights the scene as the
//! brute-force random walks do, within the bench's 2 % and the renders' noise; a scene without
//! water is named with the reason. No Python.

use poser::bench::column::{BOUND, Options, run, table};

#[test]
fn the_column_agrees_with_the_random_walks_on_reef_strip() {
    let tmp = tempfile::tempdir().unwrap();
    let mut opts = Options::new(true, env!("CARGO_BIN_EXE_poser").into(), tmp.path().into());
    opts.only = Some("reef_strip".into());
    let rows = run(std::path::Path::new("."), &opts).unwrap();
    let t = table(&rows);
    assert_eq!(rows.len(), 1, "{t}");
    let r = &rows[0];
    assert_eq!(r.not_applied, None, "{t}");
    assert_eq!((r.width, r.height, r.samples), (24, 16, 64), "{t}");
    // Measured at 5 % of full size and 256 spp: +1.2 / +1.6 / +1.8 % (± 0.1). Without the
    // scene's backdrop the random walks lose the light the sea surface returns from the water
    // past the 12 × 9 m seabed, and blue is 6.4 % off: this fails then.
    for (c, d) in r.difference().iter().enumerate() {
        let (d, se) = d.unwrap_or_else(|| panic!("channel {c} is dark: {t}"));
        assert!(se < 0.01, "channel {c}: standard error {se}: {t}");
        assert!(
            d.abs() <= BOUND + 3.0 * se,
            "channel {c}: {d:+} ± {se}: {t}"
        );
    }
}

#[test]
fn a_scene_the_column_does_not_apply_to_says_why() {
    let tmp = tempfile::tempdir().unwrap();
    let mut opts = Options::new(true, env!("CARGO_BIN_EXE_poser").into(), tmp.path().into());
    opts.only = Some("in_air".into());
    let rows = run(std::path::Path::new("."), &opts).unwrap();
    assert_eq!(rows.len(), 1);
    let why = rows[0].not_applied.as_deref().unwrap_or_default();
    assert_eq!(why, "the scene has no water");
    assert!(table(&rows).contains("does not apply"));
}
