"""Pure geometry and unit conversions for the Blender backend (no bpy; unit-testable).

Everything here works in the conventions of poser's resolved model: OpenCV camera frame
(x right, y down, z forward), metres, radians, 4x4 matrices as nested row-major lists.

| function | what it converts |
|---|---|
| `blender_intrinsics` | fx, cx, cy, W, H -> lens (mm), shift_x, shift_y for sensor_fit HORIZONTAL |
| `fisheye_params` | fx, W, lens model -> Cycles panoramic parameters |
| `light_power` | radiant intensity I (W/sr, per channel) -> Blender power P = 4 pi I and colour |
| `emitter_scale` | the n^2 correction (n_cam / n_water)^2 per channel for emitters in water |
| `read_ply` | a port housing's shell or inner glass face, from the PLY poser writes |
"""

import math
import struct

import numpy as np

SENSOR_WIDTH_MM = 36.0
# Blender's camera looks along local -Z with +Y up; OpenCV looks along +Z with +Y down.
CV_TO_BLENDER = np.diag([1.0, -1.0, -1.0, 1.0])


def mat4(rows):
    """A 4x4 numpy matrix from nested row-major lists."""
    m = np.asarray(rows, dtype=float)
    if m.shape != (4, 4):
        raise ValueError(f"expected a 4x4 matrix, got shape {m.shape}")
    return m


def blender_intrinsics(fx, fy, cx, cy, width, height):
    """Cycles perspective camera parameters reproducing OpenCV intrinsics exactly.

    sensor_fit = HORIZONTAL, sensor width 36 mm; shifts are in units of the image width (the
    fit dimension) for both axes; +shift_x moves the principal point left, +shift_y down
    (docs/render-conventions.md §1.2). Cycles has one focal length: fx must equal fy.
    """
    if abs(fx - fy) > 1e-9 * max(abs(fx), 1.0):
        raise ValueError(f"Cycles needs square pixels (fx = fy), got fx={fx} fy={fy}")
    return {
        "lens": fx * SENSOR_WIDTH_MM / width,
        "sensor_width": SENSOR_WIDTH_MM,
        "shift_x": (width / 2.0 - cx) / width,
        "shift_y": (cy - height / 2.0) / width,
    }


def blender_fstop(f_number, lens_mm, focal_length):
    """Blender f-stop giving the physical thin-lens aperture radius focal_length / (2 N).

    Cycles takes the aperture radius as lens / (2 f-stop) with `lens` in mm, and poser's
    `lens` is fx * 36 mm / W (a 36 mm wide virtual sensor), not the physical focal length:
    f-stop = N * lens[m] / focal_length. Without a focal length, N itself."""
    if not focal_length:
        return float(f_number)
    return float(f_number) * float(lens_mm) * 1e-3 / float(focal_length)


def fisheye_params(lens_model, fx, width, height):
    """Cycles panoramic camera parameters for a fisheye lens of focal length fx pixels.

    Equisolid (r = 2 f sin(theta/2)) uses Cycles' FISHEYE_EQUISOLID with f in mm on a sensor
    of 36 mm width; equidistant (r = f theta) uses FISHEYE_LENS_POLYNOMIAL with theta = r/f.
    """
    lens_mm = fx * SENSOR_WIDTH_MM / width
    if lens_model == "fisheye_equidistant":
        # Cycles' own FISHEYE_EQUIDISTANT stretches its circle over the whole (non-square)
        # frame; the lens polynomial theta = -k1 r (r in mm on the sensor) is exact instead.
        return {"panorama_type": "FISHEYE_LENS_POLYNOMIAL", "fisheye_fov": 2.0 * math.pi,
                "polynomial": [0.0, -1.0 / lens_mm, 0.0, 0.0, 0.0], "lens": lens_mm}
    if lens_model == "fisheye_equisolid":
        # Cycles clips at fisheye_fov; the full image diagonal must be inside it.
        r_max = 0.5 * math.hypot(width, height) / (2.0 * fx)
        fov = 4.0 * math.asin(min(r_max, 1.0)) if r_max < 1.0 else 2.0 * math.pi
        return {"panorama_type": "FISHEYE_EQUISOLID", "fisheye_fov": min(fov + 1e-3, 2 * math.pi),
                "fisheye_lens": lens_mm, "lens": lens_mm}
    raise ValueError(f"not a fisheye lens model: {lens_model!r}")


def emitter_scale(n_cam, n_water):
    """Per-channel factor (n_cam / n_water)^2 applied to every emitter located in water.

    Cycles does not apply the n^2 radiance law at refractive interfaces; Mitsuba (the
    radiometric reference) does. Scaling emitters in water by this factor makes Cycles agree
    (docs/render-conventions.md §3.4).
    """
    return [(n_cam[c] / n_water[c]) ** 2 for c in range(3)]


