"""Process a simulated survey with COLMAP (pycolmap) for `poser evaluate`.

Two jobs, both reading a JSON request written by the Rust side and writing a JSON result
(atomically: temporary name, then rename). Pixel coordinates follow COLMAP's convention, pixel
centres at +0.5, the same as poser's.

``bundle`` (observations mode): a reconstruction is built from the request's cameras (initial
intrinsics, e.g. the in-air focal length a practitioner reads from EXIF), images (initial,
perturbed ``cam_from_world`` poses), 3D points (initial, perturbed positions) and their 2D
observations; COLMAP's bundle adjuster then refines poses, points and the camera model's
intrinsics (self-calibration). The gauge is fixed by two cameras (COLMAP's
``TWO_CAMS_FROM_WORLD``); the result is compared with the truth by a similarity on the Rust side.
With ``gcps`` (control points weighted in the adjustment, ``poser evaluate --gcp-sigma``), each
control point's known position enters COLMAP's bundle adjustment as a weighted constraint, and
the gauge is theirs (no camera is held): see ``add_gcp_views``.
With a ``rig`` (a rig calibrated beforehand), the cameras form one COLMAP rig, each rig pose
one frame; the intrinsics and the sensors' poses in the rig are held, and the bundle adjuster
refines the frames' poses and the points, the first frame held (the baseline sets the scale).

``images`` (images mode): COLMAP's own pipeline on rendered images: SIFT extraction, matching
(sequential or exhaustive) and incremental mapping, with the same camera model, shared by all
images, initialised from the request's camera.

Request (``bundle``)::

    {"job": "bundle", "model": "simple_radial", "refine_principal_point": true,
     "cameras": [{"id": 1, "width": W, "height": H, "fx": .., "fy": .., "cx": .., "cy": ..}],
     "images": [{"id": 1, "name": "..", "camera": 1, "qvec": [w, x, y, z], "tvec": [..],
                 "observations": [[u, v, point_id], ...]}],
     "points": [{"id": 1, "xyz": [x, y, z]}],
     "gcps": [{"id": 1, "xyz": [x, y, z], "sigma": 0.002}],      # optional; point ids, m
     "tie_sigma_px": 0.3,                                        # with gcps: the pixels' sigma
     "rig": {"sensor_from_rig": [{"qvec": .., "tvec": ..}, ...],   # optional; per camera
             "frames": [{"id": 1, "qvec": .., "tvec": ..}]}}      # rig_from_world per pose
    (with a rig, each image also has ``"frame": id``)

Request (``images``)::

    {"job": "images", "model": ..., "image_dir": "..", "work_dir": "..", "matcher":
     "sequential" | "exhaustive", "cameras": [one camera as above], "images": [{"name": ..}]}

Result (both)::

    {"cameras": [{"id", "model", "params", "width", "height"}],
     "images": [{"id", "name", "qvec", "tvec"}],          # registered images, cam_from_world
     "points": [{"id", "xyz", "error", "track"}],          # track = number of observations
     "summary": {...}}

Usage: python evaluate.py REQUEST.json RESULT.json
"""

from __future__ import annotations

import json
import math
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

MODELS = {
    # poser name -> (COLMAP model, params from (fx, fy, cx, cy))
    "pinhole": ("PINHOLE", lambda fx, fy, cx, cy: [fx, fy, cx, cy]),
    "simple_radial": (
        "SIMPLE_RADIAL",
        lambda fx, fy, cx, cy: [0.5 * (fx + fy), cx, cy, 0.0],
    ),
    "radial": ("RADIAL", lambda fx, fy, cx, cy: [0.5 * (fx + fy), cx, cy, 0.0, 0.0]),
    "opencv": ("OPENCV", lambda fx, fy, cx, cy: [fx, fy, cx, cy, 0.0, 0.0, 0.0, 0.0]),
    "full_opencv": (
        "FULL_OPENCV",
        lambda fx, fy, cx, cy: [fx, fy, cx, cy] + [0.0] * 8,
    ),
}


class EvaluateError(Exception):
    """A request COLMAP cannot process; the message says what to change."""


