"""Light passes (`light_passes`, `kernels/light_split.py`) and Light Paths ▸ Clamping: the passes sum to Combined,
closed forms of what goes where, and the clamp scaling a sample's part to its limit. On the NumPy backend, and on the
Numba kernel where it matters that it does no extra work (tests/tracer/kernels/test_backends.py holds the two
kernels to each other path by path with light passes and clamping on)."""

import dataclasses

import numpy as np
import pytest

from addon.tracer import colorimetry
from addon.tracer.errors import SpectralError
from addon.tracer.kernels.light_split import (
    CATEGORIES, DIFFUSE_DIRECT, DIFFUSE_INDIRECT, EMISSION, ENVIRONMENT, VOLUME_DIRECT, VOLUME_INDIRECT)
from addon.tracer.light_passes import LIGHT_PASSES, light_rgb
from addon.tracer.render import band_scenes, render, render_unit
from addon.tracer.scene import BlackbodyEmission
from addon.tracer.validation import check_settings
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s

PASSES = tuple(LIGHT_PASSES)


def everything(**settings):
    """A medium, a floor, an emissive lamp the camera sees, a finite sun and an environment (seen past the floor's
    corners): light of every category."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.5, 0.5), albedo=0.9, g=0.3)
    floor = s.parallelogram((-3.0, -3.0, -0.4), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, reflectance=0.6, name="floor")
    lamp = s.parallelogram((-1.5, 1.5, 1.6), (1.5, 0.0, 0.0), (0.0, -3.0, 0.4), 1, reflectance=0.3,
                           emission=s.smooth_ramp(1.0, 3.0), name="lamp")
    lights = [s.sun([0.3, 0.2, 1.0], 2.0, angle=0.2), s.environment(0.4)]
    return s.scene(s.perspective_camera(10, 10, fov_degrees=60.0), [medium], lights, [floor, lamp], **settings)


def slab(thickness, **settings):
    """A wide grey slab (extinction 0.5, albedo 0.9, g 0.3) seen from above under a delta sun, nothing else."""
    grid = s.box_grid(cells=(8, 8, 2), size=(6.0, 6.0, thickness))
    medium = s.medium(grid, extinction=0.5, albedo=0.9, g=0.3)
    return s.scene(s.ortho_camera(4, 4, scale=1.0), [medium], [s.sun([0.3, 0.2, 1.0], 2.0)], **settings)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_light_categories_sum_to_combined(backend):
    """Emission + Environment + Volume Direct + Volume Indirect + the surface-first light (Diffuse Direct and
    Indirect × colour) = Combined per pixel, within float error; every category holds light here, and the passes
    asked for are the categories' images."""
    result = render(everything(passes=PASSES), spp=16, seed=1, backend=backend)
    film = result.film
    categories = light_rgb(film)
    combined = film.rgb()
    np.testing.assert_allclose(categories.sum(axis=2), combined, rtol=1e-9, atol=1e-12 * np.abs(combined).max())
    for slot in range(CATEGORIES):
        assert categories[..., slot, :].mean() > 0.0, f"category {slot} is empty"
    assert sorted(result.passes.images) == sorted(PASSES)
    for name, slot in LIGHT_PASSES.items():
        np.testing.assert_array_equal(result.passes.images[name], categories[..., slot, :])


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_no_clamping_and_no_passes_leave_the_image_exactly(backend):
    """Light passes on (the paths take their marks) and clamping off, or limits no sample reaches, give exactly the
    image of a render without either (same seed: the same paths, the same sums)."""
    plain = render(everything(), spp=8, seed=3, backend=backend).film
    for settings in ({"passes": PASSES}, {"clamp_direct": 0.0, "clamp_indirect": 0.0},
                     {"passes": PASSES, "clamp_direct": 1e300, "clamp_indirect": 1e300}):
        film = render(everything(**settings), spp=8, seed=3, backend=backend).film
        np.testing.assert_array_equal(film.sum_xyz, plain.sum_xyz)
        np.testing.assert_array_equal(film.sum_sq, plain.sum_sq)


def test_an_emitting_absorbing_medium_is_emission_and_environment():
    """A hot medium that only absorbs (albedo 0) in front of a uniform environment: no path scatters, so Volume
    Direct and Indirect are exactly 0, Emission + Environment = Combined, and the Environment is the background
    seen through the medium, Y_env·e^(−τ) along the orthographic camera's rays through the box (τ = 0.5 × 2):
    within 4 binomial standard errors of that fraction over the 64 × 64 paths (delta tracking ends a path at a real
    collision)."""
    hot = BlackbodyEmission(temperature=s.box_grid(), temperature_scale=1000.0, temperature_offset=1000.0)
    medium = s.medium(s.box_grid(), extinction=0.5, albedo=0.0, emission=hot)
    scene = s.scene(s.ortho_camera(8, 8, scale=1.0), [medium], [s.environment(1.0)], passes=PASSES)
    spp = 64
    film = render(scene, spp=spp, seed=5, backend="numpy").film
    light = film.light_xyz
    for slot in (VOLUME_DIRECT, VOLUME_INDIRECT, DIFFUSE_DIRECT, DIFFUSE_INDIRECT):
        assert np.all(light[..., slot, :] == 0.0)
    assert light[..., EMISSION, 1].min() > 0.0
    np.testing.assert_allclose(light[..., EMISSION, :] + light[..., ENVIRONMENT, :], film.xyz, rtol=1e-12)
    transmittance = np.exp(-1.0)
    seen = light[..., ENVIRONMENT, 1].mean() / colorimetry.spectrum_to_xyz(np.ones(GRID.size))[1]
    paths = spp * film.width * film.height
    assert abs(seen - transmittance) <= 4.0 * np.sqrt(transmittance * (1 - transmittance) / paths)


