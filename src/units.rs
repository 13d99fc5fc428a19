//! Physical units in scene files: parse `"18 mm"`, `"0.2 m/s"`, `"232 bar"` into SI numbers.
