"""The render loop: passes cut into units (tiles), progress by samples done, cancellation between units,
the same film for any split of the work, and per-wavelength bands that together estimate the whole
spectrum."""

import math
import threading

import numpy as np
import pytest

from addon.tracer.errors import SpectralError
from addon.tracer.render import FIRST_UNIT, GROWTH, Tiler, pass_sizes, passes, render
from addon.tracer.wavelengths import GRID
from addon.tracer import colorimetry
from tests.support import scenes as s

TINY_UNITS = 1e-12  # seconds: every unit is one pixel of one pass


def furnace(width=6, height=6, **settings):
    return s.scene(s.perspective_camera(width, height), [s.medium(s.box_grid(), extinction=1.5)], [s.environment()],
                   max_depth=300, rr_depth=300, **settings)


def test_pass_sizes_double_up_to_a_cap_and_sum_to_spp():
    assert pass_sizes(1) == [1]
    assert pass_sizes(40) == [1, 2, 4, 8, 16, 9]
    assert all(sum(pass_sizes(n)) == n for n in range(1, 100))
    many = pass_sizes(3 * 10**5)
    assert sum(many) == 3 * 10**5 and len(many) == 4 + math.ceil((3 * 10**5 - 15) / 16)


def test_passes_are_planned_lazily_and_contiguously():
    plan = passes(10**15)  # a list would not fit in memory
    first = [next(plan) for _ in range(6)]
    assert first == [(0, 1), (1, 2), (3, 4), (7, 8), (15, 16), (31, 16)]


def tile_cover(tiler, samples, width, height):
    coverage = np.zeros((height, width), dtype=int)
    sizes = []
    for x0, y0, w, h in tiler.tiles(samples):
        coverage[y0:y0 + h, x0:x0 + w] += 1
        sizes.append(w * h)
        assert h == 1 or (x0, w) == (0, width)  # whole rows, or part of one row
    return coverage, sizes


@pytest.mark.parametrize("samples", [1, 3, 16])
def test_tiles_cover_the_image_once_and_grow_from_a_small_first_unit(samples):
    tiler = Tiler(37, 23)
    coverage, sizes = tile_cover(tiler, samples, 37, 23)
    assert (coverage == 1).all()
    assert sizes[0] * samples <= FIRST_UNIT
    # Nothing measured yet: each tile is at most GROWTH times the first unit (the tiler learns as it goes).


def test_tiles_are_sized_from_the_measured_throughput():
    tiler = Tiler(200, 100, seconds=0.25)
    tiler.largest = 10**9  # growth is tested below
    tiler.measured((0, 0, 200, 50), samples=1, seconds=0.1)  # 100 k pixel-samples per second
    coverage, sizes = tile_cover(tiler, 4, 200, 100)
    assert (coverage == 1).all()
    assert sizes[0] == 6200  # 25 k pixel-samples: whole rows of 200 pixels at 4 samples, rounded down
    tiler.measured((0, 0, 200, 5), samples=1, seconds=0.1)  # ten times slower: the next tiles shrink at once
    assert next(tiler.tiles(4))[2:] == (200, 3)
    tiler.measured((0, 0, 10, 10), samples=1, seconds=0.0001)  # faster again: trusted by halves
    assert tiler.cost == pytest.approx((1e-4 + 1e-6) / 2)


def test_rows_measured_in_one_pass_size_the_tiles_of_the_next():
    """Cheap rows (sky) then expensive ones (cloud): every tile of the next pass is predicted to take at
    most the unit's time, and the cheap rows are not cut as finely as the expensive ones."""
    width, height, seconds = 50, 100, 0.25
    cost = np.where(np.arange(height) < 60, 1e-6, 1e-3)  # seconds per pixel-sample of each row
    tiler = Tiler(width, height, seconds)
    tiler.largest = 10**9
    for row in range(height):
        tiler.measured((0, row, width, 1), samples=1, seconds=cost[row] * width)
    for samples in (1, 16):
        tiles = list(tiler.tiles(samples))
        coverage = np.zeros(height, dtype=int)
        for x0, y0, w, h in tiles:
            coverage[y0:y0 + h] += w
            assert cost[y0:y0 + h].sum() * w * samples <= seconds + 1e-9
        assert (coverage == width).all()
    assert tiles[0] == (0, 0, width, 60)  # 16 samples: all the cheap rows in one tile (48 ms)…
    assert {w for _, y0, w, _ in tiles[1:]} <= {15, 5}  # …then 15 of 50 pixels of a row per tile (0.24 s)


