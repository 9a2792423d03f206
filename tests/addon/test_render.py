"""Rendering: the Spectral Volume engine (F12), Render to Image, the render job, and the CLI."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.cli import command as cli
from addon.export.scene import export_scene
from addon.jobs.tracer_job import TracerJob
from addon.tracer import image_io
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from tests.addon.builders import basic_scene

bpy = pytest.importorskip("bpy")

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow  # the first render compiles the kernel unless cached (minutes: README.md)


def _reference(scene):
    return render(export_scene(bpy.context.evaluated_depsgraph_get()).scene).film


def test_f12_writes_combined_and_xyz_passes(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.filepath = str(tmp_path / "f12.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    channels = image_io.read_exr(tmp_path / "f12.exr")
    assert {"ViewLayer.XYZ.X", "ViewLayer.XYZ.Y", "ViewLayer.XYZ.Z", "ViewLayer.XYZ Variance.Y",
            "ViewLayer.Combined.R", "ViewLayer.Combined.A"} <= set(channels)
    film = _reference(scene)  # same scene and seed: the same image
    y = channels["ViewLayer.XYZ.Y"]
    assert y.shape == (12, 16) and y.max() > 0
    np.testing.assert_allclose(y, film.xyz[..., 1], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(channels["ViewLayer.Combined.R"], film.rgb()[..., 0], rtol=1e-4, atol=1e-6)
    assert channels["ViewLayer.Combined.A"].min() == 1.0


@pytest.mark.parametrize("crop", [False, True])
def test_f12_renders_the_render_region(registered, tmp_path, crop):
    """Blender keeps the full frame (empty outside the region) or crops it to the region: of 16 × 12
    pixels, x 5.28…12.32 → columns 5…11 and y 1.2…6.6 → rows 1…5 from the bottom (Blender truncates)."""
    scene, _cloud = basic_scene(tmp_path)
    render = scene.render
    render.engine = "SPECTRAL_VOLUME"
    render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    render.filepath = str(tmp_path / "region.exr")
    render.use_border, render.use_crop_to_border = True, crop
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.33, 0.77, 0.1, 0.55
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    channels = image_io.read_exr(tmp_path / "region.exr")
    alpha, y = channels["ViewLayer.Combined.A"], channels["ViewLayer.XYZ.Y"]
    if crop:
        assert alpha.shape == (5, 7) and alpha.min() == 1.0
    else:
        assert alpha.shape == (12, 16)
        inside = np.zeros((12, 16), dtype=bool)
        inside[12 - 6:12 - 1, 5:12] = True  # rows counted from the top
        assert (alpha[inside] == 1.0).all() and (alpha[~inside] == 0.0).all()
        y = y[inside]
    assert y.max() > 0


@pytest.mark.parametrize("crop", [False, True])
def test_render_to_image_and_the_cli_place_the_render_region_as_f12(registered, tmp_path, crop):
    """Crop off: the full frame with the region in place, empty (alpha 0) outside; crop on: the region
    alone. Before, Render to Image and the CLI wrote the region alone either way."""
    scene, _cloud = basic_scene(tmp_path)
    render = scene.render
    render.engine = "SPECTRAL_VOLUME"
    render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    render.filepath = str(tmp_path / "f12.exr")
    render.use_border, render.use_crop_to_border = True, crop
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.33, 0.77, 0.1, 0.55
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(tmp_path / "image.exr")) == {"FINISHED"}
    blend = tmp_path / "region.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = _run_cli("render", blend, "--out", tmp_path / "cli.exr", "--quiet")
    assert done.returncode == 0, done.stderr
    f12 = image_io.read_exr(tmp_path / "f12.exr")
    alpha = f12["ViewLayer.Combined.A"]
    assert alpha.shape == ((5, 7) if crop else (12, 16)) and alpha.min() == (1.0 if crop else 0.0)
    for written in ("image.exr", "cli.exr"):
        channels = image_io.read_exr(tmp_path / written)
        for name in ("ViewLayer.Combined.A", "ViewLayer.Combined.R", "ViewLayer.XYZ.Y", "ViewLayer.XYZ Variance.Z"):
            np.testing.assert_allclose(channels[name], f12[name], rtol=1e-4, atol=1e-6, err_msg=f"{written} {name}")
    image = bpy.data.images["Spectral"]
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(*alpha.shape, 4)[::-1]
    np.testing.assert_array_equal(pixels[..., 3], alpha)


def f12_fails_and_keeps_the_old_file(scene, tmp_path, match):
    """F12 with the Spectral Volume engine raises `match` and leaves the previous render's file as it was."""
    scene.render.engine = "SPECTRAL_VOLUME"
    output = tmp_path / "f12.exr"
    output.write_bytes(b"previous render")
    scene.render.filepath = str(output)
    with pytest.raises(RuntimeError, match=match):
        bpy.ops.render.render(write_still=True)
    assert output.read_bytes() == b"previous render"