def light_power(per_channel, scale=(1.0, 1.0, 1.0), factor=1.0):
    """Split a per-channel quantity into Blender's (colour, scalar strength).

    `factor` converts the model's unit to Blender's (4 pi for W/sr -> W). Returns
    (color [3], strength); colour is normalised so that its largest component is 1.
    """
    v = [max(0.0, float(per_channel[c]) * float(scale[c])) for c in range(3)]
    m = max(v)
    if m <= 0.0:
        return [1.0, 1.0, 1.0], 0.0
    return [x / m for x in v], m * factor


def frame_looking_along(direction):
    """A 3x3 rotation whose local -Z axis is `direction` (Blender lights emit along -Z)."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    z = -d
    helper = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def compose(rotation, translation):
    m = np.eye(4)
    m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


# ------------------------------------------------------------------------------------------
# Housings. poser writes each camera's housing (crates/poser-optics, `housing_shell`) as two
# PLY files in the OpenCV camera frame (src/backend/blender/housing.rs):
#   shell: closed surface around the camera, normals pointing OUT of the housing (into the
#          water); faces tagged GLASS_OUTER (outer glass face) or BODY (opaque housing body).
#   inner: the air->glass surface (tag INNER), normals pointing TOWARDS the camera (into the air).
# A mesh is a dict {verts: (N,3), faces: [tuple], tags: [int], normals: (N,3) or None}.
# ------------------------------------------------------------------------------------------

INNER = 0
GLASS_OUTER = 1
BODY = 2

_PLY_VERTEX = ("property double x", "property double y", "property double z")
_PLY_NORMAL = ("property double nx", "property double ny", "property double nz")
_PLY_FACE = ("property list uint uint vertex_indices", "property uchar tag")


def _mesh(verts, faces, tags, normals=None):
    return {"verts": np.asarray(verts, dtype=float), "faces": faces, "tags": tags,
            "normals": None if normals is None else np.asarray(normals, dtype=float)}


def read_ply(path):
    """A housing mesh from poser's PLY (binary little-endian; vertices `double x y z` and
    optionally `double nx ny nz`; faces `list uint uint vertex_indices` and `uchar tag`). Any
    other layout is refused with ValueError."""
    with open(path, "rb") as f:
        data = f.read()
    marker = b"end_header\n"
    end = data.find(marker)
    if not data.startswith(b"ply\n") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    lines = [ln for ln in data[:end].decode("ascii", "replace").split("\n")
             if ln and not ln.startswith("comment")]

    def fail(why):
        raise ValueError(f"{path}: not a poser housing PLY ({why})")

    if lines[:2] != ["ply", "format binary_little_endian 1.0"]:
        fail("format")
    head = lines[2].split()
    if len(head) != 3 or head[:2] != ["element", "vertex"] or not head[2].isdigit():
        fail("vertex element")
    n_verts = int(head[2])
    props = tuple(lines[3:6])
    with_normals = tuple(lines[6:9]) == _PLY_NORMAL
    rest = lines[9:] if with_normals else lines[6:]
    if props != _PLY_VERTEX or len(rest) != 3:
        fail("vertex properties")
    face = rest[0].split()
    if face[:2] != ["element", "face"] or len(face) != 3 or not face[2].isdigit():
        fail("face element")
    if tuple(rest[1:]) != _PLY_FACE:
        fail("face properties")
    n_faces = int(face[2])
    width = 6 if with_normals else 3
    body = data[end + len(marker):]
    size = n_verts * width * 8
    if len(body) < size:
        fail("truncated vertices")
    vdata = np.frombuffer(body[:size], dtype="<f8").reshape(n_verts, width)
    faces, tags = [], []
    at = size
    for _ in range(n_faces):
        if at + 4 > len(body):
            fail("truncated faces")
        (count,) = struct.unpack_from("<I", body, at)
        if count < 3 or at + 4 + 4 * count + 1 > len(body):
            fail("bad face")
        idx = struct.unpack_from(f"<{count}I", body, at + 4)
        if max(idx) >= n_verts:
            fail("vertex index out of range")
        faces.append(idx)
        tags.append(body[at + 4 + 4 * count])
        at += 4 + 4 * count + 1
    if at != len(body):
        fail("trailing bytes")
    return _mesh(vdata[:, :3].copy(), faces, tags,
                 vdata[:, 3:].copy() if with_normals else None)


def transform_points(points, m):
    """Apply a 4x4 rigid transform to an (n, 3) array of points."""
    m = np.asarray(m, dtype=float)
    return np.asarray(points, dtype=float) @ m[:3, :3].T + m[:3, 3]


def transform_mesh(mesh, m):
    """Apply a 4x4 rigid transform to a mesh (normals rotated)."""
    m = np.asarray(m, dtype=float)
    verts = transform_points(mesh["verts"], m)
    normals = None if mesh["normals"] is None else mesh["normals"] @ m[:3, :3].T
    return {"verts": verts, "faces": mesh["faces"], "tags": mesh["tags"], "normals": normals}


def reverse_mesh(mesh):
    """Flip every face (and normal) of a mesh."""
    normals = None if mesh["normals"] is None else -mesh["normals"]
    return {"verts": mesh["verts"], "faces": [tuple(reversed(f)) for f in mesh["faces"]],
            "tags": mesh["tags"], "normals": normals}


def box_mesh(lo, hi, tag=0):
    """Axis-aligned box with outward normals; 24 vertices so that faces stay flat."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    verts, faces, normals = [], [], []
    for axis in range(3):
        for side in (0, 1):
            nrm = np.zeros(3)
            nrm[axis] = 1.0 if side else -1.0
            b, c = (axis + 1) % 3, (axis + 2) % 3
            quad = []
            for (sb, sc) in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = np.zeros(3)
                p[axis] = hi[axis] if side else lo[axis]
                p[b] = hi[b] if sb else lo[b]
                p[c] = hi[c] if sc else lo[c]
                quad.append(p)
            base = len(verts)
            verts += quad
            normals += [nrm] * 4
            f = (base, base + 1, base + 2, base + 3)  # b x c = axis -> +axis normal
            faces.append(f if side else tuple(reversed(f)))
    return _mesh(verts, faces, [tag] * 6, normals)


