"""Building and rendering with the real bpy."""

import json
import math
import os

import bpy
import numpy as np
import pytest
from bpy_extras.object_utils import world_to_camera_view
from conftest import put_port
from mathutils import Vector
from poser_blender import builder as pbuild
from poser_blender import geometry as geo


def _fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy.context.scene


def test_camera_projects_like_opencv(scene_desc):
    scene = _fresh()
    built = pbuild.build(scene_desc, ".", scene)
    cam = scene_desc["cameras"][0]
    scene.camera = built.cameras[0]
    scene.render.resolution_x, scene.render.resolution_y = cam["width"], cam["height"]
    bpy.context.view_layer.update()
    pose = np.asarray(scene_desc["poses"][0]["world_from_rig"])
    for p_cam in ([0.3, -0.2, 2.0], [-0.5, 0.4, 3.0], [0.0, 0.0, 1.0]):
        world = pose[:3, :3] @ np.asarray(p_cam) + pose[:3, 3]
        ndc = world_to_camera_view(scene, built.cameras[0], Vector(world))
        u = ndc.x * cam["width"]
        v = (1.0 - ndc.y) * cam["height"]
        # u = fx X/Z + cx with pixel centres at +0.5 (COLMAP's convention; OpenCV's is -0.5).
        assert u == pytest.approx(cam["fx"] * p_cam[0] / p_cam[2] + cam["cx"], abs=1e-4)
        assert v == pytest.approx(cam["fy"] * p_cam[1] / p_cam[2] + cam["cy"], abs=1e-4)


@pytest.mark.parametrize("port", ["flat", "dome", "cylinder"])
def test_light_reflected_into_the_housing_ends_on_its_walls(scene_desc, housings, port):
    # HOUSING_INSIDE: whatever the port glass reflects back into the housing must meet the
    # black walls before the water's cut-out. On a dome the walls once lay exactly on the
    # cut-out's back, the water boundary won, and the reflected light reached the sky.
    put_port(scene_desc["cameras"][0], housings[port])
    scene = _fresh()
    pbuild.build(scene_desc, ".", scene)
    scene.frame_set(0)
    dg = bpy.context.evaluated_depsgraph_get()
    m = np.asarray(scene_desc["poses"][0]["world_from_rig"], dtype=float)
    origin = Vector(m[:3, 3])
    rng = np.random.default_rng(1)
    for _ in range(64):
        d = rng.normal(size=3)
        d[2] = -abs(d[2]) - 0.3  # backwards (camera -z) and sideways, camera frame
        d = m[:3, :3] @ (d / np.linalg.norm(d))
        hit, _, _, _, obj, _ = scene.ray_cast(dg, origin, Vector(d))
        assert hit and obj.name in ("housing:cam", "port inner:cam"), (
            f"a ray leaving the pupil backwards along {d} met {obj.name if hit else 'nothing'}")
        if obj.name == "housing:cam":
            # Strictly inside the cut-out, not coincident with it (a tie can go either way).
            walls = _first_hit(dg, obj, origin, d)
            water = _first_hit(dg, bpy.data.objects["poser_water"], origin, d)
            assert water - walls > 1e-5, f"walls at {walls} m, the cut-out at {water} m"


def _first_hit(dg, obj, origin, d):
    """Distance along world direction `d` from `origin` to `obj`'s first face."""
    ev = obj.evaluated_get(dg)
    inv = ev.matrix_world.inverted()
    o = inv @ origin
    dl = (inv.to_3x3() @ Vector(d)).normalized()
    hit, loc, _, _ = ev.ray_cast(o, dl)
    assert hit, f"{obj.name} not met"
    return (ev.matrix_world @ loc - origin).length


