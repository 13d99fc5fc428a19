//! The invalid-scene corpus (`tests/invalid/*.toml`): every scene's full diagnostic text is
//! snapshotted with insta, and checked structurally so the test fails if diagnostics break:
//! each scene declares the codes it must produce (`# expect: E0100 …`), its `--set`
//! overrides (`# sets: a.b=c`), every error carries `file:line:column`, a source excerpt with
//! a caret and a `help:` line. Files named `warn_*` are valid with warnings; the rest must be
//! rejected. A proptest feeds garbled scenes and overrides and checks nothing panics.

use poser::scene::{self, Severity};
use std::path::{Path, PathBuf};

fn header(text: &str, key: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix(&format!("# {key}:")))
        .map(|s| s.trim().to_string())
        .collect()
}

/// Load a corpus scene (path relative to the crate) and return (rendered text, diagnostics).
fn run(rel: &Path) -> (String, Vec<poser::scene::Diagnostic>, bool) {
    let bytes = std::fs::read(rel).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    let sets = header(&text, "sets");
    match scene::load(rel, &sets) {
        Ok(l) => (l.render_warnings(), l.warnings, true),
        Err(f) => (f.render(), f.diagnostics, false),
    }
}

#[test]
fn invalid_corpus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut count = 0;
    insta::glob!("invalid/*.toml", |path| {
        count += 1;
        let rel: PathBuf = path.strip_prefix(root).unwrap().to_path_buf();
        let name = rel.file_name().unwrap().to_string_lossy().to_string();
        let text = String::from_utf8_lossy(&std::fs::read(&rel).unwrap()).to_string();
        let expect: Vec<String> = header(&text, "expect")
            .iter()
            .flat_map(|l| l.split_whitespace().map(str::to_string))
            .collect();
        assert!(!expect.is_empty(), "{name}: no `# expect:` header");
        let (rendered, diags, ok) = run(&rel);
        if name.starts_with("warn_") {
            assert!(ok, "{name} should be valid (with warnings):\n{rendered}");
        } else {
            assert!(!ok, "{name} should be rejected but loaded");
        }
        for code in &expect {
            assert!(
                diags.iter().any(|d| d.code == code),
                "{name}: expected diagnostic {code}, got:\n{rendered}"
            );
        }
        for d in &diags {
            let loc = d
                .location
                .as_deref()
                .unwrap_or_else(|| panic!("{name}: {} has no location:\n{}", d.code, d.rendered));
            // file:line:column with a path relative to the crate (stable snapshots).
            let parts: Vec<&str> = loc.rsplitn(3, ':').collect();
            assert_eq!(parts.len(), 3, "{name}: bad location {loc}");
            assert!(
                parts[0].parse::<usize>().is_ok() && parts[1].parse::<usize>().is_ok(),
                "{name}: {loc}"
            );
            assert!(
                !Path::new(parts[2]).is_absolute(),
                "{name}: absolute path in {loc}"
            );
            assert!(
                d.rendered.contains(&format!("┌─ {loc}")),
                "{name}: location missing from:\n{}",
                d.rendered
            );
            assert!(
                d.rendered.contains('^'),
                "{name}: no caret in:\n{}",
                d.rendered
            );
            assert!(
                d.rendered.contains("= help: "),
                "{name}: no help line in:\n{}",
                d.rendered
            );
            let tag = match d.severity {
                Severity::Error => format!("error[{}]", d.code),
                Severity::Warning => format!("warning[{}]", d.code),
            };
            assert!(
                d.rendered.starts_with(&tag),
                "{name}: rendered text does not start with {tag}"
            );
        }
        insta::assert_snapshot!(rendered);
    });
    assert!(count >= 40, "the corpus has only {count} scenes");
}

/// All errors are reported at once, not just the first.
#[test]
fn many_errors_are_reported_together() {
    let (_, diags, ok) = run(Path::new("tests/invalid/many_errors_at_once.toml"));
    assert!(!ok);
    assert!(
        diags
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .count()
            >= 5,
        "{diags:#?}"
    );
}

/// Diagnostics in an included file point into that file.
#[test]
fn include_errors_point_into_the_included_file() {
    let (_, diags, _) = run(Path::new(
        "tests/invalid/include_error_in_included_file.toml",
    ));
    let d = diags.iter().find(|d| d.code == "E0100").unwrap();
    assert_eq!(
        d.location.as_deref(),
        Some("tests/invalid/shared/bad_rig.toml:5:1")
    );
    assert!(d.rendered.contains("did you mean `convergence`?"));
}

/// An unknown key that a base file sets points into the base, says it is inherited, shows
/// the include line and names `{ unset = true }`; with that line the variant loads.
#[test]
fn an_inherited_key_is_located_in_the_base_and_can_be_unset() {
    let (_, diags, ok) = run(Path::new("tests/invalid/include_flat_key_under_dome.toml"));
    assert!(!ok);
    let d = diags.iter().find(|d| d.code == "E0100").unwrap();
    assert_eq!(
        d.location.as_deref(),
        Some("tests/invalid/shared/base_flat_port.toml:7:1")
    );
    assert!(d.message.contains("inherited from"), "{}", d.rendered);
    assert!(d.rendered.contains("included here"), "{}", d.rendered);
    assert!(
        d.help
            .as_deref()
            .unwrap()
            .contains("pupil_distance = { unset = true }"),
        "{}",
        d.rendered
    );
    // The variant that unsets it loads, as a dome, without the key.
    let l = scene::load(Path::new("tests/invalid/shared/dome_variant.toml"), &[]).unwrap();
    assert!(matches!(
        l.model.cameras[0].port,
        poser::model::Port::Dome { .. }
    ));
    // The same removal from the command line.
    let l = scene::load(
        Path::new("tests/invalid/include_flat_key_under_dome.toml"),
        &["camera.port.pupil_distance={ unset = true }".to_string()],
    )
    .unwrap();
    assert!(matches!(
        l.model.cameras[0].port,
        poser::model::Port::Dome { .. }
    ));
    // Unsetting a key nothing sets is an error at the key, on the command line too.
    let f = scene::load(
        Path::new("tests/invalid/shared/dome_variant.toml"),
        &["camera.port.tilt={ unset = true }".to_string()],
    )
    .err()
    .unwrap();
    let d = f.errors().find(|d| d.code == "E0021").unwrap();
    assert_eq!(d.location.as_deref(), Some("<command line>:1:19"));
}