def submesh(mesh, tag):
    """The faces of `mesh` carrying `tag`, with only the vertices they use."""
    faces = [f for f, t in zip(mesh["faces"], mesh["tags"]) if t == tag]
    used = sorted({i for f in faces for i in f})
    remap = {old: new for new, old in enumerate(used)}
    normals = None if mesh["normals"] is None else mesh["normals"][used]
    return _mesh(mesh["verts"][used], [tuple(remap[i] for i in f) for f in faces],
                 [tag] * len(faces), normals)


def inflate(mesh, eps):
    """Move every vertex by `eps` along its outward normal (the given vertex normals, or the
    mean of the adjacent face normals)."""
    v = np.asarray(mesh["verts"], dtype=float)
    if mesh["normals"] is not None:
        n = np.asarray(mesh["normals"], dtype=float)
    else:
        n = np.zeros_like(v)
        for f in mesh["faces"]:
            fn = np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]])
            fn /= np.linalg.norm(fn)
            for i in f:
                n[i] += fn
        n /= np.linalg.norm(n, axis=1)[:, None]
    return {"verts": v + eps * n, "faces": mesh["faces"], "tags": mesh["tags"],
            "normals": mesh["normals"]}


def merge_meshes(meshes):
    """One mesh from several; faces of parts without vertex normals are marked flat."""
    verts, faces, tags, normals, smooth = [], [], [], [], []
    base = 0
    for m in meshes:
        verts.append(m["verts"])
        faces += [tuple(base + i for i in f) for f in m["faces"]]
        tags += list(m["tags"])
        nrm = m["normals"]
        smooth += [nrm is not None] * len(m["faces"])
        if nrm is None:
            nrm = np.full_like(m["verts"], np.nan)
        normals.append(nrm)
        base += len(m["verts"])
    return {"verts": np.concatenate(verts), "faces": faces, "tags": tags,
            "normals": np.concatenate(normals), "smooth": smooth}


def loop_normals(mesh):
    """Per-corner shading normals: the given vertex normal on smooth faces, the geometric face
    normal on flat ones (so that a flat port face is never bent by its neighbours)."""
    v = np.asarray(mesh["verts"], dtype=float)
    nrm = mesh.get("normals")
    smooth = mesh.get("smooth") or [nrm is not None] * len(mesh["faces"])
    out = []
    for f, sm in zip(mesh["faces"], smooth):
        if sm:
            out += [nrm[i] for i in f]
        else:
            fn = np.zeros(3)
            for i in range(1, len(f) - 1):
                fn += np.cross(v[f[i]] - v[f[0]], v[f[i + 1]] - v[f[0]])
            fn /= np.linalg.norm(fn)
            out += [fn] * len(f)
    return out


def srgb_encode(x):
    """Linear -> sRGB transfer function (IEC 61966-2-1), clipped to [0, 1]."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