def make_camera(pycolmap, cam: dict, model: str):
    """A COLMAP camera of `model` initialised from the request's intrinsics."""
    if model not in MODELS:
        raise EvaluateError(
            f"unknown camera model {model!r}; use one of {sorted(MODELS)}"
        )
    name, params = MODELS[model]
    return pycolmap.Camera(
        camera_id=int(cam["id"]),
        model=name,
        width=int(cam["width"]),
        height=int(cam["height"]),
        params=params(
            float(cam["fx"]), float(cam["fy"]), float(cam["cx"]), float(cam["cy"])
        ),
    )


def rigid(pycolmap, qvec, tvec):
    """``cam_from_world`` from a (w, x, y, z) quaternion and a translation."""
    w, x, y, z = (float(a) for a in qvec)
    return pycolmap.Rigid3d(
        pycolmap.Rotation3d([x, y, z, w]), np.asarray(tvec, dtype=float)
    )


def qvec_of(rot) -> list[float]:
    """(w, x, y, z), w >= 0, of a pycolmap Rotation3d (stored x, y, z, w)."""
    x, y, z, w = (float(a) for a in rot.quat)
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    return [w, x, y, z]


def build_reconstruction(pycolmap, req: dict):
    """A COLMAP reconstruction of the request's initial cameras, images, points and tracks,
    and the map from COLMAP's point ids (it numbers them itself) to the request's."""
    rec = pycolmap.Reconstruction()
    ids: dict[int, int] = {}  # COLMAP's point id -> the request's
    model = req["model"]
    rig = req.get("rig")
    # Observations per point: (image id, point2D index).
    tracks: dict[int, list[tuple[int, int]]] = {}
    images = []
    for im in req["images"]:
        obs = im["observations"]
        xy = np.array([[o[0], o[1]] for o in obs], dtype=float).reshape(-1, 2)
        images.append(
            pycolmap.Image(
                name=im["name"],
                keypoints=xy,
                camera_id=int(im["camera"]),
                image_id=int(im["id"]),
            )
        )
        for k, o in enumerate(obs):
            tracks.setdefault(int(o[2]), []).append((int(im["id"]), k))
    if rig is None:
        for cam in req["cameras"]:
            rec.add_camera_with_trivial_rig(make_camera(pycolmap, cam, model))
        for im, image in zip(req["images"], images):
            rec.add_image_with_trivial_frame(
                image, rigid(pycolmap, im["qvec"], im["tvec"])
            )
    else:
        add_rig(pycolmap, rec, req, images)
    for p in req["points"]:
        elems = tracks.get(int(p["id"]), [])
        if len(elems) < 2:
            continue
        track = pycolmap.Track()
        for image_id, k in elems:
            track.add_element(image_id, k)
        pid = rec.add_point3D(np.asarray(p["xyz"], dtype=float), track)
        ids[pid] = int(p["id"])
    return rec, ids


def add_rig(pycolmap, rec, req: dict, images: list) -> None:
    """A calibrated rig: one COLMAP rig whose reference sensor is the request's first camera,
    the others at their ``sensor_from_rig`` poses, and one frame per rig pose holding that
    pose's images, initialised at the frame's ``rig_from_world``."""
    rig_req = req["rig"]
    for cam in req["cameras"]:
        rec.add_camera(make_camera(pycolmap, cam, req["model"]))
    rig = pycolmap.Rig(rig_id=1)
    for k, cam in enumerate(req["cameras"]):
        sensor = rec.camera(int(cam["id"])).sensor_id
        if k == 0:
            rig.add_ref_sensor(sensor)
        else:
            s = rig_req["sensor_from_rig"][k]
            rig.add_sensor(sensor, rigid(pycolmap, s["qvec"], s["tvec"]))
    rec.add_rig(rig)
    by_frame: dict[int, list] = {}
    for im, image in zip(req["images"], images):
        by_frame.setdefault(int(im["frame"]), []).append(image)
    for f in rig_req["frames"]:
        fid = int(f["id"])
        members = by_frame.get(fid, [])
        if not members:
            continue
        frame = pycolmap.Frame()
        frame.frame_id = fid
        frame.rig_id = 1
        for image in members:
            frame.add_data_id(image.data_id)
        frame.rig_from_world = rigid(pycolmap, f["qvec"], f["tvec"])
        rec.add_frame(frame)
        for image in members:
            image.frame_id = fid
            rec.add_image(image)
        rec.register_frame(fid)


