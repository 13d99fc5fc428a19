"""Tests of the COLMAP evaluation driver with the real pycolmap."""

import json
import subprocess
import sys

import numpy as np
import pytest

import pycolmap  # pinned in backends/requirements.txt; a missing one fails loudly


def quat_wxyz(r: np.ndarray) -> list[float]:
    """(w, x, y, z) of a rotation matrix (Shepperd's method, w >= 0 branch is enough here)."""
    w = np.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    if w > 1e-6:
        return [
            w,
            (r[2, 1] - r[1, 2]) / (4 * w),
            (r[0, 2] - r[2, 0]) / (4 * w),
            (r[1, 0] - r[0, 1]) / (4 * w),
        ]
    x = np.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0
    return [
        (r[2, 1] - r[1, 2]) / (4 * x),
        x,
        (r[0, 1] + r[1, 0]) / (4 * x),
        (r[0, 2] + r[2, 0]) / (4 * x),
    ]


def rot(axis_angle: np.ndarray) -> np.ndarray:
    return pycolmap.Rotation3d(np.asarray(axis_angle, dtype=float)).matrix()


def synthetic(
    f_init: float,
    seed: int = 1,
    noise: float = 0.3,
    relief: float = 0.3,
    wobble: float = 1.0,
) -> tuple[dict, float]:
    """A pinhole block over rough ground (`relief`, m): tilted cameras (a diver's wobble, its
    size scaled by `wobble`), ids from 100."""
    rng = np.random.default_rng(seed)
    f, w, h = 800.0, 1200, 800
    pts = np.c_[
        rng.uniform(-3, 3, 500), rng.uniform(-2, 2, 500), rng.normal(0, relief, 500)
    ]
    images = []
    image_id = 0
    for x in np.linspace(-2, 2, 6):
        for y in np.linspace(-1.2, 1.2, 4):
            image_id += 1
            r = rot(wobble * rng.normal(0, 0.08, 3)) @ np.diag([1.0, -1.0, -1.0])
            c = np.array([x, y, 2.0]) + wobble * rng.normal(0, 0.05, 3)
            t = -r @ c
            obs = []
            for k, p in enumerate(pts):
                xc = r @ p + t
                u, v = f * xc[0] / xc[2] + w / 2, f * xc[1] / xc[2] + h / 2
                if 0 < u < w and 0 < v < h and xc[2] > 0:
                    obs.append(
                        [u + rng.normal(0, noise), v + rng.normal(0, noise), 100 + k]
                    )
            rp = rot(rng.normal(0, 0.01, 3)) @ r
            cp = c + rng.normal(0, 0.02, 3)
            images.append(
                {
                    "id": image_id,
                    "name": f"img_{image_id:03}",
                    "camera": 1,
                    "qvec": quat_wxyz(rp),
                    "tvec": list(-rp @ cp),
                    "observations": obs,
                }
            )
    req = {
        "job": "bundle",
        "model": "simple_radial",
        "cameras": [
            {
                "id": 1,
                "width": w,
                "height": h,
                "fx": f_init,
                "fy": f_init,
                "cx": 600.0,
                "cy": 400.0,
            }
        ],
        "images": images,
        "points": [
            {"id": 100 + k, "xyz": list(p + rng.normal(0, 0.02, 3))}
            for k, p in enumerate(pts)
        ],
        "threads": 1,
    }
    return req, f


def test_bundle_recovers_the_focal_length_from_a_wrong_start(driver):
    req, f = synthetic(f_init=700.0)
    out = driver.bundle(pycolmap, req)
    cam = out["cameras"][0]
    assert cam["model"] == "SIMPLE_RADIAL"
    assert abs(cam["params"][0] - f) / f < 0.01
    assert out["summary"]["reprojection_error"] < 0.5
    assert out["summary"]["registered"] == len(req["images"])
    # The request's point ids come back, not COLMAP's own numbering.
    ids = {p["id"] for p in out["points"]}
    assert min(ids) >= 100
    assert ids <= {p["id"] for p in req["points"]}


