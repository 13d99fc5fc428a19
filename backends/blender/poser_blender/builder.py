"""Build a poser scene in Blender from its JSON description, and render it with Cycles.

The description (format `poser-blender/1`) is written by `poser compile --backend blender`
(Rust, `src/backend/blender`); every user string in it is data only. What gets built:

| element | Blender representation |
|---|---|
| rig pose | Empty `poser_rig`, keyframed once per pose (frame = pose index, constant interpolation) |
| camera | Empty (OpenCV frame) child of the rig + Camera child; exact intrinsics via lens/shift |
| distortion, fx != fy | CUSTOM camera running poser's fixed OSL shader `camera.osl` (parameters only): Newton inverse of Brown-Conrady per film sample, as crates/poser-optics/src/lens.rs; exact, no resampling |
| port | the housing poser computed (PLY assets `cameras[].housing`, read by `geometry.read_ply`): inner air->glass surface (Glass, IOR n_g/1) + housing shell carved out of the water mesh (outer face Glass IOR n_w/n_g); black housing walls inside it (HOUSING_INSIDE); no housing shadow (HOUSING_SHADOW) |
| water | one closed mesh `poser_water` (box minus housings), Volume Coefficients node; per pose a shape key |
| lights | point/spot (P = 4 pi I, radius 0, blend 0), sun (angle 0), area (P = L pi A), ambient = world |
| objects | Blender primitives (plane/box) or imported PLY assets; Diffuse BSDF; glass objects (GLASS_OBJECTS): Glass BSDF, a glass sphere or cylinder from poser's PLY with its normals (`shaded_ply`, `geometry.read_ply`), carved out of the water; filled objects (FILLED_OBJECTS): the same, of their water's index, with that water's Volume Coefficients inside |
| targets | planes with the target's PNG texture; 3D test objects as white boxes + black disks |
| sea waves | the native backend's periodic height field (`wave_field`): one period as a smooth glass mesh, instanced; caustics by MNEE (surface = caster, objects and targets = receivers, sun = caustics light) |
| seed | one Cycles seed per image (`poses[].seeds`, derived by poser from the scene seed) |
| depth (`render.outputs` has "depth") | a second 1-sample render per image: glass -> Refraction BSDF, water off, surfaces emit their camera-frame z; `<image>.depth.exr` |

Emitters in water are scaled by (n_cam/n_water)^2 per camera before each render (the n^2
convention, docs/render-conventions.md §3.4).

SAVED_AS_RENDERED: `build` ends by setting everything a render sets per image for the first
image (strengths with the n^2 factor, seed, camera, resolution), so a .blend saved with
`--save-blend`, or a scene imported by the add-on, renders what `poser render` renders.
"""

import json
import math
import os
import sys
import time

import bpy
import numpy as np

from . import geometry as geo

FORMAT = "poser-blender/1"
# Distance between a port's outer glass face and the water volume's boundary behind it, m:
# above float32 resolution at survey coordinates, far below anything visible (the unabsorbed
# layer changes transmittance by < 1e-5).
WATER_GAP = 5e-5
# HOUSING_SHADOW: the port glass objects are invisible to shadow rays and, in water, the
# housing body is a pure volume boundary of the water mesh, so the camera housing casts no
# shadow, as in the native backend (whose scene has no housing) and the analytic truth.
# Measured on tests/canonical/sun_seabed.toml (160x120, 16 spp): with the shadow, 85 pixels
# in one corner were at 16 % of their sunlit radiance and the image mean was 0.37 % low
# (Cycles/analytic 0.9968); without it 1.0005. Consequence: a light placed inside a housing
# shines through its port unrefracted (as in the native backend); put lights in the water
# (docs/render-conventions.md §4).


# ------------------------------------------------------------------------------------------
# Small helpers
# ------------------------------------------------------------------------------------------


def _matrix(m):
    from mathutils import Matrix

    return Matrix([list(map(float, row)) for row in np.asarray(m, dtype=float)])


def blender_name(name):
    """Blender names are C strings: NUL, the only character they cannot hold, becomes U+FFFD."""
    return str(name).replace("\0", "\ufffd")


def _new_object(coll, name, data):
    obj = bpy.data.objects.new(blender_name(name), data)
    coll.objects.link(obj)
    return obj


def _mesh_from(name, mesh, smooth):
    """A Blender mesh; with `smooth`, shading uses the mesh's analytic normals (custom
    normals) on faces that have them and the flat face normal elsewhere."""
    me = bpy.data.meshes.new(name)
    verts = np.asarray(mesh["verts"], dtype=float)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in mesh["faces"]])
    tags = mesh.get("tags")
    if tags is not None:
        me.polygons.foreach_set("material_index", [int(t) for t in tags])
    normals = mesh.get("normals")
    if smooth and normals is not None:
        me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
        me.normals_split_custom_set([tuple(n) for n in geo.loop_normals(mesh)])
    else:
        me.polygons.foreach_set("use_smooth", [False] * len(me.polygons))
    me.update()
    return me


def _nodes(mat):
    if mat.node_tree is None:  # Blender < 5 creates materials without nodes
        mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    return nt, out


def _glass_material(name, ior, volume=None):
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    g = nt.nodes.new("ShaderNodeBsdfGlass")
    g.distribution = "GGX"
    g.inputs["Roughness"].default_value = 0.0
    g.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    g.inputs["IOR"].default_value = float(ior)
    nt.links.new(g.outputs[0], out.inputs["Surface"])
    if volume is not None:
        _volume_node(nt, out, volume)
    mat["poser_role"] = "glass"
    return mat, g


def _volume_node(nt, out, water):
    n = nt.nodes.new("ShaderNodeVolumeCoefficients")
    ph = water["phase"]
    if ph["kind"] == "fournier_forand":
        n.phase = "FOURNIER_FORAND"
        n.inputs["IOR"].default_value = float(ph["n"])
        n.inputs["Backscatter"].default_value = float(ph["backscatter"])
    else:
        n.phase = "HENYEY_GREENSTEIN"
        n.inputs["Anisotropy"].default_value = float(ph.get("g", 0.0))
    n.inputs["Absorption Coefficients"].default_value = tuple(map(float, water["absorption"]))
    n.inputs["Scatter Coefficients"].default_value = tuple(map(float, water["scattering"]))
    nt.links.new(n.outputs[0], out.inputs["Volume"])
    return n


def _volume_only_material(name, water):
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    _volume_node(nt, out, water)
    mat["poser_role"] = "boundary"
    return mat


def _black_material(name, water=None):
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    nt.links.new(d.outputs[0], out.inputs["Surface"])
    if water is not None:
        _volume_node(nt, out, water)
    mat["poser_role"] = "housing"
    return mat


def _diffuse_material(name, material, scale=(1.0, 1.0, 1.0)):
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Roughness"].default_value = 0.0
    albedo = [float(a) for a in material["albedo"]]
    d.inputs["Color"].default_value = (*albedo, 1.0)
    # Only the checker reaches here: every other pattern is baked by poser into an image
    # texture (objects with `shape.texture`, see _texture_material).
    pattern = material.get("pattern")
    if pattern and pattern["type"] == "checker":
        tc = nt.nodes.new("ShaderNodeTexCoord")
        mp = nt.nodes.new("ShaderNodeMapping")
        mp.inputs["Scale"].default_value = tuple(float(s) for s in scale)
        nt.links.new(tc.outputs["Object"], mp.inputs["Vector"])
        if pattern["type"] == "checker":
            size = float(pattern["size"])
            ck = nt.nodes.new("ShaderNodeTexChecker")
            ck.inputs["Scale"].default_value = 1.0 / size
            c2 = [a * float(pattern["contrast"]) for a in albedo]
            # Cycles picks Color1 where floor(x)+floor(y)+floor(z) is odd; poser's checker
            # multiplies the albedo by `contrast` there (src/mesh.rs pattern_factor).
            ck.inputs["Color1"].default_value = (*c2, 1.0)
            ck.inputs["Color2"].default_value = (*albedo, 1.0)
            nt.links.new(mp.outputs[0], ck.inputs["Vector"])
            nt.links.new(ck.outputs["Color"], d.inputs["Color"])
    nt.links.new(d.outputs[0], out.inputs["Surface"])
    return mat


