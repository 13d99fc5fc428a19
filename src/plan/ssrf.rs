//! Subsurface native XML (`.ssrf`) export of a simulated dive, following Subsurface's writer
//! (`core/save-xml.cpp`) and reader rules (`core/parse-xml.cpp`): SI units with decorative
//! suffixes, `m:ss min` times, `%` gas fractions, one `<cylinder>` per cylinder, samples with
//! depth, cylinder pressure, NDL, TTS, stop depth/time and the in-deco flag.
//!
//! | element/attribute | written as |
//! |---|---|
//! | `dive@date`, `@time` | `2026-01-01`, `09:00:00` (fixed: the simulation has no calendar) |
//! | `cylinder@size`, `@workpressure`, `@start`, `@end` | `12.0 l`, `200.0 bar` |
//! | `cylinder@o2`, `@he` | `21.0%` |
//! | `water@salinity` | `1030 g/l` (sea) or `1000 g/l` (fresh) |
//! | `sample@time`, `@ndl`, `@tts`, `@stoptime` | `m:ss min` |
//! | `sample@depth`, `@stopdepth` | `15.0 m` |
//! | `sample@pressure` | `187.3 bar` |
//! | `dive@otu`, `@cns` | `42`, `17%` (whole numbers, only when not zero, as Subsurface saves its computed OTU and max CNS) |

use super::deco::Ndl;
use super::dive::DiveReport;
use crate::model::Model;
use quick_xml::Writer;
use quick_xml::events::{BytesEnd, BytesStart, BytesText, Event};

/// `m:ss min` as Subsurface writes sample times.
pub fn min_sec(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02} min", s / 60, s % 60)
}

/// Subsurface's `put_milli`-style number: at least one decimal, trailing zeros dropped.
fn milli(v: f64) -> String {
    let mut s = format!("{:.3}", (v * 1000.0).round() / 1000.0);
    while s.ends_with('0') && !s.ends_with(".0") {
        s.pop();
    }
    s
}

fn pct(f: f64) -> String {
    format!("{}%", milli(f * 100.0))
}

type W = Writer<Vec<u8>>;

fn start(w: &mut W, name: &str, attrs: &[(&str, String)]) -> Result<(), String> {
    let mut e = BytesStart::new(name);
    for (k, v) in attrs {
        e.push_attribute((*k, v.as_str()));
    }
    w.write_event(Event::Start(e)).map_err(|e| e.to_string())
}

fn empty(w: &mut W, name: &str, attrs: &[(&str, String)]) -> Result<(), String> {
    let mut e = BytesStart::new(name);
    for (k, v) in attrs {
        e.push_attribute((*k, v.as_str()));
    }
    w.write_event(Event::Empty(e)).map_err(|e| e.to_string())
}

fn end(w: &mut W, name: &str) -> Result<(), String> {
    w.write_event(Event::End(BytesEnd::new(name)))
        .map_err(|e| e.to_string())
}

/// The dive as a Subsurface log (bytes of a UTF-8 XML document).
pub fn to_ssrf(model: &Model, report: &DiveReport) -> Result<Vec<u8>, String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    let cfg = &report.config;
    let dive = &report.dive;
    let salinity = if cfg.env.water_density > 1010.0 {
        "1030 g/l"
    } else {
        "1000 g/l"
    };
    start(
        &mut w,
        "divelog",
        &[("program", "subsurface".into()), ("version", "3".into())],
    )?;
    start(&mut w, "dives", &[])?;
    let mut dive_attrs = vec![
        ("number", "1".to_string()),
        ("date", "2026-01-01".into()),
        ("time", "09:00:00".into()),
        ("duration", min_sec(dive.runtime)),
    ];
    // Subsurface's computed `otu` and `cns` (its `maxcns`), written as it saves them: whole
    // numbers, only when not zero.
    let (otu, cns) = (
        dive.oxygen.otu.round() as i64,
        dive.oxygen.cns_percent.round() as i64,
    );
    if otu != 0 {
        dive_attrs.push(("otu", otu.to_string()));
    }
    if cns > 0 {
        dive_attrs.push(("cns", format!("{cns}%")));
    }
    start(&mut w, "dive", &dive_attrs)?;
    let mut notes = format!(
        "Planned by poser from scene '{}': {} poses, survey {} at up to {} m. ",
        model.name,
        model.poses.len(),
        min_sec(dive.bottom_time),
        milli(dive.max_depth)
    );
    for p in &report.verdict.problems {
        notes.push_str(p);
        notes.push_str(". ");
    }
    start(&mut w, "notes", &[])?;
    w.write_event(Event::Text(BytesText::new(notes.trim_end())))
        .map_err(|e| e.to_string())?;
    end(&mut w, "notes")?;

    // Cylinders: each with its own gas and the pressure the simulation left in it.
    for (t, u) in cfg.tanks.iter().zip(&dive.gas.cylinders) {
        empty(&mut w, "cylinder", &cylinder_attrs(t, u))?;
    }
    start(
        &mut w,
        "divecomputer",
        &[("model", "POSER simulator".into())],
    )?;
    empty(
        &mut w,
        "depth",
        &[("max", format!("{} m", milli(dive.max_depth)))],
    )?;
    empty(
        &mut w,
        "surface",
        &[(
            "pressure",
            format!("{} bar", milli(cfg.env.surface_pressure)),
        )],
    )?;
    empty(&mut w, "water", &[("salinity", salinity.into())])?;
    gas_changes(&mut w, report)?;
    for s in &dive.samples {
        empty(&mut w, "sample", &sample_attrs(s))?;
    }
    end(&mut w, "divecomputer")?;
    end(&mut w, "dive")?;
    end(&mut w, "dives")?;
    end(&mut w, "divelog")?;
    let mut out = w.into_inner();
    out.push(b'\n');
    Ok(out)
}