def test_f12_with_bad_input_reports_and_keeps_the_old_file(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    cloud.data.filepath = str(tmp_path / "gone.vdb")
    f12_fails_and_keeps_the_old_file(scene, tmp_path, r"Volume 'Cloud': VDB file .*gone.vdb does not exist")


def test_render_to_image_fills_a_float_image_and_an_exr(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    exr = tmp_path / "out" / "render.exr"
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(exr)) == {"FINISHED"}
    image = bpy.data.images["Spectral"]
    assert image.is_float and tuple(image.size) == (16, 12) and image.colorspace_settings.name == "Linear Rec.709"
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(12, 16, 4)[::-1]
    film = _reference(scene)
    np.testing.assert_allclose(pixels[..., :3], film.rgb(), rtol=1e-4, atol=1e-6)
    channels = image_io.read_exr(exr)
    np.testing.assert_allclose(channels["ViewLayer.XYZ.Y"], film.xyz[..., 1], rtol=1e-4, atol=1e-6)


def _passes_blender_sees(path) -> list[str]:
    """The passes Blender finds in an EXR file: the outputs its compositor's Image node offers."""
    tree = bpy.data.node_groups.new("Passes", "CompositorNodeTree")
    node = tree.nodes.new("CompositorNodeImage")
    node.image = bpy.data.images.load(str(path))
    return [socket.name for socket in node.outputs if socket.enabled]


def test_render_to_image_names_its_exr_channels_as_f12(registered, tmp_path):
    """One naming: the same channels, in the view layer's name, and Blender opens both as the same passes
    (before, Render to Image's `spectral.X` and `variance.X` opened as passes "spectral" and "variance")."""
    scene, _cloud = basic_scene(tmp_path)
    scene.view_layers[0].name = "Front"
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.filepath = str(tmp_path / "f12.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(tmp_path / "image.exr")) == {"FINISHED"}
    f12, image = image_io.read_exr(tmp_path / "f12.exr"), image_io.read_exr(tmp_path / "image.exr")
    assert sorted(image) == sorted(f12)
    assert "Front.XYZ Variance.Z" in image and "Front.Combined.A" in image
    np.testing.assert_allclose(image["Front.XYZ.Y"], f12["Front.XYZ.Y"], rtol=1e-4, atol=1e-6)
    assert _passes_blender_sees(tmp_path / "image.exr") == _passes_blender_sees(tmp_path / "f12.exr") == [
        "Combined", "Alpha", "XYZ", "XYZ Variance"]


def test_failed_render_to_image_touches_nothing(registered, tmp_path):
    scene, cloud = basic_scene(tmp_path)
    image = bpy.data.images.new("Spectral", 4, 4, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.full(64, 0.25, dtype=np.float32))
    exr = tmp_path / "render.exr"
    exr.write_bytes(b"previous render")
    cloud.data.filepath = str(tmp_path / "gone.vdb")
    with pytest.raises(RuntimeError, match="Nothing rendered: Volume 'Cloud'"):
        bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(exr))
    assert tuple(image.size) == (4, 4) and set(image.pixels[:]) == {0.25}
    assert exr.read_bytes() == b"previous render"


def test_cancelled_job_leaves_no_result(registered, tmp_path):
    basic_scene(tmp_path)
    job = TracerJob(export_scene(bpy.context.evaluated_depsgraph_get()).scene)
    job.cancel()
    job.start()
    job._thread.join(timeout=300)
    assert not job.running and job.error is None and job.result.cancelled and not job.succeeded


def test_job_reports_progress_from_its_thread(registered, tmp_path):
    basic_scene(tmp_path)
    job = TracerJob(export_scene(bpy.context.evaluated_depsgraph_get()).scene)
    job.start()
    job._thread.join(timeout=300)
    assert job.succeeded and job.fraction == 1.0


@pytest.fixture
def compiling(monkeypatch):
    """The kernel "compiles" on every render: it says so, then renders as usual."""
    from addon.tracer.kernels import numba_cache

    def ready(dispatcher, prepare, cancel=None, notice=None):
        notice(numba_cache.compiling_message())
        prepare()
        return True

    monkeypatch.setattr(numba_cache, "ready", ready)


def test_job_says_when_the_kernel_compiles_until_rendering_starts(registered, tmp_path, compiling, monkeypatch):
    basic_scene(tmp_path)
    job = TracerJob(export_scene(bpy.context.evaluated_depsgraph_get()).scene)
    seen = []
    job.run(notice=lambda text: seen.append(job.message))
    assert len(seen) == 1 and seen[0].startswith("Compiling the kernel (")
    assert job.message is None and job.succeeded


def test_f12_stats_say_when_the_kernel_compiles_then_count_samples(registered, tmp_path, compiling, monkeypatch):
    from addon.engine.render_engine import SpectralVolumeEngine

    scene, _cloud = basic_scene(tmp_path)
    scene.render.engine = "SPECTRAL_VOLUME"
    lines = []
    show = SpectralVolumeEngine._show_stats
    monkeypatch.setattr(SpectralVolumeEngine, "_show_stats", lambda self, text: (lines.append(text), show(self, text)))
    assert bpy.ops.render.render() == {"FINISHED"}
    assert lines[0].startswith("Compiling the kernel (")
    assert lines[-1].startswith(f"{scene.spectral.samples}/{scene.spectral.samples} samples")


def test_cli_command_is_registered_and_removed(clean):
    import addon

    addon.register()
    assert cli._handle is not None
    addon.unregister()
    assert cli._handle is None


def _run_cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "addon.cli", *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, timeout=600, env=env)