def test_the_sea_under_a_surface_has_black_sides_and_bottom(scene_desc):
    # SEA_WALLS: below a sea surface, light leaving Cycles' finite box sideways or downwards
    # must not see the sky (native's sea is unbounded); the top stays a volume boundary.
    scene_desc["surface"] = {"kind": "flat"}
    scene_desc["poses"] = [{**p, "world_from_rig": [r[:3] + [r[3] - (4.0 if i == 2 else 0.0)]
                                                    for i, r in enumerate(p["world_from_rig"])]}
                           for p in scene_desc["poses"]]
    pbuild.build(scene_desc, ".", _fresh())
    water = bpy.data.objects["poser_water"].data
    slots = [m.name for m in water.materials]
    by_normal = {}
    for poly in water.polygons[:6]:  # the box comes first, then the housing's cut-out
        by_normal[tuple(round(x) for x in poly.normal)] = slots[poly.material_index]
    assert by_normal[(0, 0, 1)] == "water boundary"
    for n in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, -1)]:
        assert by_normal[n] == "sea sides and bottom", n
    bsdf = [n for n in water.materials[pbuild.SEA_WALLS].node_tree.nodes
            if n.bl_idname == "ShaderNodeBsdfDiffuse"][0]
    assert tuple(bsdf.inputs["Color"].default_value)[:3] == (0.0, 0.0, 0.0)


def test_water_port_lights_and_poses_are_built(scene_desc):
    scene = _fresh()
    built = pbuild.build(scene_desc, ".", scene)
    n_g = scene_desc["cameras"][0]["port"]["glass"]["ior"][1]  # N-BK7, 550 nm
    water = bpy.data.objects["poser_water"]
    names = [m.name for m in water.data.materials]
    # The housing body is a pure volume boundary too (no housing shadow, HOUSING_SHADOW).
    assert names == ["water boundary", "water boundary", "water boundary", "sea sides and bottom"]
    nodes = {n.bl_idname: n for n in water.data.materials[1].node_tree.nodes}
    vol = nodes["ShaderNodeVolumeCoefficients"]
    assert tuple(vol.inputs["Absorption Coefficients"].default_value) == pytest.approx(
        (0.4, 0.1, 0.05))
    assert "ShaderNodeBsdfGlass" not in nodes, "the water boundary is a pure volume boundary"
    # Glass -> water face: IOR n_w/n_g (Cycles takes the ratio inside/outside per surface).
    outer = bpy.data.objects["port outer:cam"].data.materials[0].node_tree.nodes
    glass = [n for n in outer if n.bl_idname == "ShaderNodeBsdfGlass"][0]
    assert glass.inputs["IOR"].default_value == pytest.approx(1.334 / n_g, rel=1e-6)
    inner = bpy.data.objects["port inner:cam"].data.materials[0].node_tree.nodes
    glass = [n for n in inner if n.bl_idname == "ShaderNodeBsdfGlass"][0]
    assert glass.inputs["IOR"].default_value == pytest.approx(n_g, rel=1e-6)
    # One shape key per pose (+ basis) moves the housing cut-out with the rig.
    assert len(water.data.shape_keys.key_blocks) == 1 + len(scene_desc["poses"])
    # HOUSING_INSIDE: black walls inside the cut-out end the light the port reflects back into
    # the housing; shadow rays pass them (no housing shadow).
    body = bpy.data.objects["housing:cam"]
    assert not body.visible_shadow and body.parent == bpy.data.objects["port inner:cam"].parent
    bsdf = [n for n in body.data.materials[0].node_tree.nodes
            if n.bl_idname == "ShaderNodeBsdfDiffuse"][0]
    assert tuple(bsdf.inputs["Color"].default_value)[:3] == (0.0, 0.0, 0.0)
    assert len(body.data.polygons) == 5  # flat port: the back and four sides
    # n^2: the spot in water, seen from a camera in air, is scaled by (1/n_w)^2.
    k = geo.emitter_scale([1.0] * 3, [1.334] * 3)
    pbuild._apply_emitters(built, k)
    spot = bpy.data.lights["light:strobe"]
    assert spot.type == "SPOT" and spot.spot_blend == 0.0 and spot.shadow_soft_size == 0.0
    assert spot.spot_size == pytest.approx(1.0)
    assert spot.energy == pytest.approx(4.0 * math.pi * 2.0 / 1.334**2, rel=1e-6)
    assert tuple(spot.color) == pytest.approx((0.5, 1.0, 0.25))
    bg = scene.world.node_tree.nodes["Background"]
    assert bg.inputs["Strength"].default_value == pytest.approx(0.2 / 1.334**2, rel=1e-6)


