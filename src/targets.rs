//! Calibration targets, scale bars and GSD targets: their 3D points and printed patterns.
