"""The Spectral EXR from Blender: the Render settings' option (View Layer ▸ Passes) writes it next to F12's render
output, the .blend command line's --spectral-exr writes it, a farm and the Cycles emulation say they leave it out, and
bad bins are named by their field. The tracer's spectral image itself is tests/tracer/test_spectral_film.py's."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from addon.export.scene import export_scene  # noqa: E402
from addon.tracer import colorimetry, image_io  # noqa: E402
from addon.tracer.errors import SpectralError  # noqa: E402
from addon.tracer.wavelengths import GRID  # noqa: E402
from tests.addon.test_data_passes import surfaces_scene  # noqa: E402


def spectral_channels(path) -> tuple[list[str], dict, object]:
    """The S0 channel names of a spectral EXR, its channels and its header."""
    oiio = image_io._open_image_io()
    image = oiio.ImageInput.open(str(path))
    spec = image.spec()
    image.close()
    return [name for name in spec.channelnames if name.startswith("S0.")], image_io.read_exr(path), spec


def xyz_of_bins(spectrum: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The XYZ of a spectral image: each bin's value times the integral of the tracer's XYZ weights over the bin."""
    weights = colorimetry.xyz_weights()
    per_bin = np.array([[np.trapezoid(weights[c, (GRID >= lo) & (GRID <= hi)], GRID[(GRID >= lo) & (GRID <= hi)])
                         for c in range(3)] for lo, hi in zip(edges[:-1], edges[1:])])
    return spectrum @ per_bin


def test_f12_writes_the_spectral_exr_next_to_the_render_output(registered, tmp_path):
    """F12 with Spectral EXR on (20 nm bins): `<output>_spectral.exr` beside the output path, its channels named by
    the bins' centres, relative units (the sun's spectral setting has a luminous strength), and its bins integrate to the XYZ pass's
    image mean Y within 5 standard errors of the per-pixel difference plus 2 % (the bins' discretisation and the
    380–780 nm range against the whole 360–830 nm)."""
    scene, _ = surfaces_scene()
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.spectral.spectral_exr, scene.spectral.spectral_exr_step = True, 20.0
    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    scene.render.filepath = str(tmp_path / "frames" / "f12.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    path = tmp_path / "frames" / "f12_spectral.exr"
    names, channels, spec = spectral_channels(path)
    assert names == [f"S0.{nm}nm" for nm in range(390, 780, 20)]
    assert spec.getattribute("spectralLayoutVersion") == "1.0"
    assert spec.getattribute("emissiveUnits") == "relative"
    assert {"R", "G", "B", "A"} <= set(channels)

    spectrum = np.stack([channels[name] for name in names], axis=2)
    from_bins = xyz_of_bins(spectrum, np.arange(380.0, 781.0, 20.0))[..., 1]
    rendered = image_io.read_exr(scene.render.filepath)["ViewLayer.XYZ.Y"]
    difference = (from_bins - rendered).ravel()
    error = difference.std(ddof=1) / np.sqrt(difference.size)
    assert rendered.mean() > 0 and spectrum.mean() > 0
    assert abs(difference.mean()) <= 5 * error + 0.02 * rendered.mean(), (difference.mean(), error, rendered.mean())


def test_render_to_image_writes_it_next_to_the_render_output_too(registered, tmp_path):
    scene, _ = surfaces_scene(8, 6)
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.spectral.spectral_exr = True
    scene.render.filepath = str(tmp_path / "still")
    assert bpy.ops.spectral.render_image(image_name="Spectral") == {"FINISHED"}
    names, channels, _ = spectral_channels(tmp_path / "still_spectral.exr")
    assert len(names) == 40 and channels[names[0]].shape == (6, 8)


def test_a_render_region_is_placed_in_the_full_frame_as_the_image_is(registered, tmp_path):
    """Render Region with Crop off: the spectral EXR is the full frame, the region's spectrum where the image has the
    region, zeros (alpha 0) around it, as Render to Image's EXR."""
    scene, _ = surfaces_scene(16, 12)
    render = scene.render
    render.engine = "SPECTRAL_VOLUME"
    scene.spectral.spectral_exr = True
    render.filepath = str(tmp_path / "region")
    render.use_border, render.use_crop_to_border = True, False
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.25, 0.75, 0.1, 0.6
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(tmp_path / "image.exr")) == {"FINISHED"}
    names, channels, _ = spectral_channels(tmp_path / "region_spectral.exr")
    image = image_io.read_exr(tmp_path / "image.exr")
    alpha = image["ViewLayer.Combined.A"]
    assert channels["A"].shape == alpha.shape == (12, 16)
    np.testing.assert_allclose(channels["A"], alpha, rtol=1e-6)
    outside = alpha == 0.0
    assert outside.any() and not outside.all()  # the region, and the frame around it
    spectrum = np.stack([channels[name] for name in names], axis=2)
    assert not spectrum[outside].any() and spectrum[~outside].mean() > 0


def test_the_blend_command_line_writes_the_spectral_exr(registered, tmp_path):
    """Frame placeholders as in --out; Blender's own sun (its Watts) and World are radiant, so the units are
    absolute."""
    from tests.addon.test_render import _run_cli

    scene, _ = surfaces_scene(8, 6)
    scene.render.engine = "SPECTRAL_VOLUME"
    bpy.data.lights["Sun"].spectral.enabled = False
    blend = tmp_path / "spectral.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = _run_cli("render", blend, "--out", tmp_path / "cli_#.exr", "--frame", 3, "--spectral-exr",
                    tmp_path / "cli_#_spectral.exr", "--quiet")
    assert done.returncode == 0, done.stderr
    names, channels, spec = spectral_channels(tmp_path / "cli_3_spectral.exr")
    assert len(names) == 40 and channels[names[20]].shape == (6, 8) and channels[names[20]].mean() > 0
    assert spec.getattribute("emissiveUnits") == "W.m^-2.sr^-1"
    done = _run_cli("render", blend, "--out", tmp_path / "other.exr", "--spectral-exr", tmp_path / "other.png")
    assert done.returncode == 1 and "other.png: the file is written as EXR" in done.stderr


@pytest.mark.parametrize("renderer", ["farm", "emulation"])
def test_a_farm_makes_the_spectral_image_and_the_emulation_says_it_writes_none(registered, renderer):
    from addon.jobs.kinds import render_job

    scene, _ = surfaces_scene()
    scene.spectral.spectral_exr = True
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    assert export.scene.settings.spectrum
    if renderer == "emulation":
        scene.spectral.renderer = "CYCLES"
    job = render_job(scene, export, scheduler="tcp://127.0.0.1:1" if renderer == "farm" else None)
    warned = any("does not make the spectral image yet: no Spectral EXR written" in w for w in job.warnings)
    if renderer == "farm":
        assert job.scene.settings.spectrum and not warned  # the farm's tasks sum the spectral bins too
    else:
        assert warned


def test_bad_bins_are_named_by_their_field(registered):
    scene, _ = surfaces_scene()
    scene.spectral.spectral_exr = True
    scene.spectral.spectral_exr_step = 7.0
    with pytest.raises(SpectralError, match=r"Spectral EXR Step \(View Layer ▸ Passes\): 380–780 nm is not a whole"):
        export_scene(bpy.context.evaluated_depsgraph_get())
    scene.spectral.spectral_exr_step, scene.spectral.lambda_min = 10.0, 400.0
    with pytest.raises(SpectralError, match=r"Spectral EXR Start \(View Layer ▸ Passes\)"):
        export_scene(bpy.context.evaluated_depsgraph_get())
