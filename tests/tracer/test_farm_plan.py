"""A farm's plan (addon/tracer/farm_plan.py): its tiles cover the image once, its passes are the single-process
render's, and merging their results in any completion order gives the single-process film bit for bit."""

import numpy as np
import pytest

from addon.tracer import farm_plan
from addon.tracer import render as single
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from tests.support.farm import assert_same_film


def test_tiles_cover_the_image_once():
    coverage = np.zeros((10, 12), dtype=int)
    for x0, y0, width, height in farm_plan.image_tiles(12, 10, 5):
        coverage[y0:y0 + height, x0:x0 + width] += 1
    assert (coverage == 1).all()
    with pytest.raises(SpectralError, match="tile size"):
        farm_plan.image_tiles(12, 10, 0)


def test_plan_uses_the_single_process_passes():
    sizes, tiles, units = farm_plan.plan(12, 10, bands=3, spp=40, tile_size=5)
    assert sizes == single.pass_sizes(40)
    assert len(units) == len(sizes) * 3 * len(tiles)
    for band in range(3):
        for tile_index in range(len(tiles)):
            ranges = [u.samples for u in units if u.band == band and u.tile_index == tile_index]
            assert ranges == [(sum(sizes[:i]), sum(sizes[:i + 1])) for i in range(len(sizes))]


def test_merging_in_any_completion_order_is_bit_identical():
    """Synthetic pass results with a wide dynamic range, so that summation order shows in the bits."""
    width, height, bands, spp = 7, 5, 2, 40
    sizes, tiles, units = farm_plan.plan(width, height, bands, spp, tile_size=3)
    rng = np.random.default_rng(1)
    passes = rng.lognormal(0.0, 6.0, size=(len(sizes), bands, height, width, 3))
    expected = Film(width, height, bands)
    for index, size in enumerate(sizes):
        for band in range(bands):
            expected.add(band, 0, 0, passes[index, band], passes[index, band] ** 2, size, passes[index, band, ..., 0])

    def tile_of(unit):
        x0, y0, w, h = unit.tile
        values = passes[unit.pass_index, unit.band, y0:y0 + h, x0:x0 + w]
        return values, values**2, values[..., 0]

    for trial in range(5):
        order = rng.permutation(len(units))
        film = Film(width, height, bands)
        merger = farm_plan.PassMerger(film, sizes, tiles)
        for step, index in enumerate(order):
            merger.add(units[index], *tile_of(units[index]))
            # The sample count of a band always describes every pixel: only whole passes are added.
            for band in range(bands):
                merged = sum(sizes[:merger.next_pass[band]])
                assert film.samples[band] == merged
        assert merger.complete
        assert_same_film(expected, film)

    # The test has teeth: adding tiles as they come (passes out of order) changes the bits.
    naive = Film(width, height, bands)
    for index in rng.permutation(len(units)):
        unit = units[index]
        xyz, squares, transparent = tile_of(unit)
        naive.add(unit.band, unit.tile[1], unit.tile[0], xyz, squares, sizes[unit.pass_index], transparent)
    assert not np.array_equal(naive.sum_xyz, expected.sum_xyz)
