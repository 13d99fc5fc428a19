"""The `poser` Python module against the `poser` command line: the same numbers, bit for bit.

Runs against the wheel installed in the pinned venv (test.sh builds it with maturin) and the
release binary (`POSER_BIN`, default target/release/poser).
"""

import csv
import io
import json
import os
import re
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

import poser

ROOT = Path(__file__).resolve().parents[3]
POSER = Path(os.environ.get("POSER_BIN", ROOT / "target" / "release" / "poser"))
FLAT = ROOT / "scenarios" / "calibration_flat.toml"
DOME = ROOT / "scenarios" / "dome_orbit.toml"
RIG = ROOT / "scenarios" / "paper_survey.toml"


def cli(*args, cwd=None):
    assert POSER.exists(), f"{POSER} is missing: run `cargo build --release` (test.sh does)"
    r = subprocess.run(
        [str(POSER), *map(str, args)], capture_output=True, text=True, cwd=cwd, check=False
    )
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_load_set_and_properties():
    s = poser.load(FLAT, set={"water.temperature": 12})
    assert s.name == "calibration_flat"
    assert isinstance(s, poser.Scene)
    assert len(s.poses) == len(s.truth()["images"]) // len(s.cameras)
    m = s.poses[0]["world_from_rig"]
    assert m.shape == (4, 4) and np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3))
    assert s.files[0].endswith("calibration_flat.toml")
    # The override took effect: a colder sea has a higher index.
    warm = poser.load(FLAT, set={"water.temperature": 28})
    assert s.to_dict()["water"]["ior"][1] > warm.to_dict()["water"]["ior"][1]
    # The same model as the CLI's (`explain --json`), and the same text.
    assert s.to_dict() == json.loads(cli("explain", FLAT, "--json", "--set", "water.temperature=12"))
    assert s.explain() == cli("explain", FLAT, "--set", "water.temperature=12")


def test_invalid_scene_raises_scene_error_with_locations(tmp_path):
    bad = ROOT / "tests" / "invalid" / "hg_g_out_of_range.toml"
    with pytest.raises(poser.SceneError) as e:
        poser.load(bad)
    d = [x for x in e.value.diagnostics if x.severity == "error"]
    assert d and d[0].code == "E0203"
    # Where the CLI points, from its own `┌─ file:line:col` line.
    r = subprocess.run([str(POSER), "validate", str(bad)], capture_output=True, text=True)
    loc = re.search(r"┌─ (.+):(\d+):(\d+)", r.stderr)
    assert (d[0].file, d[0].line, d[0].column) == (loc[1], int(loc[2]), int(loc[3]))
    assert "forward scattering" in d[0].help
    assert "E0203" in str(e.value)
    # A key on a known line of a file of ours: an unknown top-level key on line 1.
    p = tmp_path / "scene.toml"
    p.write_text("bogus_key = 1\n" + FLAT.read_text())
    with pytest.raises(poser.SceneError) as e:
        poser.load(p)
    d = e.value.diagnostics[0]
    assert (d.code, d.file, d.line, d.column) == ("E0100", str(p), 1, 1), repr(d)
    assert d.help
    # A bad override points at the pseudo-file of the command line.
    with pytest.raises(poser.SceneError) as e:
        poser.load(FLAT, set={"water.temperature": "hot"})
    assert e.value.diagnostics[0].file == "<command line>"
    # Errors, never a crash.
    with pytest.raises(poser.SceneError):
        poser.load(tmp_path / "missing.toml")
    with pytest.raises(ValueError):
        poser.load(FLAT, set={"water": {"temperature": 12}})
    assert issubclass(poser.SceneError, poser.PoserError)


def points_csv(path, pts):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["id", "x", "y", "z"])
        for i, p in enumerate(pts):
            w.writerow([f"p{i}", *(repr(float(c)) for c in p)])


def read_projection(text):
    rows = list(csv.DictReader(io.StringIO(text)))
    uv = np.array(
        [[float(r["u"]) if r["u"] else np.nan, float(r["v"]) if r["v"] else np.nan] for r in rows]
    )
    return uv, [r["status"] for r in rows]


