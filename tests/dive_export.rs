//! Subsurface export and plot of a simulated dive: structure, units and values read back.
use crate::support;
use poser::plan::dive::plan_dive;
use quick_xml::Reader;
use quick_xml::events::Event;
use std::collections::HashMap;
use support::plan as common;

fn parse_min(s: &str) -> f64 {
    // Subsurface's sampletime(): "m:ss min".
    let v = s.trim_end_matches(" min");
    let (m, sec) = v.split_once(':').expect("m:ss");
    m.parse::<f64>().unwrap() * 60.0 + sec.parse::<f64>().unwrap()
}
fn lead(s: &str) -> f64 {
    // Subsurface's parse_float(): the leading number, the unit suffix is decoration.
    s.split_whitespace()
        .next()
        .unwrap()
        .trim_end_matches('%')
        .parse()
        .unwrap()
}

#[test]
fn ssrf_round_trip() {
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let r = plan_dive(&m, 10.0).unwrap();
    let xml = poser::plan::ssrf::to_ssrf(&m, &r).unwrap();
    let mut reader = Reader::from_reader(xml.as_slice());
    let mut stack: Vec<String> = Vec::new();
    let mut samples: Vec<HashMap<String, String>> = Vec::new();
    let mut cylinders = Vec::new();
    let mut dive_attrs = HashMap::new();
    let mut buf = Vec::new();
    loop {
        let ev = reader.read_event_into(&mut buf).expect("well-formed XML");
        let (e, is_empty) = match &ev {
            Event::Start(e) => (Some(e.clone()), false),
            Event::Empty(e) => (Some(e.clone()), true),
            Event::End(_) => {
                stack.pop();
                (None, false)
            }
            Event::Eof => break,
            _ => (None, false),
        };
        if let Some(e) = e {
            let name = e.name().into_inner().to_string();
            let attrs: HashMap<String, String> = e
                .attributes()
                .map(|a| {
                    let a = a.unwrap();
                    (
                        a.key.into_inner().to_string(),
                        a.normalized_value(quick_xml::XmlVersion::Implicit1_0)
                            .unwrap()
                            .into_owned(),
                    )
                })
                .collect();
            let path = format!("{}/{}", stack.join("/"), name);
            match path.as_str() {
                "divelog/dives/dive" => dive_attrs = attrs,
                "divelog/dives/dive/cylinder" => cylinders.push(attrs),
                "divelog/dives/dive/divecomputer/sample" => samples.push(attrs),
                _ => {}
            }
            if !is_empty {
                stack.push(name);
            }
        }
        buf.clear();
    }
    assert!(stack.is_empty(), "unbalanced elements");
    // One air cylinder of 12 l filled to 200 bar, emptied (the dive needs ~5000 l).
    assert_eq!(cylinders.len(), 1);
    assert_eq!(cylinders[0]["size"], "12.0 l");
    // Air is 20.9 % O₂ everywhere (`Gas::AIR`, Subsurface's `O2_IN_AIR`).
    assert_eq!(cylinders[0]["o2"], "20.9%");
    assert_eq!(lead(&cylinders[0]["start"]), 200.0);
    assert!(lead(&cylinders[0]["end"]) <= 1.0 + 1e-9);
    // Samples: every 10 s, times strictly increasing, start and end at the surface.
    assert!(samples.len() > 600, "{} samples", samples.len());
    let times: Vec<f64> = samples.iter().map(|s| parse_min(&s["time"])).collect();
    assert!(times.windows(2).all(|w| w[1] > w[0]));
    let duration = parse_min(&dive_attrs["duration"]);
    assert!((duration - r.dive.runtime).abs() <= 1.0);
    assert!((times.last().unwrap() - r.dive.runtime).abs() <= 10.0);
    let depths: Vec<f64> = samples.iter().map(|s| lead(&s["depth"])).collect();
    assert_eq!(depths[0], 0.0);
    let maxd = depths.iter().cloned().fold(0.0, f64::max);
    assert!((maxd - 15.0).abs() < 0.01, "max depth {maxd}");
    // The deco obligation is visible: some sample in deco with a 3 m stop depth; before it,
    // NDL counts down at 15 m.
    let deco: Vec<&HashMap<String, String>> =
        samples.iter().filter(|s| s["in_deco"] == "1").collect();
    assert!(!deco.is_empty());
    assert!(deco.iter().all(|s| lead(&s["stopdepth"]) >= 3.0));
    assert!(deco.iter().any(|s| parse_min(&s["stoptime"]) >= 60.0));
    let ndl_15: Vec<f64> = samples
        .iter()
        .filter(|s| lead(&s["depth"]) > 14.9 && s["in_deco"] == "0")
        .map(|s| parse_min(&s["ndl"]))
        .collect();
    assert!(ndl_15.len() > 100);
    assert!(
        ndl_15.first().unwrap() > ndl_15.last().unwrap(),
        "NDL must count down at depth"
    );
    // Pressure readings fall monotonically.
    let p: Vec<f64> = samples.iter().map(|s| lead(&s["pressure"])).collect();
    assert!(p.windows(2).all(|w| w[1] <= w[0] + 1e-9));
    assert_eq!(p[0], 200.0);
}