def _texture_material(name, path, interpolation="Closest", extension="EXTEND"):
    """Diffuse BSDF whose colour is an image of linear values (Non-Color) at the mesh's UVs.
    Baked object textures use "Linear" with "EXTEND": bilinear between texel centres, edges
    repeated, as Mitsuba's bitmap (bilinear, clamp) and poser's native sampler. Textured meshes
    use "Linear" with their material's wrap (REPEAT, EXTEND or MIRROR)."""
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Roughness"].default_value = 0.0
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.interpolation = interpolation
    tex.extension = extension
    img = bpy.data.images.load(path, check_existing=True)
    img.colorspace_settings.name = "Non-Color"
    tex.image = img
    tc = nt.nodes.new("ShaderNodeTexCoord")
    nt.links.new(tc.outputs["UV"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], d.inputs["Color"])
    nt.links.new(d.outputs[0], out.inputs["Surface"])
    return mat


def _vertex_color_material(name):
    """Diffuse BSDF whose colour is the mesh's linear vertex colours (`Col`), interpolated
    across each triangle as the native renderer and Mitsuba's mesh_attribute do."""
    mat = bpy.data.materials.new(name)
    nt, out = _nodes(mat)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Roughness"].default_value = 0.0
    vc = nt.nodes.new("ShaderNodeVertexColor")
    vc.layer_name = "Col"
    nt.links.new(vc.outputs["Color"], d.inputs["Color"])
    nt.links.new(d.outputs[0], out.inputs["Surface"])
    return mat


def _import_parts(base_dir, parts, name):
    """A textured mesh from its per-material PLY files (src/texture/mapped.rs): joined into one
    mesh, one material slot per part."""
    import bmesh

    bm = bmesh.new()
    mats = []
    for k, part in enumerate(parts):
        pm = _import_ply(os.path.join(base_dir, part["path"]), f"{name}#{k}")
        before = len(bm.faces)
        bm.from_mesh(pm)
        bm.faces.ensure_lookup_table()
        for f in bm.faces[before:]:
            f.material_index = k
        bpy.data.meshes.remove(pm)
        if part.get("texture"):
            path = os.path.join(base_dir, part["texture"])
            mats.append(_texture_material(f"{name}#{k}", path, "Linear", part["extension"]))
        elif part.get("vertex_colors"):
            mats.append(_vertex_color_material(f"{name}#{k}"))
        else:
            mats.append(_diffuse_material(f"{name}#{k}", {"albedo": part["color"]}))
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    for m in mats:
        me.materials.append(m)
    return me


# ------------------------------------------------------------------------------------------
# The scene
# ------------------------------------------------------------------------------------------


class Built:
    """Handles to what `build` created, for rendering."""

    def __init__(self, scene, desc):
        self.scene = scene
        self.desc = desc
        self.rig = None
        self.cameras = []  # bpy camera objects, in model order
        self.lights = []  # (light data, colour, strength, in_water)
        self.world_bg = None  # (background node, colour, strength, in_water)
        self.glass_nodes = []  # (glass node, function(channel) -> ior)
        self.solids = {}  # glass sphere/cylinder PLY path -> mesh, read once (`_solid`)
        self.water = None
        self.depth_mat = None  # created on the first depth render
        self.depth_nodes = None
        self.depth_twins = {}


def validate(desc):
    if not isinstance(desc, dict) or desc.get("format") != FORMAT:
        raise ValueError(f"not a poser Blender scene description (expected format {FORMAT!r})")
    if not desc.get("cameras"):
        raise ValueError("the scene has no camera")
    if not desc.get("poses"):
        raise ValueError("the scene has no pose")
    for cam in desc["cameras"]:
        if cam.get("port", {}).get("kind", "none") != "none" and not cam.get("housing"):
            raise ValueError(f"camera {cam.get('name')!r} has a port but no housing meshes")


def _channel(values, c):
    return float(values[c])


def build(desc, base_dir=".", scene=None):
    """Build the described scene into `scene` (a new one when None); returns `Built`."""
    validate(desc)
    if scene is None:
        scene = bpy.data.scenes.new(desc.get("name") or "poser")
    built = Built(scene, desc)
    coll = bpy.data.collections.new("poser: " + str(desc.get("name", "")))
    scene.collection.children.link(coll)
    water = desc.get("water")
    built.water = water
    ref = int(desc.get("reference_channel", 1))
    n_w = water["ior"] if water else [1.0, 1.0, 1.0]

    _render_settings(scene, desc)

    # Rig, keyframed per pose.
    rig = _new_object(coll, "poser_rig", None)
    rig.empty_display_size = 0.1
    rig.rotation_mode = "QUATERNION"
    built.rig = rig
    for i, pose in enumerate(desc["poses"]):
        rig.matrix_world = _matrix(pose["world_from_rig"])
        rig.keyframe_insert("location", frame=i)
        rig.keyframe_insert("rotation_quaternion", frame=i)
    # SHADOWS: poser's exact f64 values beside Blender's float32 ones, for `poser import`
    # (backends/blender/read_blend.py uses a shadow only while it agrees with Blender's value).
    rig["poser_keys"] = _flat([p["world_from_rig"] for p in desc["poses"]])
    scene["poser_bounces"] = int(desc["render"].get("max_bounces", 64))
    _constant_interpolation(rig)
    scene.frame_start = 0
    scene.frame_end = len(desc["poses"]) - 1

    # Cameras and the air->glass faces of their ports.
    shells = []
    for ci, cam in enumerate(desc["cameras"]):
        frame = _new_object(coll, f"camera_frame:{cam['name']}", None)
        frame.parent = rig
        frame.matrix_parent_inverse.identity()
        frame.matrix_basis = _matrix(cam["rig_from_camera"])
        frame["poser_basis"] = _flat([cam["rig_from_camera"]])
        frame.empty_display_size = 0.05
        data = bpy.data.cameras.new(f"camera:{cam['name']}")
        _set_intrinsics(data, cam)
        data["poser_camera"] = _camera_shadow(ci, cam)
        obj = _new_object(coll, f"camera:{cam['name']}", data)
        obj.parent = frame
        obj.matrix_parent_inverse.identity()
        obj.matrix_basis = _matrix(geo.CV_TO_BLENDER)
        obj["poser_basis"] = _flat([geo.CV_TO_BLENDER])
        built.cameras.append(obj)
        h = cam.get("housing") if cam["port"].get("kind", "none") != "none" else None
        if h is None:
            shells.append(None)
            continue
        shell = geo.read_ply(os.path.join(base_dir, h["shell"]))
        inner = geo.read_ply(os.path.join(base_dir, h["inner"]))
        glass = cam["port"]["glass"]["ior"]
        mat_in, node_in = _glass_material(f"glass air->glass:{cam['name']}", glass[ref])
        built.glass_nodes.append((node_in, lambda c, g=glass: g[c]))
        me = _mesh_from(f"port inner:{cam['name']}", inner, smooth=inner["normals"] is not None)
        me.materials.append(mat_in)
        inner_obj = _new_object(coll, f"port inner:{cam['name']}", me)
        inner_obj.visible_shadow = False  # HOUSING_SHADOW
        inner_obj.parent = frame
        inner_obj.matrix_parent_inverse.identity()
        shells.append((ci, shell, glass))

    scene.camera = built.cameras[0]  # the saved .blend opens looking through camera 0
    _build_water(built, coll, desc, shells, n_w, ref, base_dir)
    _build_lights(built, coll, desc)
    _build_objects(built, coll, desc, base_dir)
    _build_targets(built, coll, desc, base_dir)
    if desc.get("surface", {}).get("kind") == "waves":
        _build_waves(built, coll, desc, n_w, ref)
    # Everything a render sets per image is set here too, for the first image (pose 0, camera
    # 0): light and world strengths with the n^2 factor, the seed. A saved .blend, or a scene
    # imported by the add-on, then renders what `poser render` renders (SAVED_AS_RENDERED).
    prepare_image(built, 0, 0)
    return built


def image_seed(desc, pose_index, cam_index):
    """The Cycles seed of one image: poser derives one per (pose, camera) from the scene seed
    (src/backend/blender/data.rs `cycles_seed`); descriptions without them use the scene's."""
    seeds = desc["poses"][pose_index].get("seeds")
    if seeds:
        return int(seeds[cam_index]) % (2**31)
    return int(desc["render"]["seed"]) % (2**31)


def _emitter_scale(desc, cam, per_channel):
    """The n^2 factor of emitters in water for renders through camera `cam`: the reference
    channel's for a single RGB pass, each channel's for per-channel passes."""
    water = desc.get("water")
    if not water:
        return [1.0] * 3
    n_cam = _n_cam(desc, cam)
    if per_channel:
        return geo.emitter_scale(n_cam, water["ior"])
    ref = int(desc.get("reference_channel", 1))
    return geo.emitter_scale([n_cam[ref]] * 3, [water["ior"][ref]] * 3)


