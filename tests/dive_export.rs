//! Subsurface export and plot of a simulated dive: structure, units and values read back.
mod support;
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
    assert_eq!(cylinders[0]["o2"], "21.0%");
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