def test_tiny_render_writes_linear_exr_and_srgb_png(scene_desc, tmp_path):
    # Air, ambient only, no objects: every pixel sees the sky radiance exactly.
    scene_desc["water"] = None
    scene_desc["objects"] = []
    scene_desc["lights"] = [scene_desc["lights"][1]]
    scene_desc["cameras"][0]["port"] = {"kind": "none"}
    scene = _fresh()
    built = pbuild.build(scene_desc, ".", scene)
    lines = []
    written = pbuild.render(built, str(tmp_path), poses=[1],
                            progress=lambda d, t, n: lines.append((d, t, n)))
    assert written == [os.path.join(str(tmp_path), "p1.exr")]
    assert lines == [(1, 1, "p1")]
    px = pbuild._load_pixels(written[0])
    assert px.shape == (24, 32, 4)
    assert np.abs(px[..., :3] - 0.2).max() < 1e-6
    png = pbuild._load_pixels(str(tmp_path / "p1.png"))
    want = round(255 * float(geo.srgb_encode(0.2))) / 255.0
    assert np.abs(png[..., :3] - want).max() < 1.5 / 255.0
    assert sorted(os.listdir(tmp_path)) == ["p1.exr", "p1.png"], "no temporary files left"


def test_description_is_checked():
    with pytest.raises(ValueError):
        pbuild.validate({"format": "something else"})
    with pytest.raises(ValueError):
        pbuild.validate(json.loads('{"format": "poser-blender/1", "cameras": [], "poses": []}'))


def test_arguments():
    opts = pbuild.parse_args(["--out", "o", "--samples", "8", "--poses", "0,2", "--no-png"])
    assert opts["out"] == "o" and opts["samples"] == 8 and opts["poses"] == [0, 2]
    assert not opts["png"] and opts["render"]
    assert pbuild.script_args(["blender", "-b", "-P", "s.py", "--", "--no-render"]) == [
        "--no-render"]
    assert pbuild.script_args(["/usr/bin/blender", "-b", "-P", "s.py"]) == []
    assert pbuild.script_args(["scene.py", "--samples", "4"]) == ["--samples", "4"]
    with pytest.raises(SystemExit):
        pbuild.parse_args(["--bogus"])


def _squares_facing_camera(angles_deg, size):
    """Black squares 2 m from the camera at field angles (theta, phi) in degrees, facing it;
    returns the objects and the angles in radians."""
    objs, dirs = [], []
    for k, (th, ph) in enumerate(angles_deg):
        th, ph = math.radians(th), math.radians(ph)
        d = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
        m = np.eye(4)
        m[:3, :3] = geo.frame_looking_along(d)
        m[:3, 3] = 2.0 * d
        objs.append({"name": f"sq{k}", "shape": {"type": "plane", "width": size, "height": size},
                     "scale": [1, 1, 1], "matrix": m.tolist(),
                     "material": {"albedo": [0, 0, 0], "pattern": None}})
        dirs.append((th, ph))
    return objs, dirs


def _white_sky_scene(name, camera, objs):
    """A one-camera, one-pose description: `objs` in air under a white ambient sky."""
    eye = np.eye(4).tolist()
    camera = dict(camera, name="c", rig_from_camera=eye, port={"kind": "none"})
    return {"format": "poser-blender/1", "name": name,
            "render": {"samples": 64, "seed": 1, "max_bounces": 2, "exposure": 1.0},
            "cameras": [camera],
            "poses": [{"name": "p", "world_from_rig": eye, "images": ["p"]}],
            "water": None, "surface": {"kind": "none"},
            "bounds": {"min": [-5] * 3, "max": [5] * 3}, "sun": None,
            "lights": [{"name": "sky", "mount": "world", "type": "ambient",
                        "radiance": [1, 1, 1]}],
            "objects": objs, "targets": []}


