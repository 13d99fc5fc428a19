"""Render a Mitsuba 3 scene file as it is, for `poser import --verify`.

The first sensor's film is resized to --width x --height (same field of view), the scene's own
integrator is used (a `path` integrator when the file has none), and the image is written as a
linear RGB EXR. Run by poser with the pinned interpreter; prints `image FILE` when done.
"""

import argparse

import mitsuba as mi


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--xml", required=True)
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, required=True)
    ap.add_argument("--spp", type=int, required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    mi.set_variant("scalar_rgb")
    scene = mi.load_file(a.xml)
    sensor = scene.sensors()[0]
    params = mi.traverse(sensor)
    size = mi.ScalarVector2u(a.width, a.height)
    for k in list(params.keys()):
        if k.endswith("film.size") or k.endswith("film.crop_size"):
            params[k] = size
        elif k.endswith("film.crop_offset"):
            params[k] = mi.ScalarPoint2u(0, 0)
    params.update()
    integrator = scene.integrator() or mi.load_dict({"type": "path"})
    img = mi.render(scene, sensor=sensor, integrator=integrator, spp=a.spp, seed=0)
    mi.Bitmap(img).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False
    ).write(a.out)
    print(f"image {a.out}", flush=True)


if __name__ == "__main__":
    main()