@pytest.mark.parametrize("scene", [FLAT, DOME, RIG])
@pytest.mark.parametrize("frame", ["camera", "world"])
def test_project_matches_the_cli_bit_for_bit(tmp_path, scene, frame):
    rng = np.random.default_rng(7)
    s = poser.load(scene)
    if frame == "camera":
        pts = rng.uniform([-2, -2, -0.5], [2, 2, 6], size=(300, 3))
    else:
        # Around what pose 1 looks at, plus points anywhere.
        c = s.truth()["images"][1 * len(s.cameras)]["world_from_camera"]
        ahead = c["translation"] + 2.0 * c["rotation"][:, 2]
        pts = np.vstack([ahead + rng.normal(0, 0.6, size=(200, 3)), rng.uniform(-5, 5, (100, 3))])
    names = [c["name"] for c in s.cameras]
    for cam in names[:2]:
        for ch in ("r", "g", "b"):
            uv, status = s.project(pts, camera=cam, frame=frame, pose=1, channel=ch)
            path = tmp_path / "pts.csv"
            points_csv(path, pts)
            out = cli(
                "project", scene, "--points", path, "--frame", frame, "--pose", 1,
                "--camera", cam, "--channel", ch,
            )
            want_uv, want_status = read_projection(out)
            assert list(status) == want_status
            # Bit for bit: NaN where the CLI writes no pixel, the same f64 elsewhere.
            assert np.array_equal(uv, want_uv, equal_nan=True)
            assert uv.dtype == np.float64 and uv.shape == (len(pts), 2)
    assert {"ok", "behind_camera"} <= set(status) or frame == "world"


def test_project_refuses_bad_input():
    s = poser.load(FLAT)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        s.project(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="not finite"):
        s.project([[0.0, np.nan, 1.0]])
    with pytest.raises(ValueError, match="no such camera"):
        s.project([[0, 0, 1]], camera="nope")
    with pytest.raises(ValueError, match="out of range"):
        s.project([[0, 0, 1]], frame="world", pose=10_000)
    with pytest.raises(ValueError, match="frame"):
        s.project([[0, 0, 1]], frame="rig")
    with pytest.raises(ValueError, match="channel"):
        s.project([[0, 0, 1]], channel="ir")
    uv, status = s.project(np.empty((0, 3)))
    assert uv.shape == (0, 2) and status.shape == (0,)
    # Integer and list input are converted.
    uv2, _ = s.project([[0, 0, 2]])
    uv3, _ = s.project(np.array([[0.0, 0.0, 2.0]]))
    assert np.array_equal(uv2, uv3)
    # One point as a 1-D array is N = 1 (it used to raise numpy's "dimensionality mismatch").
    uv4, st4 = s.project(np.array([0.0, 0.0, 2.0]))
    assert uv4.shape == (1, 2) and st4.shape == (1,) and np.array_equal(uv4, uv3)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        s.project(np.zeros(4))
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        s.project(np.zeros((2, 3, 3)))
    # A transposed (non-contiguous) view keeps each point's x, y, z together.
    pts = np.array([[0.0, 0.1], [0.0, -0.1], [2.0, 3.0]]).T
    uv5, _ = s.project(pts)
    uv6, _ = s.project(np.ascontiguousarray(pts))
    assert np.array_equal(uv5, uv6, equal_nan=True)


