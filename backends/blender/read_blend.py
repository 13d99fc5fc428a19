"""Read a Blender scene (.blend) for `poser import`: cameras, poses, lights, meshes and water
in poser's units, as JSON; meshes as binary PLY files beside the result.

Run by the poser binary (src/import/blender.rs embeds this file) as
    python read_blend.py REQUEST.json RESULT.json
with the pinned `bpy`. REQUEST: {"blend": path, "work": folder for the PLY files}.

Safety: the file is opened with Python auto-execution off (`use_scripts=False`, and the
preference off), so no text block, driver expression or registered script in it runs. Nothing
is written but RESULT and `work/mesh_<i>.ply`.

Exactness: a .blend that poser saved (`--save-blend`) carries poser's own f64 values as custom
properties (`poser_*`, see poser_blender/builder.py `SHADOWS`). Blender stores transforms and
most settings in float32; where a property agrees with Blender's own value to float32
precision it is used instead, so the round trip is exact. Where they disagree (the scene was
edited in Blender) Blender's value wins and the element is marked `edited`.

Units (docs/import.md): point and spot lights W -> W/sr (/4 pi); area lights W -> radiance
W/(m^2 sr) (/(pi A)); sun W/m^2 as is; world background strength x colour = radiance;
Volume Absorption sigma_a = (1 - colour) density, Volume Scatter sigma_s = colour density.
"""
import json
import math
import os
import sys

import numpy as np

CV_TO_BLENDER = np.diag([1.0, -1.0, -1.0, 1.0])
MAX_FRAMES = 10000
F32 = 2e-6  # relative agreement of a float32 setting with its f64 shadow


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    raise SystemExit(2)


class Reader:
    def __init__(self, bpy, work):
        self.bpy = bpy
        self.work = work
        self.notes = []
        self.edited = []
        self.port_glass = False  # glass (or poser's housing) at a camera
        # A file poser saved: its image textures are poser's own bakes of the scene's patterns,
        # imported as their mean colour (the round trip gives back the scene, not the bake).
        self.poser_saved = False

    def note(self, element, message, help_=None):
        self.notes.append({"element": element, "message": message, "help": help_})

    # ---- exact values ----------------------------------------------------------------

    def shadow(self, idblock, key, blender_value, what):
        """poser's f64 value `idblock[key]` when it agrees with Blender's own (float32) value,
        else Blender's value (and `what` is recorded as edited)."""
        b = np.asarray(blender_value, dtype=float)
        if idblock is None or key not in idblock:
            return b
        p = np.asarray(idblock[key], dtype=float)
        if p.shape != b.shape:
            self.edited.append(what)
            return b
        scale = max(1.0, float(np.max(np.abs(p))) if p.size else 1.0)
        if np.all(np.abs(p - b) <= F32 * scale):
            return p
        self.edited.append(what)
        return b

    def basis(self, obj, fi):
        b = np.array(obj.matrix_basis, dtype=float)
        keys = obj.get("poser_keys")
        if keys is not None and 16 * (fi + 1) <= len(keys):
            exact = np.asarray(keys[16 * fi:16 * fi + 16], dtype=float).reshape(4, 4)
            holder = {"k": exact}
            return self.shadow(holder, "k", b, f"transform of `{obj.name}`")
        return self.shadow(obj, "poser_basis", b.ravel(), f"transform of `{obj.name}`").reshape(4, 4)

    def world(self, obj, fi):
        """obj.matrix_world in f64, from exact bases where poser left them."""
        blender = np.array(obj.matrix_world, dtype=float)
        if obj.constraints or (obj.parent is not None and obj.parent_type != "OBJECT"):
            return blender
        m = self.basis(obj, fi)
        if obj.parent is not None:
            m = self.world(obj.parent, fi) @ np.array(obj.matrix_parent_inverse, dtype=float) @ m
        scale = max(1.0, float(np.max(np.abs(blender))))
        if np.max(np.abs(m - blender)) > 1e-5 * scale:
            return blender  # something (a driver, a modifier of the transform) moved it
        return m


def colour_of(node_input):
    v = node_input.default_value
    return [float(v[0]), float(v[1]), float(v[2])]


def srgb_to_linear(v):
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def image_mean(img):
    """Mean linear colour of an image texture."""
    n = img.size[0] * img.size[1]
    if n == 0:
        return None
    px = np.empty(n * img.channels, dtype=np.float32)
    img.pixels.foreach_get(px)
    px = px.reshape(n, img.channels)[:, :3].astype(float)
    if px.shape[1] < 3:  # grey (and alpha)
        px = np.repeat(px[:, :1], 3, axis=1)
    if not img.is_float and img.colorspace_settings.name.lower().startswith("srgb"):
        px = srgb_to_linear(px)
    return [float(x) for x in px.mean(axis=0)]


def output_node(nt):
    outs = [n for n in nt.nodes if n.bl_idname in ("ShaderNodeOutputMaterial", "ShaderNodeOutputWorld")]
    for n in outs:
        if n.is_active_output:
            return n
    return outs[0] if outs else None


def linked(node_input):
    if node_input is None or not node_input.is_linked:
        return None
    return node_input.links[0].from_node


def phase_of(node, r, where):
    """The phase function of a scattering node: the HG anisotropy g (a float), or
    {"n": particle index, "backscatter": B} for Fournier-Forand."""
    phase = getattr(node, "phase", "HENYEY_GREENSTEIN")
    if phase == "FOURNIER_FORAND":
        return {"n": float(node.inputs["IOR"].default_value),
                "backscatter": float(node.inputs["Backscatter"].default_value)}
    if phase != "HENYEY_GREENSTEIN":
        r.note(where, f"phase function {phase} is imported as Henyey-Greenstein")
    return float(node.inputs["Anisotropy"].default_value) if "Anisotropy" in node.inputs else 0.0


