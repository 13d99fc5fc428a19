"""Load the DISORT reference of `poser column` under a unique module name (no clash with other backends)."""

import importlib.util
import sys
from pathlib import Path

import pytest

REFERENCE = Path(__file__).resolve().parents[1] / "disort_reference.py"


@pytest.fixture(scope="session")
def reference():
    spec = importlib.util.spec_from_file_location("poser_column_disort_reference", REFERENCE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["poser_column_disort_reference"] = mod
    spec.loader.exec_module(mod)
    return mod