# Distance of a control point's three views from it, m: far enough that each view projects
# the point's displacement parallel to its image plane (the relative error of that linear
# reading is the displacement over this distance, 1e-4 for a 0.1 m displacement).
GCP_VIEW_DISTANCE = 1000.0
# Each view's image size, px (the point projects to its centre; the adjustment does not clip).
GCP_VIEW_SIZE = 1000


def add_gcp_views(pycolmap, rec, req: dict, ids: dict[int, int]) -> list[int]:
    """Control points weighted in the adjustment, as Metashape weights a marker by its accuracy.

    COLMAP's bundle adjuster sums squared reprojection errors in pixels; a position prior on
    a 3D point is added to that sum as pseudo-observations: each control point is seen by three
    views of its own, held (pose and intrinsics constant), looking at its known position along
    −x, −y and −z from ``GCP_VIEW_DISTANCE``. A view reads the point's displacement across its
    line of sight in pixels at ``F / D`` px per metre, so each axis is read by two views and
    the point adds ``|X − G|² · 2 (F/D)²`` to the cost. With ``F/D = s_px / (s_G √2)`` that is
    ``s_px² |X − G|² / s_G²``: the control point's squared error in units of its own sigma,
    on the same scale as a tie point's squared pixel error in units of ``s_px`` (the request's
    ``tie_sigma_px``). Returns the image ids of the views (removed again by
    ``remove_gcp_views``)."""
    by_request = {v: k for k, v in ids.items()}
    tie_sigma = float(req["tie_sigma_px"])
    if not (math.isfinite(tie_sigma) and tie_sigma > 0):
        raise EvaluateError(
            f"tie_sigma_px {tie_sigma}: expected a positive pixel sigma"
        )
    next_camera = max(rec.cameras) + 1
    next_image = max(rec.images) + 1
    views = []
    axes = np.eye(3)
    for g in req["gcps"]:
        pid = by_request.get(int(g["id"]))
        if pid is None:
            continue  # not reconstructed (seen by fewer than two images)
        sigma = float(g["sigma"])
        if not (math.isfinite(sigma) and sigma > 0):
            raise EvaluateError(f"gcp {g['id']}: sigma {sigma} m, expected > 0")
        known = np.asarray(g["xyz"], dtype=float)
        focal = tie_sigma / (sigma * math.sqrt(2.0)) * GCP_VIEW_DISTANCE
        c = GCP_VIEW_SIZE / 2.0
        for k in range(3):
            # Rows of cam_from_world: the view's x, y and z (its axis, towards the point).
            z = -axes[k]
            x = axes[(k + 1) % 3]
            r = np.stack([x, np.cross(z, x), z])
            centre = known + GCP_VIEW_DISTANCE * axes[k]
            rec.add_camera_with_trivial_rig(
                pycolmap.Camera(
                    camera_id=next_camera,
                    model="PINHOLE",
                    width=GCP_VIEW_SIZE,
                    height=GCP_VIEW_SIZE,
                    params=[focal, focal, c, c],
                )
            )
            image = pycolmap.Image(
                name=f"gcp-view-{next_image}",
                keypoints=np.array([[c, c]], dtype=float),
                camera_id=next_camera,
                image_id=next_image,
            )
            rec.add_image_with_trivial_frame(
                image, pycolmap.Rigid3d(pycolmap.Rotation3d(r), -r @ centre)
            )
            rec.add_observation(pid, pycolmap.TrackElement(next_image, 0))
            views.append(next_image)
            next_camera += 1
            next_image += 1
    return views


