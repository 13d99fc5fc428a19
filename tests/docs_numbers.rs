//! The README's deformation table is the bench's measurement, not typed in: each row must
//! match `docs/bench/evaluate.json` (written by `poser bench evaluate --quick --json …`).

#[test]
fn readme_deformation_table_matches_the_bench_report() {
    let readme = std::fs::read_to_string("README.md").unwrap();
    let bench: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/evaluate.json").unwrap())
            .unwrap();
    let rows = [
        ("| in air |", "in_air"),
        (
            "| flat port, pupil 1 mm from the glass |",
            "flat_port_deformation_pupil_1mm",
        ),
        ("| flat port, pupil 3 cm |", "flat_port_deformation"),
        (
            "| flat port, pupil 10 cm |",
            "flat_port_deformation_pupil_10cm",
        ),
        (
            "| flat port, pupil 3 cm, with an oblique pass |",
            "flat_port_deformation_obliques",
        ),
        ("| centred dome |", "flat_port_deformation_dome"),
    ];
    for (prefix, scene) in rows {
        let line = readme
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("README has no row `{prefix}`"));
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let r = bench
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["scene"] == scene && r["form"] == "quick")
            .unwrap_or_else(|| panic!("no quick row for {scene}"));
        assert_eq!(cells[2], r["images"].to_string(), "{line}");
        let bowl = format!("{:.1} mm", r["bowl_mm"].as_f64().unwrap());
        assert_eq!(cells[4], bowl, "{line}");
        let share = format!("{} %", (100.0 * r["bowl_share"].as_f64().unwrap()).round());
        assert_eq!(cells[5], share, "{line}");
    }
}

/// docs/bench/images.md is `poser bench images --quick --json docs/bench/images.json`'s output:
/// each scene's size, images and registered share there match the JSON.
#[test]
fn images_bench_table_matches_its_json() {
    let md = std::fs::read_to_string("docs/bench/images.md").unwrap();
    let bench: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/images.json").unwrap()).unwrap();
    let rows = bench.as_array().unwrap();
    assert_eq!(
        rows.len(),
        6,
        "the five shipped survey scenes and the textured site"
    );
    for r in rows {
        let denoised = r["denoise_radius"]
            .as_f64()
            .map_or(String::new(), |d| format!(", denoised (σ {d} px)"));
        let prefix = format!(
            "| {} | {} | {}×{}, {} spp{denoised} | {} | {} ({:.0} %) |",
            r["scene"].as_str().unwrap(),
            r["form"].as_str().unwrap(),
            r["width"],
            r["height"],
            r["samples"],
            r["images"],
            r["registered"],
            100.0 * r["share"].as_f64().unwrap()
        );
        assert!(
            md.lines().any(|l| l.starts_with(&prefix)),
            "docs/bench/images.md has no row `{prefix}`"
        );
    }
}

/// The README's speed table, docs/bench/render.md and the plot's data are one run of
/// `poser bench render --readme README.md --json docs/bench/render.json …`, which covers every
/// shipped scene.
#[test]
fn readme_speed_table_is_the_render_bench_report_over_every_shipped_scene() {
    let report: poser::bench::render::Report =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/render.json").unwrap()).unwrap();
    let readme = std::fs::read_to_string("README.md").unwrap();
    assert!(
        readme.contains(&report.readme_block()),
        "README's generated block is not the one docs/bench/render.json gives; rerun the command \
         in the README's section `Speed against error`"
    );
    let md = std::fs::read_to_string("docs/bench/render.md").unwrap();
    assert_eq!(md.trim_end(), report.to_markdown().trim_end());
    assert!(
        report.form == poser::bench::render::Form::new(false),
        "not the full form"
    );
    for scene in poser::bench::parity::shipped_scenes(std::path::Path::new(".")) {
        let name = scene.file_stem().unwrap().to_string_lossy();
        let row = report.scenes.iter().find(|s| s.scene == name);
        let row = row.unwrap_or_else(|| panic!("{name} is not in docs/bench/render.json"));
        assert!(
            row.curves
                .iter()
                .any(|c| c.backend == "native" && c.error.is_none()),
            "{name}: no native curve"
        );
    }
}

/// docs/bench/sensor.md's table is `poser bench sensor --quick --json docs/bench/sensor.json`'s
/// rows as the bench prints them (`POSER_UPDATE_DOCS=1` rewrites the table from the JSON), over
/// the six survey scenes and three estimators.
#[test]
fn column_bench_table_is_its_json() {
    let rows: Vec<poser::bench::column::Row> =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/column.json").unwrap()).unwrap();
    let shipped = poser::bench::column::shipped_scenes(std::path::Path::new(".")).unwrap();
    let benched: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    assert_eq!(
        benched, shipped,
        "every shipped scene is in the bench: rerun it"
    );
    table_in_markdown("docs/bench/column.md", &poser::bench::column::table(&rows));
}

/// Check (or with `POSER_UPDATE_DOCS=1` rewrite) the generated table between the markers of a
/// Markdown file.
fn table_in_markdown(path: &str, table: &str) {
    let md = std::fs::read_to_string(path).unwrap();
    let (begin, end) = ("<!-- table: begin -->\n", "<!-- table: end -->");
    let (Some(b), Some(e)) = (md.find(begin), md.find(end)) else {
        panic!("{path} lacks its table markers")
    };
    let current = &md[b + begin.len()..e];
    if std::env::var_os("POSER_UPDATE_DOCS").is_some() {
        let new = format!("{}{begin}{table}{}", &md[..b], &md[e..]);
        std::fs::write(path, new).unwrap();
        return;
    }
    assert_eq!(current, table, "{path}: rerun with POSER_UPDATE_DOCS=1");
}

/// docs/bench/parity.md's table is `poser bench parity --quick --decisive 400 --json
/// docs/bench/parity.json`'s rows as the bench prints them, over every shipped scene.
#[test]
fn parity_bench_table_is_its_json() {
    let rows: Vec<poser::bench::parity::Row> =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/parity.json").unwrap()).unwrap();
    let shipped: Vec<String> = poser::bench::parity::shipped_scenes(std::path::Path::new("."))
        .iter()
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    let benched: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
    assert_eq!(
        benched, shipped,
        "every shipped scene is in the bench: rerun it"
    );
    table_in_markdown("docs/bench/parity.md", &poser::bench::parity::table(&rows));
}

#[test]
fn sensor_bench_table_is_its_json() {
    let rows: Vec<poser::bench::sensor::Row> =
        serde_json::from_str(&std::fs::read_to_string("docs/bench/sensor.json").unwrap()).unwrap();
    assert_eq!(
        rows.len(),
        poser::bench::sensor::SCENES.len() * poser::bench::sensor::MODES.len()
    );
    table_in_markdown("docs/bench/sensor.md", &poser::bench::sensor::table(&rows));
}
