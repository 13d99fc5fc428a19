"""Pure conversions and the housing meshes poser writes (no rendering)."""

import math
from collections import Counter

import numpy as np
import pytest
from poser_blender import geometry as geo


def test_intrinsics_follow_the_tested_recipe():
    p = geo.blender_intrinsics(150.0, 150.0, 80.0, 60.0, 160, 120)
    assert p["lens"] == pytest.approx(150.0 * 36.0 / 160.0)
    assert p["shift_x"] == 0.0 and p["shift_y"] == 0.0
    p = geo.blender_intrinsics(150.0, 150.0, 83.7, 57.2, 160, 120)
    # Principal point right of centre -> negative shift_x; above centre -> negative shift_y;
    # both in units of the width (sensor_fit HORIZONTAL).
    assert p["shift_x"] == pytest.approx(-3.7 / 160.0)
    assert p["shift_y"] == pytest.approx(-2.8 / 160.0)
    with pytest.raises(ValueError):
        geo.blender_intrinsics(150.0, 151.0, 80.0, 60.0, 160, 120)


def test_n2_factor_and_light_units():
    k = geo.emitter_scale([1.0] * 3, [1.334] * 3)
    assert k[1] == pytest.approx(1.0 / 1.334**2)
    colour, strength = geo.light_power([1.0, 2.0, 0.5], [1.0, 1.0, 1.0], 4.0 * math.pi)
    assert colour == pytest.approx([0.5, 1.0, 0.25])
    assert strength == pytest.approx(8.0 * math.pi)
    assert geo.light_power([0.0, 0.0, 0.0]) == ([1.0, 1.0, 1.0], 0.0)


def _closed_and_outward(mesh):
    edges = Counter()
    for f in mesh["faces"]:
        for i in range(len(f)):
            a, b = f[i], f[(i + 1) % len(f)]
            edges[(a, b)] += 1
    # Closed and consistently oriented: every directed edge has exactly one reverse twin.
    for (a, b), n in edges.items():
        assert n == 1 and edges[(b, a)] == 1, f"edge {(a, b)} not shared properly"
    v = mesh["verts"]
    tris = np.array([(f[0], f[i], f[i + 1]) for f in mesh["faces"] for i in range(1, len(f) - 1)])
    vol = float(np.einsum("ij,ij->i", v[tris[:, 0]],
                          np.cross(v[tris[:, 1]], v[tris[:, 2]])).sum()) / 6.0
    return vol


@pytest.mark.parametrize("kind", ["flat", "dome", "cylinder"])
def test_housings_poser_writes_read_back_closed_outward_and_holding_the_camera(housings, kind):
    # The shells are built and tested in crates/poser-optics (port/housing.rs); here: the PLY
    # that `poser compile --backend blender` writes reads back as such a shell.
    shell = geo.read_ply(housings[kind]["housing"]["shell"])
    inner = geo.read_ply(housings[kind]["housing"]["inner"])
    assert set(shell["tags"]) == {geo.GLASS_OUTER, geo.BODY} and set(inner["tags"]) == {geo.INNER}
    assert _closed_and_outward(shell) > 0.0, "shell normals must point into the water"
    # The camera (origin) is inside: the solid angle the shell subtends from it is 4 pi.
    v = shell["verts"]
    tris = np.array([(f[0], f[i], f[i + 1]) for f in shell["faces"] for i in range(1, len(f) - 1)])
    a, b, c = v[tris[:, 0]], v[tris[:, 1]], v[tris[:, 2]]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
           + np.einsum("ij,ij->i", b, c) * la)
    omega = float(np.sum(2.0 * np.arctan2(num, den)))
    assert omega == pytest.approx(4.0 * math.pi, rel=1e-6)
    # Curved glass carries unit shading normals; the flat port none.
    assert (shell["normals"] is None) == (kind == "flat")
    if shell["normals"] is not None:
        assert np.allclose(np.linalg.norm(shell["normals"], axis=1), 1.0)
    # Inner (air->glass) faces look at the camera.
    iv = inner["verts"]
    for f in inner["faces"][:50]:
        n = np.cross(iv[f[1]] - iv[f[0]], iv[f[2]] - iv[f[0]])
        assert np.dot(n, iv[f[0]]) < 0.0


def test_a_ply_of_another_layout_is_refused(housings, tmp_path):
    good = open(housings["dome"]["housing"]["shell"], "rb").read()
    cases = {
        "ascii": good.replace(b"binary_little_endian", b"ascii", 1),
        "float": good.replace(b"property double x", b"property float x", 1),
        "truncated": good[:-7],
        "trailing": good + b"\0",
        "not a ply": b"solid x\n",
    }
    for name, data in cases.items():
        path = tmp_path / f"{name.replace(' ', '_')}.ply"
        path.write_bytes(data)
        with pytest.raises(ValueError, match="PLY"):
            geo.read_ply(str(path))


def test_srgb_encoding():
    assert geo.srgb_encode([0.0, 1.0, 2.0]) == pytest.approx([0.0, 1.0, 1.0])
    assert geo.srgb_encode(0.2) == pytest.approx(1.055 * 0.2 ** (1 / 2.4) - 0.055)