def remove_gcp_views(rec, views: list[int]) -> None:
    """Take the control points' views out of the reconstruction again: their observations
    and their frames, so the statistics, the focal probe and the export see only the
    survey's images."""
    for image_id in views:
        rec.delete_observation(image_id, 0)
        rec.deregister_frame(rec.image(image_id).frame_id)


def ba_options(pycolmap, req: dict):
    """Self-calibrating bundle adjustment: focal, principal point (if asked) and distortion;
    with a calibrated rig, the intrinsics and the rig's relative poses held."""
    opts = pycolmap.BundleAdjustmentOptions()
    calibrated = req.get("rig") is not None
    opts.refine_focal_length = not calibrated
    opts.refine_principal_point = (
        bool(req.get("refine_principal_point", False)) and not calibrated
    )
    opts.refine_extra_params = not calibrated
    opts.refine_sensor_from_rig = False
    opts.print_summary = False
    so = opts.ceres.solver_options
    so.max_num_iterations = int(req.get("max_iterations", 200))
    so.num_threads = int(req.get("threads", os.cpu_count() or 1))
    so.function_tolerance = 1e-10
    # Direct sparse Schur up to large blocks: the iterative solver COLMAP switches to above
    # 1000 images converges slowly on the weakly determined focal length of a survey block.
    opts.ceres.max_num_images_direct_sparse_cpu_solver = 20000
    return opts


def bundle(pycolmap, req: dict) -> dict:
    """Observations mode: bundle-adjust the request from its perturbed initialisation."""
    if len(req["images"]) < 3:
        raise EvaluateError(
            f"only {len(req['images'])} image(s) observe the tie points; bundle adjustment "
            "needs at least 3 (help: widen the network or raise the tie-point density)"
        )
    rec, ids = build_reconstruction(pycolmap, req)
    if rec.num_points3D() < 10:
        raise EvaluateError(
            f"only {rec.num_points3D()} tie point(s) are seen in two or more images "
            "(help: raise --density or the overlap)"
        )
    rec.update_point_3d_errors()
    initial_error = rec.compute_mean_reprojection_error()
    opts = ba_options(pycolmap, req)
    config = pycolmap.BundleAdjustmentConfig()
    for image_id in sorted(rec.reg_image_ids()):
        config.add_image(image_id)
    views = add_gcp_views(pycolmap, rec, req, ids) if req.get("gcps") else []
    if req.get("gcps") and len(views) < 9:
        raise EvaluateError(
            f"only {len(views) // 3} control point(s) are seen in two or more images; "
            "weighting them in the adjustment needs at least 3 (help: add targets inside "
            "the surveyed area or name more of them as control points)"
        )
    for image_id in views:
        # The views are held: they carry the control points' known positions.
        config.add_image(image_id)
        config.set_constant_cam_intrinsics(rec.image(image_id).camera_id)
        config.set_constant_rig_from_world_pose(rec.image(image_id).frame_id)
    if views:
        # The control points fix the datum (position, orientation and scale).
        if req.get("rig") is not None:
            for cam in req["cameras"]:
                config.set_constant_cam_intrinsics(int(cam["id"]))
    elif req.get("rig") is None:
        config.fix_gauge(pycolmap.BundleAdjustmentGauge.TWO_CAMS_FROM_WORLD)
    else:
        # The calibrated rig fixes the scale (its baseline) and the intrinsics; the first
        # frame's pose fixes the other six degrees of freedom.
        for cam in req["cameras"]:
            config.set_constant_cam_intrinsics(int(cam["id"]))
        config.set_constant_rig_from_world_pose(min(rec.reg_frame_ids()))
    adjuster = pycolmap.create_default_ceres_bundle_adjuster(opts, config, rec)
    summary = adjuster.solve()
    # The covariance of the problem just solved (its gauge, the control points' held views
    # in it), before the views leave the reconstruction.
    covariance = (
        focal_covariance(pycolmap, rec, req, adjuster) if req.get("rig") is None else {}
    )
    remove_gcp_views(rec, views)
    rec.update_point_3d_errors()
    diverged = drop_diverged_points(rec)
    # The focal probe, when the adjustment calibrated the camera itself (not a calibrated rig).
    sensitivity = (
        focal_sensitivity(pycolmap, rec, req) if req.get("rig") is None else None
    )
    result = export(rec, ids)
    survey_cameras = {int(c["id"]) for c in req["cameras"]}
    result["cameras"] = [c for c in result["cameras"] if c["id"] in survey_cameras]
    result["summary"] = {
        "initial_reprojection_error": initial_error,
        "reprojection_error": rec.compute_mean_reprojection_error(),
        "termination": str(summary.termination_type).rsplit(".", 1)[-1],
        "usable": bool(summary.is_solution_usable()),
        "registered": rec.num_reg_images(),
        "images": len(req["images"]),
        "mean_track_length": rec.compute_mean_track_length(),
        "observations": rec.compute_num_observations(),
        "focal_sensitivity": sensitivity,
        **covariance,
        "gcps_weighted": len(views) // 3,
        "diverged_points": diverged,
        "colmap": pycolmap.COLMAP_version,
    }
    return result