def prepare_image(built, pose_index, cam_index):
    """Pose, camera, resolution, seed and emitter strengths of image (pose, camera), as the
    single-pass render uses them (a scene with per-channel passes gets every channel's n^2
    factor in the light colours, its passes set each channel's own)."""
    desc = built.desc
    scene = built.scene
    cam = desc["cameras"][cam_index]
    scene.frame_set(pose_index)
    scene.camera = built.cameras[cam_index]
    scene.render.resolution_x = int(cam["width"])
    scene.render.resolution_y = int(cam["height"])
    _apply_crop(scene, desc["render"].get("crop"), int(cam["width"]), int(cam["height"]))
    scene.cycles.seed = image_seed(desc, pose_index, cam_index)
    _apply_emitters(built, _emitter_scale(desc, cam, bool(desc.get("per_channel_passes"))))


def _apply_crop(scene, crop, width, height):
    """`render.crop` ([x, y, w, h] px from the top-left corner, or None): a border render
    cropped to the border, so that the image written is the rectangle alone, on the whole
    image's pixel grid. Blender takes the border as fractions of the image from the bottom-left
    corner and truncates fraction x size to whole pixels; a quarter pixel inside each edge keeps
    that truncation on the intended pixel whichever way the float rounds."""
    r = scene.render
    if crop is None:
        r.use_border = False
        r.use_crop_to_border = False
        return
    x, y, w, h = (int(v) for v in crop)
    r.use_border = True
    r.use_crop_to_border = True
    r.border_min_x = (x + 0.25) / width
    r.border_max_x = (x + w + 0.25) / width
    r.border_min_y = (height - y - h + 0.25) / height
    r.border_max_y = (height - y + 0.25) / height


def _flat(matrices):
    """Row-major 4x4 matrices as one flat list of f64 (an ID property array of doubles)."""
    return [float(x) for m in matrices for row in m for x in row]


def _camera_shadow(index, cam):
    """The camera's exact intrinsics (only what is set; ID properties hold no None)."""
    out = {"index": int(index), "lens": str(cam.get("lens", "rectilinear"))}
    for k in ("width", "height"):
        out[k] = int(cam[k])
    for k in ("fx", "fy", "cx", "cy", "focus_distance", "f_number", "focal_length"):
        if cam.get(k) is not None:
            out[k] = float(cam[k])
    for k, v in (cam.get("distortion") or {}).items():
        out[k] = float(v)
    return out


def _constant_interpolation(obj):
    ad = obj.animation_data
    if ad is None or ad.action is None:
        return
    try:
        curves = ad.action.fcurves
    except AttributeError:  # Blender 5 layered actions
        curves = []
        for layer in ad.action.layers:
            for strip in layer.strips:
                for bag in strip.channelbags:
                    curves.extend(bag.fcurves)
    for fc in curves:
        for kp in fc.keyframe_points:
            kp.interpolation = "CONSTANT"


# Sources of the package's non-Python files (the custom camera shader), filled in by a
# generated script that embeds them; read from beside this module otherwise.
RESOURCES = {}


def resource(name):
    """Text of a package resource file (`camera.osl`)."""
    if name in RESOURCES:
        return RESOURCES[name]
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), name),
              encoding="utf-8") as f:
        return f.read()


def _osl_bytecode(source):
    """Compile OSL source with Cycles' bundled compiler; returns (bytecode, md5 hex)."""
    import hashlib
    import tempfile

    import _cycles

    with tempfile.TemporaryDirectory(prefix="poser-osl-") as tmp:
        src = os.path.join(tmp, "poser_camera.osl")
        oso = os.path.join(tmp, "poser_camera.oso")
        with open(src, "w", encoding="utf-8") as f:
            f.write(source)
        if not _cycles.osl_compile(src, oso):
            raise RuntimeError("Cycles could not compile poser's camera shader (camera.osl)")
        with open(oso, encoding="utf-8") as f:
            code = f.read()
    return code, hashlib.md5(code.encode(), usedforsecurity=False).hexdigest()


def _custom_camera(data, cam):
    """Cycles custom (OSL) camera running poser_blender/camera.osl: exact OpenCV intrinsics,
    fx != fy, Brown-Conrady distortion on any lens model. The shader is poser's fixed file;
    the scene's numbers are only its parameters."""
    text = bpy.data.texts.get("poser_camera.osl")
    if text is None:
        text = bpy.data.texts.new("poser_camera.osl")
        text.from_string(resource("camera.osl"))
    code, digest = _osl_bytecode(text.as_string())
    data.type = "CUSTOM"
    data.custom_mode = "INTERNAL"
    # Assigning the text runs Cycles' own update, which compiles the shader and creates the
    # parameter properties (shown in the Lens panel); it needs the `oslquery` module, which
    # the bpy wheel ships but does not put on sys.path. The bytecode and the parameters are
    # set here in any case.
    _ensure_oslquery()
    _quiet(lambda: setattr(data, "custom_shader", text))
    data.custom_bytecode = code
    data.custom_bytecode_hash = digest
    d = cam.get("distortion") or {}
    params = data.cycles_custom
    for k in ("width", "height", "fx", "fy", "cx", "cy"):
        params[k] = float(cam[k])
    for k in ("k1", "k2", "k3", "p1", "p2"):
        params[k] = float(d.get(k, 0.0))
    params["lens"] = {"rectilinear": 0, "fisheye_equidistant": 1,
                      "fisheye_equisolid": 2}[cam.get("lens", "rectilinear")]
    r2 = cam.get("r2_max")
    params["r2_max"] = 1e30 if r2 is None else float(min(r2, 1e30))
    # Thin lens (as Mitsuba's `thinlens` and Cycles' own cameras): aperture radius f/(2N),
    # focus plane at z = focus_distance.
    aperture, focus = 0.0, 1.0
    if cam.get("focus_distance") and cam.get("f_number") and cam.get("focal_length"):
        aperture = float(cam["focal_length"]) / (2.0 * float(cam["f_number"]))
        focus = float(cam["focus_distance"])
    params["aperture_radius"] = aperture
    params["focus_distance"] = focus
    data.update_tag()


def _ensure_oslquery():
    try:
        import oslquery  # noqa: F401
    except ImportError:
        lib = os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib")
        if os.path.isdir(lib):
            for d in sorted(os.listdir(lib)):
                site = os.path.join(lib, d, "site-packages")
                if os.path.isdir(os.path.join(site, "oslquery")) and site not in sys.path:
                    sys.path.append(site)


