"""Render a Blender file (.blend) as it is with Cycles, for `poser import --verify`.

The scene's own camera (the scene camera) at its first frame, the resolution set to
--width x --height (100 %, no border: the same field of view), --spp samples per pixel with a
fixed seed, on the CPU; the file's own Cycles settings otherwise (bounces, clamping, filter,
light tree). Denoising and adaptive sampling are turned off so that every pixel takes the same
samples, the film is made opaque, and the image is written as a linear (scene-referred) RGB
OpenEXR. Run by poser with the pinned interpreter as
    python render_source.py --blend FILE --width W --height H --spp N --out OUT.exr
Safety: the file is opened with Python auto-execution off (`use_scripts=False`, and the
preference off): no text block, driver expression or handler in it runs. Nothing is written but
OUT (through a temporary file beside it).
"""

import argparse
import os
import sys


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    raise SystemExit(2)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--blend", required=True)
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, required=True)
    ap.add_argument("--spp", type=int, required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    try:
        import bpy
    except ImportError:
        fail("the `bpy` module is not available\n  help: run `backends/setup.sh`")
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(a.blend), load_ui=False, use_scripts=False)
    scene = bpy.context.scene
    if scene.camera is None:
        fail(f"{a.blend}: the scene has no camera")
    scene.frame_set(scene.frame_start)
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = a.width, a.height, 100
    r.use_border = False
    r.film_transparent = False
    r.use_motion_blur = False
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = a.spp
    cy.seed = 0
    cy.use_animated_seed = False
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    # Display settings only (an EXR holds scene-linear values either way).
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    im = r.image_settings
    im.file_format = "OPEN_EXR"
    im.color_mode = "RGB"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    tmp = a.out + ".tmp.exr"
    r.filepath = tmp
    bpy.ops.render.render(write_still=True)
    if not os.path.exists(tmp):
        fail("Cycles wrote no image")
    os.replace(tmp, a.out)
    print(f"image {a.out}", flush=True)


if __name__ == "__main__":
    main()