def volume_of(node, r, where):
    """(sigma_a, sigma_s, g) of a volume node tree, or None."""
    if node is None:
        return None
    t = node.bl_idname
    if t == "ShaderNodeAddShader":
        parts = [volume_of(linked(i), r, where) for i in node.inputs if i.is_linked]
        parts = [p for p in parts if p is not None]
        if not parts:
            return None
        sa = sum(np.asarray(p[0]) for p in parts)
        ss = sum(np.asarray(p[1]) for p in parts)
        gs = [p[2] for p in parts if np.any(np.asarray(p[1]) > 0)]
        if len({json.dumps(x) for x in gs}) > 1:
            r.note(where, "two scattering volumes with different anisotropy; the first's is used")
        return (list(sa), list(ss), gs[0] if gs else 0.0)
    if t == "ShaderNodeVolumeAbsorption":
        c = np.asarray(colour_of(node.inputs["Color"]))
        d = float(node.inputs["Density"].default_value)
        return (list(np.maximum(1.0 - c, 0.0) * d), [0.0] * 3, 0.0)
    if t == "ShaderNodeVolumeScatter":
        c = np.asarray(colour_of(node.inputs["Color"]))
        d = float(node.inputs["Density"].default_value)
        return ([0.0] * 3, list(c * d), phase_of(node, r, where))
    if t == "ShaderNodeVolumePrincipled":
        # Cycles' svm_node_principled_volume: scattering colour x density; absorption
        # (1 - colour)(1 - sqrt(absorption colour)) x density.
        c = np.clip(np.asarray(colour_of(node.inputs["Color"])), 0.0, None)
        a = np.sqrt(np.clip(np.asarray(colour_of(node.inputs["Absorption Color"])), 0.0, None))
        d = max(float(node.inputs["Density"].default_value), 0.0)
        if float(node.inputs["Emission Strength"].default_value) > 0.0 or \
                float(node.inputs["Blackbody Intensity"].default_value) > 0.0:
            r.note(where, "the Principled Volume's emission is not imported")
        if any(i.is_linked for i in node.inputs):
            r.note(where, "the Principled Volume's linked inputs are read at their unlinked values")
        sa = np.maximum(1.0 - c, 0.0) * np.maximum(1.0 - a, 0.0) * d
        return (list(sa), list(c * d), float(node.inputs["Anisotropy"].default_value))
    if t == "ShaderNodeVolumeCoefficients":
        return (colour_of(node.inputs["Absorption Coefficients"]),
                colour_of(node.inputs["Scatter Coefficients"]), phase_of(node, r, where))
    r.note(where, f"volume shader `{node.name}` ({t}) is not imported",
           "poser reads Volume Absorption, Volume Scatter, their sum, Principled Volume and Volume Coefficients")
    return None


WRAPS = {"REPEAT": "repeat", "EXTEND": "clamp", "MIRROR": "mirror", "CLIP": "clamp"}
MAX_TEXTURE_SIDE = 16384  # poser's limit on a mesh's image (src/texture/mapped.rs)


def image_texture(node, into, r, where):
    """What poser needs to draw the Image Texture `node` (linked into `into`) as a mesh's
    image texture: {"image", "uv_map", "wrap"}; or None (noted) when the node does something
    poser's textured meshes cannot (then the image's mean colour is used)."""
    img = node.image
    name = f"image texture `{img.name}`"
    link = into.links[0]
    if link.from_socket.name != "Color":
        r.note(where, f"{name}: its `{link.from_socket.name}` output, not its colour, feeds the base colour")
        return None
    if img.source not in ("FILE", "GENERATED"):
        r.note(where, f"{name}: a `{img.source}` image (not one still image) is not drawn as a texture")
        return None
    if node.projection != "FLAT":
        r.note(where, f"{name}: the `{node.projection}` projection is not drawn as a texture",
               "poser's textured meshes read the UV map (the Flat projection)")
        return None
    uv_map = None
    vec = linked(node.inputs.get("Vector"))
    if vec is not None:
        out = node.inputs["Vector"].links[0].from_socket.name
        if vec.bl_idname == "ShaderNodeUVMap" and not vec.from_instancer:
            uv_map = vec.uv_map or None
        elif vec.bl_idname == "ShaderNodeTexCoord" and out == "UV" and not vec.from_instancer:
            uv_map = None
        else:
            r.note(where, f"{name}: its coordinates come from a `{vec.bl_idname}` node "
                   f"(`{out}`), which poser does not follow",
                   "feed the texture a UV map directly (bake a Mapping node into the UVs)")
            return None
    w, h = int(img.size[0]), int(img.size[1])
    if w == 0 or h == 0:
        fail(f"{where}: {name} has no pixels (its file `{img.filepath}` is missing "
             f"or unreadable)\n  help: pack the image into the .blend or put it where the file says")
    if w > MAX_TEXTURE_SIDE or h > MAX_TEXTURE_SIDE:
        fail(f"{where}: {name} is {w}x{h} pixels, more than poser's "
             f"{MAX_TEXTURE_SIDE} a side\n  help: scale the image down")
    if node.extension == "CLIP":
        r.note(where, f"{name}: `Clip` extension (black outside the image) is imported as `Extend`")
    if node.interpolation != "Linear":
        r.note(where, f"{name}: `{node.interpolation}` interpolation becomes poser's bilinear lookup "
               "(at the mipmap level the cameras' sampling asks for)")
    return {"image": img, "uv_map": uv_map, "wrap": WRAPS.get(node.extension, "repeat")}