def _dark_centroid(w, u, v):
    """Darkness-weighted centroid (pixel centres at +0.5) in the 11x11 window about (u, v)."""
    i0, j0 = int(u) - 5, int(v) - 5
    jj, ii = np.mgrid[j0:j0 + 11, i0:i0 + 11]
    win = w[j0:j0 + 11, i0:i0 + 11]
    return (win * (ii + 0.5)).sum() / win.sum(), (win * (jj + 0.5)).sum() / win.sum()


@pytest.mark.parametrize("lens", ["fisheye_equidistant", "fisheye_equisolid"])
def test_fisheye_projects_like_the_lens_model(lens, tmp_path):
    # Small black squares facing the camera on a white sky, at field angles up to 70 degrees,
    # with an off-centre principal point; their centroids must land where the lens model
    # (r = f theta or r = 2 f sin(theta/2)) puts them.
    W, H, fx, cx, cy = 160, 120, 40.0, 86.3, 55.1
    objs, dirs = _squares_facing_camera([(0, 0), (30, 20), (55, 160), (70, -60), (45, -120)],
                                        0.06)
    desc = _white_sky_scene("fisheye", {"width": W, "height": H, "lens": lens, "fx": fx,
                                        "fy": fx, "cx": cx, "cy": cy}, objs)
    built = pbuild.build(desc, ".", _fresh())
    exr = pbuild.render(built, str(tmp_path), png=False)[0]
    w = np.clip(1.0 - pbuild._load_pixels(exr)[::-1, :, 1], 0.0, None)  # row 0 = top
    for th, ph in dirs:
        r = fx * th if lens == "fisheye_equidistant" else 2.0 * fx * math.sin(th / 2.0)
        u, v = cx + r * math.cos(ph), cy + r * math.sin(ph)
        mu, mv = _dark_centroid(w, u, v)
        # Measured <= 0.06 px; the 1.5 px^2 blobs carry ~0.03 px of 64-spp coverage noise and
        # the square's own fisheye distortion, so 0.15 px.
        assert abs(mu - u) < 0.15 and abs(mv - v) < 0.15, (lens, th, mu - u, mv - v)


def _distort(x, y, d):
    """Brown-Conrady (OpenCV), as crates/poser-optics/src/lens.rs `Lens::distort`."""
    r2 = x * x + y * y
    radial = 1.0 + r2 * (d["k1"] + r2 * (d["k2"] + r2 * d["k3"]))
    return (x * radial + 2.0 * d["p1"] * x * y + d["p2"] * (r2 + 2.0 * x * x),
            y * radial + d["p1"] * (r2 + 2.0 * y * y) + 2.0 * d["p2"] * x * y)


@pytest.mark.parametrize("lens", ["rectilinear", "fisheye_equidistant"])
def test_custom_camera_projects_with_distortion(lens, tmp_path):
    # poser's OSL camera (camera.osl): Brown-Conrady distortion and fx != fy. Small black
    # squares on a white sky must land where lens model + distortion put their centres.
    W, H, fx, fy, cx, cy = 160, 120, 110.0, 104.0, 86.3, 55.1
    dist = {"k1": -0.21, "k2": 0.05, "k3": -0.004, "p1": 0.0015, "p2": -0.001}
    objs, dirs = _squares_facing_camera([(0, 0), (20, 20), (30, 160), (33, -30), (25, -120)],
                                        0.04)
    desc = _white_sky_scene("distorted", {"width": W, "height": H, "lens": lens, "fx": fx,
                                          "fy": fy, "cx": cx, "cy": cy, "distortion": dist,
                                          "r2_max": None}, objs)
    built = pbuild.build(desc, ".", _fresh())
    data = built.cameras[0].data
    assert data.type == "CUSTOM" and data.custom_mode == "INTERNAL"
    assert data.custom_shader.name == "poser_camera.osl" and data.custom_bytecode
    assert data.cycles_custom["k1"] == pytest.approx(dist["k1"])
    assert data.cycles_custom["fy"] == pytest.approx(fy)
    assert built.scene.camera == built.cameras[0]
    exr = pbuild.render(built, str(tmp_path), png=False)[0]
    w = np.clip(1.0 - pbuild._load_pixels(exr)[::-1, :, 1], 0.0, None)  # row 0 = top
    errs = []
    for th, ph in dirs:
        r = math.tan(th) if lens == "rectilinear" else th
        xd, yd = _distort(r * math.cos(ph), r * math.sin(ph), dist)
        u, v = fx * xd + cx, fy * yd + cy
        mu, mv = _dark_centroid(w, u, v)
        errs.append((mu - u, mv - v))
    print(lens, "centroid errors (px):", errs)
    for eu, ev in errs:
        # The ~2 px^2 blobs carry ~0.03 px of 64-spp coverage noise, and the distortion
        # bends each square (its centroid is not exactly its centre's image): 0.15 px.
        assert abs(eu) < 0.15 and abs(ev) < 0.15, (lens, errs)


