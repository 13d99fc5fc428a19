"""Calibrate a camera from rendered images of a checkerboard with OpenCV, for `poser lesson`.

The Rust side writes a JSON request; this script detects the board's inner corners in the
images themselves (``cv2.findChessboardCorners`` + ``cv2.cornerSubPix``, never the truth),
calibrates with ``cv2.calibrateCamera`` (k1, k2, p1, p2, k3) and writes a JSON result
(atomically: temporary name, then rename).

Pixel convention: OpenCV's, pixel centres at integers. poser's (and COLMAP's) centres are at
+0.5, so ``cx_poser = cx_opencv + 0.5``; the result gives both.

Colour: with ``per_channel`` the corners are also detected and the camera calibrated in each of
the R, G and B channels separately, each starting from the grey calibration and holding its
principal point and k3 (so that channel noise does not move them). The lateral colour at the image corners is then measured
through those three calibrations: each corner pixel of the green calibration is turned into its
ray and projected through the red and the blue ones; the distance between the red and blue
pixels, averaged over the four corners, is the lateral chromatic aberration in pixels. The
"corner pixels" are the board corners observed nearest to each image corner, so that the
distortion polynomials are never used outside the region they were fitted on.

Request::

    {"images": ["/abs/img_0001.png", ...], "pattern": [cols, rows],   # inner corners
     "square": 0.05, "per_channel": true}

Result::

    {"conventions": "...", "width": W, "height": H, "views": [names used],
     "rejected": [names without a full board], "rms": px,
     "fx": .., "fy": .., "cx": .., "cy": .., "cx_poser": .., "cy_poser": ..,
     "dist": {"k1", "k2", "p1", "p2", "k3"},
     "residuals": [[u, v, du, dv], ...],                 # observed - reprojected, px
     "channels": {"r": {"rms", "fx", "fy", "cx", "cy", "dist"}, "g": ..., "b": ...},
     "lateral_colour": {"r_minus_b_px", "r_minus_g_px", "b_minus_g_px",
                        "detected_r_minus_b_px", "points", "radius_fraction"}}

Usage: python calibrate.py REQUEST.json RESULT.json
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

CONVENTIONS = (
    "OpenCV pixel convention: pixel centres at integer coordinates "
    "(poser's and COLMAP's are at +0.5: cx_poser = cx_opencv + 0.5)"
)
SUBPIX = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)
DIST = ("k1", "k2", "p1", "p2", "k3")


class Failure(Exception):
    """A calibration that cannot be done; the message says what to change."""


def board_points(cols: int, rows: int, square: float) -> np.ndarray:
    """The board's inner corners in its own plane (z = 0), metres, OpenCV's row-major order."""
    grid = np.zeros((rows * cols, 3), np.float32)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square
    return grid


def detect(gray: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """Sub-pixel inner corners of the board in one 8-bit image, or None."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH + cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, corners = cv2.findChessboardCorners(gray, pattern, flags=flags)
    if not ok:
        return None
    return cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), SUBPIX)


def calibrate(
    obj: list[np.ndarray],
    img: list[np.ndarray],
    size: tuple[int, int],
    guess: dict | None = None,
) -> tuple[dict, list[list[float]]]:
    """Intrinsics, distortion and per-corner residuals of one calibration. With `guess` (a
    previous calibration), start from it and hold its principal point and k3: how the colour
    channels are calibrated, so that they differ only where dispersion makes them differ."""
    if guess is None:
        rms, k, d, rvecs, tvecs = cv2.calibrateCamera(obj, img, size, None, None)
    else:
        k0, d0 = matrix(guess)
        flags = (
            cv2.CALIB_USE_INTRINSIC_GUESS
            + cv2.CALIB_FIX_PRINCIPAL_POINT
            + cv2.CALIB_FIX_K3
        )
        rms, k, d, rvecs, tvecs = cv2.calibrateCamera(
            obj, img, size, k0.copy(), d0.copy(), flags=flags
        )
    d = d.ravel()
    residuals = []
    for o, i, r, t in zip(obj, img, rvecs, tvecs):
        proj, _ = cv2.projectPoints(o, r, t, k, d)
        for (u, v), (pu, pv) in zip(i.reshape(-1, 2), proj.reshape(-1, 2)):
            residuals.append([float(u), float(v), float(u - pu), float(v - pv)])
    cal = {
        "rms": float(rms),
        "fx": float(k[0, 0]),
        "fy": float(k[1, 1]),
        "cx": float(k[0, 2]),
        "cy": float(k[1, 2]),
        "dist": {n: float(x) for n, x in zip(DIST, d)},
    }
    return cal, residuals