/// A cylinder's attributes: size, working pressure, gas, its use and switch depth, and the
/// start and end pressures of the simulation.
fn cylinder_attrs(
    t: &super::gas::Tank,
    u: &super::gas::CylinderUse,
) -> Vec<(&'static str, String)> {
    let mut attrs = vec![
        ("size", format!("{} l", milli(t.volume))),
        ("workpressure", format!("{} bar", milli(t.fill))),
        ("description", t.name.clone()),
        ("o2", pct(t.gas.o2)),
    ];
    if t.gas.he > 0.0 {
        attrs.push(("he", pct(t.gas.he)));
    }
    if t.role.switched() {
        attrs.push(("use", "OC-gas".into()));
        if let Some(d) = t.switch_depth {
            attrs.push(("depth", format!("{} m", milli(d))));
        }
    }
    attrs.push(("start", format!("{} bar", milli(t.fill))));
    // Subsurface ignores a pressure of 0; an empty cylinder is written as 1 bar.
    attrs.push((
        "end",
        format!(
            "{} bar",
            milli(((u.end_pressure * 1000.0).round() / 1000.0).max(1.0))
        ),
    ));
    attrs
}

/// The gas changes as Subsurface's `gaschange` events (type 11: O₂ %; type 25: O₂ % + He % << 16).
fn gas_changes(w: &mut W, report: &DiveReport) -> Result<(), String> {
    let (cfg, dive) = (&report.config, &report.dive);
    for sw in &dive.switches {
        if sw.time <= 0.0 && sw.cylinder == 0 {
            continue;
        }
        let g = cfg.tanks[sw.cylinder].gas;
        let o2 = (g.o2 * 100.0).round() as u32;
        let he = (g.he * 100.0).round() as u32;
        empty(
            w,
            "event",
            &[
                ("time", min_sec(sw.time.round())),
                ("type", if he > 0 { "25" } else { "11" }.into()),
                ("value", (o2 + (he << 16)).to_string()),
                ("name", "gaschange".into()),
                ("cylinder", sw.cylinder.to_string()),
            ],
        )?;
    }
    Ok(())
}

/// A profile sample's attributes: time, depth, one pressure per cylinder, NDL, TTS and the
/// decompression state.
fn sample_attrs(s: &super::dive::Sample) -> Vec<(&'static str, String)> {
    let mut a = vec![
        ("time", min_sec(s.time)),
        (
            "depth",
            format!("{} m", milli((s.depth * 100.0).round() / 100.0)),
        ),
    ];
    // One pressure per cylinder (`pressure`, `pressure1`…`pressure4`). Subsurface reads a
    // pressure of 0 as "no value": write the floor 1 bar when empty.
    for (i, p) in s.pressures.iter().enumerate().take(5) {
        let key = [
            "pressure",
            "pressure1",
            "pressure2",
            "pressure3",
            "pressure4",
        ][i];
        a.push((
            key,
            format!("{} bar", milli(((p * 10.0).round() / 10.0).max(1.0))),
        ));
    }
    match s.ndl {
        Some(Ndl::Limit(n)) => a.push(("ndl", min_sec((n / 60.0).floor() * 60.0))),
        Some(Ndl::Unlimited) => a.push(("ndl", min_sec(super::deco::NDL_CAP))),
        Some(Ndl::InDeco) | None => a.push(("ndl", min_sec(0.0))),
    }
    a.push(("tts", min_sec((s.tts / 60.0).ceil() * 60.0)));
    if s.in_deco {
        a.push(("in_deco", "1".into()));
        if let Some(d) = s.stop_depth {
            a.push(("stopdepth", format!("{} m", milli(d))));
        }
        // Always written: Subsurface copies an omitted value from the previous sample.
        let t = s.stop_time.unwrap_or(0.0);
        a.push(("stoptime", min_sec((t / 60.0).ceil() * 60.0)));
    } else {
        a.push(("in_deco", "0".into()));
        a.push(("stopdepth", "0.0 m".into()));
        a.push(("stoptime", min_sec(0.0)));
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn number_formats_like_subsurface() {
        assert_eq!(milli(15.0), "15.0");
        assert_eq!(milli(54.229), "54.229");
        assert_eq!(milli(2.5), "2.5");
        assert_eq!(min_sec(90.0), "1:30 min");
        assert_eq!(min_sec(6240.0), "104:00 min");
        assert_eq!(pct(0.21), "21.0%");
    }
}
