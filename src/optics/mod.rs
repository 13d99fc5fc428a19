//! The optics core: refractive indices (water, glass), water IOPs and phase functions, lens
//! models, housing ports with exact forward and backward projection, sun position.

pub mod glass;
pub mod phase;
pub mod sun;
pub mod water;
