"""Pure geometry and unit conversions for the Blender backend (no bpy; unit-testable).

Everything here works in the conventions of poser's resolved model: OpenCV camera frame
(x right, y down, z forward), metres, radians, 4x4 matrices as nested row-major lists.

| function | what it converts |
|---|---|
| `blender_intrinsics` | fx, cx, cy, W, H -> lens (mm), shift_x, shift_y for sensor_fit HORIZONTAL |
| `fisheye_params` | fx, W, lens model -> Cycles panoramic parameters |
| `light_power` | radiant intensity I (W/sr, per channel) -> Blender power P = 4 pi I and colour |
| `emitter_scale` | the n^2 correction (n_cam / n_water)^2 per channel for emitters in water |
| `housing_*` | closed housing shells and glass surfaces for flat, dome and cylinder ports |
"""

import math

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
# Camera rays (for sizing the housings)
# ------------------------------------------------------------------------------------------


def camera_ray(cam, u, v):
    """Unit ray direction in the camera frame through pixel position (u, v)."""
    x = (u - cam["cx"]) / cam["fx"]
    y = (v - cam["cy"]) / cam["fy"]
    lens = cam.get("lens", "rectilinear")
    if lens == "rectilinear":
        d = np.array([x, y, 1.0])
        return d / np.linalg.norm(d)
    r = math.hypot(x, y)
    if lens == "fisheye_equidistant":
        theta = r
    else:
        theta = 2.0 * math.asin(min(r / 2.0, 1.0))
    if r == 0.0:
        return np.array([0.0, 0.0, 1.0])
    s = math.sin(theta)
    return np.array([s * x / r, s * y / r, math.cos(theta)])


def border_rays(cam, n=8):
    """Ray directions through points along the image border (and the centre)."""
    w, h = cam["width"], cam["height"]
    pts = [(w / 2.0, h / 2.0)]
    for i in range(n + 1):
        t = i / n
        pts += [(t * w, 0.0), (t * w, h), (0.0, t * h), (w, t * h)]
    return [camera_ray(cam, u, v) for (u, v) in pts]


def max_field_angle(cam):
    return max(math.acos(max(-1.0, min(1.0, d[2]))) for d in border_rays(cam))


# ------------------------------------------------------------------------------------------
# Housings. Each builder returns two meshes in the OpenCV camera frame:
#   shell: closed surface around the camera, normals pointing OUT of the housing (into the
#          water); faces tagged 1 (outer glass face) or 2 (opaque housing body).
#   inner: the air->glass surface, normals pointing TOWARDS the camera (into the air).
# A mesh is a dict {verts: (N,3), faces: [tuple], tags: [int], normals: (N,3) or None}.
# ------------------------------------------------------------------------------------------

GLASS_OUTER = 1
BODY = 2


def _mesh(verts, faces, tags, normals=None):
    return {"verts": np.asarray(verts, dtype=float), "faces": faces, "tags": tags,
            "normals": None if normals is None else np.asarray(normals, dtype=float)}


def _basis(n):
    n = np.asarray(n, dtype=float)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = helper - helper.dot(n) * n
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    return u, v, n


def housing_flat(cam, port):
    """Flat port: glass slab between the planes n.x = d and n.x = d + t."""
    u, v, n = _basis(port["normal"])
    d, t = float(port["distance"]), float(port["thickness"])
    dd = d + 2.0 * t
    a_vals, b_vals = [0.0], [0.0]
    max_tilt = math.radians(80.0)
    for ray in border_rays(cam):
        c = ray.dot(n)
        if c < math.cos(max_tilt):
            # Clamp grazing rays to 80 degrees from the port normal.
            tang = ray - c * n
            tang /= max(np.linalg.norm(tang), 1e-12)
            ray = math.cos(max_tilt) * n + math.sin(max_tilt) * tang
            c = ray.dot(n)
        p = ray * dd / c
        a_vals.append(p.dot(u))
        b_vals.append(p.dot(v))
    span = max(max(a_vals) - min(a_vals), max(b_vals) - min(b_vals))
    margin = 0.1 * span + 2.0 * t + 1e-3
    a0, a1 = min(a_vals) - margin, max(a_vals) + margin
    b0, b1 = min(b_vals) - margin, max(b_vals) + margin
    back = -(0.5 * span + 0.02)

    def corner(a, b, h):
        return a * u + b * v + h * n

    def quad_ring(h):
        return [corner(a0, b0, h), corner(a1, b0, h), corner(a1, b1, h), corner(a0, b1, h)]

    # Shell: 8 corners; front (h = d + t) and back (h = back) rings.
    verts = quad_ring(d + t) + quad_ring(back)
    # Winding chosen so that normals point outwards (right-hand rule, u x v = n).
    faces = [(0, 1, 2, 3)]  # front face, normal +n
    tags = [GLASS_OUTER]
    faces.append((4, 7, 6, 5))  # back, normal -n
    tags.append(BODY)
    for i in range(4):
        j = (i + 1) % 4
        faces.append((i, i + 4, j + 4, j))
        tags.append(BODY)
    shell = _mesh(verts, faces, tags)
    inner = _mesh(quad_ring(d), [(0, 3, 2, 1)], [0])  # normal -n (towards the camera)
    return shell, inner