#[test]
fn svg_plot_has_three_series() {
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let r = plan_dive(&m, 10.0).unwrap();
    let svg = poser::plan::plot::svg(&r, "paper survey").unwrap();
    assert!(svg.starts_with("<svg"));
    assert!(
        svg.contains("depth (m)") && svg.contains("NDL (min)") && svg.contains("runtime (min)")
    );
    assert!(
        svg.matches("<polyline").count() >= 3,
        "depth, ceiling and NDL lines"
    );
}

#[test]
fn exports_are_deterministic() {
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let a = plan_dive(&m, 10.0).unwrap();
    let b = plan_dive(&m, 10.0).unwrap();
    assert_eq!(
        poser::plan::ssrf::to_ssrf(&m, &a).unwrap(),
        poser::plan::ssrf::to_ssrf(&m, &b).unwrap()
    );
    assert_eq!(
        poser::plan::plot::svg(&a, "t").unwrap(),
        poser::plan::plot::svg(&b, "t").unwrap()
    );
}

/// Every element `name` of the document with its attributes.
fn elements(xml: &[u8], name: &str) -> Vec<HashMap<String, String>> {
    let mut reader = Reader::from_reader(xml);
    let mut out = Vec::new();
    let mut buf = Vec::new();
    loop {
        match reader.read_event_into(&mut buf).expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) if e.name().into_inner() == name => {
                out.push(
                    e.attributes()
                        .map(|a| {
                            let a = a.unwrap();
                            (
                                a.key.into_inner().to_string(),
                                a.normalized_value(quick_xml::XmlVersion::Implicit1_0)
                                    .unwrap()
                                    .into_owned(),
                            )
                        })
                        .collect(),
                );
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    out
}

#[test]
fn ssrf_two_gases_per_cylinder() {
    // 30 m for 35 min on air with an EAN50 deco cylinder: two <cylinder>s with their own gas
    // and end pressure, a gaschange event at the switch, a pressure per cylinder in the samples.
    let mut d = common::diver(24.0, 232.0);
    d.cylinders.push(poser::model::Cylinder {
        name: "deco".into(),
        volume: 0.007,
        pressure: 200e5,
        o2: 0.5,
        he: 0.0,
        role: poser::model::CylinderRole::Deco,
        switch_depth: None,
    });
    let length = 35.0 * 60.0 * 0.2;
    let (poses, net) = common::lawnmower(1, length, 2.0, 30.0, 0.2, length / 20.0);
    let m = common::model(poses, net, Some(d), 32.0);
    let r = plan_dive(&m, 10.0).unwrap();
    let xml = poser::plan::ssrf::to_ssrf(&m, &r).unwrap();
    let cyl = elements(&xml, "cylinder");
    assert_eq!(cyl.len(), 2);
    assert_eq!(lead(&cyl[0]["o2"]), 20.9);
    assert_eq!(lead(&cyl[1]["o2"]), 50.0);
    assert_eq!(lead(&cyl[1]["depth"]), 21.0);
    for (c, u) in cyl.iter().zip(&r.dive.gas.cylinders) {
        assert!((lead(&c["end"]) - u.end_pressure).abs() < 0.01, "{c:?}");
    }
    assert!(lead(&cyl[1]["end"]) < 200.0, "the deco gas was breathed");
    let ev = elements(&xml, "event");
    let gc: Vec<_> = ev.iter().filter(|e| e["name"] == "gaschange").collect();
    assert_eq!(gc.len(), 1, "{ev:?}");
    assert_eq!(
        (gc[0]["cylinder"].as_str(), gc[0]["value"].as_str()),
        ("1", "50")
    );
    let sw = r.dive.switches.iter().find(|s| s.cylinder == 1).unwrap();
    assert!((parse_min(&gc[0]["time"]) - sw.time).abs() <= 1.0);
    let samples = elements(&xml, "sample");
    assert!(
        samples
            .iter()
            .all(|s| s.contains_key("pressure") && s.contains_key("pressure1"))
    );
    // The deco cylinder's pressure only falls after the switch.
    let before: Vec<f64> = samples
        .iter()
        .filter(|s| parse_min(&s["time"]) < sw.time - 1.0)
        .map(|s| lead(&s["pressure1"]))
        .collect();
    assert!(before.iter().all(|&p| p == 200.0));
    assert!(lead(&samples.last().unwrap()["pressure1"]) < 200.0);
}
