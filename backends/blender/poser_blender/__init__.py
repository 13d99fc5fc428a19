"""poser's Blender backend: build a poser scene description (JSON) in Blender and render it.

`geometry` holds the pure conversions (intrinsics, light units, n^2 factors, housings);
`builder` creates the Blender objects and renders with Cycles. Generated `scene.py` scripts
embed this package's source, so they run with only `bpy` installed.
"""

from .builder import FORMAT, build, main, parse_args, render, validate

__all__ = ["FORMAT", "build", "main", "parse_args", "render", "validate"]
