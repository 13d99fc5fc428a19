//! Mitsuba backend: compiled XML snapshots, byte stability, escaping and path safety.
mod mitsuba_support;
use mitsuba_support::*;
use poser::backend::mitsuba;

#[test]
fn smoke_write() {
    let m = showcase();
    let c = mitsuba::build(&m).unwrap();
    let dir = std::path::Path::new("/tmp/mi_showcase");
    mitsuba::write(&c, dir).unwrap();
}