def test_every_feature_builds_and_renders(scene_desc, housings, tmp_path):
    # Two cameras (dome, cylinder), water in a box around them, waves with caustics and the
    # sun above, area + point lights, a checker pattern, per-channel passes, a saved .blend.
    d = scene_desc
    cam2 = json.loads(json.dumps(d["cameras"][0]))
    cam2["name"] = "right"
    cam2["rig_from_camera"] = [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    put_port(cam2, housings["cylinder"])
    put_port(d["cameras"][0], housings["dome"])
    d["cameras"].append(cam2)
    for p in d["poses"]:
        p["images"] = ["left_" + p["name"], "right_" + p["name"]]
    d["water"]["extent"] = {"kind": "box_around_camera", "half_size": [3.0, 3.0, 3.0]}
    d["water"]["scattering"] = [0.05, 0.05, 0.05]
    d["surface"] = {"kind": "waves", "height": 0.5, "wavelength": 4.0, "wind_speed": 5.0}
    # Two lattice waves of period 16 m (as poser's WaveField writes them): Hs = 4 sqrt(sum a^2/2).
    k = 2.0 * np.pi / 16.0
    d["wave_field"] = {"period": 16.0, "significant_height": 0.5, "max_abs_height": 0.25,
                       "components": [[4 * k, 0.0, 0.125, 0.3], [3 * k, 2 * k, 0.125, 1.1]]}
    d["caustics"] = True
    d["per_channel_passes"] = True
    d["sun"] = {"direction": [0.3, 0.1, -0.95], "irradiance": [900, 950, 1000],
                "in_water": False, "angle": 0.00935, "caustics": True}
    d["lights"].append({"name": "panel", "mount": "world", "type": "area",
                        "frame": [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 1.5], [0, 0, 0, 1]],
                        "width": 0.5, "height": 0.3, "radiance": [10, 10, 10]})
    d["lights"].append({"name": "bulb", "mount": "world", "type": "point",
                        "position": [0.5, 0.5, 1.0], "intensity": [3, 3, 3]})
    d["objects"][0]["material"]["pattern"] = {"type": "checker", "size": 0.2, "contrast": 0.3}
    d["render"]["samples"] = 2
    scene = _fresh()
    built = pbuild.build(d, ".", scene)
    # The sea surface: the given field, tiled on its lattice, the caustics caster; objects are
    # receivers.
    z = np.array([v.co.z for v in built.wave_mesh.vertices])
    assert abs(pbuild.significant_height([(0, 0, h) for h in z]) - 0.5) < 0.01
    assert len(built.wave_tiles) >= 1
    assert all(o.cycles.is_caustics_caster for o in built.wave_tiles)
    assert all(abs(o.location.x / 16.0 - round(o.location.x / 16.0)) < 1e-9
               for o in built.wave_tiles)
    assert bpy.data.objects["object:floor"].cycles.is_caustics_receiver
    assert bpy.data.lights["light:panel"].type == "AREA"
    written = pbuild.render(built, str(tmp_path), poses=[1])
    assert [os.path.basename(p) for p in written] == ["left_p1.exr", "right_p1.exr"]
    for p in written:
        px = pbuild._load_pixels(p)[..., :3]
        assert np.isfinite(px).all() and (px >= 0).all()
        assert px.max() > 0.0
    blend = tmp_path / "all.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), check_existing=False)
    assert blend.stat().st_size > 0


