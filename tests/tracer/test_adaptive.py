"""Adaptive sampling (`addon.tracer.adaptive` and the render loop): quiet pixels stop at the minimum, noisy
ones get every sample, the image stays an unbiased estimate within its noise, and progress still ends at 1."""

import numpy as np
import pytest

from addon.tracer import adaptive
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from addon.tracer.render import Tiler, render
from tests.support import scenes as s
from addon.tracer.validation import validate


def cube_in_the_sky(**settings):
    """A grey absorbing-and-scattering cube in a uniform environment: the sky around it is quiet (its only
    noise is the colour noise of the sampled wavelengths, error ≈ 0.4 / √samples), the cube is not."""
    return s.scene(s.perspective_camera(16, 16, fov_degrees=60.0), [s.medium(s.box_grid(), extinction=2.0, albedo=0.5)],
                   [s.environment()], backend="numpy", **settings)


def test_quiet_pixels_stop_at_the_minimum_and_noisy_ones_get_every_sample():
    seen = []
    result = render(cube_in_the_sky(spp=64, noise_threshold=0.1, min_samples=4),
                    progress=lambda film, fraction: seen.append(fraction))
    samples = result.film.pixel_samples[0]
    assert 7 <= samples[0, 0] <= 31 and 7 <= samples[-1, -1] <= 31  # the sky's corners: about 16 samples
    assert samples[8, 8] == 64  # the cube's centre (error ≈ 1.4 / √samples)
    assert seen[-1] == pytest.approx(1.0) and all(b >= a for a, b in zip(seen, seen[1:]))

    full = render(cube_in_the_sky(spp=64, seed=1)).film
    assert (full.pixel_samples == 64).all()
    for region in (samples < 64, samples == 64):  # the sky and the cube: the same means within 4 σ
        difference = (result.film.xyz[region] - full.xyz[region]).mean(axis=0)
        sigma = np.sqrt((result.film.variance[region] + full.variance[region]).sum(axis=0)) / region.sum()
        assert (np.abs(difference) < 4 * sigma).all(), (difference, sigma)


def test_without_a_threshold_every_pixel_gets_every_sample():
    result = render(cube_in_the_sky(spp=12))
    assert (result.film.pixel_samples == 12).all()


def test_a_pixel_stays_active_while_a_neighbour_is_noisy():
    film = Film(5, 4)
    film.sum_xyz[0] = 4.0
    film.sum_sq[0] = 4.0
    film.pixel_samples[0] = 4  # every pixel 1 in each of its 4 samples: no noise
    film.sum_sq[0, 2, 3] = 8.0  # one noisy pixel
    active = adaptive.active_pixels(film, 0.01)
    expected = np.zeros((4, 5), dtype=bool)
    expected[1:4, 2:5] = True
    np.testing.assert_array_equal(active, expected)


def test_minimum_samples_follow_the_threshold_unless_given():
    assert adaptive.minimum_samples(0.01, 0, 1024) == 64
    assert adaptive.minimum_samples(0.001, 0, 1024) > 64
    assert adaptive.minimum_samples(0.01, 10, 1024) == 10
    assert adaptive.minimum_samples(0.01, 0, 16) == 16


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_tiles_cover_every_active_pixel_once_in_boxes_of_them(seed):
    rng = np.random.default_rng(seed)
    active = np.zeros((23, 37), dtype=bool)
    active[3:12, 10:20] = rng.random((9, 10)) < 0.7  # a noisy region
    tiler = Tiler(37, 23, seconds=0.25)
    tiler.measured((0, 0, 37, 23), samples=1, seconds=0.25 * 37 * 23 / 200)  # 200 pixel-samples a unit
    coverage = np.zeros(active.shape, dtype=int)
    for x0, y0, width, height in tiler.tiles(4, active):
        coverage[y0:y0 + height, x0:x0 + width] += 1
        assert active[y0:y0 + height, x0:x0 + width].any()
        assert active[y0, x0:x0 + width].any() and active[y0 + height - 1, x0:x0 + width].any()  # cropped
    assert (coverage[active] == 1).all() and coverage.max() == 1
    assert coverage[:3].sum() == 0 and coverage[12:].sum() == 0 and coverage[:, :10].sum() == 0


@pytest.mark.parametrize("field, value", [("noise_threshold", -0.1), ("noise_threshold", 2.0),
                                          ("noise_threshold", float("nan")), ("min_samples", -1)])
def test_bad_adaptive_settings_are_refused(field, value):
    with pytest.raises(SpectralError, match=f"render.{field}"):
        validate(cube_in_the_sky(**{field: value}))
