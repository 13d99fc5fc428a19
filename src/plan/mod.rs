//! Survey planning: networks, GSD, coverage, dive profile, decompression, gas, Subsurface.

pub mod deco;
pub mod dive;
pub mod footprints;
pub mod gas;
pub mod network;
pub mod oxygen;
pub mod plot;
pub mod ssrf;
pub mod survey;