def write_texture(img, path):
    """The image's pixels as float32 RGB rows, Blender's first row (the image's bottom, v = 0)
    first; returns how the values are encoded: "srgb" (an 8-bit sRGB image's bytes / 255) or
    "linear"."""
    w, h = int(img.size[0]), int(img.size[1])
    px = np.empty(w * h * img.channels, dtype=np.float32)
    img.pixels.foreach_get(px)
    px = px.reshape(h, w, img.channels)
    rgb = np.empty((h, w, 3), dtype="<f4")
    if img.channels >= 3:
        rgb[...] = px[:, :, :3]
    else:  # grey (and alpha)
        rgb[...] = px[:, :, :1]
    srgb = not img.is_float and img.colorspace_settings.name.lower().startswith("srgb")
    with open(path + ".tmp", "wb") as f:
        f.write(rgb.tobytes())
    os.replace(path + ".tmp", path)
    return "srgb" if srgb else "linear"


def surface_of(mat, r, where):
    """('diffuse', albedo) | ('textured', (albedo, texture)) | ('glass', ior) |
    ('volume', coefficients) | ('skip', None)."""
    if mat is None:
        r.note(where, "has no material; imported with Blender's default grey (0.8)")
        return ("diffuse", [0.8] * 3)
    role = mat.get("poser_role")
    if role in ("glass", "housing"):
        return (role, None)
    nt = mat.node_tree
    if nt is None:
        return ("diffuse", [float(x) for x in mat.diffuse_color[:3]])
    out = output_node(nt)
    if out is None:
        return ("diffuse", [float(x) for x in mat.diffuse_color[:3]])
    surf = linked(out.inputs.get("Surface"))
    vol = linked(out.inputs.get("Volume"))
    if surf is None and vol is not None:
        v = volume_of(vol, r, where)
        return ("volume", v) if v is not None else ("skip", None)
    if surf is None:
        return ("skip", None)
    t = surf.bl_idname
    if t in ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction"):
        # A volume inside glass fills the object (`fill_of`).
        return ("glass", float(surf.inputs["IOR"].default_value))
    if vol is not None:
        r.note(where, "a volume inside a visible surface that is not glass is not imported",
               "a Glass or Refraction BSDF around a volume, or a volume alone, is a filled "
               "object (docs/import.md)")
    if t in ("ShaderNodeBsdfPrincipled", "ShaderNodeBsdfDiffuse"):
        key = "Base Color" if t == "ShaderNodeBsdfPrincipled" else "Color"
        inp = surf.inputs[key]
        src = linked(inp)
        tex = None
        if src is not None and src.bl_idname == "ShaderNodeTexImage" and src.image is not None:
            tex = None if r.poser_saved else image_texture(src, inp, r, where)
            albedo = image_mean(src.image)
            if tex is None:
                r.note(where, f"image texture `{src.image.name}` is imported as its mean colour",
                       "poser's objects take a pattern or a printed target instead")
        elif src is not None:
            albedo = colour_of(inp)
            r.note(where, f"`{key}` is driven by a `{src.bl_idname}` node; its unlinked value is used")
        else:
            albedo = colour_of(inp)
        if albedo is None:
            albedo = [0.8] * 3
        if t == "ShaderNodeBsdfPrincipled":
            extra = [k for k in ("Specular IOR Level", "Metallic", "Transmission Weight", "Coat Weight")
                     if k in surf.inputs and float(surf.inputs[k].default_value) > 0.0]
            msg = "Principled BSDF is imported as a Lambertian with its base colour"
            if extra:
                msg += f" ({', '.join(extra)} dropped)"
            r.note(where, msg, "poser's surfaces are diffuse")
        elif float(surf.inputs["Roughness"].default_value) > 0.0:
            r.note(where, "the Diffuse BSDF's roughness (Oren-Nayar) is dropped")
        if tex is not None:
            return ("textured", (albedo, tex))
        return ("diffuse", albedo)
    if t == "ShaderNodeEmission":
        r.note(where, "an emitting surface is not imported",
               "poser's lights are point, spot, area, ambient and the sun")
        return ("skip", None)
    r.note(where, f"surface shader `{t}` is not imported", "poser's surfaces are diffuse")
    return ("skip", None)


def corner_uvs(me, name, r, where):
    """The texture coordinates of every triangle corner (loop triangles' loops, in order) from
    the UV map `name`, or the one Cycles renders with; None (noted) when there is none."""
    layers = me.uv_layers
    layer = layers.get(name) if name else next((uv for uv in layers if uv.active_render), None)
    if layer is None:
        r.note(where, f"has no UV map{f' `{name}`' if name else ''} for its image texture; "
               "the image's mean colour is used")
        return None
    loops = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
    me.loop_triangles.foreach_get("loops", loops)
    uv = np.empty(len(me.loops) * 2, dtype=np.float32)
    layer.uv.foreach_get("vector", uv)
    uv = uv.reshape(-1, 2)[loops]
    if not np.all(np.isfinite(uv)):
        fail(f"{where}: UV map `{layer.name}` has a coordinate that is not a number")
    return uv


def write_ply(path, verts, tris, uv=None):
    """A binary PLY of triangles (double x y z; float u v when `uv` is given)."""
    tris = np.asarray(tris, dtype=np.int32).reshape(-1, 3)
    uv_props = "property float u\nproperty float v\n" if uv is not None else ""
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(verts)}\nproperty double x\nproperty double y\nproperty double z\n"
        f"{uv_props}"
        f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode("ascii")
    if uv is None:
        body = np.asarray(verts, dtype="<f8").tobytes()
    else:
        rows = np.zeros(len(verts), dtype=[("p", "<f8", 3), ("uv", "<f4", 2)])
        rows["p"], rows["uv"] = verts, uv
        body = rows.tobytes()
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"] = 3
    faces["i"] = tris
    with open(path + ".tmp", "wb") as f:
        f.write(head + body + faces.tobytes())
    os.replace(path + ".tmp", path)


