"""poser for Blender: import a poser scene into the open Blender.

Install: copy the folders `poser_addon` and `poser_blender` (both in `backends/blender/` of the
poser sources) into Blender's `scripts/addons/` directory and enable "poser" in the
preferences; or run from a poser checkout, where `poser_blender` is found beside this folder.

What it adds:

| where | what |
|---|---|
| File > Import > poser scene (.toml) | loads, validates and compiles a scene file in-process with the `poser` Python module (the wheel, docs/python.md), then builds it as below; an invalid scene reports its first error with file, line and column |
| File > Import > poser scene (.json) | builds the scene written by `poser compile --backend blender` into a new Blender scene |
| 3D View sidebar, tab "poser" | the scenario's name, pose stepping (one frame per pose) and one button per camera |
"""

import json
import os
import sys
import tempfile

import bpy
from bpy.props import IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

bl_info = {
    "name": "poser",
    "author": "poser contributors",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > poser scene (.toml, .json); 3D View > Sidebar > poser",
    "description": "Import underwater photogrammetry survey scenes compiled by poser",
    "category": "Import-Export",
}


def _builder():
    try:
        import poser_blender
    except ImportError:
        here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        if here not in sys.path:
            sys.path.append(here)
        import poser_blender
    return poser_blender


def import_scene(path, context=None):
    """Build the poser scene described by the JSON file at `path` into a new Blender scene."""
    pb = _builder()
    with open(path, encoding="utf-8") as f:
        desc = json.load(f)
    pb.validate(desc)
    scene = bpy.data.scenes.new(str(desc.get("name") or "poser"))
    built = pb.build(desc, os.path.dirname(os.path.abspath(path)), scene)
    scene["poser_source"] = os.path.abspath(path)
    scene["poser_cameras"] = [c.name for c in built.cameras]
    scene.camera = built.cameras[0]
    window = getattr(context, "window", None) if context is not None else None
    if window is not None:
        window.scene = scene
    return scene


NO_MODULE = (
    "the `poser` Python module is not installed in Blender's Python: install the wheel "
    "(docs/python.md), or run `poser compile SCENE --backend blender -o DIR` and import "
    "DIR/scene.json"
)


def import_toml(path, context=None, overrides=None):
    """Load, validate and compile the poser scene file at `path` in-process (the `poser` module),
    then build it into a new Blender scene. `overrides` are `--set` values, e.g.
    `{"water.temperature": 12}`. Raises `poser.SceneError` for an invalid scene."""
    try:
        import poser
    except ImportError as e:
        raise ImportError(NO_MODULE) from e
    scene = poser.load(path, set=overrides or {})
    # The compiled scene's textures and meshes are read from here while the .blend is open.
    out = tempfile.mkdtemp(prefix=f"poser-{scene.name[:32]}-".replace(os.sep, "_"))
    scene.compile("blender", out)
    return import_scene(os.path.join(out, "scene.json"), context)


def _first_error(e):
    """`file:line:column: message (help)` of a SceneError's first error."""
    for d in getattr(e, "diagnostics", []):
        if d.severity == "error":
            where = f"{d.file}:{d.line}:{d.column}: " if d.line is not None else ""
            hint = f" (help: {d.help})" if d.help else ""
            return f"{where}{d.message}{hint}"
    return str(e)


class POSER_OT_import_toml(bpy.types.Operator, ImportHelper):
    """Import a poser scene file (.toml): validated and compiled in-process by the poser module"""

    bl_idname = "import_scene.poser_toml"
    bl_label = "Import poser scene file"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".toml"
    filter_glob: StringProperty(default="*.toml", options={"HIDDEN"})

    def execute(self, context):
        try:
            scene = import_toml(self.filepath, context)
        except ImportError as e:
            self.report({"ERROR"}, f"poser: {e}")
            return {"CANCELLED"}
        except Exception as e:  # poser.SceneError / PoserError, OSError
            if type(e).__name__ not in ("SceneError", "PoserError") and not isinstance(
                e, (OSError, ValueError, KeyError)
            ):
                raise
            self.report({"ERROR"}, f"poser: {_first_error(e)}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"poser: imported {scene.name!r}")
        return {"FINISHED"}


class POSER_OT_import(bpy.types.Operator, ImportHelper):
    """Import a scene compiled by `poser compile --backend blender` (scene.json)"""

    bl_idname = "import_scene.poser"
    bl_label = "Import poser scene"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        try:
            scene = import_scene(self.filepath, context)
        except (OSError, ValueError, KeyError) as e:
            self.report({"ERROR"}, f"poser: {e}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"poser: imported {scene.name!r}")
        return {"FINISHED"}


class POSER_OT_view_camera(bpy.types.Operator):
    """Make this camera the scene camera"""

    bl_idname = "poser.view_camera"
    bl_label = "Use camera"
    bl_options = {"REGISTER", "UNDO"}
    index: IntProperty(default=0, min=0)

    def execute(self, context):
        names = list(context.scene.get("poser_cameras", []))
        if self.index >= len(names) or names[self.index] not in bpy.data.objects:
            return {"CANCELLED"}
        context.scene.camera = bpy.data.objects[names[self.index]]
        return {"FINISHED"}


class POSER_PT_panel(bpy.types.Panel):
    bl_label = "poser"
    bl_idname = "POSER_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "poser"

    def draw(self, context):
        layout = self.layout
        layout.operator(POSER_OT_import_toml.bl_idname, icon="IMPORT")
        layout.operator(POSER_OT_import.bl_idname, icon="IMPORT")
        scene = context.scene
        if "poser_source" not in scene:
            layout.label(text="No poser scene in this Blender scene")
            return
        layout.label(text=f"Scenario: {scene.name}")
        layout.prop(scene, "frame_current", text="Pose")
        for i, name in enumerate(scene.get("poser_cameras", [])):
            op = layout.operator(POSER_OT_view_camera.bl_idname, text=name, icon="CAMERA_DATA")
            op.index = i


def _menu(self, context):
    self.layout.operator(POSER_OT_import_toml.bl_idname, text="poser scene (.toml)")
    self.layout.operator(POSER_OT_import.bl_idname, text="poser scene (.json)")


_classes = (POSER_OT_import_toml, POSER_OT_import, POSER_OT_view_camera, POSER_PT_panel)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