def _quiet(fn):
    """Run fn with Blender's report printing to stderr suppressed (fd level)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            return fn()
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def needs_custom_camera(cam):
    """Distortion or non-square pixels: the built-in cameras cannot represent them."""
    d = cam.get("distortion") or {}
    distorted = any(float(d.get(k, 0.0)) != 0.0 for k in ("k1", "k2", "k3", "p1", "p2"))
    return distorted or abs(float(cam["fx"]) - float(cam["fy"])) > 1e-9 * abs(float(cam["fx"]))


def _set_intrinsics(data, cam):
    data.clip_start = 1e-4
    data.clip_end = 1e5
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = geo.SENSOR_WIDTH_MM
    data.sensor_height = geo.SENSOR_WIDTH_MM * cam["height"] / cam["width"]
    data.lens_unit = "MILLIMETERS"
    lens = cam.get("lens", "rectilinear")
    if needs_custom_camera(cam):
        _custom_camera(data, cam)
        return
    p = geo.blender_intrinsics(cam["fx"], cam["fy"], cam["cx"], cam["cy"], cam["width"],
                               cam["height"])
    data.shift_x = p["shift_x"]
    data.shift_y = p["shift_y"]
    data.lens = p["lens"]
    if lens == "rectilinear":
        data.type = "PERSP"
    else:
        f = geo.fisheye_params(lens, cam["fx"], cam["width"], cam["height"])
        data.type = "PANO"
        # Panoramic cameras take shift_y in units of the image height (measured: with the
        # width, as for PERSP, the principal point lands (1 - H/W) short).
        data.shift_y = (cam["cy"] - cam["height"] / 2.0) / cam["height"]
        data.panorama_type = f["panorama_type"]
        data.fisheye_fov = f["fisheye_fov"]
        if "fisheye_lens" in f:
            data.fisheye_lens = f["fisheye_lens"]
        for k, c in enumerate(f.get("polynomial", [])):
            setattr(data, f"fisheye_polynomial_k{k}", c)
    if cam.get("focus_distance") and cam.get("f_number"):
        data.dof.use_dof = True
        data.dof.focus_distance = float(cam["focus_distance"])
        data.dof.aperture_fstop = geo.blender_fstop(float(cam["f_number"]), data.lens,
                                                    cam.get("focal_length"))


def _render_settings(scene, desc):
    r = desc["render"]
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = int(r["samples"])
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.seed = int(r["seed"]) % (2**31)
    cy.use_animated_seed = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.light_sampling_threshold = 0.0
    # LIGHT_TREE: off. With it, a scene lit by the sun, strobes and the sky at once rendered
    # archaeology's red 6-8 % too bright (64 and 128 spp, 1/20 size), where each light alone,
    # and all of them with the tree off, agree with native within 0.05-0.7 %. The red there is
    # mostly the strobes', the sun's a tenth of it; the tree picks lights by an estimate that
    # does not see that, and the rare red-rich picks do not average out at these sample counts.
    cy.use_light_tree = False
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    # poser's max_bounces counts scattering vertices (surface or medium) on a path; Cycles
    # counts the events after which a path continues (0 = direct light and single
    # scattering only), and counts each glass face a camera ray crosses as a transmission
    # bounce. So every budget is one less than poser's, and the port's faces are added to
    # the total and transmission budgets.
    b = max(int(r.get("max_bounces", 64)), 1) - 1
    glass = int(r.get("port_interfaces", 0))
    cy.max_bounces = b + glass
    cy.transmission_bounces = b + glass
    cy.volume_bounces = b
    cy.diffuse_bounces = b
    cy.glossy_bounces = b
    cy.transparent_max_bounces = 64
    scene.render.use_persistent_data = True
    cam0 = desc["cameras"][0]
    scene.render.resolution_x = int(cam0["width"])
    scene.render.resolution_y = int(cam0["height"])
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = 1.0
    scene.render.pixel_aspect_y = 1.0
    scene.render.film_transparent = False
    scene.render.use_motion_blur = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    im = scene.render.image_settings
    im.file_format = "OPEN_EXR"
    im.color_depth = "32"
    im.color_mode = "RGB"
    im.exr_codec = "ZIP"
    threads = int(os.environ.get("POSER_THREADS", "0"))
    if threads > 0:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = threads


def _water_box(desc, pose_index):
    """World-space (lo, hi) of the water volume's outer box for a pose."""
    water = desc["water"]
    ext = water["extent"]
    if ext["kind"] == "box_around_camera":
        hs = np.asarray(ext["half_size"], dtype=float)
        pose = geo.mat4(desc["poses"][pose_index]["world_from_rig"])
        los, his = [], []
        for cam in desc["cameras"]:
            c = (pose @ geo.mat4(cam["rig_from_camera"]))[:3, 3]
            los.append(c - hs)
            his.append(c + hs)
        return np.min(los, axis=0), np.max(his, axis=0)
    b = desc["bounds"]
    lo = np.asarray(b["min"], dtype=float)
    hi = np.asarray(b["max"], dtype=float)
    if desc.get("surface", {}).get("kind") in ("flat", "waves"):
        top = 0.0 if desc["surface"]["kind"] == "flat" else wave_water_top(desc)
        hi = hi.copy()
        hi[2] = top
        lo = lo.copy()
        lo[2] = min(lo[2], top - 1.0)
    return lo, hi


def wave_water_top(desc):
    """Top of the water volume under a wavy surface: 1 mm below its lowest possible trough, so
    that the glass surface never dips into the volume (the layer between them is clear; the sun
    is dimmed by its extinction instead, `_sun_layer_factor`)."""
    field = desc.get("wave_field") or {}
    depth = field.get("max_abs_height", 0.5 * float(desc["surface"].get("height", 0.0)))
    return -float(depth) - 1e-3


def _sun_layer_factor(desc, sun):
    """Per-channel transmittance of the water between z = 0 and the water volume's top under a
    wavy surface, along the sun's refracted (flat-surface) direction: the native backend
    attenuates the sun from z = 0."""
    water = desc.get("water")
    if water is None or desc.get("surface", {}).get("kind") != "waves" or sun.get("in_water"):
        return [1.0, 1.0, 1.0]
    d = np.asarray(sun["direction"], dtype=float)
    d /= np.linalg.norm(d)
    out = []
    for c in range(3):
        sin_w = math.sqrt(max(0.0, 1.0 - d[2] ** 2)) / float(water["ior"][c])
        cos_w = math.sqrt(max(1e-12, 1.0 - sin_w ** 2))
        sigma = float(water["absorption"][c]) + float(water["scattering"][c])
        out.append(math.exp(-sigma * -wave_water_top(desc) / cos_w))
    return out


# SEA_WALLS: material index of the sea box's sides and bottom, black. Under a sea surface
# native's sea is unbounded: light that leaves sideways or downwards never comes back. Cycles'
# box is finite (`bounds`: 5 absorption lengths, 5-400 m), and open sides would let the
# ambient light in through the water left to them. Measured on calibration_by_port (a camera
# looking horizontally through water absorbing 0.03/m in blue, 1/4 size, 64 spp): open sides
# +4.2 % in B against native, black ones −0.1 %.
SEA_WALLS = 3


def _sea_below_surface(desc):
    return (desc["water"]["extent"]["kind"] == "everywhere"
            and desc.get("surface", {}).get("kind") in ("flat", "waves"))


def _water_mesh(desc, pose_index, shells, cutouts):
    lo, hi = _water_box(desc, pose_index)
    box = geo.box_mesh(lo, hi, 0)
    if _sea_below_surface(desc):
        box["tags"] = [SEA_WALLS] * 5 + [0]  # box_mesh's faces: -x, +x, -y, +y, -z, +z (top)
    parts = [box]
    for m, shell in _shells_at(desc, pose_index, shells):
        parts.append(geo.reverse_mesh(geo.transform_mesh(shell, m)))
    parts += cutouts
    return geo.merge_meshes(parts)


def _shells_at(desc, pose_index, shells):
    """(world_from_camera, shell) of every port shell at pose `pose_index`."""
    pose = geo.mat4(desc["poses"][pose_index]["world_from_rig"])
    return [(pose @ geo.mat4(desc["cameras"][ci]["rig_from_camera"]), shell)
            for ci, shell, _ in (s for s in shells if s is not None)]


def _water_verts(desc, pose_index, shells, cutouts):
    """The vertices of `_water_mesh(desc, pose_index, shells, cutouts)`, in its order, without
    building its faces: one shape key per pose (a survey has hundreds; building each pose's
    whole mesh in Python took 70 s for flat_port_deformation_dome's 891 poses). The glass
    objects' `cutouts` (`_glass_cutouts`) stand still; the shells follow the rig."""
    lo, hi = _water_box(desc, pose_index)
    parts = [geo.box_mesh(lo, hi, 0)["verts"]]
    parts += [geo.transform_points(shell["verts"], m)
              for m, shell in _shells_at(desc, pose_index, shells)]
    parts += [c["verts"] for c in cutouts]
    return np.concatenate(parts)


