"""The Denoise options: F12, Render to Image and the command line denoise the Combined image (never the XYZ
and variance passes); the render panel shows the options, greyed out where Open Image Denoise cannot load."""

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from addon.export.scene import export_scene
from addon.tracer import denoise, image_io
from addon.tracer.render import render
from tests.addon.builders import basic_scene, tiny_render
from tests.addon.recording import draw

bpy = pytest.importorskip("bpy")

ROOT = Path(__file__).resolve().parents[2]
NOT_HERE = "Open Image Denoise is not available on this platform (test)"
pytestmark = pytest.mark.slow  # the first render of a process compiles the kernel


def denoised_scene(tmp_path):
    """The basic cloud at 48×36 pixels and 4 samples, with Denoise on."""
    scene, _cloud = basic_scene(tmp_path)
    tiny_render(scene, 48, 36, samples=4)
    scene.spectral.denoise = True
    return scene


def raw_film(scene):
    """The raw film F12 renders (same scene, seed and samples)."""
    return render(export_scene(bpy.context.evaluated_depsgraph_get()).scene).film


def raw_and_converged(scene):
    """The raw film F12 renders and a converged render's RGB."""
    exported = export_scene(bpy.context.evaluated_depsgraph_get()).scene
    return render(exported).film, render(exported, spp=512, seed=12345).film.rgb()


def f12_exr(scene, tmp_path):
    """F12 with the scene written as a multilayer EXR: its channels, and its Combined RGB."""
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.filepath = str(tmp_path / "f12.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    channels = image_io.read_exr(tmp_path / "f12.exr")
    return channels, np.stack([channels[f"ViewLayer.Combined.{c}"] for c in "RGB"], axis=-1)


def rmse(image, reference):
    return float(np.sqrt(np.mean((image - reference) ** 2)))


def test_f12_denoises_combined_only(registered, tmp_path):
    scene = denoised_scene(tmp_path)
    channels, combined = f12_exr(scene, tmp_path)
    film, converged = raw_and_converged(scene)
    assert not np.allclose(combined, film.rgb(), rtol=1e-3, atol=1e-4)
    assert rmse(combined, converged) < 0.8 * rmse(film.rgb(), converged)
    np.testing.assert_allclose(combined, denoise.denoised_rgb(film), rtol=1e-3, atol=1e-5)
    np.testing.assert_allclose(channels["ViewLayer.XYZ.Y"], film.xyz[..., 1], rtol=1e-4, atol=1e-6)  # raw


def test_render_to_image_denoises_its_image_not_the_exr_passes(registered, tmp_path):
    scene = denoised_scene(tmp_path)
    exr = tmp_path / "render.exr"
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(exr)) == {"FINISHED"}
    pixels = np.array(bpy.data.images["Spectral"].pixels[:], dtype=np.float32).reshape(36, 48, 4)[::-1, :, :3]
    film, converged = raw_and_converged(scene)
    np.testing.assert_allclose(pixels, denoise.denoised_rgb(film), rtol=1e-4, atol=1e-6)
    assert rmse(pixels, converged) < 0.8 * rmse(film.rgb(), converged)
    channels = image_io.read_exr(exr)
    np.testing.assert_allclose(channels["ViewLayer.XYZ.Y"], film.xyz[..., 1], rtol=1e-4, atol=1e-6)


def test_without_oidn_f12_warns_and_writes_the_raw_image(registered, tmp_path, monkeypatch):
    monkeypatch.setattr(denoise, "_loaded", (None, NOT_HERE))
    scene = denoised_scene(tmp_path)
    _channels, combined = f12_exr(scene, tmp_path)
    np.testing.assert_allclose(combined, raw_film(scene).rgb(), rtol=1e-4, atol=1e-6)


def test_the_cli_denoises_its_png_and_combined(registered, tmp_path):
    scene = denoised_scene(tmp_path)
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    out = tmp_path / "cli.exr"
    done = subprocess.run([sys.executable, "-m", "addon.cli", "render", str(blend), "--out", str(out),
                           "--png", str(tmp_path / "cli.png"), "--frame", "1", "--quiet"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    channels = image_io.read_exr(out)
    combined = np.stack([channels[f"ViewLayer.Combined.{c}"] for c in "RGB"], axis=-1)
    film, converged = raw_and_converged(scene)
    np.testing.assert_allclose(combined, denoise.denoised_rgb(film), rtol=1e-3, atol=1e-5)
    assert (tmp_path / "cli.png").stat().st_size > 0


@pytest.mark.parametrize("loads", [True, False])
def test_the_render_panel_shows_denoise_greyed_where_oidn_cannot_load(registered, monkeypatch, loads):
    if not loads:
        monkeypatch.setattr(denoise, "_loaded", (None, NOT_HERE))
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    layout = draw(bpy.types.SPECTRAL_PT_render, SimpleNamespace(scene=scene, engine=scene.render.engine))
    settings = scene.spectral
    for name in ("denoise", "viewport_denoise"):
        assert layout.setting_before(layout.index("prop", settings, name), "enabled") is loads
    headings = [kwargs.get("heading", "") for call, _args, kwargs in layout.calls if call == "column"]
    assert any(("not available" in heading) != loads and heading.startswith("Denoise") for heading in headings)
