//! The 60 m trimix dive of issue 38 (`tests/in/trimix_dive.toml`): TX15/55 (hypoxic at the
//! surface) in twin 12 l, an EAN32 travel gas, EAN50 and O₂ for the decompression, which is
//! planned (`diver.deco = "planned"`). It is "OK, decompression planned" with its runtime,
//! CNS % and OTU, every gas where it is breathed within its limits, and every lost-gas plan
//! holding. Its runtime is compared with an independent ZHL-16C + GF planner in
//! `backends/deco/tests/test_deco_reference.py` (full tier).
use std::process::Command;

fn report() -> (serde_json::Value, String) {
    let scene = format!("{}/tests/in/trimix_dive.toml", env!("CARGO_MANIFEST_DIR"));
    let run = |json: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_poser"));
        c.arg("dive").arg(&scene);
        if json {
            c.arg("--json");
        }
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    (serde_json::from_str(&run(true)).unwrap(), run(false))
}

#[test]
fn trimix_dive_with_travel_and_deco_gases_is_planned_ok() {
    let (r, text) = report();
    let v = &r["verdict"];
    assert_eq!(v["ok"], true, "{text}");
    assert_eq!(v["deco_planned"], true, "{text}");
    assert!(
        text.contains("Verdict: OK, decompression planned"),
        "{text}"
    );
    let d = &r["dive"];
    let f = |x: &serde_json::Value| x.as_f64().unwrap();
    // Runtime: descent + survey + ascent, the ascent with its stops.
    let runtime = f(&d["runtime"]);
    let stops: f64 = d["stops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| f(&s["duration"]))
        .sum();
    assert!(
        (runtime - f(&d["descent_time"]) - f(&d["bottom_time"]) - f(&d["tts_at_end"])).abs() < 1e-6
    );
    assert!(stops > 600.0 && stops < f(&d["tts_at_end"]), "{stops}");
    // CNS and OTU of the whole dive: real, and within the limits.
    let (cns, otu) = (f(&d["oxygen"]["cns_percent"]), f(&d["oxygen"]["otu"]));
    assert!(
        cns > 5.0 && cns < 80.0 && otu > 10.0 && otu < 300.0,
        "{cns} {otu}"
    );
    assert!(text.contains(&format!("CNS {cns:.1} %")) && text.contains(&format!("OTU {otu:.1}")));
    // The gases: EAN32 from the surface to 30 m, the trimix from 30 m, EAN32 again at 30 m,
    // EAN50 at 21 m, O₂ at the 3 m stop.
    let names: Vec<String> = r["config"]["tanks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["name"].as_str().unwrap().to_string())
        .collect();
    let seq: Vec<(String, f64)> = d["switches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                names[s["cylinder"].as_u64().unwrap() as usize].clone(),
                f(&s["depth"]),
            )
        })
        .collect();
    let want = [
        ("travel", 0.0),
        ("back", 30.0),
        ("travel", 30.0),
        ("EAN50", 21.0),
        ("O2", 3.0),
    ];
    assert_eq!(seq.len(), want.len(), "{seq:?}");
    for ((n, dep), (wn, wd)) in seq.iter().zip(want) {
        assert!(n == wn && (dep - wd).abs() < 1e-6, "{seq:?}");
    }
    for c in d["gas"]["cylinders"].as_array().unwrap() {
        assert_eq!(c["po2_ok"], true, "{c}");
        assert_eq!(c["hypoxic"], false, "{c}");
        assert_eq!(c["reserve_ok"], true, "{c}");
    }
    // Every lost-gas plan (travel, EAN50, O₂) holds, each longer than the plan.
    let lost = v["lost_gas"].as_array().unwrap();
    assert_eq!(lost.len(), 3, "{lost:?}");
    for p in lost {
        assert_eq!(p["holds"], true, "{p}");
        assert!(f(&p["runtime"]) > runtime, "{p}");
    }
}