def test_a_thin_slab_under_the_sun_is_mostly_direct_light():
    """Single scattering dominates a thin slab (optical depth 0.05 across): light scattered more than once, Volume
    Indirect, is a small fraction of Volume Direct (of order ωτ: below 15 %), and there is no Emission or
    Environment (a delta sun is never seen)."""
    film = render(slab(0.1, passes=PASSES), spp=256, seed=2, backend="numpy").film
    light = film.light_xyz.mean(axis=(0, 1))[:, 1]
    assert light[EMISSION] == 0.0 and light[ENVIRONMENT] == 0.0
    assert light[VOLUME_DIRECT] > 0.0 and light[VOLUME_INDIRECT] > 0.0
    assert light[VOLUME_INDIRECT] < 0.15 * light[VOLUME_DIRECT]


def _samples(scene, count):
    """Each of `count` samples of the one pixel (0, 0) of `scene` on its own: (Combined XYZ, category XYZ) per
    sample."""
    kernel_scene = band_scenes(scene)[0]
    combined, categories = [], []
    for sample in range(count):
        sums = render_unit(kernel_scene, 0, (sample, sample + 1), (0, 0, 1, 1), 7, "numpy", CATEGORIES)
        combined.append(sums[0][0, 0])
        categories.append(sums[3][0, 0])
    return np.array(combined), np.array(categories)


def test_clamping_scales_a_sample_part_to_its_limit():
    """Clamp Indirect: each sample whose indirect light (here Volume Indirect: a delta sun gives no bounce-hit light,
    so the direct part is the next-event estimate at the first vertex) has linear Rec.709 |R| + |G| + |B| above 3 ×
    the limit is scaled to exactly that, the rest of the sample left alone, samples below the limit unchanged (the
    same paths: clamping draws no random number)."""
    count = 48
    combined, categories = _samples(slab(2.0), count)
    direct = categories[:, EMISSION] + categories[:, VOLUME_DIRECT]
    indirect = categories[:, VOLUME_INDIRECT]
    np.testing.assert_allclose(direct + indirect, combined, rtol=1e-12, atol=1e-15)
    size = np.abs(colorimetry.xyz_to_rgb(indirect)).sum(axis=1)
    limit = float(np.median(size[size > 0])) / 3.0
    clamped, _ = _samples(slab(2.0, clamp_indirect=limit), count)
    scale = np.where(size > 3.0 * limit, 3.0 * limit / np.maximum(size, 1e-300), 1.0)
    assert np.sum(scale < 1.0) >= 5 and np.sum((scale == 1.0) & (size > 0)) >= 5  # the median splits them
    np.testing.assert_allclose(clamped, direct + indirect * scale[:, None], rtol=1e-9, atol=1e-15)
    scaled = scale < 1.0
    after = np.abs(colorimetry.xyz_to_rgb(clamped[scaled] - direct[scaled])).sum(axis=1)
    np.testing.assert_allclose(after, 3.0 * limit, rtol=1e-9)


def test_clamp_limits_are_checked():
    """A negative limit is refused, naming the setting."""
    with pytest.raises(SpectralError, match="render.clamp_indirect"):
        check_settings(dataclasses.replace(slab(0.1).settings, clamp_indirect=-1.0))


def test_the_command_line_writes_the_light_passes_with_blenders_names(tmp_path):
    """`--passes` with light passes (names with spaces, as Blender 5's): the EXR holds ViewLayer.Emission.R/G/B, …,
    ViewLayer.Volume Indirect.R/G/B, and with a scene read back from its file (clamping off) they sum to Combined
    within float32 rounding where no surface is in view (the slab alone, under a sun, with an environment)."""
    from addon.tracer import cli, image_io, scene_io

    scene = slab(0.5, spp=4)
    scene = dataclasses.replace(scene, lights=(*scene.lights, s.environment(0.3)))
    folder = scene_io.save_scene(scene, tmp_path / "scene")
    out = tmp_path / "out.exr"
    code = cli.main(["render", str(folder), "--out", str(out), "--backend", "numpy", "--quiet", "--passes",
                     ",".join(PASSES)])
    assert code == 0
    channels = image_io.read_exr(out)
    for letter in "RGB":
        total = sum(channels[f"ViewLayer.{name}.{letter}"].astype(np.float64) for name in PASSES)
        combined = channels[f"ViewLayer.Combined.{letter}"]
        np.testing.assert_allclose(total, combined, rtol=1e-5, atol=1e-6 * np.abs(combined).max())
    assert channels["ViewLayer.Volume Direct.G"].mean() > 0.0 and channels["ViewLayer.Environment.G"].mean() > 0.0
