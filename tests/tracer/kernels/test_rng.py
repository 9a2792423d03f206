"""The paths' random numbers (`kernels.rng`): Sobol points against SciPy's, the stratification that
Owen scrambling must keep, uniformity, and the same numbers from scalar (Numba) and array (NumPy) code."""

import numpy as np
import pytest
from numba import njit
from scipy.stats import qmc

from addon.tracer.kernels import rng

LOW = rng.LOW_DISCREPANCY_DIMENSIONS
# uint64 arithmetic wraps by design; NumPy warns when a scalar (not an array) does
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")


def test_sobol_points_are_scipys():
    """SciPy enumerates Sobol points in Gray-code order: its point i is our point i ^ (i >> 1)."""
    index = np.arange(1024, dtype=np.uint64)
    gray = index ^ (index >> np.uint64(1))
    ours = np.stack([rng.sobol(gray, d) for d in range(4)], axis=1) * 2.0**-32
    assert np.array_equal(ours, qmc.Sobol(4, scramble=False).random_base2(10))


def test_byte_tables_multiply_the_generator_matrices():
    indices = np.random.default_rng(3).integers(0, 2**32, 500, dtype=np.uint64)
    for dimension in range(4):
        for index in indices:
            expected = 0
            for bit in range(32):
                if int(index) >> bit & 1:
                    expected ^= int(rng.SOBOL_MATRICES[dimension, bit])
            assert int(rng.sobol(index, dimension)) == expected


def _pixel_samples(pixel_key, count):
    """The first LOW numbers of samples 0..count-1 of one pixel: shape (count, LOW)."""
    samples = np.arange(count, dtype=np.uint64)
    return np.stack([rng.low_discrepancy(np.full(count, pixel_key), samples, np.full(count, c, dtype=np.uint64))
                     for c in range(LOW)], axis=1)


@pytest.mark.parametrize("pixel", [0, 1, 77, 123456])
def test_each_dimension_is_stratified_over_a_pixels_samples(pixel):
    """Every power-of-two prefix of a pixel's samples puts one sample in each interval of that size,
    in every low-discrepancy dimension (a scrambled (0, 1)-sequence)."""
    values = _pixel_samples(rng.pixel_key(5, 2, pixel), 256)
    for count in (2, 16, 256):
        cells = np.sort(np.floor(values[:count] * count), axis=0)
        assert np.array_equal(cells, np.tile(np.arange(count)[:, None], (1, LOW)))


@pytest.mark.parametrize("pixel", [0, 9, 4242])
def test_the_first_two_dimensions_of_a_group_are_stratified_together(pixel):
    """Sobol dimensions 0 and 1 form a (0, 2)-sequence, and scrambling keeps it: 64 samples fill an
    8 × 8 grid of cells once each, in each group of four dimensions."""
    values = _pixel_samples(rng.pixel_key(0, 0, pixel), 64)
    for first in range(0, LOW, int(rng.GROUP)):
        cells = np.floor(values[:, first] * 8) * 8 + np.floor(values[:, first + 1] * 8)
        assert np.array_equal(np.sort(cells), np.arange(64))


def test_numbers_are_uniform_over_pixels():
    """A fixed sample and dimension over 200 000 pixels: the Kolmogorov–Smirnov distance to uniform is
    below 0.005 (its 1 % critical value at this size is 0.0036)."""
    pixels = np.arange(200_000)
    keys = rng.pixel_key(11, 0, pixels)
    for counter in (0, 3, LOW - 1):
        for sample in (0, 5, 1000):
            u = np.sort(rng.low_discrepancy(keys, np.full(pixels.size, sample, dtype=np.uint64),
                                            np.full(pixels.size, counter, dtype=np.uint64)))
            assert np.all((u >= 0.0) & (u < 1.0))
            distance = np.max(np.abs(u - (np.arange(u.size) + 0.5) / u.size))
            assert distance < 0.005, (counter, sample, distance)


def test_groups_are_decorrelated():
    """The same dimension of two groups (0 and 4) over one pixel's 4096 samples: correlation near 0
    (|r| < 0.06, about 4 standard errors), where an unshuffled index would give r = 1."""
    values = _pixel_samples(rng.pixel_key(1, 0, 3), 4096)
    r = np.corrcoef(values[:, 0], values[:, int(rng.GROUP)])[0, 1]
    assert abs(r) < 0.06


@njit
def _scalar_numbers(pixel_key, count):
    out = np.empty((count, LOW))
    for sample in range(count):
        for counter in range(LOW):
            out[sample, counter] = rng.low_discrepancy(pixel_key, np.uint64(sample), np.uint64(counter))
    return out


def test_scalar_and_array_code_draw_the_same_numbers():
    key = rng.pixel_key(7, 1, 99)
    assert np.array_equal(_scalar_numbers(key, 64), _pixel_samples(key, 64))
