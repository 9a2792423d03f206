"""The Cycles emulation's band arithmetic, without Blender: band edges, XYZ weights, band means, packing of
bands into renders, and the per-band numbers of a tracer scene."""

import math

import numpy as np
import pytest

from addon.cycles_emulation import bands, parameters
from addon.tracer import colorimetry, spectra
from addon.tracer.errors import SpectralError
from addon.tracer.scene import Camera, Fluorescence, Grid, Light, Medium, RenderSettings, Scene
from addon.tracer.wavelengths import GRID


def test_bands_partition_the_range():
    split = bands.split(360, 830, 7)
    assert split.count == 7 and split.edges[0] == 360 and split.edges[-1] == 830
    masks = split.masks
    inside = (GRID >= 360) & (GRID <= 830)
    assert np.array_equal(masks.sum(axis=0), inside.astype(int))  # every node of the range in exactly one band
    assert np.all(np.diff(split.edges) > 0)


@pytest.mark.parametrize("count", [1, 5, 16])
@pytest.mark.parametrize("cmf", ["cie1931", "wyman3"])
def test_weights_add_up_to_the_cmf_integrals(count, cmf):
    split = bands.split(360, 830, count)
    weights = bands.xyz_weights(split, cmf)
    expected = colorimetry.spectrum_to_xyz(np.where((GRID >= 360) & (GRID <= 830), 1.0, 0.0), cmf)
    np.testing.assert_allclose(weights.sum(axis=0), expected, rtol=1e-12)
    if cmf == "cie1931":
        # A flat spectrum of 1 from 360 nm has Y = 1 but for its ramp from 0 at 359 nm (ȳ(360) is 4e-6 of its peak).
        assert weights.sum(axis=0)[1] == pytest.approx(1.0, abs=1e-7)


def test_band_means_of_flat_and_stepped_spectra():
    split = bands.split(400, 700, 3)
    np.testing.assert_allclose(bands.band_means(np.full(GRID.size, 0.7), split), [0.7, 0.7, 0.7])
    step = np.where(GRID < 500, 1.0, 0.0)
    np.testing.assert_allclose(bands.band_means(step, split), [1.0, 0.0, 0.0], atol=1e-12)
    uv = bands.split(250, 350, 2)  # outside the CMFs: plain means
    np.testing.assert_allclose(bands.band_means(GRID, uv), [274.5, 325.0])


@pytest.mark.parametrize("count", [1, 2, 3, 4, 9, 10, 16])
def test_packing_uses_ceil_k_over_3_renders_when_g_is_constant(count):
    renders = bands.pack([("hg", 0.3)] * count)
    assert len(renders) == math.ceil(count / 3)
    assert sorted(k for render in renders for k in render) == list(range(count))
    assert all(len(render) <= 3 for render in renders)


@pytest.mark.parametrize("count", [1, 4, 9])
def test_packing_uses_k_renders_when_g_varies(count):
    renders = bands.pack([("hg", k / 10) for k in range(count)])
    assert renders == tuple((k,) for k in range(count))


def test_packing_groups_equal_phases_only():
    renders = bands.pack(["a", "b", "a", "a", "b", "a"])
    assert renders == ((0, 2, 3), (1, 4), (5,))
    with pytest.raises(SpectralError, match="at least one"):
        bands.pack([])


def _scene(anisotropy, fluorescent=False, band_range=(360.0, 830.0)):
    grid = Grid(np.ones((2, 2, 2), dtype=np.float32), np.eye(4))
    albedo = np.stack([np.full(GRID.size, 0.5), np.where(GRID < 550, 0.9, 0.2)])
    fluorescence = Fluorescence(spectra.gaussian(350, 20), spectra.gaussian(520, 20), 0.5) if fluorescent else None
    medium = Medium("Cloud", grid, 2.0, spectra.constant(3.0), np.array([0.0, 1.0]), albedo, anisotropy,
                    fluorescence=fluorescence)
    sun = Light("sun", spectra.illuminant("D65"), strength=3.0, direction=np.array([0, 0, 1.0]), name="Sun")
    world = Light("environment", spectra.constant(1.0), strength=0.5, name="World")
    settings = RenderSettings(lambda_min=band_range[0], lambda_max=band_range[1])
    return Scene(Camera(np.eye(4), 8, 6), (medium,), (sun, world), settings=settings)