def strip(name, prefix):
    return name[len(prefix):] if name.startswith(prefix) else name


def read(bpy, blend, work):
    prefs = bpy.context.preferences
    prefs.filepaths.use_scripts_auto_execute = False
    bpy.ops.wm.open_mainfile(filepath=blend, load_ui=False, use_scripts=False)
    r = Reader(bpy, work)
    scene = bpy.context.scene
    r.poser_saved = scene.get("poser_bounces") is not None
    rd = scene.render
    width = int(round(rd.resolution_x * rd.resolution_percentage / 100.0))
    height = int(round(rd.resolution_y * rd.resolution_percentage / 100.0))
    if abs(rd.pixel_aspect_x - rd.pixel_aspect_y) > 1e-6:
        r.note("scene", "non-square pixel aspect is imported as square")
    for text in bpy.data.texts:
        if text.use_module or text.name.endswith(".py"):
            r.note(f"text `{text.name}`", "a script in the file was not run and is not imported")

    # Cameras: poser's in their rig order, else the scene camera first, then by name.
    cams = [o for o in scene.objects if o.type == "CAMERA"]
    if not cams:
        fail(f"{blend}: no camera\n  help: a poser scene needs a camera")

    def order(o):
        p = o.data.get("poser_camera")
        if p is not None:
            return (0, int(p.get("index", 0)), o.name)
        return (1 if o == scene.camera else 2, 0, o.name)

    cams.sort(key=order)
    if scene.camera is not None and scene.camera in cams and cams[0].data.get("poser_camera") is None:
        cams.remove(scene.camera)
        cams.insert(0, scene.camera)

    # Frames: one pose per frame when the first camera moves, else one.
    f0, f1 = scene.frame_start, scene.frame_end
    if f1 - f0 + 1 > MAX_FRAMES:
        r.note("scene", f"frames {f0}..{f1}: only the first {MAX_FRAMES} are imported")
        f1 = f0 + MAX_FRAMES - 1
    frames = list(range(f0, f1 + 1))
    worlds = {}  # (camera index, frame index) -> world_from_camera (OpenCV axes)
    light_objs = [o for o in scene.objects if o.type == "LIGHT"]
    light_worlds = {}
    # Only transforms are read per frame: meshes leave the depsgraph meanwhile (poser's water
    # carries one shape key per pose, which would make every frame cost O(poses)).
    hidden = [o for o in scene.objects if o.type not in ("CAMERA", "LIGHT", "EMPTY") and not o.hide_viewport]
    for o in hidden:
        o.hide_viewport = True
    for fi, f in enumerate(frames):
        scene.frame_set(f)
        for ci, c in enumerate(cams):
            worlds[(ci, fi)] = r.world(c, fi) @ CV_TO_BLENDER
        if fi == 0:
            for lo in light_objs:
                light_worlds[lo.name] = r.world(lo, 0)
    moving = any(np.max(np.abs(worlds[(0, fi)] - worlds[(0, 0)])) > 0 for fi in range(len(frames)))
    rig_keys = None
    for o in [cams[0]] + list(_ancestors(cams[0])):
        if o.get("poser_keys") is not None:
            rig_keys = len(o["poser_keys"]) // 16
    if rig_keys is not None:
        n_frames = min(rig_keys, len(frames))
    else:
        n_frames = len(frames) if moving else 1
    for o in hidden:
        o.hide_viewport = False
    scene.frame_set(frames[0])
    poses = [worlds[(0, fi)] for fi in range(n_frames)]

    cameras = []
    for ci, c in enumerate(cams):
        rel = [np.linalg.inv(worlds[(0, fi)]) @ worlds[(ci, fi)] for fi in range(n_frames)]
        if ci > 0 and any(np.max(np.abs(m - rel[0])) > 1e-6 for m in rel):
            r.note(f"camera `{c.name}`", "moves relative to the first camera; not imported",
                   "poser's cameras form a rigid rig; import it on its own")
            continue
        cam = camera(r, c, width, height)
        if cam is None:
            continue
        cam["rig_from_camera"] = rel[0].tolist()
        cameras.append(cam)

    # Render settings.
    cy = scene.cycles
    b = [cy.diffuse_bounces, cy.volume_bounces]
    if len(set(b)) > 1:
        r.note("scene", f"Cycles diffuse ({b[0]}) and volume ({b[1]}) bounces differ; "
               "poser's render.bounces is the larger + 1")
    render = {"samples": int(cy.samples), "bounces": int(min(max(b), cy.max_bounces)) + 1}
    if scene.get("poser_bounces") is not None:
        render["bounces"] = int(scene["poser_bounces"])

    # Meshes, water, port glass, glass objects.
    meshes, water, glass = [], None, []
    cam_centres = [worlds[(ci, 0)][:3, 3] for ci in range(len(cams))]
    for o in scene.objects:
        if o.hide_render or o.type not in ("MESH", "CURVE", "SURFACE", "META", "FONT"):
            continue
        where = f"object `{o.name}`"
        mats = [s.material for s in o.material_slots] or [None]
        kind, value = surface_of(mats[0], r, where)
        tex = None
        if kind == "textured":
            kind, (value, tex) = "diffuse", value
        if len(mats) > 1 and kind == "diffuse":
            r.note(where, f"has {len(mats)} materials; the first is used for all faces")
        if kind == "housing":
            r.port_glass = True
            continue
        if kind == "volume" and o.name != "poser_water":
            f = volume_solid(r, o, value, cam_centres, bpy.context.evaluated_depsgraph_get(), where)
            if f is not None:
                glass.append(f)
                continue
        if kind == "volume" or o.name == "poser_water":
            water = water_of(r, o, mats, value, water, where)
            continue
        if kind == "glass":
            centre = np.array(o.matrix_world, dtype=float)[:3, 3]
            near = [cams[i].name for i, cc in enumerate(cam_centres) if np.linalg.norm(cc - centre) < 0.5]
            if near:
                r.port_glass = True
                r.note(where, f"glass at camera `{strip(near[0], 'camera:')}` is taken as its housing port and not imported",
                       "declare it as `[camera.port]` (type = \"flat\" or \"dome\", with its "
                       "thickness, radius and material) so that poser refracts through it exactly")
            else:
                g = glass_box(r, o, mats[0], bpy.context.evaluated_depsgraph_get(), where)
                if g is not None:
                    fill = fill_of(r, mats[0], where)
                    if fill is not None:
                        g["fill"] = fill
                    glass.append(g)
            continue
        if kind != "diffuse":
            continue
        depsgraph = bpy.context.evaluated_depsgraph_get()
        ev = o.evaluated_get(depsgraph)
        me = ev.to_mesh()
        try:
            me.calc_loop_triangles()
            n = len(me.vertices)
            if n == 0 or len(me.loop_triangles) == 0:
                continue
            co = np.empty(n * 3, dtype=np.float32)
            me.vertices.foreach_get("co", co)
            tris = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
            me.loop_triangles.foreach_get("vertices", tris)
            uv = None
            if tex is not None:
                uv = corner_uvs(me, tex["uv_map"], r, where)
                if uv is None:
                    tex = None
        finally:
            ev.to_mesh_clear()
        m = r.world(o, 0)
        local = co.reshape(-1, 3).astype(float)
        exact = o.get("poser_vertices")
        if exact is not None and len(exact) == local.size:
            local = r.shadow(o, "poser_vertices", local.ravel(), where).reshape(-1, 3)
        verts = local @ m[:3, :3].T + m[:3, 3]
        path = os.path.join(work, f"mesh_{len(meshes)}.ply")
        texture = None
        if tex is not None:
            # One vertex per distinct (vertex, texture coordinate) pair of the triangles' corners.
            keys = np.zeros(len(tris), dtype=[("i", "<i4"), ("u", "<f4"), ("v", "<f4")])
            keys["i"], keys["u"], keys["v"] = tris, uv[:, 0], uv[:, 1]
            uniq, inverse = np.unique(keys, return_inverse=True)
            verts, tris = verts[uniq["i"]], inverse.astype(np.int32).ravel()
            # glTF's and poser's v = 0 is the image's first row; Blender's the image's bottom.
            corner_uv = np.stack([uniq["u"], 1.0 - uniq["v"]], axis=1)
            tex_path = os.path.join(work, f"texture_{len(meshes)}.f32")
            img = tex["image"]
            texture = {"file": os.path.basename(tex_path), "name": img.name,
                       "width": int(img.size[0]), "height": int(img.size[1]),
                       "encoding": write_texture(img, tex_path), "wrap": tex["wrap"]}
            write_ply(path, verts, tris, corner_uv)
        else:
            write_ply(path, verts, tris)
        meshes.append({"name": strip(o.name, "object:"), "ply": os.path.basename(path),
                       "albedo": value, "triangles": int(len(tris) // 3), "texture": texture})

    world_out = world_light(r, scene)
    if world_out is not None and world_out[0] == "volume":
        water = water_of(r, None, [], world_out[1], water, "world")
        world_out = None

    lights = []
    for lo in light_objs:
        if lo.hide_render:
            continue
        found = light(r, lo, light_worlds[lo.name], cams[0], poses[0])
        if found is not None:
            lights.append(found)
    if world_out is not None:
        lights.append(world_out[1])

    if water is not None and scene.get("poser_bounces") is None and \
            min(cy.volume_bounces, cy.max_bounces) == 0:
        r.note("scene", "Cycles renders the water with 0 volume bounces (Blender's default): a "
               "path ends where it scatters in the volume (single scattering only), while poser "
               f"follows it up to render.bounces = {render['bounces']}, so the imported water is "
               "brighter",
               "raise Cycles' Volume bounces (Light Paths) to the Diffuse bounces to compare like "
               "with like")
    if r.edited:
        shown = sorted(set(r.edited))
        r.note("scene", "edited in Blender since poser saved it (float32 values used): "
               + ", ".join(shown[:8]) + (" …" if len(shown) > 8 else ""))
    return {
        "file": blend,
        "name": scene.name,
        "blender": bpy.app.version_string,
        "render": render,
        "poses": [p.tolist() for p in poses],
        "cameras": cameras,
        "lights": lights,
        "water": water,
        "meshes": meshes,
        "glass": glass,
        "port_glass": r.port_glass,
        "notes": r.notes,
    }


def glass_ior(mat):
    """The smooth, clear Glass or Refraction BSDF feeding `mat`'s surface: (IOR, None), or
    (None, why not)."""
    nt = mat.node_tree if mat is not None else None
    out = output_node(nt) if nt is not None else None
    surf = linked(out.inputs.get("Surface")) if out is not None else None
    if surf is None or surf.bl_idname not in ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction"):
        return None, "its glass is not a Glass or Refraction BSDF on the material's output"
    if linked(surf.inputs["IOR"]) is not None:
        return None, "its glass's IOR is driven by a node"
    rough = surf.inputs.get("Roughness")
    if rough is not None and (linked(rough) is not None or float(rough.default_value) > 1e-4):
        return None, "its glass is rough (poser's glass objects are smooth)"
    colour = surf.inputs.get("Color")
    if colour is not None and (linked(colour) is not None
                               or any(abs(float(c) - 1.0) > 1e-4 for c in colour.default_value[:3])):
        return None, "its glass is tinted (poser's glass objects are clear)"
    return float(surf.inputs["IOR"].default_value), None


def glass_box(r, o, mat, depsgraph, where):
    """A glass object away from the cameras, when its glass is smooth and clear: a box (every
    vertex at a corner of its bounding box in the object's frame, all eight corners used):
    {"name", "cube": world matrix of the cube [-1, 1]^3, row-major, "ior": Cycles' IOR
    (relative to the medium around it)}; or a sphere (every vertex, at least 32, at one
    distance from its bounding box's centre, the box a cube): {"name", "sphere": world matrix
    of the unit sphere, "ior", "vertices"}; else None, with a note."""
    help_ = ("poser imports smooth, clear boxes and spheres as glass objects (docs/scenes.md, "
             "\"Glass objects\")")
    ior, why = glass_ior(mat)
    if ior is None:
        r.note(where, f"this glass object is not imported: {why}", help_)
        return None
    solid = solid_of(r, o, depsgraph, where)
    if solid is None:
        r.note(where, "this glass object is not imported: its mesh is neither a box nor a sphere",
               help_)
        return None
    return {**solid, "ior": ior}


def solid_of(r, o, depsgraph, where):
    """The mesh of `o` as a box (every vertex at a corner of its bounding box in the object's
    frame, all eight corners used): {"name", "cube": world matrix of the cube [-1, 1]^3,
    row-major}; or as a sphere (every vertex, at least 32, at one distance from its bounding
    box's centre, the box a cube): {"name", "sphere": world matrix of the unit sphere,
    "vertices"}; else None."""
    ev = o.evaluated_get(depsgraph)
    me = ev.to_mesh()
    try:
        co = np.empty(len(me.vertices) * 3, dtype=np.float32)
        me.vertices.foreach_get("co", co)
    finally:
        ev.to_mesh_clear()
    local = co.reshape(-1, 3).astype(float)
    exact = o.get("poser_vertices")
    if exact is not None and len(exact) == local.size:
        local = r.shadow(o, "poser_vertices", local.ravel(), where).reshape(-1, 3)
    if len(local) < 8:
        return None
    lo, hi = local.min(axis=0), local.max(axis=0)
    ext = hi - lo
    tol = 1e-5 * max(1.0, float(np.max(np.abs(local))))
    at_lo, at_hi = np.abs(local - lo) <= tol, np.abs(local - hi) <= tol
    corners = {tuple(c) for c in at_hi.astype(int).tolist()}
    centre = 0.5 * (lo + hi)
    name = strip(o.name, "object:")
    if np.min(ext) > tol and np.all(at_lo | at_hi) and len(corners) == 8:
        cube = np.diag([0.5 * ext[0], 0.5 * ext[1], 0.5 * ext[2], 1.0])
        cube[:3, 3] = centre
        return {"name": name, "cube": (r.world(o, 0) @ cube).tolist()}
    radius = 0.5 * float(ext[0])
    dist = np.linalg.norm(local - centre, axis=1)
    if (len(local) >= 32 and radius > tol and np.all(np.abs(ext - 2.0 * radius) <= 2.0 * tol)
            and np.all(np.abs(dist - radius) <= tol)):
        ball = np.diag([radius, radius, radius, 1.0])
        ball[:3, 3] = centre
        return {"name": name, "sphere": (r.world(o, 0) @ ball).tolist(),
                "vertices": len(local)}
    return None


def fill_of(r, mat, where):
    """The volume inside a glass object's Glass BSDF (a filled object: a tank, a jar), as
    `water_of` reads a water (poser's exact values from the material's `poser_fill` when it
    saved them), or None."""
    nt = mat.node_tree if mat is not None else None
    out = output_node(nt) if nt is not None else None
    vol = linked(out.inputs.get("Volume")) if out is not None else None
    if vol is None:
        return None
    v = volume_of(vol, r, where)
    if v is None:
        return None
    holder = mat.get("poser_fill")
    out = coefficients(r, holder, v, where)
    if holder is not None and "ior" in holder:
        out["ior"] = [float(x) for x in holder["ior"]]
    return out


def volume_solid(r, o, value, cam_centres, depsgraph, where):
    """A volume alone on a box or sphere mesh that no camera is inside or above (a tank seen
    through its side, a jar): a filled object without refraction at its faces ("ior": 1, the
    index relative to what is around it, as Cycles' volume boundary has none), or None (the
    scene's water, `water_of`)."""
    if value is None:
        return None
    solid = solid_of(r, o, depsgraph, where)
    if solid is None:
        return None
    m = np.asarray(solid.get("cube") or solid.get("sphere"), dtype=float)
    inv = np.linalg.inv(m)
    corners = np.array([[x, y, z, 1.0] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    world = corners @ m.T
    lo, hi = world[:, :3].min(axis=0), world[:, :3].max(axis=0)
    for c in cam_centres:
        local = inv @ np.append(np.asarray(c, dtype=float), 1.0)
        inside = (np.all(np.abs(local[:3]) <= 1.0) if "cube" in solid
                  else float(np.linalg.norm(local[:3])) <= 1.0)
        above = c[2] >= hi[2] and np.all(c[:2] >= lo[:2]) and np.all(c[:2] <= hi[:2])
        if inside or above:
            return None
    return {**solid, "ior": 1.0, "fill": coefficients(r, None, value, where)}


def coefficients(r, holder, value, where):
    """{"absorption", "scattering", "g"[, "ff"]} of the volume `value` (`volume_of`), poser's
    exact values from `holder` where they agree with Blender's."""
    sa, ss, g = value
    out = {"absorption": r.shadow(holder, "absorption", sa, where).tolist(),
           "scattering": r.shadow(holder, "scattering", ss, where).tolist()}
    if isinstance(g, dict):
        out["ff"] = {"n": float(r.shadow(holder, "particle_index", g["n"], where)),
                     "backscatter": float(r.shadow(holder, "backscatter", g["backscatter"], where))}
        if holder is not None and "junge_slope" in holder:
            out["ff"]["mu"] = float(holder["junge_slope"])
        out["g"] = 0.0
    else:
        out["g"] = float(r.shadow(holder, "g", g, where))
    return out


def _ancestors(o):
    while o.parent is not None:
        o = o.parent
        yield o


def camera(r, c, width, height):
    d = c.data
    where = f"camera `{c.name}`"
    p = d.get("poser_camera")
    out = {"name": strip(strip(c.name, "camera:"), "camera_frame:"), "width": width, "height": height}
    if p is not None and "width" in p:
        out["width"], out["height"] = int(p["width"]), int(p["height"])
        if (out["width"], out["height"]) != (width, height):
            r.edited.append("resolution")
            out["width"], out["height"] = width, height
    W, H = out["width"], out["height"]
    if d.type == "CUSTOM":
        params = getattr(d, "cycles_custom", None)
        keys = ("fx", "fy", "cx", "cy")
        if params is None or any(k not in params for k in keys):
            r.note(where, "a custom (OSL) camera that is not poser's is not imported")
            return None
        for k in keys:
            out[k] = float(params[k])
        dist = {k: float(params[k]) for k in ("k1", "k2", "k3", "p1", "p2") if k in params}
        out["lens"] = ["rectilinear", "fisheye_equidistant", "fisheye_equisolid"][int(params.get("lens", 0))]
        if any(v != 0.0 for v in dist.values()):
            out["distortion"] = dist
    elif d.type == "PERSP":
        fit = d.sensor_fit
        if fit == "AUTO":
            fit_px, sensor = max(W, H), d.sensor_width
        elif fit == "HORIZONTAL":
            fit_px, sensor = W, d.sensor_width
        else:
            fit_px, sensor = H, d.sensor_height
        f = d.lens / sensor * fit_px
        out.update({"fx": f, "fy": f, "cx": W / 2.0 - d.shift_x * fit_px,
                    "cy": H / 2.0 + d.shift_y * fit_px, "lens": "rectilinear"})
    elif d.type == "PANO" and p is not None:
        out.update({"lens": str(p.get("lens", "rectilinear"))})
        for k in ("fx", "fy", "cx", "cy"):
            out[k] = float(p[k])
    else:
        r.note(where, f"a `{d.type}` camera is not imported", "poser's cameras are perspective")
        return None
    if p is not None:
        for k in ("fx", "fy", "cx", "cy"):
            out[k] = float(r.shadow(p, k, out[k], f"{where} {k}"))
        dist = out.get("distortion")
        if dist is not None:
            for k in dist:
                dist[k] = float(r.shadow(p, k, dist[k], f"{where} {k}"))
        if "lens" in p:
            out["lens"] = str(p["lens"])
    if d.clip_start > 0.100001 or d.clip_end < 100.0:  # beyond Blender's defaults
        r.note(where, f"clipping ({d.clip_start:g} to {d.clip_end:g} m) is not imported",
               "poser's cameras see every distance")
    if d.dof.use_dof:
        if d.dof.focus_object is not None:
            r.note(where, "the focus object is dropped; the focus distance is used")
        aperture = d.lens * 1e-3 / (2.0 * d.dof.aperture_fstop)  # m (Cycles: lens / 2 f-stop)
        focus = float(d.dof.focus_distance)
        pitch = 3.76e-6
        fl = out["fx"] * pitch
        if p is not None and "focal_length" in p and "f_number" in p:
            fl, n = float(p["focal_length"]), float(p["f_number"])
            focus = float(r.shadow(p, "focus_distance", focus, f"{where} focus"))
            out.update({"focal_length": fl, "f_number": n, "focus_distance": focus})
        else:
            out.update({"focal_length": fl, "f_number": fl / (2.0 * aperture), "focus_distance": focus})
    return out


def light(r, lo, m, cam0, rig0):
    d = lo.data
    where = f"light `{lo.name}`"
    p = d.get("poser_light")
    name = strip(lo.name, "light:")
    colour = np.asarray(d.color[:3], dtype=float)
    energy = float(d.energy)
    scale = np.asarray(p["scale"], dtype=float) if p is not None and "scale" in p else np.ones(3)
    pos = m[:3, 3]
    aim = -m[:3, 2] / np.linalg.norm(m[:3, 2])
    mounted = cam0 in list(_descendants_of_ancestors(lo)) if lo.parent is not None else False
    if p is not None and "mount" in p:
        mounted = p["mount"] == "rig"
    out = {"name": name}
    if d.type in ("POINT", "SPOT"):
        factor = 4.0 * math.pi
        vals = colour * energy / factor / scale
        out["intensity"] = r.shadow(p, "values", vals, where).tolist()
        out["type"] = "point" if d.type == "POINT" else "spot"
        if d.shadow_soft_size > 0.0:
            r.note(where, f"radius {d.shadow_soft_size:g} m is imported as a point")
        if d.type == "SPOT":
            out["beam_angle"] = float(r.shadow(p, "beam_angle", d.spot_size, where))
            out["aim"] = aim
            if d.spot_blend > 0.0:
                r.note(where, "the spot's blend (soft edge) is imported sharp", "poser's spots have a sharp edge")
    elif d.type == "AREA":
        if d.shape in ("SQUARE", "DISK"):
            w = h = float(d.size)
        else:
            w, h = float(d.size), float(d.size_y)
        if d.shape in ("DISK", "ELLIPSE"):
            r.note(where, f"a {d.shape.lower()} area light becomes the rectangle of its bounding size")
        w = float(r.shadow(p, "width", w, where))
        h = float(r.shadow(p, "height", h, where))
        sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
        if abs(sx - 1.0) > 1e-6 or abs(sy - 1.0) > 1e-6:
            w, h = w * sx, h * sy
        factor = math.pi * w * h if getattr(d, "normalize", True) else math.pi
        if not getattr(d, "normalize", True):
            r.note(where, "an area light without `normalize` is read as radiance = colour x power / pi")
        vals = colour * energy / factor / scale
        out.update({"type": "area", "width": w, "height": h, "aim": aim,
                    "radiance": r.shadow(p, "values", vals, where).tolist()})
    elif d.type == "SUN":
        vals = colour * energy / scale
        out.update({"type": "sun", "direction": aim,
                    "irradiance": r.shadow(p, "values", vals, where).tolist()})
        if d.angle > 1e-6 and not (p is not None and p.get("caustics")):
            r.note(where, f"the sun's angular diameter ({math.degrees(d.angle):.3g}°) is dropped")
        return out
    else:
        r.note(where, f"a `{d.type}` light is not imported")
        return None
    if mounted:
        inv = np.linalg.inv(rig0)
        out["mount"] = "rig"
        out["position"] = (inv[:3, :3] @ pos + inv[:3, 3]).tolist()
        if "aim" in out:
            out["aim"] = (inv[:3, :3] @ out["aim"]).tolist()
    else:
        out["mount"] = "world"
        out["position"] = pos.tolist()
        if "aim" in out:
            out["aim"] = out["aim"].tolist()
    return out


def _descendants_of_ancestors(lo):
    """Objects sharing an ancestor with `lo` (its rig)."""
    root = lo
    while root.parent is not None:
        root = root.parent
    stack = [root]
    while stack:
        o = stack.pop()
        yield o
        stack.extend(o.children)


def world_light(r, scene):
    w = scene.world
    if w is None:
        return None
    p = w.get("poser_light")
    nt = w.node_tree
    if nt is None:
        c = np.asarray(w.color[:3], dtype=float)
        vals = c
    else:
        out = output_node(nt)
        if out is None:
            return None
        vol = linked(out.inputs.get("Volume"))
        if vol is not None:
            v = volume_of(vol, r, "world")
            if v is not None:
                r.note("world", "the world volume is read as water everywhere")
                return ("volume", v)
        bg = linked(out.inputs.get("Surface"))
        if bg is None:
            return None
        if bg.bl_idname != "ShaderNodeBackground":
            r.note("world", f"a `{bg.bl_idname}` world is not imported", "poser's ambient light is uniform")
            return None
        if linked(bg.inputs["Color"]) is not None:
            r.note("world", "an environment texture is imported as uniform grey of strength x 0.5")
            c = np.full(3, 0.5)
        else:
            c = np.asarray(colour_of(bg.inputs["Color"]))
        vals = c * float(bg.inputs["Strength"].default_value)
    scale = np.asarray(p["scale"], dtype=float) if p is not None and "scale" in p else np.ones(3)
    vals = r.shadow(p, "values", vals / scale, "world")
    if not np.any(vals > 0):
        return None
    return ("light", {"name": str(p.get("name", "ambient")) if p is not None else "world",
                      "type": "ambient", "radiance": vals.tolist()})


def water_of(r, o, mats, value, water, where):
    if water is not None:
        r.note(where, "a second volume is not imported", "poser has one water")
        return water
    holder = None
    for m in mats:
        if m is not None and m.get("poser_water") is not None:
            holder = m["poser_water"]
    if value is None and holder is None:
        return water
    value = value if value is not None else ([0.0] * 3, [0.0] * 3, 0.0)
    out = {**coefficients(r, holder, value, where), "top": None, "ior": None}
    if holder is not None and "ior" in holder:
        out["ior"] = [float(x) for x in holder["ior"]]
    if holder is not None and "surface" in holder:
        out["surface"] = str(holder["surface"])
    if o is not None:
        m = np.array(o.matrix_world, dtype=float)
        bb = np.array([m[:3, :3] @ np.array(v[:]) + m[:3, 3] for v in o.bound_box])
        out["top"] = float(bb[:, 2].max())
        out["bounds"] = [bb.min(axis=0).tolist(), bb.max(axis=0).tolist()]
    return out


def _json_default(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    raise TypeError(type(x))


def main():
    if len(sys.argv) != 3:
        fail("usage: read_blend.py REQUEST.json RESULT.json")
    with open(sys.argv[1], encoding="utf-8") as f:
        req = json.load(f)
    try:
        import bpy
    except ImportError:
        fail("the `bpy` module is not available\n  help: run `backends/setup.sh`")
    blend = os.path.abspath(req["blend"])
    with open(blend, "rb") as f:
        magic = f.read(7)
    if magic not in (b"BLENDER",) and not magic.startswith(b"\x1f\x8b") and not magic.startswith(b"\x28\xb5\x2f\xfd"):
        fail(f"{req['blend']}: not a .blend file")
    try:
        result = read(bpy, blend, req["work"])
    except SystemExit:
        raise
    except Exception as e:  # noqa: BLE001 - reported to the user with the file
        fail(f"{req['blend']}: {type(e).__name__}: {e}")
    tmp = sys.argv[2] + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(result, f, default=_json_default)
    os.replace(tmp, sys.argv[2])


if __name__ == "__main__":
    main()
