"""Tests of the Mitsuba render driver with the real mitsuba package (scalar_rgb)."""

import json

import numpy as np
import pytest

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <integrator type="path"/>
  <emitter type="constant"><rgb name="radiance" value="{r}, {g}, {b}"/></emitter>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="16"/><integer name="height" value="12"/>
      <string name="pixel_format" value="rgb"/><string name="component_format" value="float32"/>
      <rfilter type="box"/>
    </film>
  </sensor>
</scene>
"""


def write_scene(tmp_path, views):
    manifest = {"format": "poser-mitsuba/2", "scene": "t", "variant": "scalar_rgb", "exposure": 2.0,
                "unit": 1.0, "views": views}
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))


def test_combine_single_and_per_channel(driver):
    a = np.full((2, 3, 3), 1.0, np.float32)
    assert driver.combine_passes([a], [None]) is not None
    passes = [np.full((2, 3, 3), float(k + 1), np.float32) for k in range(3)]
    out = driver.combine_passes(passes, [0, 1, 2])
    assert out[0, 0].tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError):
        driver.combine_passes(passes, [0, None, 2])


def test_preview_is_srgb_with_exposure(driver):
    rgb = np.array([[[0.0, 0.0031308, 1.0], [0.5, 2.0, 0.214]]], np.float32)
    png = driver.to_preview(rgb, 1.0)
    assert png.dtype == np.uint8
    assert png[0, 0].tolist() == [0, 10, 255]
    assert png[0, 1, 1] == 255  # clipped
    assert png[0, 1, 2] == 127  # linear 0.214 is sRGB 0.4996
    assert driver.to_preview(rgb * 0.5, 2.0)[0, 1, 2] == 127


def test_select_views(driver):
    m = {"views": [{"pose": 0}, {"pose": 1}, {"pose": 2}]}
    assert driver.select_views(m, None) == m["views"]
    assert driver.select_views(m, [2, 0]) == [{"pose": 0}, {"pose": 2}]
    assert driver.parse_poses("1, 3") == [1, 3]
    assert driver.parse_poses(None) is None


def test_bad_manifest_is_a_clear_error(driver, tmp_path):
    (tmp_path / "manifest.json").write_text(json.dumps({"format": "other"}))
    with pytest.raises(ValueError, match="unknown format"):
        driver.load_manifest(tmp_path)


def test_render_single_and_dispersion_passes(driver, tmp_path):
    import mitsuba as mi

    (tmp_path / "one.xml").write_text(SCENE.format(r=0.25, g=0.5, b=0.75))
    for k, c in enumerate("rgb"):
        vals = [0.0, 0.0, 0.0]
        vals[k] = 0.1 * (k + 1)
        # Other channels are filled with garbage that must not leak into the combination.
        vals = [v if i == k else 9.0 for i, v in enumerate(vals)]
        (tmp_path / f"disp.{c}.xml").write_text(SCENE.format(r=vals[0], g=vals[1], b=vals[2]))
    views = [
        {"image": "one", "pose": 0, "camera": "c", "width": 16, "height": 12, "seed": 1, "spp": 4,
         "passes": [{"channel": None, "xml": "one.xml"}]},
        {"image": "disp", "pose": 1, "camera": "c", "width": 16, "height": 12, "seed": 2, "spp": 4,
         "passes": [{"channel": k, "xml": f"disp.{c}.xml"} for k, c in enumerate("rgb")]},
    ]
    write_scene(tmp_path, views)
    out = tmp_path / "out"
    lines = []
    written = driver.run(tmp_path, out, None, None, log=lambda s, flush=False: lines.append(s))
    assert [p.name for p in written] == ["one.exr", "disp.exr"]
    assert lines[0] == "progress 1 4 one"
    assert lines[-1] == "image disp.exr"
    mi.set_variant("scalar_rgb")
    one = np.array(mi.Bitmap(str(out / "one.exr")))
    # A constant environment seen by a pinhole: every pixel is exactly the radiance.
    np.testing.assert_allclose(one.reshape(-1, 3).mean(0), [0.25, 0.5, 0.75], rtol=1e-5)
    disp = np.array(mi.Bitmap(str(out / "disp.exr")))
    np.testing.assert_allclose(disp.reshape(-1, 3).mean(0), [0.1, 0.2, 0.3], rtol=1e-5)
    assert (out / "disp.png").exists()
    assert not list(out.glob(".*tmp*"))
    # Pose selection renders only that pose.
    out2 = tmp_path / "out2"
    driver.run(tmp_path, out2, [1], 2, log=lambda s, flush=False: None)
    assert sorted(p.name for p in out2.iterdir()) == ["disp.exr", "disp.png"]


def test_main_reports_errors(driver, tmp_path, capsys):
    assert driver.main(["--scene-dir", str(tmp_path), "--out", str(tmp_path / "o")]) == 1
    assert "error:" in capsys.readouterr().err


DEPTH_SCENE = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
  <integrator type="path"/>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="9"/><integer name="height" value="7"/></film>
  </sensor>
  <shape type="cube">
    <transform name="to_world"><scale x="5" y="5" z="0.05"/><translate z="0.5"/></transform>
    <bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="10"/><translate z="2"/></transform>
    <bsdf type="null"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="10"/><translate z="3"/></transform>
    <bsdf type="diffuse"/>
  </shape>
</scene>
"""


def test_depth_crosses_glass_and_null_surfaces(driver, tmp_path):
    """The depth ray goes through a glass slab (refracted) and a null surface to the diffuse
    plane at z = 3: camera-frame z is 3 in every pixel, to float32 precision."""
    import mitsuba as mi

    mi.set_variant(driver.VARIANT)
    xml = tmp_path / "d.xml"
    xml.write_text(DEPTH_SCENE)
    z = driver.depth_image(mi, xml, 1.0)
    assert z.shape == (7, 9)
    assert np.allclose(z, 3.0, atol=1e-5), z
    # The same document read as millimetres: 3 mm.
    assert np.allclose(driver.depth_image(mi, xml, 1000.0), 3e-3, atol=1e-8)