def _build_water(built, coll, desc, shells, n_w, ref, base_dir):
    water = desc.get("water")
    if water is None:
        # Air: the outer port face is a standalone glass surface (normals outward, IOR n_g).
        for s in shells:
            if s is None:
                continue
            ci, shell, glass = s
            cam = desc["cameras"][ci]
            mat, node = _glass_material(f"glass glass->air:{cam['name']}", glass[ref])
            built.glass_nodes.append((node, lambda c, g=glass: g[c]))
            me = _mesh_from(f"port outer:{cam['name']}", shell, smooth=shell["normals"] is not None)
            me.materials.append(mat)
            me.materials.append(mat)
            me.materials.append(_black_material(f"housing:{cam['name']}"))
            obj = _new_object(coll, f"port outer:{cam['name']}", me)
            obj.visible_shadow = False  # HOUSING_SHADOW
            obj.parent = built.cameras[ci].parent
            obj.matrix_parent_inverse.identity()
        return
    # Each port's outer (glass->water) face is its own object: Glass BSDF with IOR n_w/n_g and
    # normals towards the camera (the water side is "inside"). The water mesh's cut-out lies
    # WATER_GAP further out and is a pure volume boundary: Cycles then keeps a volume-only
    # shader on its volume stack (a glass shader there blocks distant-light shadow rays).
    for s in shells:
        if s is None:
            continue
        ci, shell, glass = s
        cam = desc["cameras"][ci]
        mat, node = _glass_material(f"glass glass->water:{cam['name']}", n_w[ref] / glass[ref])
        built.glass_nodes.append((node, lambda c, g=glass: n_w[c] / g[c]))
        face = geo.reverse_mesh(geo.submesh(shell, geo.GLASS_OUTER))
        me = _mesh_from(f"port outer:{cam['name']}", face, smooth=face["normals"] is not None)
        me.materials.append(mat)
        obj = _new_object(coll, f"port outer:{cam['name']}", me)
        obj.visible_shadow = False  # HOUSING_SHADOW
        obj.parent = built.cameras[ci].parent
        obj.matrix_parent_inverse.identity()
        _housing_inside(built, coll, ci, shell)
    gapped = [None if s is None else (s[0], geo.inflate(s[1], WATER_GAP), s[2]) for s in shells]
    cutouts = _glass_cutouts(built, base_dir)
    mesh = _water_mesh(desc, 0, gapped, cutouts)
    me = _mesh_from("poser_water", mesh, smooth=True)
    boundary = _volume_only_material("water boundary", water)
    boundary["poser_water"] = {
        **_exact_medium(water),
        "surface": str(desc.get("surface", {}).get("kind", "flat")),
    }
    me.materials.append(boundary)
    me.materials.append(boundary)
    # The housing body too (HOUSING_SHADOW): a black surface here, even one made transparent
    # for shadow rays, still shadowed the sun (measured); a pure volume boundary does not.
    me.materials.append(boundary)
    me.materials.append(_black_material("sea sides and bottom", water))  # SEA_WALLS
    obj = _new_object(coll, "poser_water", me)
    obj.visible_shadow = True
    n_poses = len(desc["poses"])
    if n_poses > 1:
        obj.shape_key_add(name="basis", from_mix=False)
        for i in range(n_poses):
            key = obj.shape_key_add(name=f"pose {i}", from_mix=False)
            verts = _water_verts(desc, i, gapped, cutouts) if i else mesh["verts"]
            key.data.foreach_set("co", np.asarray(verts, dtype=np.float32).ravel())
            # Constant interpolation: 0 before pose i, 1 at pose i, 0 after (O(1) keys each).
            for f, value in ((0, 0.0), (i, 1.0), (i + 1, 0.0)):
                if f == 0 and i == 0 and value == 0.0:
                    continue
                key.value = value
                key.keyframe_insert("value", frame=f)
        _constant_interpolation(me.shape_keys)


def _housing_inside(built, coll, ci, shell):
    """HOUSING_INSIDE: the housing body's walls, black, inside the water mesh's cut-out (which
    lies WATER_GAP further out). Light that the port glass reflects back into the housing
    ends on them, as in a real housing, instead of crossing the cut-out (a pure volume
    boundary) and the water to the sky or the seabed. Without them paper_survey at 1/20 size,
    64 spp, scattering off, rendered a veil of 0.0004 in G and 0.0009 in B over a black seabed
    (native: 0), +33 % in G over the real signal; coral_self_occlusion (dome), with the walls
    coinciding with the cut-out's back, +8 / +4 / +5 % and up to 2.8x at the camera's
    anti-solar point. Invisible to shadow rays (HOUSING_SHADOW)."""
    cam = built.desc["cameras"][ci]
    # WATER_GAP inside the shell along the faces' own normals: the cut-out is the shell moved
    # out along its vertex normals, which on a dome's or a cylinder's end disk are radial, so
    # walls at the shell itself would coincide with the cut-out there and lose to it.
    body = geo.submesh(shell, geo.BODY)
    body = geo.inflate({**body, "normals": None}, -WATER_GAP)
    me = _mesh_from(f"housing:{cam['name']}", body, smooth=False)
    me.materials.append(_black_material(f"housing inside:{cam['name']}"))
    obj = _new_object(coll, f"housing:{cam['name']}", me)
    obj.visible_shadow = False
    obj.parent = built.cameras[ci].parent
    obj.matrix_parent_inverse.identity()


def _build_lights(built, coll, desc):
    water = desc.get("water")
    in_water = water is not None
    for li, light in enumerate(desc.get("lights", [])):
        kind = light["type"]
        name = f"light:{light['name']}"
        if kind == "ambient":
            _world(built, light["radiance"], in_water, light["name"])
            continue
        if kind == "point":
            data = bpy.data.lights.new(name, "POINT")
            rot = np.eye(3)
            pos = light["position"]
            values, factor = light["intensity"], 4.0 * math.pi
        elif kind == "spot":
            data = bpy.data.lights.new(name, "SPOT")
            data.spot_size = min(2.0 * float(light["half_angle"]), math.pi)
            data.spot_blend = 0.0
            data.show_cone = True
            rot = geo.frame_looking_along(light["direction"])
            pos = light["position"]
            values, factor = light["intensity"], 4.0 * math.pi
        elif kind == "area":
            data = bpy.data.lights.new(name, "AREA")
            data.shape = "RECTANGLE"
            data.size = float(light["width"])
            data.size_y = float(light["height"])
            data.normalize = True
            frame = geo.mat4(light["frame"])
            # Model: emits along local +z; Blender: along local -z.
            rot = frame[:3, :3] @ np.diag([1.0, -1.0, -1.0])
            pos = frame[:3, 3]
            values = light["radiance"]
            factor = math.pi * float(light["width"]) * float(light["height"])
        else:
            raise ValueError(f"unknown light type {kind!r}")
        if hasattr(data, "shadow_soft_size"):
            data.shadow_soft_size = 0.0
        if hasattr(data, "use_soft_falloff"):
            data.use_soft_falloff = False
        obj = _new_object(coll, name, data)
        # AREA_SEEN: a light object's camera visibility is off by default in Blender 5; an area
        # light seen directly by a camera without a port (a camera ray, not a transmission ray
        # through the port's glass) rendered black, where native and Mitsuba see its radiance.
        obj.visible_camera = True
        if light.get("mount") == "rig":
            obj.parent = built.rig
            obj.matrix_parent_inverse.identity()
            obj.matrix_basis = _matrix(geo.compose(rot, pos))
        else:
            obj.matrix_world = _matrix(geo.compose(rot, pos))
        obj["poser_basis"] = _flat([geo.compose(rot, pos)])
        shadow = {"values": [float(x) for x in values], "mount": str(light.get("mount", "world"))}
        if kind == "spot":
            shadow["beam_angle"] = min(2.0 * float(light["half_angle"]), math.pi)
        if kind == "area":
            shadow["width"] = float(light["width"])
            shadow["height"] = float(light["height"])
        data["poser_light"] = shadow
        built.lights.append({"data": data, "values": values, "factor": factor,
                             "in_water": in_water})
    sun = desc.get("sun")
    if sun is not None:
        data = bpy.data.lights.new("sun", "SUN")
        data.angle = float(sun.get("angle", 0.0))
        obj = _new_object(coll, "sun", data)
        obj.matrix_world = _matrix(geo.compose(geo.frame_looking_along(sun["direction"]),
                                               [0.0, 0.0, 10.0]))
        obj["poser_basis"] = _flat([geo.compose(geo.frame_looking_along(sun["direction"]),
                                                [0.0, 0.0, 10.0])])
        if sun.get("caustics"):
            data.cycles.is_caustics_light = True
        layer = _sun_layer_factor(desc, sun)
        values = [float(e) * t for e, t in zip(sun["irradiance"], layer)]
        data["poser_light"] = {"values": values, "in_water": bool(sun.get("in_water"))}
        built.lights.append({"data": data, "values": values, "factor": 1.0,
                             "in_water": bool(sun.get("in_water"))})
    if built.world_bg is None:
        _world(built, [0.0, 0.0, 0.0], in_water)


def _world(built, radiance, in_water, name="ambient"):
    scene = built.scene
    world = scene.world or bpy.data.worlds.new("poser world")
    scene.world = world
    if world.node_tree is None:
        world.use_nodes = True
    nt = world.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputWorld")
    bg = nt.nodes.new("ShaderNodeBackground")
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    built.world_bg = {"node": bg, "values": radiance, "factor": 1.0, "in_water": in_water}
    world["poser_light"] = {"values": [float(x) for x in radiance], "name": name}


def _apply_emitters(built, scale, channel=None):
    """Set light and world strengths for a render: per-channel `scale` (n^2 correction for
    emitters in water) and, for per-channel passes, only `channel`."""
    one = (1.0, 1.0, 1.0)
    for rec in built.lights + ([built.world_bg] if built.world_bg else []):
        s = scale if rec["in_water"] else one
        vals = list(rec["values"])
        if channel is not None:
            vals = [vals[channel]] * 3
            s = [s[channel]] * 3
        colour, strength = geo.light_power(vals, s, rec["factor"])
        if "data" in rec:
            rec["data"].color = colour
            rec["data"].energy = strength
            holder = rec["data"].get("poser_light")
        else:
            rec["node"].inputs["Color"].default_value = (*colour, 1.0)
            rec["node"].inputs["Strength"].default_value = strength
            holder = built.scene.world.get("poser_light")
        if holder is not None and channel is None:
            holder["scale"] = [float(x) for x in s]


