//! Survey planning: networks, GSD, coverage, dive profile, decompression, gas, Subsurface.

pub mod network;