def test_growth_of_tiles_is_bounded_while_the_throughput_is_unknown():
    tiler = Tiler(100_000, 2)
    tiler.measured((0, 1, 1000, 1), samples=1, seconds=1e-9)  # absurdly fast (a timer's resolution)
    tiler.measured((0, 1, 10, 1), samples=1, seconds=1e-9)  # a pass's last, small tile does not hold growth back
    assert next(tiler.tiles(1))[2] == 1000 * GROWTH


def test_progress_is_reported_after_each_unit_by_samples_done():
    seen = []
    result = render(furnace(spp=15), progress=lambda film, fraction: seen.append((fraction, film.pixel_samples.sum())))
    pixels = 36
    assert [count for _, count in seen] == [pixels * n for n in (1, 3, 7, 15)]  # one unit per pass: 36 pixels
    assert [fraction for fraction, _ in seen] == [count / (pixels * 15) for _, count in seen]
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


def test_cancel_is_honoured_within_a_pass_and_the_film_holds_the_units_done():
    """The first unit (nothing measured yet) is the whole first pass of 36 pixels; then units are one
    pixel each: a cancel after 50 units leaves 36 pixels + 13 pixels done of the passes of 2 and 4 samples."""
    asked, seen = [], []

    def cancel():
        asked.append(1)
        return len(asked) > 50

    result = render(furnace(spp=64), cancel=cancel, unit_seconds=TINY_UNITS,
                    progress=lambda film, fraction: seen.append(fraction))
    film = result.film
    assert result.cancelled and len(seen) == 50
    assert film.samples.tolist() == [3]
    assert np.sort(film.pixel_samples.ravel()).tolist() == [3] * 23 + [7] * 13
    assert film.pixel_samples.ravel()[:13].tolist() == [7] * 13  # reading order
    assert seen[-1] == film.pixel_samples.sum() / (36 * 64)
    assert np.all(np.isfinite(film.xyz)) and np.all(film.variance > 0)


def test_cancel_before_the_first_unit_renders_nothing():
    result = render(furnace(spp=4), cancel=lambda: True)
    assert result.cancelled and result.film.pixel_samples.sum() == 0


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_any_split_into_units_gives_the_same_film(backend):
    """One-pixel units against whole passes: every pixel gets the same pass sums in the same order."""
    scene = furnace(width=5, height=4, spp=20, bands=2, seed=9)
    whole = render(scene, backend=backend).film
    pieces = render(scene, backend=backend, unit_seconds=TINY_UNITS).film
    assert np.array_equal(whole.pixel_samples, pieces.pixel_samples)
    assert np.array_equal(whole.sum_xyz, pieces.sum_xyz) and np.array_equal(whole.sum_sq, pieces.sum_sq)


def test_renders_on_two_threads_take_turns_and_give_their_own_images(monkeypatch):
    """The Rendered viewport and F12 may render at once: their kernel launches never overlap (Numba's
    workqueue threading layer would abort), and each gets the image it would get alone."""
    from addon.tracer import render as loop

    scenes = [furnace(width=5, height=4, spp=6, seed=seed) for seed in (1, 2)]
    alone = [render(scene).film for scene in scenes]
    unlocked, real_unit = [], loop.render_unit

    def unit(*args):
        unlocked.append(not loop.KERNEL_LAUNCH.locked())
        return real_unit(*args)

    monkeypatch.setattr(loop, "render_unit", unit)
    films = [None, None]

    def render_one(index):
        films[index] = render(scenes[index], unit_seconds=TINY_UNITS).film

    threads = [threading.Thread(target=render_one, args=(index,)) for index in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(120)
    assert len(unlocked) >= 2 * len(pass_sizes(6)) and not any(unlocked)
    for film, reference in zip(films, alone):
        assert np.array_equal(film.sum_xyz, reference.sum_xyz)


def test_the_first_render_says_when_the_kernel_compiles(monkeypatch):
    from addon.tracer.kernels import numba_cache

    def slow_ready(dispatcher, prepare, cancel=None, notice=None):
        notice(numba_cache.compiling_message())
        prepare()
        return True

    monkeypatch.setattr(numba_cache, "ready", slow_ready)
    notices = []
    render(furnace(spp=1), notice=notices.append)
    assert len(notices) == 1 and notices[0].startswith("Compiling the kernel (")


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
