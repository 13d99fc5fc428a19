"""Tests of the OpenCV calibration driver on synthetic images of a board (pinhole cameras,
images made by warping a flat board picture with the exact homography of each view)."""

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

W, H, F = 640, 480, 500.0
SQUARE = 0.04
COLS, ROWS = 9, 6  # inner corners; the board has 10 x 7 squares


def board_picture(px: int = 40) -> tuple[np.ndarray, float]:
    """The printed board (white margin of one square), and its pixels per metre."""
    sq_w, sq_h = COLS + 1, ROWS + 1
    img = np.full(((sq_h + 2) * px, (sq_w + 2) * px), 255, np.uint8)
    for j in range(sq_h):
        for i in range(sq_w):
            if (i + j) % 2 == 0:
                img[(j + 1) * px : (j + 2) * px, (i + 1) * px : (i + 2) * px] = 0
    return img, px / SQUARE


def render(k: np.ndarray, rvec, tvec, pic: np.ndarray, ppm: float) -> np.ndarray:
    """The board seen by camera k at pose (rvec, tvec): board-plane metres with the first
    inner corner at the origin, as OpenCV numbers its object points."""
    r, _ = cv2.Rodrigues(np.asarray(rvec, float))
    # board pixel (x, y) -> board metres (x / ppm - 2 squares, y / ppm - 2 squares)
    m = np.array([[1 / ppm, 0, -2 * SQUARE], [0, 1 / ppm, -2 * SQUARE], [0, 0, 1]])
    h = k @ np.c_[r[:, :2], np.asarray(tvec, float)] @ m
    return cv2.warpPerspective(pic, h, (W, H), flags=cv2.INTER_AREA, borderValue=128)


def views(k_by_channel: dict, tmp_path) -> list[str]:
    pic, ppm = board_picture()
    poses = [
        ([0.0, 0.0, 0.0], [-0.16, -0.1, 0.55]),
        ([0.3, 0.0, 0.0], [-0.16, -0.1, 0.6]),
        ([-0.3, 0.1, 0.0], [-0.16, -0.1, 0.6]),
        ([0.0, 0.35, 0.1], [-0.2, -0.1, 0.6]),
        ([0.0, -0.35, -0.1], [-0.12, -0.1, 0.6]),
        ([0.2, 0.2, 0.3], [-0.1, -0.15, 0.65]),
        ([-0.2, -0.2, -0.2], [-0.2, -0.05, 0.5]),
        ([0.1, -0.25, 0.0], [-0.25, -0.18, 0.7]),
    ]
    paths = []
    for i, (r, t) in enumerate(poses):
        chans = [render(k_by_channel[c], r, t, pic, ppm) for c in "bgr"]
        p = tmp_path / f"img_{i:04d}.png"
        cv2.imwrite(str(p), np.dstack(chans))
        paths.append(str(p))
    return paths


def kmat(f: float) -> np.ndarray:
    return np.array([[f, 0.0, (W - 1) / 2], [0.0, f, (H - 1) / 2], [0.0, 0.0, 1.0]])


def test_recovers_a_pinhole_camera(driver, tmp_path):
    k = kmat(F)
    out = driver.run(
        {
            "images": views({"r": k, "g": k, "b": k}, tmp_path),
            "pattern": [COLS, ROWS],
            "square": SQUARE,
            "per_channel": True,
        }
    )
    assert len(out["views"]) == 8 and out["rejected"] == []
    assert out["rms"] < 0.3
    assert out["fx"] == pytest.approx(F, rel=0.01)
    assert out["fy"] == pytest.approx(F, rel=0.01)
    # OpenCV's convention: the image centre is ((W - 1) / 2, (H - 1) / 2) ...
    assert out["cx"] == pytest.approx((W - 1) / 2, abs=2.0)
    # ... and poser's is half a pixel further.
    assert out["cx_poser"] == pytest.approx(out["cx"] + 0.5)
    assert abs(out["dist"]["k1"]) < 0.05
    # The same camera in every channel: no lateral colour.
    assert out["lateral_colour"]["detected_r_minus_b_px"] < 0.1
    assert out["lateral_colour"]["r_minus_b_px"] < 0.3


def test_measures_lateral_colour(driver, tmp_path):
    # Red imaged 1 % larger than blue about the centre: at a corner r px from the centre the
    # two images are 0.01 r apart.
    k = {"r": kmat(F * 1.01), "g": kmat(F * 1.005), "b": kmat(F)}
    out = driver.run(
        {
            "images": views(k, tmp_path),
            "pattern": [COLS, ROWS],
            "square": SQUARE,
            "per_channel": True,
        }
    )
    lc = out["lateral_colour"]
    centre = np.array([(W - 1) / 2, (H - 1) / 2])
    r = np.mean(np.linalg.norm(np.array(lc["points"]) - centre, axis=1))
    assert lc["detected_r_minus_b_px"] == pytest.approx(0.01 * r, rel=0.2)
    # Through the calibrations it is less exact: each channel's distortion terms trade a little
    # with its focal length (measured here: 2.66 px for 1.99 px).
    assert lc["r_minus_b_px"] == pytest.approx(0.01 * r, rel=0.5)
    assert out["channels"]["r"]["fx"] / out["channels"]["b"]["fx"] == pytest.approx(
        1.01, abs=0.005
    )


def test_too_few_boards_is_a_clear_error(driver, tmp_path):
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((H, W, 3), 128, np.uint8))
    req = tmp_path / "req.json"
    req.write_text(
        json.dumps({"images": [str(blank)], "pattern": [COLS, ROWS], "square": 0.04})
    )
    p = subprocess.run(
        [sys.executable, driver.__file__, str(req), str(tmp_path / "res.json")],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 1
    assert "error: the board was found in only 0 of 1 images" in p.stderr
    assert "help:" in p.stderr
    assert not (tmp_path / "res.json").exists()