def test_a_point_run_off_to_a_camera_centre_is_dropped_and_counted(driver):
    req, _ = synthetic(f_init=800.0)
    assert driver.bundle(pycolmap, req)["summary"]["diverged_points"] == 0
    rec, _ = driver.build_reconstruction(pycolmap, req)
    rec.update_point_3d_errors()
    assert driver.drop_diverged_points(rec) == 0
    sound = rec.compute_mean_reprojection_error()
    # Move one point to within a micrometre of the camera centre of an image that sees it:
    # its residuals there have no bound, and the mean with it is meaningless.
    pid = max(rec.points3D, key=lambda k: rec.points3D[k].track.length())
    image = rec.image(rec.points3D[pid].track.elements[0].image_id)
    centre = image.projection_center()
    rec.points3D[pid].xyz = centre + np.array([1e-6, 0.0, 1e-9])
    rec.update_point_3d_errors()
    assert rec.compute_mean_reprojection_error() > 1e3 * sound
    assert driver.drop_diverged_points(rec) == 1
    assert pid not in rec.points3D
    assert abs(rec.compute_mean_reprojection_error() - sound) < 0.05 * sound


def test_the_covariance_tells_a_determined_focal_length_from_one_that_trades_with_height(
    driver,
):
    # Rough ground and a wobble: the focal length is held (measured: 0.19 % of f per px of
    # image noise, under the 1 % bar), and the probe agrees (a 179 % rise).
    req, _ = synthetic(f_init=800.0)
    s = driver.bundle(pycolmap, req)["summary"]
    assert s["focal_covariance"] == "ok"
    assert 0 < s["focal_sd"] < 0.01
    assert s["focal_sensitivity"] > 0.005
    # Flat ground under a perfectly regular block (one height, looking straight down): focal
    # length and height trade, and the normal matrix says so (singular, or a deviation far
    # above the bar).
    req, _ = synthetic(f_init=800.0, relief=0.0, wobble=0.0)
    s = driver.bundle(pycolmap, req)["summary"]
    assert s["focal_covariance"] == "rank_deficient" or s["focal_sd"] > 0.01, s
    # Relief does not help a perfectly regular block: with every camera at one height and
    # looking one way, scaling f and every depth below the cameras' plane by one factor leaves
    # every image as it is (measured: singular; probe 0.005 %).
    req, _ = synthetic(f_init=800.0, wobble=0.0)
    s = driver.bundle(pycolmap, req)["summary"]
    assert s["focal_covariance"] == "rank_deficient", s
    assert s["focal_sensitivity"] < 0.005


def test_quaternions_round_trip(driver):
    q = quat_wxyz(rot([0.3, -0.2, 0.1]))
    r = driver.rigid(pycolmap, q, [1.0, 2.0, 3.0])
    assert np.allclose(driver.qvec_of(r.rotation), q, atol=1e-12)


def test_too_few_images_is_a_clear_error(driver):
    req, _ = synthetic(f_init=800.0)
    req["images"] = req["images"][:2]
    with pytest.raises(driver.EvaluateError, match="at least 3"):
        driver.bundle(pycolmap, req)


def test_unknown_model_is_refused(driver):
    req, _ = synthetic(f_init=800.0)
    req["model"] = "fisheye_of_doom"
    with pytest.raises(driver.EvaluateError, match="unknown camera model"):
        driver.bundle(pycolmap, req)


def test_command_line_writes_the_result_atomically(driver, tmp_path):
    req, _ = synthetic(f_init=780.0)
    (tmp_path / "req.json").write_text(json.dumps(req))
    r = subprocess.run(
        [
            sys.executable,
            driver.__file__,
            str(tmp_path / "req.json"),
            str(tmp_path / "res.json"),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "res.json").read_text())
    assert set(res) == {"cameras", "images", "points", "summary"}
    assert not list(tmp_path.glob(".poser-*"))


