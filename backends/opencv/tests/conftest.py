"""Load the OpenCV calibration driver under a unique module name (no clash with other backends)."""

import importlib.util
import sys
from pathlib import Path

import pytest

DRIVER = Path(__file__).resolve().parents[1] / "calibrate.py"


@pytest.fixture(scope="session")
def driver():
    spec = importlib.util.spec_from_file_location("poser_opencv_calibrate", DRIVER)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["poser_opencv_calibrate"] = mod
    spec.loader.exec_module(mod)
    return mod