def _save_blend(tmp_path):
    basic_scene(tmp_path)
    path = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def test_cli_renders_a_blend_to_exr(registered, tmp_path):
    blend = _save_blend(tmp_path)
    out = tmp_path / "cli.exr"
    done = _run_cli("render", blend, "--out", out, "--frame", 1, "--spp", 1, "--quiet")
    assert done.returncode == 0, done.stderr
    assert "wrote" in done.stdout
    channels = image_io.read_exr(out)
    assert channels["ViewLayer.XYZ.Y"].shape == (12, 16) and channels["ViewLayer.XYZ.Y"].max() > 0


def test_cli_reports_bad_input_and_keeps_the_output(registered, tmp_path):
    blend = _save_blend(tmp_path)
    (tmp_path / "cloud.vdb").unlink()
    out = tmp_path / "cli.exr"
    out.write_bytes(b"previous render")
    done = _run_cli("render", blend, "--out", out, "--quiet")
    assert done.returncode == 1
    assert "error: Volume 'Cloud': VDB file" in done.stderr and "Traceback" not in done.stderr
    assert out.read_bytes() == b"previous render"
    missing = _run_cli("render", tmp_path / "nowhere.blend", "--out", out)
    assert missing.returncode == 1 and "nowhere.blend does not exist" in missing.stderr
    assert _run_cli("draw").returncode == 2