def matrix(cal: dict) -> tuple[np.ndarray, np.ndarray]:
    k = np.array(
        [[cal["fx"], 0.0, cal["cx"]], [0.0, cal["fy"], cal["cy"]], [0.0, 0.0, 1.0]]
    )
    return k, np.array([cal["dist"][n] for n in DIST])


def lateral_colour(channels: dict, img: dict, size: tuple[int, int]) -> dict:
    """Lateral colour at the image corners, through the per-channel calibrations.

    For each corner of the image, the board corner seen nearest to it (in green, any view) is
    turned into its ray by the green calibration and projected through the red and the blue
    ones; the distances are averaged over the four image corners. Staying on observed corners
    keeps the distortion polynomials inside the region they were fitted on. ``detected_*`` is
    the same distance measured directly between the corners detected in each channel.
    """
    w, h = size
    green = np.concatenate([v.reshape(-1, 2) for v in img["g"]])
    red = np.concatenate([v.reshape(-1, 2) for v in img["r"]])
    blue = np.concatenate([v.reshape(-1, 2) for v in img["b"]])
    picks = [
        int(np.argmin(np.linalg.norm(green - np.array(c), axis=1)))
        for c in ([0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0])
    ]
    pts = green[picks].reshape(-1, 1, 2)
    kg, dg = matrix(channels["g"])
    rays = cv2.undistortPoints(pts, kg, dg).reshape(-1, 2)
    xyz = np.c_[rays, np.ones(len(rays))]
    zero = np.zeros(3)

    def project(c: str) -> np.ndarray:
        k, d = matrix(channels[c])
        return cv2.projectPoints(xyz, zero, zero, k, d)[0].reshape(-1, 2)

    p = {c: project(c) for c in "rgb"}

    def mean(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.mean(np.linalg.norm(a - b, axis=1)))

    centre = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    return {
        "r_minus_b_px": mean(p["r"], p["b"]),
        "r_minus_g_px": mean(p["r"], p["g"]),
        "b_minus_g_px": mean(p["b"], p["g"]),
        "detected_r_minus_b_px": mean(red[picks], blue[picks]),
        "points": green[picks].tolist(),
        "radius_fraction": float(
            np.mean(np.linalg.norm(green[picks] - centre, axis=1))
            / np.linalg.norm(centre)
        ),
    }


def run(req: dict) -> dict:
    cols, rows = (int(x) for x in req["pattern"])
    if cols < 2 or rows < 2:
        raise Failure(
            f"pattern {cols} x {rows}: a board needs at least 2 x 2 inner corners"
        )
    pattern = (cols, rows)
    grid = board_points(cols, rows, float(req["square"]))
    per_channel = bool(req.get("per_channel", False))
    views, rejected = [], []
    obj: list[np.ndarray] = []
    img: dict[str, list[np.ndarray]] = {"gray": [], "r": [], "g": [], "b": []}
    size = None
    for path in req["images"]:
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            raise Failure(f"cannot read image {path}")
        h, w = bgr.shape[:2]
        if size is None:
            size = (w, h)
        elif size != (w, h):
            raise Failure(
                f"{path}: {w} x {h} px, the others are {size[0]} x {size[1]} px"
            )
        found = {"gray": detect(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), pattern)}
        if per_channel:
            for c, i in (("b", 0), ("g", 1), ("r", 2)):
                found[c] = detect(np.ascontiguousarray(bgr[:, :, i]), pattern)
        if any(v is None for v in found.values()):
            rejected.append(Path(path).name)
            continue
        views.append(Path(path).name)
        obj.append(grid)
        for c, v in found.items():
            img[c].append(v)
    if len(views) < 3:
        raise Failure(
            f"the board was found in only {len(views)} of {len(req['images'])} images; "
            "a calibration needs at least 3 (help: show the whole board in more views)"
        )
    cal, residuals = calibrate(obj, img["gray"], size)
    out = {
        "conventions": CONVENTIONS,
        "width": size[0],
        "height": size[1],
        "views": views,
        "rejected": rejected,
        **cal,
        "cx_poser": cal["cx"] + 0.5,
        "cy_poser": cal["cy"] + 0.5,
        "residuals": residuals,
        "opencv": cv2.__version__,
    }
    if per_channel:
        channels = {c: calibrate(obj, img[c], size, cal)[0] for c in "rgb"}
        out["channels"] = channels
        out["lateral_colour"] = lateral_colour(channels, img, size)
    return out


def write_atomic(path: Path, data: dict) -> None:
    """Write JSON to a temporary file beside `path`, then rename it onto `path`."""
    fd, tmp = tempfile.mkstemp(prefix=".poser-", suffix=".json", dir=path.parent)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        json.dump(data, f)
    os.replace(tmp, path)


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    request, result = Path(argv[1]), Path(argv[2])
    with open(request, encoding="utf-8") as f:
        req = json.load(f)
    try:
        out = run(req)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    write_atomic(result, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
