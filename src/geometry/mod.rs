//! The geometry service shared by the ground truth, the planner and the native renderer: the
//! model's shapes as triangle meshes, the targets' points and printed patterns, and the BVH that
//! answers ray casts and occlusion queries. It knows nothing of rendering or lighting.
//!
//! | module | owns |
//! |---|---|
//! | [`mesh`] | triangle meshes of every scene shape (glTF, primitives, seabed, boulders), patterns, PLY |
//! | [`meshfile`] | mesh files with their colours: OBJ + MTL, PLY with vertex colours, glTF with base-colour textures |
//! | [`relief`] | a seabed's large-scale relief through surveyed heights (thin-plate spline) |
//! | [`coral`] | procedural coral colonies (branching, massive) as closed meshes |
//! | [`bommie`] | a generated textured site (a coral bommie on rubble) written as OBJ + MTL + JPEG, as a photogrammetry package exports it |
//! | [`targets`] | calibration targets: 3D points, printed reflectance, textures |
//! | [`bvh`] | [`Bvh`]: every triangle of a model in one BVH; [`Ray`], [`Hit`], [`SurfaceId`] |
//! | [`seen`] | what the cameras see: a grid of exact camera rays classified by what they hit (texture, nothing below: views past the seabed) |
//! | [`shadow`] | where a camera housing's sun shadow would fall: the images and target points it covers (Mitsuba casts it) |

pub mod bommie;
pub mod bvh;
pub mod coral;
pub mod mesh;
pub mod meshfile;
pub mod relief;
pub mod seen;
pub mod shadow;
pub mod targets;

pub use bvh::{Bvh, Hit, RAY_EPSILON, Ray, SurfaceId};