def test_cli_device_overrides_the_scenes_and_a_missing_gpu_is_named(registered, tmp_path):
    """--device, as Cycles' --cycles-device: a file saved with Device ▸ GPU Compute renders on the CPU with
    `--device CPU`; on the GPU where no CUDA driver loads (one is pretended missing) it exits 1 naming what is
    missing and keeps the output, as `--device GPU` does with a file saved for the CPU."""
    scene, _cloud = basic_scene(tmp_path)
    scene.spectral.device = "GPU"
    blend = tmp_path / "gpu.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    out = tmp_path / "cli.exr"
    done = _run_cli("render", blend, "--out", out, "--device", "CPU", "--spp", 1, "--quiet")
    assert done.returncode == 0, done.stderr
    assert image_io.read_exr(out)["ViewLayer.XYZ.Y"].max() > 0
    out.write_bytes(b"previous render")
    no_driver = dict(os.environ, NUMBA_CUDA_DRIVER=str(tmp_path / "no-driver.so"))
    for device in ([], ["--device", "GPU"]):
        done = _run_cli("render", blend, "--out", out, *device, "--spp", 1, "--quiet", env=no_driver)
        assert done.returncode == 1 and "Traceback" not in done.stderr
        assert re.search(r"error: .*(No usable CUDA device|numba-cuda)", done.stderr), done.stderr
        assert out.read_bytes() == b"previous render"
    scene.spectral.device = "CPU"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = _run_cli("render", blend, "--out", out, "--device", "GPU", "--spp", 1, "--quiet", env=no_driver)
    assert done.returncode == 1 and "No usable CUDA device" in done.stderr
    assert "invalid choice" in _run_cli("render", blend, "--out", out, "--device", "OPTIX").stderr


def test_cli_renders_the_scene_it_is_asked_for(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    bpy.ops.scene.new(type="LINK_COPY")  # the same objects, its own resolution; it becomes the active scene
    wide = bpy.context.scene
    wide.name = "Wide"
    wide.render.resolution_x, wide.render.resolution_y = 20, 10
    bpy.context.window.scene = scene  # the file opens on the first scene
    blend = tmp_path / "two scenes.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    out = tmp_path / "wide.exr"
    done = _run_cli("render", blend, "--scene", "Wide", "--out", out, "--spp", 1, "--quiet")
    assert done.returncode == 0, done.stderr
    assert image_io.read_exr(out)["ViewLayer.XYZ.Y"].shape == (10, 20)
    with pytest.raises(SpectralError, match=r"has no scene 'Tall'; its scenes: 'Scene', 'Wide'"):
        cli.open_scene(blend, "Tall")


def test_unreachable_scheduler_is_reported_and_writes_nothing(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    scene.spectral.scheduler_address = "tcp://127.0.0.1:9"  # the discard port: nothing listens there
    f12_fails_and_keeps_the_old_file(scene, tmp_path, r"cannot reach the Dask scheduler at tcp://127.0.0.1:9")
    with pytest.raises(RuntimeError, match="Render failed, nothing written: cannot reach the Dask scheduler"):
        bpy.ops.spectral.render_image(image_name="Farm")
    assert "Farm" not in bpy.data.images


def test_f12_on_a_gpu_that_is_not_there_says_why_and_writes_nothing(registered, tmp_path, monkeypatch):
    """Device ▸ GPU Compute where no CUDA device is usable (CI's machines have no NVIDIA driver; on one with a GPU
    its absence is pretended): F12 and Render to Image stop with the backend's own message, naming what is
    missing, and touch nothing."""
    from addon.tracer.kernels import cuda_target

    if cuda_target.device_problem() is None:
        monkeypatch.setattr(cuda_target, "device_problem", lambda: "No usable CUDA device: (pretended by the test)")
    scene, _cloud = basic_scene(tmp_path)
    scene.spectral.device = "GPU"
    f12_fails_and_keeps_the_old_file(scene, tmp_path, r"No usable CUDA device|numba-cuda")
    with pytest.raises(RuntimeError, match=r"Render failed, nothing written: (No usable CUDA device|.*numba-cuda)"):
        bpy.ops.spectral.render_image(image_name="Gpu")
    assert "Gpu" not in bpy.data.images