/// An override with a misspelt path points at the command line with "did you mean".
#[test]
fn set_errors_point_at_the_command_line() {
    let (r, diags, _) = run(Path::new("tests/invalid/set_unknown_path.toml"));
    let d = diags.iter().find(|d| d.code == "E0100").unwrap();
    assert_eq!(d.location.as_deref(), Some("<command line>:1:13"));
    assert!(r.contains("did you mean `temperature`?"));
}

#[test]
fn an_absurd_survey_area_is_an_error_not_an_overflow() {
    // Found by `fuzz::garbled_scenes_never_panic` (a `1e308` spliced into a lawnmower's
    // length): the strip and image counts overflowed (`usize::MAX + 1`) instead of meeting
    // the pose limit's error. Each case must be refused with that error.
    for set in [
        "network.length=1e300",
        "network.width=1e300",
        "network.length=1e15",
    ] {
        let f = match poser::scene::load(Path::new("scenarios/reef_strip.toml"), &[set.to_string()])
        {
            Ok(_) => panic!("{set}: loaded"),
            Err(f) => f,
        };
        let text = f.render();
        assert!(text.contains("more than"), "{set}: {text}");
    }
}

mod fuzz {
    use super::*;
    use proptest::prelude::*;

    const PIECES: &[&str] = &[
        "=",
        "[",
        "]",
        "[[",
        "]]",
        "{",
        "}",
        "\"",
        ",",
        ".",
        "\n",
        "#",
        " ",
        "nan",
        "inf",
        "-1",
        "0",
        "1e308",
        "99999999999",
        "\"18 mm\"",
        "\"-3 deg\"",
        "\"1e400 m\"",
        "true",
        "[]",
        "{}",
        "type = \"dome\"",
        "include = [\"x.toml\"]",
        "µ",
        "ü",
        "\u{0}",
        "'",
        "'''",
    ];

    fn examples() -> Vec<String> {
        let mut v = Vec::new();
        for e in std::fs::read_dir("scenarios").unwrap() {
            let p = e.unwrap().path();
            if p.extension().and_then(|x| x.to_str()) == Some("toml") {
                v.push(std::fs::read_to_string(p).unwrap());
            }
        }
        v.sort();
        v
    }

    fn mutate(mut s: String, ops: &[(usize, usize, usize)]) -> String {
        for &(kind, pos, piece) in ops {
            let mut at = pos % (s.len() + 1);
            while !s.is_char_boundary(at) {
                at -= 1;
            }
            match kind % 3 {
                0 => s.insert_str(at, PIECES[piece % PIECES.len()]),
                1 => {
                    let mut end = (at + 1 + piece % 40).min(s.len());
                    while !s.is_char_boundary(end) {
                        end += 1;
                    }
                    s.replace_range(at..end, "");
                }
                _ => {
                    // Replace the next number with a piece.
                    if let Some(off) = s[at..].find(|c: char| c.is_ascii_digit()) {
                        let st = at + off;
                        let en = s[st..]
                            .find(|c: char| !c.is_ascii_digit() && c != '.')
                            .map(|e| st + e)
                            .unwrap_or(s.len());
                        s.replace_range(st..en, PIECES[piece % PIECES.len()]);
                    }
                }
            }
        }
        s
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 160, failure_persistence: None, .. ProptestConfig::default() })]
        #[test]
        fn garbled_scenes_never_panic(
            which in 0usize..3,
            ops in proptest::collection::vec((0usize..3, 0usize..100_000, 0usize..1000), 1..6),
            set_key in "[a-z_.0-9]{0,24}",
            set_val in "[ -~]{0,12}",
        ) {
            let ex = examples();
            let text = mutate(ex[which % ex.len()].clone(), &ops);
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("scene.toml");
            std::fs::write(&p, text).unwrap();
            let sets = vec![format!("{set_key}={set_val}")];
            match scene::load(&p, &sets) {
                Ok(l) => { let _ = l.render_warnings(); }
                Err(f) => {
                    prop_assert!(f.errors().count() > 0);
                    for d in f.errors() {
                        prop_assert!(!d.rendered.is_empty());
                    }
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, .. ProptestConfig::default() })]
        /// Arbitrary text (TOML-ish alphabet) as a whole scene, and arbitrary unit strings.
        #[test]
        fn arbitrary_text_never_panics(text in "[a-z_.=\\[\\]{}\",0-9 \n#-]{0,300}", q in "\\PC{0,20}") {
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("scene.toml");
            std::fs::write(&p, &text).unwrap();
            let _ = scene::load(&p, &[]);
            for d in poser::units::Dim::ALL {
                let _ = poser::units::parse_quantity(&q, *d);
                let _ = poser::units::parse_vector(&q, *d);
            }
        }
    }
}