def _build_objects(built, coll, desc, base_dir):
    import bmesh

    for ob in desc.get("objects", []):
        shape = ob["shape"]
        name = f"object:{ob['name']}"
        kind = shape["type"]
        scale = ob.get("scale", [1.0, 1.0, 1.0])
        if kind == "ply":
            me = _import_ply(os.path.join(base_dir, shape["path"]), name)
            if shape.get("smooth"):
                me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
        elif kind == "ply_parts":
            me = _import_parts(base_dir, shape["parts"], name)
        elif kind == "shaded_ply":
            # A glass sphere or cylinder: poser's mesh with its true normals (GLASS_OBJECTS).
            me = _mesh_from(name, _solid(built, base_dir, shape["path"]),
                            smooth=True)
        else:
            me = bpy.data.meshes.new(name)
            bm = bmesh.new()
            if kind == "plane":
                bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.5)
                bmesh.ops.scale(bm, vec=(shape["width"], shape["height"], 1.0), verts=bm.verts)
            elif kind == "box":
                bmesh.ops.create_cube(bm, size=1.0)
                bmesh.ops.scale(bm, vec=tuple(shape["size"]), verts=bm.verts)
            else:
                bm.free()
                raise ValueError(f"object {ob['name']!r}: shape {kind!r} has no Blender form")
            bm.to_mesh(me)
            bm.free()
        if kind == "ply_parts":
            pass  # one material per part, set by _import_parts
        elif shape.get("texture"):
            path = os.path.join(base_dir, shape["texture"])
            me.materials.append(_texture_material(name, path, "Linear"))
        elif ob["material"].get("glass"):
            me.materials.append(
                _glass_object_material(
                    built, name, ob["material"]["glass"], desc, ob["material"].get("fill")
                )
            )
        else:
            me.materials.append(_diffuse_material(name, ob["material"], scale))
        obj = _new_object(coll, name, me)
        obj.matrix_world = _matrix(ob["matrix"])
        obj["poser_basis"] = _flat([ob["matrix"]])
        _caustics_receiver(obj, desc)


def _glass_object_material(built, name, glass, desc, fill=None):
    """GLASS_OBJECTS: a glass object's faces, smooth Glass BSDF of IOR n_glass / n_around
    (normals outward), per channel with the passes. In water its box is carved out of the water
    mesh WATER_GAP further out (`_glass_cutouts`), as a port's outer face is: inside it there
    is no water, and the glass shader stays off the volume stack. A filled object (FILLED_OBJECTS,
    `fill`: its water) is the same boundary, of its water's index, with that water's volume
    inside."""
    water = desc.get("water")
    n_out = [float(x) for x in water["ior"]] if water else [1.0, 1.0, 1.0]
    n_g = [float(x) for x in glass["ior"]]
    ref = int(desc.get("reference_channel", 1))
    mat, node = _glass_material(f"glass:{name}", n_g[ref] / n_out[ref], fill)
    built.glass_nodes.append((node, lambda c, g=n_g, w=n_out: g[c] / w[c]))
    if fill is not None:
        mat["poser_fill"] = _exact_medium(fill)
    return mat


def _exact_medium(water):
    """A water's or filled object's values in f64, kept on its material for `poser import`
    (Blender's node sockets hold float32)."""
    return {
        "absorption": [float(x) for x in water["absorption"]],
        "scattering": [float(x) for x in water["scattering"]],
        "g": float(water["phase"].get("g", 0.0)),
        "particle_index": float(water["phase"].get("n", 0.0)),
        "junge_slope": float(water["phase"].get("mu", 0.0)),
        "backscatter": float(water["phase"].get("backscatter", 0.0)),
        "ior": [float(x) for x in water["ior"]],
    }


def _solid(built, base_dir, path):
    """A glass sphere's or cylinder's mesh (`shaded_ply`), read once per build: the object and
    its cut-out of the water both use it."""
    if path not in built.solids:
        built.solids[path] = geo.read_ply(os.path.join(base_dir, path))
    return built.solids[path]


def _glass_cutouts(built, base_dir):
    """GLASS_OBJECTS: every glass box, sphere and cylinder (world frame), WATER_GAP larger,
    normals into it: holes of the water mesh, in the order `_water_mesh` and `_water_verts`
    both use."""
    out = []
    for ob in built.desc.get("objects", []):
        kind = ob["shape"]["type"]
        if not ob["material"].get("glass") or kind not in ("box", "shaded_ply"):
            continue
        m = geo.mat4(ob["matrix"])
        # WATER_GAP further out in the world, whatever the object's scale (the matrix's columns).
        scale = np.linalg.norm(m[:3, :3], axis=0)
        if kind == "box":
            half = 0.5 * np.asarray(ob["shape"]["size"], dtype=float) + WATER_GAP / scale
            hole = geo.box_mesh(-half, half, 0)
        else:  # a glass sphere or cylinder, centred on its frame's origin: grown per axis
            solid = _solid(built, base_dir, ob["shape"]["path"])
            half = np.max(np.abs(solid["verts"]), axis=0)
            grow = (half + WATER_GAP / scale) / half
            hole = {**solid, "verts": solid["verts"] * grow}
        out.append(geo.reverse_mesh(geo.transform_mesh(hole, m)))
    return out


def _caustics_receiver(obj, desc):
    """Under a wavy surface every object and target receives the sun's caustics (MNEE: Cycles
    finds the refracted sun paths through the caster only at receivers)."""
    if desc.get("caustics"):
        obj.cycles.is_caustics_receiver = True


def _import_ply(path, name):
    before = set(bpy.data.objects)
    # Vertex colours (textured meshes' PLY files) are written linear.
    bpy.ops.wm.ply_import(filepath=path, import_colors="LINEAR")
    new = [o for o in bpy.data.objects if o not in before]
    if not new:
        raise ValueError(f"could not import mesh {path}")
    me = new[0].data
    for o in new:
        bpy.data.objects.remove(o)
    me.name = name
    return me


def _build_targets(built, coll, desc, base_dir):
    import bmesh

    for t in desc.get("targets", []):
        name = f"target:{t['name']}"
        if t.get("kind") == "test_object":
            _caustics_receiver(_build_test_object(coll, t, name), desc)
            continue
        me = bpy.data.meshes.new(name)
        bm = bmesh.new()
        uv = bm.loops.layers.uv.new("UVMap")
        w, h = float(t["width"]), float(t["height"])
        cx, cy = float(t.get("origin", [0.0, 0.0])[0]), float(t.get("origin", [0.0, 0.0])[1])
        vs = [bm.verts.new((cx + x * w, cy + y * h, 0.0))
              for (x, y) in ((0, 0), (1, 0), (1, 1), (0, 1))]
        face = bm.faces.new(vs)
        for loop, (u, v) in zip(face.loops, ((0, 0), (1, 0), (1, 1), (0, 1))):
            loop[uv].uv = (u, v)
        bm.to_mesh(me)
        bm.free()
        me.materials.append(_texture_material(name, os.path.join(base_dir, t["texture"])))
        obj = _new_object(coll, name, me)
        obj.matrix_world = _matrix(t["matrix"])
        _caustics_receiver(obj, desc)


# Segments of the polygon standing for each disk of a 3D test object: its centroid is the
# disk's centre exactly; its area is 0.16 % smaller than the disk's (no effect on centroids).
DISK_SEGMENTS = 64