def block_truth(seed: int = 1) -> np.ndarray:
    """The true points of `synthetic(seed=seed)` (the same first draws of its generator)."""
    rng = np.random.default_rng(seed)
    return np.c_[
        rng.uniform(-3, 3, 500), rng.uniform(-2, 2, 500), rng.normal(0, 0.3, 500)
    ]


def errors(out: dict, truth: np.ndarray) -> dict[int, np.ndarray]:
    """Each reconstructed point's error against the truth, by request id (no alignment)."""
    return {p["id"]: np.asarray(p["xyz"]) - truth[p["id"] - 100] for p in out["points"]}


def with_gcps(req: dict, truth: np.ndarray, sigma: float, first=None):
    """The request with four control points near the block's corners, weighted at `sigma`
    (m); `first`: the first one's own (sigma, offset of its known z)."""
    corners = [
        int(np.argmin(np.linalg.norm(truth[:, :2] - np.array(c), axis=1)))
        for c in [(-2, -1.2), (2, -1.2), (-2, 1.2), (2, 1.2)]
    ]
    req = dict(req)
    req["gcps"] = [
        {"id": 100 + k, "xyz": list(truth[k]), "sigma": sigma} for k in corners
    ]
    if first is not None:
        req["gcps"][0]["sigma"] = first[0]
        req["gcps"][0]["xyz"][2] += first[1]
    req["tie_sigma_px"] = 0.3
    return req, [100 + k for k in corners]


def test_weighted_gcps_put_the_block_in_their_frame(driver):
    # Without control points the gauge is two perturbed cameras: the block comes back
    # shifted, turned and scaled by centimetres to decimetres. Weighted control points fix the
    # datum themselves: every point lands on its truth to the noise (measured: RMS 0.8, 0.6,
    # 1.7 mm in X, Y, Z against 263, 123, 141 mm without), with no similarity applied.
    req, _ = synthetic(f_init=760.0)
    truth = block_truth()
    free = np.array(list(errors(driver.bundle(pycolmap, req), truth).values()))
    assert np.sqrt((free**2).mean()) > 0.05
    out = driver.bundle(pycolmap, with_gcps(req, truth, 0.002)[0])
    e = np.array(list(errors(out, truth).values()))
    assert np.sqrt((e**2).mean(axis=0)).max() < 0.004, np.sqrt((e**2).mean(axis=0))
    # The control points' views are not part of the result.
    assert out["summary"]["gcps_weighted"] == 4
    assert out["summary"]["registered"] == len(req["images"])
    assert [c["id"] for c in out["cameras"]] == [1]
    assert {im["name"] for im in out["images"]} == {im["name"] for im in req["images"]}


def test_a_gcp_pulls_its_point_by_its_weight(driver):
    # One control point's known z is 10 cm off. Weighted far above its rays (sigma 0.1 mm),
    # the adjustment puts the point on the wrong coordinate; weighted far below (1 m), the
    # rays keep the point where it is (measured: 99.9 mm and 2.9 mm off its truth).
    req, _ = synthetic(f_init=760.0)
    truth = block_truth()
    for sigma, lo, hi in [(1e-4, 0.09, 0.11), (1.0, 0.0, 0.01)]:
        r, ids = with_gcps(req, truth, 0.002, first=(sigma, 0.1))
        dz = errors(driver.bundle(pycolmap, r), truth)[ids[0]][2]
        assert lo <= dz <= hi, (sigma, dz)


def test_too_few_weighted_gcps_is_a_clear_error(driver):
    req, _ = synthetic(f_init=800.0)
    r, _ = with_gcps(req, block_truth(), 0.002)
    r["gcps"] = r["gcps"][:2]
    with pytest.raises(driver.EvaluateError, match="at least 3"):
        driver.bundle(pycolmap, r)