def test_plan_of_a_scene():
    plan = parameters.plan(_scene(spectra.constant(0.4)), 9)
    assert plan.renders == ((0, 1, 2), (3, 4, 5), (6, 7, 8)) and plan.warnings == ()
    medium = plan.media[0]
    np.testing.assert_allclose(medium.extinction, 3.0)
    np.testing.assert_allclose(medium.albedo[0], 0.5)
    assert medium.albedo[1, 0] == pytest.approx(0.9) and medium.albedo[1, -1] == pytest.approx(0.2)
    # The sun's band colours reproduce its luminance (strength stays Blender's): Σ_k colour_k · w_k,Y = 1.
    assert plan.light_colours["Sun"] @ plan.weights[:, 1] == pytest.approx(1.0, rel=2e-3)
    assert plan.world.name == "World" and "World" not in plan.light_colours
    np.testing.assert_allclose(plan.world_colours[0], 1.0, rtol=1e-9)


def test_plan_renders_one_band_per_render_when_g_varies_and_warns_about_fluorescence():
    anisotropy = spectra.Spectrum(np.interp(GRID, [380, 700], [0.0, 0.9]))
    plan = parameters.plan(_scene(anisotropy, fluorescent=True, band_range=(250.0, 830.0)), 6)
    assert len(plan.renders) == 6
    assert len(plan.warnings) == 1 and "fluoresces" in plan.warnings[0]
    assert plan.media[0].excitation[0] > 0.1 and plan.media[0].excitation[-1] == pytest.approx(0.0)
    with pytest.raises(SpectralError, match="at least 1 band"):
        parameters.plan(_scene(anisotropy), 0)


def test_upsampled_colours():
    split = bands.split(360, 830, 12)
    weights = bands.xyz_weights(split)
    grey = parameters.reflectance_bands((0.5, 0.5, 0.5), split)
    np.testing.assert_allclose(grey, 0.5, atol=0.02)
    red = parameters.reflectance_bands((0.8, 0.1, 0.1), split)
    assert red[-3] > 0.5 > 0.2 > red[2]
    white = parameters.emitter_bands((2.0, 2.0, 2.0), split)
    assert white @ weights[:, 1] == pytest.approx(2.0, rel=0.01)  # white light keeps its luminance
    assert parameters.emitter_bands((0.0, 0.0, 0.0), split).tolist() == [0.0] * 12


def test_composite_film_weights_and_variance():
    from addon.cycles_emulation.composite import CompositeFilm

    film = CompositeFilm(2, 1)
    weights = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    first = np.array([[[1.0, 1.0, 9.0], [2.0, 0.0, 9.0]]])
    second = np.array([[[3.0, 1.0, 9.0], [2.0, 2.0, 9.0]]])
    film.add(first, second, weights)
    np.testing.assert_allclose(film.xyz, [[[2.0, 2.0, 0.0], [2.0, 2.0, 0.0]]])
    np.testing.assert_allclose(film.variance, [[[1.0, 0.0, 0.0], [0.0, 4.0, 0.0]]])
    np.testing.assert_allclose(film.rgb(), colorimetry.xyz_to_rgb(film.xyz))


@pytest.mark.parametrize("count", [3, 6, 12])
def test_weights_shaped_by_a_light_render_its_colour_exactly(count):
    split = bands.split(360, 830, count)
    d65 = spectra.illuminant("D65").values * ((GRID >= 360) & (GRID <= 830))
    weights = bands.xyz_weights(split, reference=d65)
    np.testing.assert_allclose(bands.band_means(d65, split) @ weights, colorimetry.spectrum_to_xyz(d65), rtol=1e-10)
    flat = bands.xyz_weights(split)
    assert np.abs(bands.band_means(d65, split) @ flat / colorimetry.spectrum_to_xyz(d65) - 1).max() > 1e-3
