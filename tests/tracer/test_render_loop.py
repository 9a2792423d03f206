"""The render loop: progressive passes with progress callbacks, cancellation between passes, and
per-wavelength bands that together estimate the whole spectrum."""

import numpy as np
import pytest

from addon.tracer.errors import SpectralError
from addon.tracer.render import pass_sizes, render
from addon.tracer.wavelengths import GRID
from addon.tracer import colorimetry
from tests.support import scenes as s


def furnace(**settings):
    return s.scene(s.perspective_camera(6, 6), [s.medium(s.box_grid(), extinction=1.5)], [s.environment()],
                   max_depth=300, rr_depth=300, **settings)


def test_pass_sizes_double_up_to_a_cap_and_sum_to_spp():
    assert pass_sizes(1) == [1]
    assert pass_sizes(40) == [1, 2, 4, 8, 16, 9]
    assert all(sum(pass_sizes(n)) == n for n in range(1, 100))


def test_progress_is_reported_after_each_pass_with_the_current_image():
    seen = []
    result = render(furnace(spp=15), progress=lambda film, fraction: seen.append((fraction, film.samples.sum())))
    assert [round(f, 6) for f, _ in seen] == [round(f, 6) for f in np.cumsum([1, 1, 1, 1]) / 4]
    assert [count for _, count in seen] == [1, 3, 7, 15]
    assert not result.cancelled and result.stats["samples_per_pixel"] == 15


def test_cancel_stops_between_passes_and_keeps_what_was_rendered():
    calls = []

    def cancel():
        calls.append(1)
        return len(calls) > 2

    result = render(furnace(spp=64), cancel=cancel)
    assert result.cancelled
    assert result.film.samples.tolist() == [3]  # passes of 1 and 2 samples finished
    assert np.all(np.isfinite(result.film.xyz)) and result.film.xyz.mean() > 0


def test_bands_together_estimate_the_whole_spectrum():
    """A white furnace split into 5 wavelength bands still returns the environment."""
    film = render(furnace(spp=32, bands=5, seed=2)).film
    assert film.bands == 5
    expected = colorimetry.spectrum_to_xyz(np.ones(GRID.size))
    mean = film.xyz.reshape(-1, 3).mean(axis=0)
    error = np.sqrt(film.variance.reshape(-1, 3).sum(axis=0)) / (film.width * film.height)
    assert np.all(np.abs(mean - expected) <= 4 * error), (mean, expected, error)


def test_more_wavelengths_per_path_than_the_kernels_carry_is_refused():
    with pytest.raises(SpectralError, match="render.wavelengths_per_path: must be 1 or 4, found 8"):
        render(furnace(spp=1, wavelengths_per_path=8))