def _build_test_object(coll, t, name):
    """3D test object: white boxes (the steps) and black disks on their top corners, all in
    the target frame given by `matrix`; one mesh with two material slots."""
    verts, faces, mats = [], [], []
    for st in t["steps"]:
        c = np.asarray(st["center"], dtype=float)
        h = 0.5 * np.asarray(st["size"], dtype=float)
        base = len(verts)
        for z in (-1.0, 1.0):
            for y in (-1.0, 1.0):
                for x in (-1.0, 1.0):
                    verts.append(tuple(c + h * (x, y, z)))
        # Corner index = x + 2 y + 4 z (each of x, y, z in {0, 1}); outward windings.
        for f in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2),
                  (1, 3, 7, 5)):
            faces.append(tuple(base + i for i in f))
            mats.append(0)
    for d in t["disks"]:
        c = np.asarray(d["center"], dtype=float)
        r = float(d["radius"])
        base = len(verts)
        for k in range(DISK_SEGMENTS):
            a = 2.0 * math.pi * k / DISK_SEGMENTS
            verts.append((c[0] + r * math.cos(a), c[1] + r * math.sin(a), c[2]))
        faces.append(tuple(range(base, base + DISK_SEGMENTS)))
        mats.append(1)
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.polygons.foreach_set("material_index", mats)
    me.polygons.foreach_set("use_smooth", [False] * len(faces))
    me.update()
    grey = {"albedo": [float(t["white"])] * 3, "pattern": None}
    me.materials.append(_diffuse_material(name + " white", grey))
    grey = {"albedo": [float(t["black"])] * 3, "pattern": None}
    me.materials.append(_diffuse_material(name + " black", grey))
    obj = _new_object(coll, name, me)
    obj.matrix_world = _matrix(t["matrix"])
    return obj


# Most tiles of the periodic sea surface per side; beyond, the tiles cover the scene's centre.
MAX_WAVE_TILES = 48
# Most grid cells per side of one wave tile; the grid samples the shortest component with at
# least WAVE_CELLS_PER_WAVELENGTH cells when this allows it.
MAX_WAVE_CELLS = 384
WAVE_CELLS_PER_WAVELENGTH = 8


def wave_surface(field):
    """One period of the sea surface as a mesh: the native backend's height field
    h(x, y) = sum a cos(kx x + ky y + phi) (crates/poser-optics/src/waves.rs, exactly periodic with period P)
    sampled on a regular grid over [0, P]^2, with its analytic normals (smooth shading)."""
    period = float(field["period"])
    comps = np.asarray(field["components"], dtype=float).reshape(-1, 4)
    kmax = float(np.max(np.hypot(comps[:, 0], comps[:, 1]))) if len(comps) else 1.0
    n = int(math.ceil(period * kmax / (2.0 * math.pi) * WAVE_CELLS_PER_WAVELENGTH))
    n = max(16, min(n, MAX_WAVE_CELLS))
    t = np.linspace(0.0, period, n + 1)
    x, y = np.meshgrid(t, t, indexing="xy")
    x, y = x.ravel(), y.ravel()
    arg = np.outer(x, comps[:, 0]) + np.outer(y, comps[:, 1]) + comps[:, 3]
    h = np.cos(arg) @ comps[:, 2]
    s = np.sin(arg)
    hx = -(s @ (comps[:, 2] * comps[:, 0]))
    hy = -(s @ (comps[:, 2] * comps[:, 1]))
    nrm = np.column_stack([-hx, -hy, np.ones_like(hx)])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    verts = np.column_stack([x, y, h])
    i = np.arange(n)
    a = (i[None, :] + (n + 1) * i[:, None]).ravel()  # lower-left corner of each cell
    # Counter-clockwise seen from above: the normals point up, into the air.
    faces = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    return {"verts": verts, "faces": faces, "normals": nrm, "cells": n}


def significant_height(verts):
    """4 x the standard deviation of the vertex heights (the grid samples one period evenly)."""
    return 4.0 * float(np.std(np.asarray(verts, dtype=float)[:, 2]))


def _build_waves(built, coll, desc, n_w, ref):
    """The wavy sea surface: the native backend's periodic height field (`wave_field`), one
    period as a smooth glass mesh (index n_w, normals up) instanced over the water's extent.
    It is the caustics caster; the objects and targets are the receivers and the sun the
    caustics light (MNEE)."""
    field = desc.get("wave_field")
    if not field:
        raise ValueError("a wavy surface needs the description's wave_field (poser >= this one)")
    surf = wave_surface(field)
    me = bpy.data.meshes.new("sea surface")
    me.from_pydata([tuple(v) for v in surf["verts"]], [], [tuple(f) for f in surf["faces"]])
    me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
    me.normals_split_custom_set_from_vertices([tuple(v) for v in surf["normals"]])
    me.update()
    mat, node = _glass_material("sea surface", n_w[ref])
    built.glass_nodes.append((node, lambda c: n_w[c]))
    me.materials.append(mat)
    period = float(field["period"])
    b = desc["bounds"]
    lo, hi = np.asarray(b["min"], dtype=float), np.asarray(b["max"], dtype=float)
    centre = 0.5 * (lo + hi)
    counts = [min(MAX_WAVE_TILES, max(1, int(math.ceil((hi[k] - lo[k]) / period))))
              for k in (0, 1)]
    # Tiles on the field's own lattice (multiples of P from the origin), so that the surface
    # is the native one at every (x, y), not a shifted copy.
    start = [math.floor((centre[k] - 0.5 * counts[k] * period) / period) * period for k in (0, 1)]
    built.wave_tiles = []
    for j in range(counts[1]):
        for i in range(counts[0]):
            obj = _new_object(coll, f"sea surface {i},{j}", me)
            obj.location = (start[0] + i * period, start[1] + j * period, 0.0)
            obj.cycles.is_caustics_caster = True
            obj.visible_shadow = True
            built.wave_tiles.append(obj)
    built.wave_mesh = me


# ------------------------------------------------------------------------------------------
# Rendering
# ------------------------------------------------------------------------------------------


def _n_cam(desc, cam):
    """Index of the medium each camera's entrance pupil sits in, per channel."""
    water = desc.get("water")
    if water is None or cam["port"]["kind"] != "none":
        return [1.0, 1.0, 1.0]
    return list(water["ior"])


def _load_pixels(path):
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    return buf.reshape(h, w, 4)


def _save_pixels(path, rgb, fmt, scene):
    """Write bottom-up RGB(A) float pixels: 32-bit linear EXR or 8-bit PNG."""
    h, w = rgb.shape[:2]
    img = bpy.data.images.new("poser out", w, h, alpha=False, float_buffer=(fmt == "OPEN_EXR"))
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = rgb[..., :3]
    img.pixels.foreach_set(rgba.ravel())
    if fmt == "OPEN_EXR":
        img.filepath_raw = path
        img.file_format = "OPEN_EXR"
        settings = scene.render.image_settings
        img.save_render(path, scene=scene)
        del settings
    else:
        img.filepath_raw = path
        img.file_format = "PNG"
        img.save()
    bpy.data.images.remove(img)


def _write_png(exr_path, png_path, exposure, scene):
    px = _load_pixels(exr_path)
    enc = geo.srgb_encode(px[..., :3] * exposure)
    _save_pixels(png_path, enc.astype(np.float32), "PNG", scene)


def render(built, out_dir, samples=None, poses=None, progress=None, png=True):
    """Render every (pose, camera) to `{image}.exr` (linear) and `{image}.png` in out_dir.

    Files are written under a temporary name and renamed, so no half-written image is left.
    """
    desc = built.desc
    scene = built.scene
    if samples:
        scene.cycles.samples = int(samples)
    os.makedirs(out_dir, exist_ok=True)
    pose_ids = list(range(len(desc["poses"]))) if poses is None else list(poses)
    ref = int(desc.get("reference_channel", 1))
    passes = [0, 1, 2] if desc.get("per_channel_passes") else [None]
    total = len(pose_ids) * len(desc["cameras"])
    done = 0
    written = []
    exposure = float(desc["render"].get("exposure", 1.0))
    for pi in pose_ids:
        pose = desc["poses"][pi]
        for ci, cam in enumerate(desc["cameras"]):
            prepare_image(built, pi, ci)
            image = pose["images"][ci]
            exr = os.path.join(out_dir, image + ".exr")
            tmp = os.path.join(out_dir, f".poser-tmp-{ci}.exr")
            if passes == [None]:
                # One pass with the reference channel's indices: the n^2 factor uses them too.
                _render_to(scene, tmp)
            else:
                combined = None
                scale = _emitter_scale(desc, cam, True)
                for c in passes:
                    _apply_emitters(built, scale, channel=c)
                    for node, ior in built.glass_nodes:
                        node.inputs["IOR"].default_value = float(ior(c))
                    _render_to(scene, tmp)
                    px = _load_pixels(tmp)
                    if combined is None:
                        combined = np.zeros_like(px)
                    combined[..., c] = px[..., c]
                for node, ior in built.glass_nodes:
                    node.inputs["IOR"].default_value = float(ior(ref))
                _save_pixels(tmp, combined, "OPEN_EXR", scene)
            if png:
                tmp_png = os.path.join(out_dir, f".poser-tmp-{ci}.png")
                _write_png(tmp, tmp_png, exposure, scene)
                os.replace(tmp_png, os.path.join(out_dir, image + ".png"))
            if wants_depth(desc):
                tmp_depth = os.path.join(out_dir, f".poser-tmp-{ci}.depth.exr")
                render_depth(built, ci, tmp_depth)
                os.replace(tmp_depth, os.path.join(out_dir, image + ".depth.exr"))
            os.replace(tmp, exr)
            written.append(exr)
            done += 1
            if progress:
                progress(done, total, image)
    return written