def test_water_cut_out_follows_the_rig_per_pose(scene_desc):
    # Pose 1 is 0.5 m east of pose 0: at frame 1 the housing cut-out of the water mesh (its
    # last vertices) must sit 0.5 m east of where it is at frame 0; the outer box stays.
    moved = [list(row) for row in scene_desc["poses"][0]["world_from_rig"]]
    moved[0][3] += 0.5
    scene_desc["poses"][1]["world_from_rig"] = moved
    scene = _fresh()
    pbuild.build(scene_desc, ".", scene)
    water = bpy.data.objects["poser_water"]

    def verts(frame):
        scene.frame_set(frame)
        dg = bpy.context.evaluated_depsgraph_get()
        me = water.evaluated_get(dg).data
        co = np.empty(len(me.vertices) * 3, dtype=np.float32)
        me.vertices.foreach_get("co", co)
        return co.reshape(-1, 3)

    v0, v1, v0b = verts(0), verts(1), verts(0)
    assert np.allclose(v1[-1] - v0[-1], [0.5, 0.0, 0.0], atol=1e-5)
    assert np.allclose(v1[:24], v0[:24]), "the scene-filling box does not move"
    assert np.allclose(v0b, v0)
    rig = bpy.data.objects["poser_rig"]
    scene.frame_set(1)
    assert rig.matrix_world.translation.x == pytest.approx(0.5)


def test_per_pose_water_vertices_are_the_whole_meshs(scene_desc):
    # The shape keys are built from the vertices alone (_water_verts); they must be the
    # vertices of the whole mesh (_water_mesh) of that pose, in its order.
    moved = [list(row) for row in scene_desc["poses"][0]["world_from_rig"]]
    moved[0][3] += 0.5
    moved[2][3] -= 0.25
    scene_desc["poses"][1]["world_from_rig"] = moved
    shells = [(ci, geo.inflate(geo.read_ply(cam["housing"]["shell"]), pbuild.WATER_GAP), None)
              for ci, cam in enumerate(scene_desc["cameras"])]
    assert any(s is not None for s in shells), "the fixture has a port"
    for i in range(len(scene_desc["poses"])):
        whole = pbuild._water_mesh(scene_desc, i, shells, [])["verts"]
        assert np.array_equal(pbuild._water_verts(scene_desc, i, shells, []), whole)


def test_depth_pass_is_camera_z_through_the_port(scene_desc, tmp_path):
    # Flat port, water, camera 2 m above the floor looking straight down: every pixel sees
    # the floor, at camera-frame z = 2 m, whatever the refraction does to the ray directions.
    scene_desc["render"]["outputs"] = ["rgb", "depth"]
    scene_desc["poses"] = scene_desc["poses"][:1]
    built = pbuild.build(scene_desc, ".", _fresh())
    pbuild.render(built, str(tmp_path), png=False)
    z = pbuild._load_pixels(str(tmp_path / "p0.depth.exr"))
    assert not (tmp_path / ".poser-tmp-0.depth.exr").exists()
    # float32 storage and Cycles' single-precision intersections: ~1e-6 relative; 1e-4 m
    # leaves room for the 0.005 px sample jitter (no depth gradient here).
    assert np.abs(z[..., :3] - 2.0).max() < 1e-4, z[..., 0].min()
    # The RGB image is unchanged by the depth render (lights restored): lit floor.
    rgb = pbuild._load_pixels(str(tmp_path / "p0.exr"))
    assert rgb[..., 1].mean() > 0.0


