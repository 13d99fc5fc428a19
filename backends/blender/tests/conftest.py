"""Shared fixtures: the builder package on sys.path, a small scene description, and port
housings computed by poser itself (the `poser` module compiles tiny scenes for Cycles)."""

import copy
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

IDENTITY = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
# Rig looking down (-z world), camera x = east, y = south, at height 2 m.
DOWN = [[1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 2.0], [0.0, 0.0, 0.0, 1.0]]

SCENE = {
    "format": "poser-blender/1",
    "name": "pytest scene",
    "description": "",
    "render": {"samples": 4, "seed": 3, "max_bounces": 8, "exposure": 1.0, "outputs": ["rgb"]},
    "reference_channel": 1,
    "per_channel_passes": False,
    "caustics": False,
    "cameras": [{
        "name": "cam", "width": 32, "height": 24, "lens": "rectilinear",
        "fx": 30.0, "fy": 30.0, "cx": 17.5, "cy": 11.0,
        "focus_distance": None, "f_number": None,
        "rig_from_camera": IDENTITY,
        # "port", "housing": the flat port of `housings` (scene_desc puts them in)
    }],
    "poses": [
        {"name": "p0", "world_from_rig": DOWN, "images": ["p0"], "time": 0.0},
        {"name": "p1", "world_from_rig": DOWN, "images": ["p1"], "time": 1.0},
    ],
    "water": {"ior": [1.331, 1.334, 1.339], "absorption": [0.4, 0.1, 0.05],
              "scattering": [0.0, 0.0, 0.0], "phase": {"kind": "henyey_greenstein", "g": 0.8},
              "extent": {"kind": "everywhere"}},
    "surface": {"kind": "none"},
    "bounds": {"min": [-6.0, -6.0, -6.0], "max": [6.0, 6.0, 6.0]},
    "sun": None,
    "lights": [
        {"name": "strobe", "mount": "rig", "type": "spot", "position": [0.1, 0.0, 0.0],
         "direction": [0.0, 0.0, 1.0], "half_angle": 0.5, "intensity": [1.0, 2.0, 0.5]},
        {"name": "sky", "mount": "world", "type": "ambient", "radiance": [0.2, 0.2, 0.2]},
    ],
    "objects": [{
        "name": "floor", "shape": {"type": "plane", "width": 4.0, "height": 4.0},
        "scale": [1.0, 1.0, 1.0], "matrix": IDENTITY,
        "material": {"albedo": [0.5, 0.5, 0.5], "pattern": None},
    }],
    "targets": [],
}


# The fixture camera (32 x 24 px, fx = 30 px, principal point (17.5, 11)) behind each kind of
# port, in water; `housings` compiles one scene per port with the poser module.
_HOUSING_SCENE = """
name = "housing fixture"
[site]
depth = "10 m"
surface = "none"
[water]
ior = 1.334
absorption = [0.4, 0.1, 0.05]
scattering = [0.0, 0.0, 0.0]
[camera]
width = 32
height = 24
sensor_width = "32 mm"
focal_length = "30 mm"
principal_point = [17.5, 11.0]
[[lights]]
type = "ambient"
radiance = 0.2
[network]
type = "explicit"
[[network.poses]]
position = [0.0, 0.0, -8.0]
look_at = [0.0, 1.0, -8.0]
[camera.port]
material = "N-BK7"
"""
_PORTS = {
    "flat": 'type = "flat"\nthickness = "10 mm"\npupil_distance = "20 mm"\n',
    "dome": 'type = "dome"\ninner_radius = "50 mm"\nthickness = "6 mm"\n'
            "decentering = [0.0, 0.0, 0.002]\n",
    "cylinder": 'type = "cylinder"\ninner_radius = "50 mm"\nthickness = "5 mm"\n'
                "axis = [0.0, 1.0, 0.0]\n",
}


@pytest.fixture(scope="session")
def housings(tmp_path_factory):
    """Per port kind, the fixture camera's `port` and `housing` (absolute PLY paths) as
    `poser compile --backend blender` describes them."""
    import json

    import poser  # the wheel the test tier installs; fails, never skips, without it

    out = {}
    for kind, port in _PORTS.items():
        d = tmp_path_factory.mktemp(f"housing_{kind}")
        (d / "scene.toml").write_text(_HOUSING_SCENE + port)
        poser.load(str(d / "scene.toml")).compile("blender", str(d / "out"))
        cam = json.loads((d / "out" / "scene.json").read_text())["cameras"][0]
        out[kind] = {"port": cam["port"],
                     "housing": {k: str(d / "out" / v) for k, v in cam["housing"].items()}}
    return out


def put_port(camera, housed):
    """Give `camera` (a description's camera) the port and housing of `housed`."""
    camera["port"] = copy.deepcopy(housed["port"])
    camera["housing"] = dict(housed["housing"])


@pytest.fixture
def scene_desc(housings):
    d = copy.deepcopy(SCENE)
    put_port(d["cameras"][0], housings["flat"])
    return d