# A tie point whose mean reprojection error after the adjustment exceeds both this many pixels
# and this many times the median point's has diverged (started far off, it ran to a camera's
# centre or behind it, where a residual has no bound); see drop_diverged_points.
DIVERGED_MIN_PX = 100.0
DIVERGED_TIMES_MEDIAN = 100.0


def drop_diverged_points(rec) -> int:
    """Remove the tie points the adjustment left with an absurd reprojection error and return
    how many. Observations mode starts every pose and point perturbed; on a weak block a few
    points can run off to a camera's centre, where their residuals reach 1e149 px: left in,
    they make the mean reprojection error meaningless and the focal probe's rise relative to
    it vanish. A camera model that fits no image (a held pinhole behind a flat port, about
    36 px everywhere) moves the median with it and keeps its points."""
    errors = {pid: p.error for pid, p in rec.points3D.items()}
    finite = sorted(e for e in errors.values() if math.isfinite(e))
    if not finite:
        return 0
    median = finite[len(finite) // 2]
    limit = max(DIVERGED_MIN_PX, DIVERGED_TIMES_MEDIAN * median)
    gone = [pid for pid, e in errors.items() if not (math.isfinite(e) and e <= limit)]
    for pid in gone:
        rec.delete_point3D(pid)
    if gone:
        rec.update_point_3d_errors()
    return len(gone)


def images(pycolmap, req: dict) -> dict:
    """Images mode: SIFT features, matching and incremental mapping on rendered images."""
    image_dir = Path(req["image_dir"])
    work = Path(req["work_dir"])
    work.mkdir(parents=True, exist_ok=True)
    db = work / "database.db"
    if db.exists():
        db.unlink()
    names = [im["name"] for im in req["images"]]
    missing = [n for n in names if not (image_dir / n).is_file()]
    if missing:
        raise EvaluateError(
            f"{len(missing)} image(s) missing in {image_dir}, e.g. {missing[0]}"
        )
    if req.get("stock") is not None:
        return images_stock(pycolmap, req, image_dir, work, db, names)
    cam = req["cameras"][0]
    model, params = MODELS[req["model"]]
    p = params(float(cam["fx"]), float(cam["fy"]), float(cam["cx"]), float(cam["cy"]))
    reader = pycolmap.ImageReaderOptions()
    reader.camera_model = model
    reader.camera_params = ",".join(repr(float(a)) for a in p)
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.num_threads = int(req.get("threads", os.cpu_count() or 1))
    extraction.sift.max_num_features = int(req.get("max_features", 8192))
    pycolmap.set_random_seed(int(req.get("seed", 0)))
    pycolmap.extract_features(
        db,
        image_dir,
        image_names=names,
        camera_mode=pycolmap.CameraMode.SINGLE,
        reader_options=reader,
        extraction_options=extraction,
        device=pycolmap.Device.cpu,
    )
    match_images(pycolmap, db, req, extraction.num_threads)
    mapper = pycolmap.IncrementalPipelineOptions()
    mapper.num_threads = extraction.num_threads
    mapper.multiple_models = False
    mapper.ba_refine_principal_point = bool(req.get("refine_principal_point", False))
    mapper.random_seed = int(req.get("seed", 0))
    # A survey's neighbours are a few degrees apart (nadir strips at 80 % overlap: about 8°
    # between consecutive images); COLMAP's default of 16° for the initial pair suits
    # turntable-like sets and leaves a strip with no pair to start from.
    mapper.mapper.init_min_tri_angle = float(req.get("init_min_tri_angle", 8.0))
    # Intrinsics held at the prior while the model grows, refined once by a global bundle
    # adjustment at the end (docs/evaluate.md): self-calibrating from the first pair of a
    # nearly flat nadir survey runs the focal length away with the distortion (measured on
    # reef_strip's quick form: 4 of 22 images registered, f 610 px for 445; held: 22 of 22).
    hold = bool(req.get("hold_intrinsics", True))
    if hold:
        mapper.ba_refine_focal_length = False
        mapper.ba_refine_extra_params = False
        mapper.ba_refine_principal_point = False
        mapper.mapper.abs_pose_refine_focal_length = False
        mapper.mapper.abs_pose_refine_extra_params = False
    rec, _ = largest_model(pycolmap, db, image_dir, work, mapper, "COLMAP")
    if hold:
        pycolmap.bundle_adjustment(rec, ba_options(pycolmap, req))
    sensitivity = focal_sensitivity(pycolmap, rec, req)
    covariance = focal_covariance(pycolmap, rec, req)
    return summarise(pycolmap, rec, req, db, names, sensitivity, covariance)


def summarise(pycolmap, rec, req, db, names, sensitivity, covariance) -> dict:
    """The reconstruction `rec` as plain JSON data with its summary."""
    result = export(rec)
    keypoints = 0
    with pycolmap.Database.open(db) as database:
        for image in database.read_all_images():
            keypoints += database.num_keypoints_for_image(image.image_id)
    result["summary"] = {
        "reprojection_error": rec.compute_mean_reprojection_error(),
        "registered": rec.num_reg_images(),
        "images": len(names),
        "mean_track_length": rec.compute_mean_track_length(),
        "observations": rec.compute_num_observations(),
        "keypoints_per_image": keypoints / max(1, len(names)),
        "focal_sensitivity": sensitivity,
        **covariance,
        "colmap": pycolmap.COLMAP_version,
    }
    return result


def match_images(pycolmap, db, req: dict, threads: int):
    """Match the features in `db` on the CPU: every pair, or with `req["matcher"]` =
    "sequential" each image with its `sequential_overlap` (10, COLMAP's default) neighbours
    in the request's order."""
    matching = pycolmap.FeatureMatchingOptions()
    matching.num_threads = threads
    matching.use_gpu = False
    if req.get("matcher", "exhaustive") == "sequential":
        pairing = pycolmap.SequentialPairingOptions()
        pairing.overlap = int(req.get("sequential_overlap", 10))
        pycolmap.match_sequential(
            db, matching_options=matching, pairing_options=pairing
        )
    else:
        pycolmap.match_exhaustive(db, matching_options=matching)


def largest_model(pycolmap, db, image_dir: Path, work: Path, mapper, who: str):
    """Incremental mapping into `work/sparse`: the model with the most images, and all."""
    sparse = work / "sparse"
    sparse.mkdir(exist_ok=True)
    maps = pycolmap.incremental_mapping(db, image_dir, sparse, options=mapper)
    if not maps:
        raise EvaluateError(
            f"{who} registered no images: too few matches between them (help: check that "
            "the scene is textured at the image's GSD, raise samples, or add overlap)"
        )
    return max(maps.values(), key=lambda r: r.num_reg_images()), maps


def images_stock(
    pycolmap, req: dict, image_dir: Path, work: Path, db: Path, names
) -> dict:
    """Images mode as another user of COLMAP would run it on poser's image files: no
    intrinsics handed over (COLMAP reads the focal length from the EXIF and starts from its
    default SIMPLE_RADIAL camera), default feature extraction, matching (exhaustive, or
    COLMAP's sequential matcher with its defaults when `req["matcher"]` says so) and
    incremental mapping with COLMAP's defaults, self-calibrating throughout, the largest
    model kept. The one option changed is the initial pair's minimum triangulation angle
    (`req["stock"]`, degrees; COLMAP's default 16). Threads and the random seed are set,
    which changes no result's quality, only its reproducibility."""
    threads = int(req.get("threads", os.cpu_count() or 1))
    pycolmap.set_random_seed(int(req.get("seed", 0)))
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.num_threads = threads
    pycolmap.extract_features(
        db,
        image_dir,
        image_names=names,
        camera_mode=pycolmap.CameraMode.AUTO,
        reader_options=pycolmap.ImageReaderOptions(),
        extraction_options=extraction,
        device=pycolmap.Device.cpu,
    )
    # The focal length COLMAP took from the EXIF (none: it guessed 1.2 × the image's size).
    with pycolmap.Database.open(db) as database:
        priors = [
            float(c.params[0])
            for c in database.read_all_cameras()
            if c.has_prior_focal_length
        ]
    match_images(pycolmap, db, req, threads)
    mapper = pycolmap.IncrementalPipelineOptions()
    mapper.num_threads = threads
    mapper.random_seed = int(req.get("seed", 0))
    mapper.mapper.init_min_tri_angle = float(req["stock"])
    rec, maps = largest_model(pycolmap, db, image_dir, work, mapper, "stock COLMAP")
    sensitivity = focal_sensitivity(pycolmap, rec, req)
    covariance = focal_covariance(pycolmap, rec, req)
    result = summarise(pycolmap, rec, req, db, names, sensitivity, covariance)
    result["summary"]["models"] = len(maps)
    result["summary"]["exif_focal_px"] = priors[0] if priors else None
    return result


# The largest focal-probe rise reported (1000 %): beyond it the number says only "determined".
RISE_CAP = 10.0


def focal_sensitivity(pycolmap, rec, req: dict) -> float | None:
    """How well the block determines the focal length: the relative rise of the mean
    reprojection error when the focal length is held 10 % above its estimate and everything
    else (poses, points, distortion) is adjusted again. A flat nadir block barely notices
    (focal length and height trade against each other); a block with relief or obliques does.
    A model with two focal lengths (fx, fy) is probed one axis at a time and the smaller rise
    returned: obliques tilted only forward determine fy and leave fx free. Rises are capped at
    RISE_CAP; None when no probe converged to a finite error."""
    base = rec.compute_mean_reprojection_error()
    axes = max((len(c.focal_length_idxs()) for c in rec.cameras.values()), default=0)
    rises = []
    for axis in range(axes):
        probe = pycolmap.Reconstruction(rec)
        for cam in probe.cameras.values():
            params = cam.params.copy()
            idxs = list(cam.focal_length_idxs())
            params[idxs[min(axis, len(idxs) - 1)]] *= 1.1
            cam.params = params
        opts = ba_options(pycolmap, req)
        opts.refine_focal_length = False
        pycolmap.bundle_adjustment(probe, opts)
        rise = (probe.compute_mean_reprojection_error() - base) / max(base, 1e-12)
        # A probe whose adjustment diverged (NaN or infinite error) measures nothing; one that
        # ran away (seen: 1e150 on crossed strips) only says the focal length is held firmly.
        if math.isfinite(rise):
            rises.append(min(rise, RISE_CAP))
    return min(rises) if rises else None


# Above this many registered images the focal covariance is not computed: COLMAP's estimate
# inverts the dense Schur complement on the poses (6 per image), O(images^3).
COVARIANCE_MAX_IMAGES = 600


def focal_covariance(pycolmap, rec, req: dict, adjuster=None) -> dict:
    """How well the adjustment's normal matrix determines the focal length: the standard
    deviation of each focal length from COLMAP's covariance of the bundle adjustment (the
    inverse normal matrix of `adjuster`'s problem; without one, of a self-calibrating
    adjustment of the registered images with the gauge fixed by two cameras), relative to the
    focal length, per pixel of image-measurement sigma (multiply by the pixels' sigma for the
    focal length's own). A flat nadir block at one height leaves focal length and height
    trading: the normal matrix is rank deficient, or the deviation large. Cameras held
    constant (the control points' views) have no covariance and are skipped.

    Returns ``focal_sd`` (the largest over the cameras' focal lengths, or None) and
    ``focal_covariance``: ``"ok"``, ``"rank_deficient"`` (COLMAP could not invert it: a
    direction of the camera's parameters and poses the images do not fix) or
    ``"not_computed"`` (too many images: COVARIANCE_MAX_IMAGES)."""
    if rec.num_reg_images() > COVARIANCE_MAX_IMAGES:
        return {"focal_sd": None, "focal_covariance": "not_computed"}
    if adjuster is None:
        config = pycolmap.BundleAdjustmentConfig()
        for image_id in sorted(rec.reg_image_ids()):
            config.add_image(image_id)
        config.fix_gauge(pycolmap.BundleAdjustmentGauge.TWO_CAMS_FROM_WORLD)
        adjuster = pycolmap.create_default_ceres_bundle_adjuster(
            ba_options(pycolmap, req), config, rec
        )
    options = pycolmap.BACovarianceOptions()
    options.params = pycolmap.BACovarianceOptionsParams.ALL
    cov = pycolmap.estimate_ba_covariance(options, rec, adjuster)
    if cov is None:
        return {"focal_sd": None, "focal_covariance": "rank_deficient"}
    worst = None
    for cam in rec.cameras.values():
        c = cov.get_other_params_cov(cam.params)
        if c is None:
            continue
        # The covariance omits the parameters held constant (the principal point unless
        # refined): the free parameters in order, so a focal length's row is its index among
        # them.
        free = [i for i in range(len(cam.params)) if not held(cam, i, req)]
        if len(free) != c.shape[0]:
            continue
        for i in cam.focal_length_idxs():
            if i in free:
                k = free.index(i)
                sd = math.sqrt(max(float(c[k, k]), 0.0)) / abs(float(cam.params[i]))
                worst = sd if worst is None else max(worst, sd)
    return {
        "focal_sd": worst,
        "focal_covariance": "ok" if worst is not None else "not_computed",
    }


def held(cam, i: int, req: dict) -> bool:
    """Whether camera parameter `i` is held constant by `ba_options` (the principal point,
    unless the request refines it)."""
    return i in cam.principal_point_idxs() and not bool(
        req.get("refine_principal_point", False)
    )


def export(rec, ids: dict[int, int] | None = None) -> dict:
    """Cameras, registered images and points of a reconstruction as plain JSON data; point ids
    are mapped through `ids` when given."""
    cams = [
        {
            "id": int(cid),
            "model": c.model.name,
            "params": [float(a) for a in c.params],
            "width": int(c.width),
            "height": int(c.height),
        }
        for cid, c in sorted(rec.cameras.items())
    ]
    imgs = []
    for iid in sorted(rec.reg_image_ids()):
        im = rec.image(iid)
        pose = im.cam_from_world()
        imgs.append(
            {
                "id": int(iid),
                "name": im.name,
                "qvec": qvec_of(pose.rotation),
                "tvec": [float(a) for a in pose.translation],
            }
        )
    pts = [
        {
            "id": int(ids[pid]) if ids is not None else int(pid),
            "xyz": [float(a) for a in p.xyz],
            "error": float(p.error),
            "track": int(p.track.length()),
        }
        for pid, p in sorted(rec.points3D.items())
    ]
    return {"cameras": cams, "images": imgs, "points": pts}


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
        import pycolmap
    except (
        ImportError
    ) as e:  # the Rust side checks first; this is the last line of defence
        print(f"error: pycolmap is not available ({e})", file=sys.stderr)
        return 3
    jobs = {"bundle": bundle, "images": images}
    job = req.get("job")
    if job not in jobs:
        print(f"error: unknown job {job!r}", file=sys.stderr)
        return 2
    try:
        out = jobs[job](pycolmap, req)
    except EvaluateError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    write_atomic(result, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
