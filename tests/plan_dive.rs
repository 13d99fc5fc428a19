//! Dive planning on Rust-built models: the paper's survey, a short survey within the NDL.
mod common;
use poser::plan::dive::*;

#[test]
fn paper_survey_verdict() {
    let m = common::paper_model(Some(common::diver(12.0, 200.0)));
    let r = plan_dive(&m, 10.0).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&r.verdict).unwrap());
    eprintln!(
        "bottom {} runtime {} stops {:?} gas {:?}",
        r.dive.bottom_time, r.dive.runtime, r.dive.stops, r.dive.gas
    );
}
