"""Extreme numbers (issue 30, item 3): light strengths bounded where read, with the bound and its reason;
vectors of any finite non-zero length normalised; integer settings bounded, and their values never change
the compiled kernel's argument types; no non-finite value ever reaches an output file."""

import dataclasses
import re

import numba
import numpy as np
import pytest

from addon.tracer import backends, image_io, lowering
from addon.tracer.errors import SpectralError
from addon.tracer.scene import DEPTH_MAX, SPP_MAX
from addon.tracer.validation import MAX_LIGHT_PEAK
from addon.tracer.scene_io import load_scene

LIGHTS = {
    "sun": {"kind": "sun", "spectrum": 1.0, "direction": [0, 0, 1]},
    "point": {"kind": "point", "spectrum": 1.0, "position": [0, 0, 2]},
    "environment": {"kind": "environment", "spectrum": 1.0},
    "sky horizon": {"kind": "sky", "spectrum": 1.0, "horizon_spectrum": {"type": "gaussian", "peak": 300,
                                                                         "width": 2}},
    "area": {"kind": "area", "spectrum": 1.0, "position": [0, 0, 2], "area_axes": [[1, 0, 0], [0, 1, 0],
                                                                                   [0, 0, 1]],
             "size_x": 1, "size_y": 1},
}


@pytest.mark.parametrize("strength", [1e300, 1e308, 1e19])
@pytest.mark.parametrize("kind", LIGHTS)
def test_an_overwhelming_light_is_refused_with_the_bound(write_scene, scene_data, kind, strength):
    """On main a sun of 1e308 vanished (its selection weight overflowed) and 1e300 put inf in the files."""
    scene_data["lights"] = [{**LIGHTS[kind], "strength": strength, "unit": "radiant"}]
    with pytest.raises(SpectralError, match=r"lights\[0\].strength: the light's spectrum × strength peaks at .* "
                                            f"more than the {re.escape(f'{MAX_LIGHT_PEAK:g}')} the tracer accepts .*float32"):
        load_scene(write_scene(scene_data))


def test_a_luminous_strength_on_a_nearly_invisible_spectrum_is_bounded_too(write_scene, scene_data):
    scene_data["lights"] = [{"kind": "sun", "spectrum": {"type": "gaussian", "peak": 362, "width": 2},
                             "direction": [0, 0, 1], "strength": 1e9}]
    with pytest.raises(SpectralError, match=r"lights\[0\].strength: .* peaks at"):
        load_scene(write_scene(scene_data))


def test_the_brightest_light_allowed_renders_finite_files(write_scene, scene_data, tmp_path):
    from addon.tracer import cli

    scene_data["lights"] = [{"kind": "sun", "spectrum": 1.0, "direction": [0, 0, 1], "unit": "radiant",
                             "strength": MAX_LIGHT_PEAK * 580 * 0.99},
                            {"kind": "point", "spectrum": 1.0, "position": [0, 0, 1e-3], "unit": "radiant",
                             "strength": MAX_LIGHT_PEAK * 580 * 0.99}]
    out = tmp_path / "bright.exr"
    code = cli.main(["render", str(write_scene(scene_data)), "--out", str(out), "--npy", str(tmp_path / "b.npy"),
                     "--spp", "4", "--quiet"])
    assert code == cli.EXIT_OK
    assert all(np.isfinite(channel).all() for channel in image_io.read_exr(out).values())
    assert np.isfinite(np.load(tmp_path / "b.npy")).all()


def test_no_file_holds_a_value_beyond_float32():
    xyz = np.ones((2, 3, 3))
    xyz[1, 2, 0] = 1e39  # finite in float64, inf in the file
    for output in (lambda: image_io.exr("a.exr", xyz, xyz), lambda: image_io.npy("a.npy", xyz),
                   lambda: image_io.png("a.png", xyz * np.nan)):
        with pytest.raises(SpectralError, match="NaN or beyond float32's range .* first at row"):
            output()


