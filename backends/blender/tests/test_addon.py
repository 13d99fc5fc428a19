"""The Blender add-on registers with bpy and imports a poser scene description."""

import json

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
