"""poser: simulate underwater photogrammetry surveys (the poser library, from Python).

    import poser
    scene = poser.load("scenarios/calibration_flat.toml", set={"water.temperature": 12})
    uv, status = scene.project([[0.0, 0.0, 1.5]])       # camera frame, metres -> pixels
    image = scene.render(0, samples=4, scale=0.25)       # (H, W, 3) float32, linear RGB

Everything is computed by the same Rust library as the `poser` command line, with the same
results. See docs/python.md in the poser sources.
"""

from ._poser import Diagnostic, PoserError, Scene, SceneError, __version__, load

__all__ = ["Diagnostic", "PoserError", "Scene", "SceneError", "__version__", "load"]
