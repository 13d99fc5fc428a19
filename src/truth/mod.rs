//! Exact ground truth: where every target lands in every image, intrinsics, poses, COLMAP export.