def _sphere_cap(center, radius, alpha, n_phi, n_theta, outward):
    """Spherical cap about +z, polar angle 0..alpha; returns verts, faces, normals, rim ids."""
    c = np.asarray(center, dtype=float)
    th = alpha * np.arange(1, n_theta + 1) / n_theta
    ph = 2.0 * math.pi * np.arange(n_phi) / n_phi
    t, p = np.meshgrid(th, ph, indexing="ij")
    dirs = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    normals = np.concatenate([[[0.0, 0.0, 1.0]], dirs.reshape(-1, 3)])
    verts = c + radius * normals
    j = np.arange(n_phi)
    k = (j + 1) % n_phi
    faces = [(0, 1 + a, 1 + b) for a, b in zip(j, k)]
    for i in range(1, n_theta):
        r0, r1 = 1 + (i - 1) * n_phi, 1 + i * n_phi
        faces += list(zip((r0 + j).tolist(), (r1 + j).tolist(), (r1 + k).tolist(),
                          (r0 + k).tolist()))
    if not outward:
        faces = [tuple(reversed(f)) for f in faces]
        normals = -normals
    rim = (1 + (n_theta - 1) * n_phi + j).tolist()
    return list(verts), faces, normals, rim


def housing_dome(cam, port, n_phi=384, n_theta=96):
    """Dome port: spherical caps of radii r and r + t about `center`, opening towards +z."""
    c = np.asarray(port["center"], dtype=float)
    r_in = float(port["inner_radius"])
    r_out = r_in + float(port["thickness"])
    alpha = min(max(max_field_angle(cam) + math.radians(15.0), math.radians(60.0)),
                math.radians(170.0))
    verts, faces, normals, rim = _sphere_cap(c, r_out, alpha, n_phi, n_theta, True)
    verts = list(verts)
    normals = list(normals)
    tags = [GLASS_OUTER] * len(faces)
    rim_z = c[2] + r_out * math.cos(alpha)
    rim_r = r_out * math.sin(alpha)
    back_z = min(rim_z, 0.0) - max(0.5 * r_out, 0.02)
    base = len(verts)
    for j in range(n_phi):
        ph = 2.0 * math.pi * j / n_phi
        verts.append(np.array([c[0] + rim_r * math.cos(ph), c[1] + rim_r * math.sin(ph), back_z]))
        normals.append(np.array([math.cos(ph), math.sin(ph), 0.0]))
    # Body: cylinder from the rim back to back_z, then a back disk (normal -z).
    for j in range(n_phi):
        k = (j + 1) % n_phi
        faces.append((rim[j], base + j, base + k, rim[k]))
        tags.append(BODY)
    faces.append(tuple(base + j for j in reversed(range(n_phi))))
    tags.append(BODY)
    shell = _mesh(verts, faces, tags, normals)
    iv, if_, inorm, _ = _sphere_cap(c, r_in, alpha, n_phi, n_theta, False)
    inner = _mesh(iv, if_, [0] * len(if_), inorm)
    return shell, inner


def housing_cylinder(cam, port, n_phi=512):
    """Cylindrical port: coaxial tubes of radii r and r + t about the port axis."""
    a = np.asarray(port["axis"], dtype=float)
    a = a / np.linalg.norm(a)
    p0 = np.asarray(port["axis_point"], dtype=float)
    r_in = float(port["inner_radius"])
    r_out = r_in + float(port["thickness"])
    # Centre the tube on the point of the axis nearest to the entrance pupil.
    centre = p0 + (-p0).dot(a) * a
    off = np.linalg.norm(-p0 - (-p0).dot(a) * a)
    worst = 0.0
    for ray in border_rays(cam):
        ca = min(abs(ray.dot(a)), math.cos(math.radians(10.0)))
        worst = max(worst, ca / math.sqrt(1.0 - ca * ca))
    half = (r_out + off) * worst * 1.3 + 2.0 * r_out
    u, v, _ = _basis(a)

    def ring(radius, h, sign):
        vs, ns = [], []
        for j in range(n_phi):
            ph = 2.0 * math.pi * j / n_phi
            radial = math.cos(ph) * u + math.sin(ph) * v
            vs.append(centre + radius * radial + h * a)
            ns.append(sign * radial)
        return vs, ns

    def tube(radius, outward):
        sign = 1.0 if outward else -1.0
        v0, n0 = ring(radius, -half, sign)
        v1, n1 = ring(radius, half, sign)
        faces = []
        for j in range(n_phi):
            k = (j + 1) % n_phi
            f = (j, k, n_phi + k, n_phi + j)  # outward for u x v = a
            faces.append(f if outward else tuple(reversed(f)))
        return v0 + v1, faces, n0 + n1

    sv, sf, sn = tube(r_out, True)
    tags = [GLASS_OUTER] * len(sf)
    sf.append(tuple(reversed(range(n_phi))))  # end cap at -half, normal -a
    tags.append(BODY)
    sf.append(tuple(n_phi + j for j in range(n_phi)))  # end cap at +half, normal +a
    tags.append(BODY)
    shell = _mesh(sv, sf, tags, sn)
    iv, ifc, inn = tube(r_in, False)
    inner = _mesh(iv, ifc, [0] * len(ifc), inn)
    return shell, inner


def housing(cam):
    """(shell, inner) for the camera's port, or None when it has no port."""
    port = cam["port"]
    kind = port["kind"]
    if kind == "none":
        return None
    if kind == "flat":
        return housing_flat(cam, port)
    if kind == "dome":
        return housing_dome(cam, port)
    if kind == "cylinder":
        return housing_cylinder(cam, port)
    raise ValueError(f"unknown port kind {kind!r}")


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