def test_truth_matches_truth_json(tmp_path):
    seen = 0
    for scene in (FLAT, RIG):
        s = poser.load(scene)
        t = s.truth()
        cli("truth", scene, "-o", tmp_path / scene.stem)
        want = json.loads((tmp_path / scene.stem / "truth.json").read_text())
        assert t["conventions"] == want["conventions"]
        assert t["cameras"] == want["cameras"] == s.cameras
        assert len(t["images"]) == len(want["images"])
        for got, exp in zip(t["images"], want["images"]):
            assert got["name"] == exp["name"] and got["pose_index"] == exp["pose_index"]
            for k in ("rotation", "translation", "quaternion"):
                assert np.array_equal(got["world_from_camera"][k], exp["world_from_camera"][k])
            p = got["points"]
            assert list(p["id"]) == [o["id"] for o in exp["points"]]
            assert list(p["target"]) == [o["target"] for o in exp["points"]]
            assert np.array_equal(
                p["uv"], np.array([[o["u"], o["v"]] for o in exp["points"]]).reshape(-1, 2)
            )
            assert np.array_equal(
                p["world"], np.array([o["world"] for o in exp["points"]]).reshape(-1, 3)
            )
            rgb = [[c if c is not None else [np.nan, np.nan] for c in o["uv_rgb"]]
                   for o in exp["points"]]
            assert np.array_equal(p["uv_rgb"], np.array(rgb).reshape(-1, 3, 2), equal_nan=True)
        seen += sum(len(im["points"]["uv"]) for im in t["images"])
    assert seen > 0


def test_plan_and_dive_match_the_cli():
    s = poser.load(RIG)
    assert s.plan() == json.loads(cli("plan", RIG, "--json"))["survey"]
    assert s.dive() == json.loads(cli("dive", RIG, "--json"))
    assert isinstance(s.dive()["verdict"]["ok"], bool)


def test_render_equals_the_cli_exr(tmp_path):
    cv2 = pytest.importorskip("cv2")
    s = poser.load(DOME)
    img = s.render(1, samples=2, scale=0.05)
    cli("render", DOME, "-o", tmp_path, "--poses", "1", "--samples", 2, "--scale", 0.05,
        "--quiet")
    name = s.poses[1]["name"]
    exr = cv2.imread(str(tmp_path / f"{name}.exr"), cv2.IMREAD_UNCHANGED)
    assert exr is not None, "OpenCV could not read the EXR (OPENCV_IO_ENABLE_OPENEXR=1?)"
    want = exr[:, :, ::-1]  # OpenCV reads BGR
    assert img.dtype == np.float32 and img.shape == want.shape
    assert np.array_equal(img, want)
    assert img.mean() > 0 and np.isfinite(img).all()
    with pytest.raises(ValueError, match="scale"):
        s.render(0, scale=0)
    with pytest.raises(ValueError, match="out of range"):
        s.render(len(s.poses))


def test_render_refuses_zero_samples():
    s = poser.load(DOME)
    with pytest.raises(poser.PoserError, match="0 samples"):
        s.render(0, samples=0, scale=0.05)


def test_render_releases_the_gil():
    s = poser.load(DOME)
    done = threading.Event()
    ticks_during = 0

    def work():
        s.render(0, samples=4, scale=0.1)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks_during += 1
    t.join()
    # With the GIL held for the whole render this loop could not run while it did.
    assert ticks_during > 1000


def test_compile_writes_what_the_cli_writes(tmp_path):
    s = poser.load(FLAT)
    for backend in ("mitsuba", "blender"):
        s.compile(backend, tmp_path / "py" / backend)
        cli("compile", FLAT, "--backend", backend, "-o", tmp_path / "cli" / backend)
        a = sorted(p.relative_to(tmp_path / "py" / backend)
                   for p in (tmp_path / "py" / backend).rglob("*") if p.is_file())
        b = sorted(p.relative_to(tmp_path / "cli" / backend)
                   for p in (tmp_path / "cli" / backend).rglob("*") if p.is_file())
        assert a == b and a
        for rel in a:
            assert (tmp_path / "py" / backend / rel).read_bytes() == (
                tmp_path / "cli" / backend / rel).read_bytes(), rel
    with pytest.raises(ValueError, match="native"):
        s.compile("native", tmp_path / "n")
    with pytest.raises(ValueError):
        s.compile("povray", tmp_path / "n")


def test_readme_example_runs(tmp_path, monkeypatch):
    """The README's Python example, as written, with matplotlib's file backend."""
    readme = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", readme, re.S)
    assert code, "README.md has no ```python example"
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda: plt.savefig(tmp_path / "shown.png"))
    exec(compile(code[1], "README.md", "exec"), {})
    assert (tmp_path / "shown.png").stat().st_size > 1000
