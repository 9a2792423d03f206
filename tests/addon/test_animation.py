"""Animation: each frame is exported from its own evaluated depsgraph, so keyframes and drivers on lights,
the World, materials, spectra and curve spectra render as animated in F12 animations and the CLI."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.jobs import tracer_job
from addon.props import curves
from addon.tracer import image_io, spectra
from tests.addon.builders import basic_scene

bpy = pytest.importorskip("bpy")

ROOT = Path(__file__).resolve().parents[2]


def _key(data, name, values):
    """Keyframe `data.name` to values[0] on frame 1, values[1] on frame 2, ..."""
    for frame, value in enumerate(values, start=1):
        setattr(data, name, value)
        data.keyframe_insert(name, frame=frame)


def _animated_scene(tmp_path):
    scene, cloud = basic_scene(tmp_path)
    sun = scene.objects["Sun"].data
    _key(sun, "energy", (1.0, 3.0))
    sun.spectral.spectrum.source = "BLACKBODY"
    _key(sun.spectral.spectrum, "temperature", (3000.0, 9000.0))
    settings = cloud.material_slots[0].material.spectral
    _key(settings, "density_scale", (1.0, 5.0))
    settings.albedo.source = "COLOR"
    _key(settings.albedo, "color", ((0.2, 0.4, 0.6), (0.6, 0.4, 0.2)))
    settings.extinction.source = "CURVE"  # creates the curve; the key below switches to it on frame 2
    _key(settings.extinction, "source", ("CONSTANT", "CURVE"))
    driver = settings.anisotropy.driver_add("value").driver
    driver.type, driver.expression = "SCRIPTED", "frame / 10"
    scene.world = bpy.data.worlds.new("World")
    scene.world.spectral.enabled = True
    _key(scene.world.spectral, "strength", (1.0, 2.0))
    scene.frame_start, scene.frame_end = 1, 2
    scene.frame_set(1)
    return scene, cloud


def test_f12_animation_exports_every_frame_from_its_depsgraph(registered, tmp_path, monkeypatch):
    scene, cloud = _animated_scene(tmp_path)
    curve = curves.sample(curves.find_mapping(cloud.material_slots[0].material.spectral.extinction.curve))
    exported = []
    monkeypatch.setattr(tracer_job, "render_tracer", lambda tracer_scene, *args, **kwargs: exported.append(tracer_scene))
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.filepath = str(tmp_path / "frame_")
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}
    assert len(exported) == 2
    for frame, tracer_scene in enumerate(exported, start=1):
        sun, world = tracer_scene.lights
        (medium,) = tracer_scene.media
        assert sun.strength == pytest.approx((1.0, 3.0)[frame - 1])
        np.testing.assert_allclose(sun.spectrum.values, spectra.blackbody((3000.0, 9000.0)[frame - 1]).values)
        assert world.strength == pytest.approx(frame)
        assert medium.density_scale == pytest.approx((1.0, 5.0)[frame - 1])
        color = tuple(np.float32(((0.2, 0.4, 0.6), (0.6, 0.4, 0.2))[frame - 1]).tolist())  # as Blender stores it
        np.testing.assert_allclose(medium.albedo_table[0], spectra.from_rgb(color).values, atol=1e-6)
        np.testing.assert_allclose(medium.anisotropy.values, frame / 10, rtol=1e-6)
        extinction = spectra.constant(1.0).values if frame == 1 else curve
        np.testing.assert_allclose(medium.extinction.values, extinction, atol=1e-6)
    assert scene.objects["Sun"].data.energy == 1.0  # the original data keep frame 1's values


def _sun_keyed_scene(tmp_path):
    """The basic scene (no World) with its sun's Power keyed 1 → 3 over frames 1–2."""
    scene, _cloud = basic_scene(tmp_path)
    _key(scene.objects["Sun"].data, "energy", (1.0, 3.0))
    scene.frame_start, scene.frame_end = 1, 2
    scene.frame_set(1)
    return scene


def _brightness_ratio(frame1, frame2) -> float:
    """Frame 2's total Y over frame 1's. The sun is the only light and both frames use the same seed, so the
    paths are the same and the ratio is the Power's, 3, up to rounding: the bounds [2.97, 3.03] are loose."""
    return float(frame2.sum() / frame1.sum())


@pytest.mark.slow
def test_f12_animation_renders_the_animated_sun(registered, tmp_path):
    scene = _sun_keyed_scene(tmp_path)
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.filepath = str(tmp_path / "frame_")
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}
    y1, y2 = (image_io.read_exr(tmp_path / f"frame_{frame:04d}.exr")["ViewLayer.XYZ.Y"] for frame in (1, 2))
    assert 2.97 < _brightness_ratio(y1, y2) < 3.03


@pytest.mark.slow
def test_cli_renders_the_animated_sun_of_each_frame(registered, tmp_path):
    _sun_keyed_scene(tmp_path)
    blend = tmp_path / "animated.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = subprocess.run([sys.executable, "-m", "addon.cli", "render", blend, "--out", tmp_path / "#.exr",
                           "--frames", "1-2", "--quiet"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    y1, y2 = (image_io.read_exr(tmp_path / f"{frame}.exr")["ViewLayer.XYZ.Y"] for frame in (1, 2))
    assert 2.97 < _brightness_ratio(y1, y2) < 3.03
