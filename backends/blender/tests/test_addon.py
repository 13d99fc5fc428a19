"""The Blender add-on registers with bpy and imports a poser scene description."""

import json
import os

import bpy
import poser_addon
import pytest


def test_addon_registers_and_imports(scene_desc, tmp_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert poser_addon.bl_info["name"] == "poser"
    poser_addon.register()
    try:
        assert hasattr(bpy.types, "POSER_PT_panel")
        assert "poser" in dir(bpy.ops.import_scene)
        path = tmp_path / "scene.json"
        path.write_text(json.dumps(scene_desc))
        assert bpy.ops.import_scene.poser(filepath=str(path)) == {"FINISHED"}
        scene = bpy.data.scenes["pytest scene"]
        assert scene.camera.name == "camera:cam"
        assert list(scene["poser_cameras"]) == ["camera:cam"]
        assert "poser_water" in scene.objects
        bad = tmp_path / "bad.json"
        bad.write_text('{"format": "nope"}')
        # In background mode an operator's ERROR report is raised; the message is the hint.
        with pytest.raises(RuntimeError, match="not a poser Blender scene description"):
            bpy.ops.import_scene.poser(filepath=str(bad))
    finally:
        poser_addon.unregister()
    assert not hasattr(bpy.types, "POSER_PT_panel")


def test_addon_imports_a_scene_file_in_process(tmp_path):
    """File > Import > poser scene (.toml): the poser module (the wheel test.sh installs)
    validates and compiles in Blender's own Python; no `poser` process is started."""
    import poser  # noqa: F401  (fails, never skips, when the wheel is missing)

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(__file__))))
    scene_file = os.path.join(root, "scenarios", "calibration_flat.toml")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    poser_addon.register()
    try:
        assert "poser_toml" in dir(bpy.ops.import_scene)
        assert bpy.ops.import_scene.poser_toml(filepath=scene_file) == {"FINISHED"}
        scene = bpy.data.scenes["calibration_flat"]
        assert scene.camera is not None and scene.camera.type == "CAMERA"
        assert "poser_water" in scene.objects
        # The camera has the scene's intrinsics: the same focal length in pixels.
        want_fx = poser.load(scene_file).cameras[0]["fx"]
        cam = scene.camera.data
        width = scene.render.resolution_x
        fx = cam.lens / cam.sensor_width * width
        assert abs(fx - want_fx) < 1e-6 * want_fx
        # An invalid scene: the first error with its place, never a traceback.
        bad = tmp_path / "bad.toml"
        bad.write_text("bogus_key = 1\n" + open(scene_file).read())
        with pytest.raises(RuntimeError, match=r"bad\.toml:1:1: unknown key `bogus_key`"):
            bpy.ops.import_scene.poser_toml(filepath=str(bad))
    finally:
        poser_addon.unregister()
