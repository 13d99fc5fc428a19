"""Shared fixtures: the builder package on sys.path and a small scene description."""

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
        "port": {"kind": "flat", "normal": [0.0, 0.0, 1.0], "distance": 0.02, "thickness": 0.01,
                 "glass": {"name": "N-BK7", "ior": [1.514, 1.518, 1.525]}},
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


@pytest.fixture
def scene_desc():
    return copy.deepcopy(SCENE)
