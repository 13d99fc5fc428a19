"""Render a scene compiled by `poser compile --backend mitsuba` with Mitsuba 3.

Reads ``manifest.json`` from the compiled directory; for every view (one pose × camera) renders
its pass(es) with variant ``scalar_rgb`` and writes ``{image}.exr`` (linear RGB, float32) and
``{image}.png`` (sRGB preview, multiplied by the manifest's exposure) into the output directory.
A view with three passes (dispersion) takes channel c of pass c and combines them into one RGB
image. Files are written atomically (temporary name, then rename).

The compiled views are in ``manifest["unit"]`` length units per metre (poser writes them in
millimetres). When the manifest has ``"depth": true``, also writes ``{image}.depth.exr``: the
camera-frame z (m) of the first surface hit through each pixel centre, 0 where nothing is hit (the native
backend's definition). The pixel-centre ray is traced exactly through the port: dielectric
surfaces are crossed by their refracted (transmitted) direction, `null` surfaces (the water's
bounds, area lights) passed through.

Machine-readable lines on stdout (the Rust side turns them into a progress bar):

    progress <passes done> <passes total> <image>
    image <file name of the EXR, relative to the output directory>

Usage: python render.py --scene-dir DIR --out DIR [--poses 0,3,5] [--spp N]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

VARIANT = "scalar_rgb"


def load_manifest(scene_dir: Path) -> dict:
    """The job list written by the compiler."""
    with open(scene_dir / "manifest.json", encoding="utf-8") as f:
        manifest = json.load(f)
    if manifest.get("format") != "poser-mitsuba/2":
        raise ValueError(f"{scene_dir}/manifest.json: unknown format {manifest.get('format')!r}")
    return manifest


def select_views(manifest: dict, poses: list[int] | None) -> list[dict]:
    """The views of the given pose indices (all when ``poses`` is None), in manifest order."""
    views = manifest["views"]
    if poses is None:
        return list(views)
    wanted = set(poses)
    return [v for v in views if v["pose"] in wanted]


def combine_passes(images: list[np.ndarray], channels: list[int | None]) -> np.ndarray:
    """One RGB image from the passes: a single full pass as is, or channel c of pass c."""
    if len(images) == 1 and channels[0] is None:
        return images[0][:, :, :3]
    out = np.zeros_like(images[0][:, :, :3])
    for img, c in zip(images, channels):
        if c is None:
            raise ValueError("a multi-pass view must name the channel of each pass")
        out[:, :, c] = img[:, :, c]
    return out


def to_preview(rgb: np.ndarray, exposure: float) -> np.ndarray:
    """8-bit sRGB preview of a linear image."""
    x = np.clip(rgb * exposure, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(srgb * 255.0).astype(np.uint8)


def _atomic(path: Path, write) -> None:
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    write(str(tmp))
    os.replace(tmp, path)


def write_images(mi, rgb: np.ndarray, out: Path, image: str, exposure: float) -> Path:
    """Write ``{image}.exr`` (float32 linear) and ``{image}.png``; returns the EXR path."""
    out.mkdir(parents=True, exist_ok=True)
    exr = out / f"{image}.exr"
    bmp = mi.Bitmap(np.ascontiguousarray(rgb, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    _atomic(exr, bmp.write)
    png = mi.Bitmap(np.ascontiguousarray(to_preview(rgb, exposure)), mi.Bitmap.PixelFormat.RGB)
    _atomic(out / f"{image}.png", png.write)
    return exr


def render_pass(mi, xml: Path, seed: int, spp: int) -> np.ndarray:
    """Render the single sensor of one scene document; returns H×W×C float32."""
    scene = mi.load_file(str(xml))
    sensors = scene.sensors()
    if len(sensors) != 1:
        raise ValueError(f"{xml}: expected one sensor, found {len(sensors)}")
    img = mi.render(scene, sensor=sensors[0], seed=seed, spp=spp)
    return np.array(img, dtype=np.float32)


def depth_image(mi, xml: Path, unit: float) -> np.ndarray:
    """Camera-frame z (m) of the first opaque surface through each pixel centre (H×W, 0: none);
    the document is in ``unit`` length units per metre."""
    scene = mi.load_file(str(xml))
    sensor = scene.sensors()[0]
    width, height = sensor.film().crop_size()
    cam_from_world = sensor.world_transform().inverse()
    ctx = mi.BSDFContext()
    out = np.zeros((height, width), dtype=np.float32)
    for j in range(height):
        for i in range(width):
            pos = mi.Point2f((i + 0.5) / width, (j + 0.5) / height)
            ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
            for _ in range(64):
                si = scene.ray_intersect(ray)
                if not si.is_valid():
                    break
                bsdf = si.bsdf(ray)
                flags = bsdf.flags()
                if mi.has_flag(flags, mi.BSDFFlags.Null):
                    ray = si.spawn_ray(ray.d)
                    continue
                if mi.has_flag(flags, mi.BSDFFlags.DeltaTransmission):
                    # sample1 above the Fresnel reflectance selects the transmitted direction.
                    bs, _ = bsdf.sample(ctx, si, 0.999999, mi.Point2f(0.5, 0.5))
                    if not mi.has_flag(bs.sampled_type, mi.BSDFFlags.DeltaTransmission):
                        break  # total internal reflection: no surface seen
                    ray = si.spawn_ray(si.to_world(bs.wo))
                    continue
                out[j, i] = (cam_from_world @ si.p)[2] / unit
                break
    return out


def write_depth(mi, depth: np.ndarray, out: Path, image: str) -> Path:
    """``{image}.depth.exr``: z in all three channels, as the native backend writes it."""
    path = out / f"{image}.depth.exr"
    rgb = np.repeat(depth[:, :, None], 3, axis=2)
    bmp = mi.Bitmap(np.ascontiguousarray(rgb, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    _atomic(path, bmp.write)
    return path


def run(scene_dir: Path, out: Path, poses: list[int] | None, spp: int | None, log=print) -> list[Path]:
    """Render the selected views; returns the EXR paths written."""
    import mitsuba as mi

    mi.set_variant(VARIANT)
    manifest = load_manifest(scene_dir)
    views = select_views(manifest, poses)
    total = sum(len(v["passes"]) for v in views)
    done = 0
    written = []
    for v in views:
        images, channels = [], []
        for p in v["passes"]:
            images.append(render_pass(mi, scene_dir / p["xml"], v["seed"], spp or v["spp"]))
            channels.append(p["channel"])
            done += 1
            log(f"progress {done} {total} {v['image']}", flush=True)
        rgb = combine_passes(images, channels)
        exr = write_images(mi, rgb, out, v["image"], float(manifest.get("exposure", 1.0)))
        written.append(exr)
        if manifest.get("depth"):
            # Geometry only: the first pass's document (indices of its channel).
            xml = scene_dir / v["passes"][0]["xml"]
            write_depth(mi, depth_image(mi, xml, float(manifest["unit"])), out, v["image"])
        log(f"image {exr.name}", flush=True)
    return written


def parse_poses(s: str | None) -> list[int] | None:
    if s is None:
        return None
    return [int(x) for x in s.split(",") if x.strip()]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene-dir", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--poses", default=None, help="comma-separated pose indices (default: all)")
    ap.add_argument("--spp", type=int, default=None, help="override the samples per pixel")
    a = ap.parse_args(argv)
    try:
        run(a.scene_dir, a.out, parse_poses(a.poses), a.spp)
    except Exception as e:  # noqa: BLE001 - report any failure as one clear line
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