# ------------------------------------------------------------------------------------------
# Depth pass
# ------------------------------------------------------------------------------------------

# Box-filter width of the depth render, px (Cycles' minimum): its one sample per pixel lands
# within +-0.005 px of the pixel centre, where the native backend evaluates depth.
DEPTH_FILTER_WIDTH = 0.01


def _depth_twin(mat, depth_mat, cache):
    """The material a surface gets for the depth render: glass -> Refraction BSDF with the
    same index ratio (no Fresnel reflection, so one sample follows the camera ray through the
    port exactly), volume boundaries -> transparent, housings -> black, everything else ->
    the camera-z emission."""
    if mat is None:
        return depth_mat
    role = mat.get("poser_role")
    if role is None:
        return depth_mat
    key = mat.name
    twin = cache.get(key)
    if role == "glass":
        ior = [n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfGlass"][0]
        ior = float(ior.inputs["IOR"].default_value)
        if twin is None:
            twin = bpy.data.materials.new("depth " + key)
            nt, out = _nodes(twin)
            r = nt.nodes.new("ShaderNodeBsdfRefraction")
            r.distribution = "GGX"
            r.inputs["Roughness"].default_value = 0.0
            r.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            nt.links.new(r.outputs[0], out.inputs["Surface"])
        r = [n for n in twin.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfRefraction"][0]
        r.inputs["IOR"].default_value = ior
    elif twin is None:
        twin = bpy.data.materials.new("depth " + key)
        nt, out = _nodes(twin)
        if role == "boundary":
            t = nt.nodes.new("ShaderNodeBsdfTransparent")
            t.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        else:
            t = nt.nodes.new("ShaderNodeBsdfDiffuse")
            t.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        nt.links.new(t.outputs[0], out.inputs["Surface"])
    cache[key] = twin
    return twin


def _depth_material(built):
    """One emission material whose strength is the camera-frame z of the shaded point:
    dot(P - C, z_cam) with C and z_cam (world) set per image."""
    if getattr(built, "depth_mat", None) is not None:
        return built.depth_mat
    mat = bpy.data.materials.new("poser depth")
    nt, out = _nodes(mat)
    geom = nt.nodes.new("ShaderNodeNewGeometry")
    sub = nt.nodes.new("ShaderNodeVectorMath")
    sub.operation = "SUBTRACT"
    dot = nt.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    nt.links.new(geom.outputs["Position"], sub.inputs[0])
    nt.links.new(sub.outputs["Vector"], dot.inputs[0])
    nt.links.new(dot.outputs["Value"], em.inputs["Strength"])
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    mat.cycles.emission_sampling = "NONE"
    built.depth_mat = mat
    built.depth_nodes = (sub, dot)
    return mat


def wants_depth(desc):
    return "depth" in (desc["render"].get("outputs") or [])


def render_depth(built, cam_index, path):
    """Render the camera-frame z (m) of the first surface seen through each pixel centre
    (through the port, as the native backend's depth) to a linear RGB EXR at `path`; 0 where
    the ray meets no surface. The scene's lights, world and water are off for this render."""
    scene = built.scene
    depth_mat = _depth_material(built)
    sub, dot = built.depth_nodes
    scene.frame_set(scene.frame_current)
    m = np.array(built.cameras[cam_index].matrix_world)
    centre = m[:3, 3]
    z_cv = -m[:3, 2] / np.linalg.norm(m[:3, 2])  # Blender looks along local -Z
    sub.inputs[1].default_value = tuple(map(float, centre))
    dot.inputs[1].default_value = tuple(map(float, z_cv))
    cache = getattr(built, "depth_twins", None)
    if cache is None:
        cache = built.depth_twins = {}
    saved_mats = []
    saved_hidden = []
    seen = set()
    for obj in scene.objects:
        if obj.type == "MESH" and obj.data is not None:
            if obj.data.name in seen:  # mesh data shared by several objects: swap once
                continue
            seen.add(obj.data.name)
            mats = list(obj.data.materials)
            if not mats:
                obj.data.materials.append(None)
                mats = [None]
                saved_mats.append((obj.data, None))
            else:
                saved_mats.append((obj.data, mats))
            for i, mt in enumerate(mats):
                obj.data.materials[i] = _depth_twin(mt, depth_mat, cache)
        elif obj.type == "LIGHT" and not obj.hide_render:
            obj.hide_render = True
            saved_hidden.append(obj)
    cy = scene.cycles
    settings = (cy.samples, cy.filter_width, cy.pixel_filter_type)
    bg = built.world_bg["node"].inputs["Strength"] if built.world_bg else None
    bg_strength = bg.default_value if bg is not None else None
    try:
        cy.samples = 1
        cy.pixel_filter_type = "BOX"
        cy.filter_width = DEPTH_FILTER_WIDTH
        if bg is not None:
            bg.default_value = 0.0
        _render_to(scene, path)
    finally:
        cy.samples, cy.filter_width, cy.pixel_filter_type = settings
        if bg is not None:
            bg.default_value = bg_strength
        for obj in saved_hidden:
            obj.hide_render = False
        for me, mats in saved_mats:
            if mats is None:
                me.materials.clear()
            else:
                for i, mt in enumerate(mats):
                    me.materials[i] = mt


def _render_to(scene, path):
    scene.render.filepath = path
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True, scene=scene.name)


# ------------------------------------------------------------------------------------------
# Command line (`python scene.py [options]` / `blender -b -P scene.py -- [options]`)
# ------------------------------------------------------------------------------------------

USAGE = """options:
  --out DIR          where to write the images (default: ./render beside the script)
  --samples N        override samples per pixel
  --poses I,J,...    render only these pose indices
  --save-blend PATH  save the built scene as a .blend (textures packed)
  --no-render        build (and save) only
  --no-png           skip the PNG previews"""


def parse_args(argv):
    """Options after `--` (Blender) or after the script name (Python)."""
    opts = {"out": None, "samples": None, "poses": None, "save_blend": None, "render": True,
            "png": True}
    i = 0
    while i < len(argv):
        a = argv[i]

        def value():
            if i + 1 >= len(argv):
                raise SystemExit(f"{a} needs a value\n{USAGE}")
            return argv[i + 1]

        if a == "--out":
            opts["out"] = value()
            i += 1
        elif a == "--samples":
            opts["samples"] = int(value())
            i += 1
        elif a == "--poses":
            opts["poses"] = [int(x) for x in value().split(",") if x.strip()]
            i += 1
        elif a == "--save-blend":
            opts["save_blend"] = value()
            i += 1
        elif a == "--no-render":
            opts["render"] = False
        elif a == "--no-png":
            opts["png"] = False
        elif a in ("-h", "--help"):
            print(USAGE)
            raise SystemExit(0)
        else:
            raise SystemExit(f"unknown option {a!r}\n{USAGE}")
        i += 1
    return opts


def script_args(argv=None):
    argv = list(sys.argv if argv is None else argv)
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    if argv and os.path.basename(argv[0]).lower().startswith("blender"):
        return []
    return argv[1:]


def progress_line(done, total, image):
    print(f"POSER_PROGRESS {done} {total} {json.dumps(image)}", flush=True)


def main(desc, base_dir, argv=None):
    """Entry point of a generated scene script."""
    opts = parse_args(script_args(argv))
    t0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = str(desc.get("name") or "poser")
    built = build(desc, base_dir, scene)
    if opts["save_blend"]:
        path = os.path.abspath(opts["save_blend"])
        os.makedirs(os.path.dirname(path), exist_ok=True)
        try:
            bpy.ops.file.pack_all()
        except RuntimeError:
            pass
        bpy.ops.wm.save_as_mainfile(filepath=path, check_existing=False, compress=True)
        print(f"POSER_SAVED {json.dumps(path)}", flush=True)
    if opts["render"]:
        out = opts["out"] or os.path.join(base_dir, "render")
        written = render(built, out, opts["samples"], opts["poses"], progress_line, opts["png"])
        print(f"POSER_DONE {len(written)} {time.time() - t0:.3f}", flush=True)
    return built