@pytest.mark.parametrize("camera", ["PERSP", "CUSTOM"])
def test_depth_of_field_is_the_physical_thin_lens(camera, tmp_path):
    # Thin lens with aperture radius A = f/(2N) focused at F (Mitsuba's `thinlens`): a black
    # square of side s px at depth z is blurred by a uniform disk of radius
    # R = fx A |z - F| / (z F) px, so its darkness has variance R^2/4 + s^2/12 per axis. Both
    # Blender cameras (PERSP with the converted f-stop, and poser's OSL camera) must give it.
    W = H = 64
    fx, cx, cy = 100.0, 32.3, 31.8
    f, n_stop, focus, z, side = 0.1, 1.0, 0.5, 2.0, 0.1
    eye = np.eye(4).tolist()
    m = np.eye(4)
    m[:3, :3] = geo.frame_looking_along([0.0, 0.0, 1.0])
    m[:3, 3] = [0.0, 0.0, z]
    dist = {"k1": 1e-12 if camera == "CUSTOM" else 0.0, "k2": 0.0, "k3": 0.0, "p1": 0.0,
            "p2": 0.0}
    desc = {"format": "poser-blender/1", "name": "dof",
            "render": {"samples": 256, "seed": 2, "max_bounces": 2, "exposure": 1.0},
            "cameras": [{"name": "c", "width": W, "height": H, "lens": "rectilinear",
                         "fx": fx, "fy": fx, "cx": cx, "cy": cy, "distortion": dist,
                         "r2_max": None, "focus_distance": focus, "f_number": n_stop,
                         "focal_length": f, "rig_from_camera": eye, "port": {"kind": "none"}}],
            "poses": [{"name": "p", "world_from_rig": eye, "images": ["p"]}],
            "water": None, "surface": {"kind": "none"},
            "bounds": {"min": [-5] * 3, "max": [5] * 3}, "sun": None,
            "lights": [{"name": "sky", "mount": "world", "type": "ambient",
                        "radiance": [1, 1, 1]}],
            "objects": [{"name": "sq", "shape": {"type": "plane", "width": side,
                                                 "height": side},
                         "scale": [1, 1, 1], "matrix": m.tolist(),
                         "material": {"albedo": [0, 0, 0], "pattern": None}}],
            "targets": []}
    built = pbuild.build(desc, ".", _fresh())
    assert built.cameras[0].data.type == camera
    exr = pbuild.render(built, str(tmp_path), png=False)[0]
    w = 1.0 - pbuild._load_pixels(exr)[::-1, :, 1].astype(float)  # row 0 = top
    jj, ii = np.mgrid[0:H, 0:W]
    sw = w.sum()
    mu, mv = (w * (ii + 0.5)).sum() / sw, (w * (jj + 0.5)).sum() / sw
    var = 0.5 * ((w * ((ii + 0.5 - mu) ** 2 + (jj + 0.5 - mv) ** 2)).sum() / sw)
    r = fx * f / (2.0 * n_stop) * abs(z - focus) / (z * focus)
    s = fx * side / z
    want = r * r / 4.0 + s * s / 12.0
    print(camera, "blur variance", var, "expected", want, "flux", sw, "vs", s * s)
    # 256 spp over ~200 blurred pixels: the variance estimate carries ~3 % noise; 10 %
    # still rejects the 36 mm-sensor aperture (variance x0.45 here) by far.
    assert var == pytest.approx(want, rel=0.10)
    assert sw == pytest.approx(s * s, rel=0.05)
    assert mu == pytest.approx(cx, abs=0.2) and mv == pytest.approx(cy, abs=0.2)


def test_build_sets_what_the_first_render_sets(scene_desc):
    # A saved .blend renders what poser renders: strengths (with the n^2 factor) and the seed
    # of image (pose 0, camera 0) are set by the build, not only by the render step.
    d = scene_desc
    d["poses"][0]["seeds"] = [1234]
    d["poses"][1]["seeds"] = [5678]
    scene = _fresh()
    built = pbuild.build(d, ".", scene)
    strobe = bpy.data.lights["light:strobe"]
    n = d["water"]["ior"][1]  # camera behind a port: n_cam = 1
    assert abs(strobe.energy - 4.0 * np.pi * 2.0 / n**2) < 1e-4
    bg = built.world_bg["node"].inputs["Strength"].default_value
    assert abs(bg - 0.2 / n**2) < 1e-6
    assert scene.cycles.seed == 1234
    pbuild.prepare_image(built, 1, 0)
    assert scene.cycles.seed == 5678
    # LIGHT_TREE: off in what is saved too (biased red with the sun, strobes and sky at once).
    assert not scene.cycles.use_light_tree