@pytest.mark.parametrize("length", [1e200, 1e-200, 1e307])
def test_a_direction_of_any_finite_non_zero_length_is_a_direction(write_scene, scene_data, length):
    """On main a direction of length 1e200 was refused as "zero length"."""
    scene_data["lights"] = [{"kind": "sun", "spectrum": 1.0, "direction": [0, length, length]},
                            {"kind": "spot", "spectrum": 1.0, "position": [0, 0, 3],
                             "spot_direction": [0, 0, -length]},
                            {"kind": "area", "spectrum": 1.0, "position": [0, 0, 2], "size_x": 1, "size_y": 1,
                             "area_axes": [[length, 0, 0], [0, length, 0], [0, 0, length]]}]
    scene = load_scene(write_scene(scene_data))
    np.testing.assert_allclose(scene.lights[0].direction, [0, 2**-0.5, 2**-0.5])
    kernel = lowering.compile_scene(scene).lights
    np.testing.assert_allclose(kernel.dir[:2], [[0, 2**-0.5, 2**-0.5], [0, 0, -1]])
    np.testing.assert_allclose(kernel.dir[2], [0, 0, -1])
    assert np.isfinite(kernel.pmf).all() and kernel.pmf.sum() == pytest.approx(1)


def test_light_choice_stays_a_distribution_when_every_light_weighs_nothing(write_scene, scene_data):
    scene_data["lights"] = [{"kind": "point", "spectrum": 1.0, "position": [1e200, 0, 0], "unit": "radiant"}]
    pmf = lowering.compile_scene(load_scene(write_scene(scene_data))).lights.pmf
    assert pmf.tolist() == [1.0]


def test_a_zero_direction_is_still_refused(write_scene, scene_data):
    scene_data["lights"][0]["direction"] = [0, 0, 0]
    with pytest.raises(SpectralError, match=r"lights\[0\].direction: a direction cannot have zero length"):
        load_scene(write_scene(scene_data))


@pytest.mark.parametrize(("field", "value", "bound"), [
    ("max_depth", 2**63, DEPTH_MAX), ("max_depth", 2**64, DEPTH_MAX), ("rr_depth", 2**63, DEPTH_MAX),
    ("spp", 2**40, SPP_MAX)])
def test_integer_settings_are_bounded(write_scene, scene_data, field, value, bound):
    """On main max_depth 2⁶³ compiled a second kernel for minutes and 2⁶⁴ was an internal error."""
    scene_data["render"][field] = value
    with pytest.raises(SpectralError, match=f"render.{field}: must be at most {bound}, found {value}"):
        load_scene(write_scene(scene_data))


def test_more_bands_than_whole_nanometres_are_refused_when_read(write_scene, scene_data):
    scene_data["render"].update(bands=2**64, lambda_min=400, lambda_max=700)
    with pytest.raises(SpectralError, match="render.bands: 400–700 nm can be split into 1 to 300 bands of whole "
                                            "nanometres, not 18446744073709551616"):
        load_scene(write_scene(scene_data))


def _kernel_types(scene, seed: int) -> tuple:
    kernel_scene = lowering.compile_scene(scene)
    return tuple(numba.typeof(argument) for argument in backends.tile_arguments(kernel_scene, 0, (0, 1),
                                                                                   (0, 0, 1, 1), seed))


def test_setting_values_never_change_the_kernels_argument_types(tiny_scene):
    """Each distinct tuple of argument types is one more kernel to compile (minutes)."""
    settings = tiny_scene.settings
    smallest = _kernel_types(dataclasses.replace(tiny_scene, settings=dataclasses.replace(
        settings, max_depth=1, rr_depth=0)), 0)
    largest = _kernel_types(dataclasses.replace(tiny_scene, settings=dataclasses.replace(
        settings, max_depth=DEPTH_MAX, rr_depth=DEPTH_MAX)), 2**64 - 1)
    assert smallest == largest


def test_an_unbounded_source_too_bright_for_float32_writes_nothing(write_scene, scene_data, tmp_path, capsys):
    """A glow is bounded only by the output check: its image cannot be stored, so no file is written."""
    from addon.tracer import cli

    scene_data["media"][0].update(extinction=0.0, glow={"spectrum": 1e300})
    scene_data["lights"] = []
    out = tmp_path / "glow.exr"
    out.write_bytes(b"previous render")
    code = cli.main(["render", str(write_scene(scene_data)), "--out", str(out), "--npy", str(tmp_path / "g.npy"),
                     "--quiet"])
    assert code == cli.EXIT_BAD_INPUT
    assert "values are NaN or beyond float32's range (3.4e38)" in capsys.readouterr().err
    assert out.read_bytes() == b"previous render" and not (tmp_path / "g.npy").exists()
