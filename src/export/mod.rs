//! Exports of a whole scene for other tools to look at (`poser export`): a glTF 2.0 binary
//! preview of the site, targets, water surface, ports, every camera pose, the swim path and the
//! lights ([`gltf`]). An export shows the resolved model; it renders nothing and computes no
//! truth, and the exact values it cannot express in the target format travel in its `extras`.
//!
//! | module | owns |
//! |---|---|
//! | [`gltf`] | `poser export SCENE -o scene.glb`: the model as one self-contained `.glb` (docs/export.md) |

pub mod gltf;
