"""Look-ups of the kernel scene's tables and grids: spectra on the wavelength grid (linear between its
nodes, 0 off the grid), cell-centre grids (trilinear, 0 outside) and the bins of discrete cdfs.

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..shared_math import floor, select, shared, shared_inline
from ..wavelengths import GRID, LAMBDA_MIN

_NODES = GRID.size


@shared
def on_grid(lam):
    """Where wavelength(s) `lam` fall on the grid, for `table_at`: (bin index, position in the bin, inside)."""
    position = lam - LAMBDA_MIN
    index = np.int64(np.minimum(np.maximum(position, 0.0), _NODES - 2.0))
    return index, position - index, (position >= 0.0) & (position <= _NODES - 1.0)


@shared
def evenly_spaced_at(values, first, spacing, x):
    """A table of `values` at the evenly spaced nodes first + k · spacing, at x: linear between its nodes,
    clamped to its end values beyond them."""
    position = np.minimum(np.maximum((x - first) / spacing, 0.0), values.shape[0] - 1.0)
    index = np.int64(np.minimum(position, values.shape[0] - 2.0))
    frac = position - index
    return values[index] * (1.0 - frac) + values[index + 1] * frac


@shared
def table_at(table, row, at):
    """Spectrum `table[row]` (a table of spectra on the grid) at the wavelengths located by `at` (`on_grid`)."""
    index, frac, inside = at
    return (table[row, index] * (1.0 - frac) + table[row, index + 1] * frac) * inside


@shared
def _corners(coordinate, cells, stride):
    """Along one axis of a grid of `cells` cells: the flat-index terms of the cells below and above the
    coordinate (clamped into the grid) and their weights, zero for a cell outside the grid."""
    floored = floor(coordinate)
    below = np.int64(floored)
    frac = coordinate - floored
    above = below + 1
    return (np.minimum(np.maximum(below, 0), cells - 1) * stride, np.minimum(np.maximum(above, 0), cells - 1) * stride,
            (1.0 - frac) * ((below >= 0) & (below < cells)), frac * ((above >= 0) & (above < cells)))


@shared_inline
def trilinear(data, offset, shape, x, y, z):
    """Trilinear interpolation of cell-centre samples at index-space point(s) (x, y, z), zero outside: the
    grid of `shape` is flattened (C order) into `data` from `offset`; corners outside add nothing."""
    x0, x1, wx0, wx1 = _corners(x, shape[0], shape[1] * shape[2])
    y0, y1, wy0, wy1 = _corners(y, shape[1], shape[2])
    z0, z1, wz0, wz1 = _corners(z, shape[2], 1)
    total = wx0 * wy0 * wz0 * data[offset + x0 + y0 + z0]  # corners in this order (x fastest) in both backends
    total = total + wx1 * wy0 * wz0 * data[offset + x1 + y0 + z0]
    total = total + wx0 * wy1 * wz0 * data[offset + x0 + y1 + z0]
    total = total + wx1 * wy1 * wz0 * data[offset + x1 + y1 + z0]
    total = total + wx0 * wy0 * wz1 * data[offset + x0 + y0 + z1]
    total = total + wx1 * wy0 * wz1 * data[offset + x1 + y0 + z1]
    total = total + wx0 * wy1 * wz1 * data[offset + x0 + y1 + z1]
    return total + wx1 * wy1 * wz1 * data[offset + x1 + y1 + z1]


@shared
def probe_chance(ks, x, y, z):
    """The chance of a sunward probe at medium vertex (x, y, z) (`probe_grid`): its cell's, the nearest cell's
    outside the grid."""
    chance, box = ks.lights.probe_chance, ks.lights.probe_box
    last = chance.shape[0] - 1.0
    i = np.int64(np.minimum(np.maximum((x - box[0, 0]) * box[1, 0], 0.0), last))
    j = np.int64(np.minimum(np.maximum((y - box[0, 1]) * box[1, 1], 0.0), last))
    k = np.int64(np.minimum(np.maximum((z - box[0, 2]) * box[1, 2], 0.0), last))
    return chance[i, j, k]


# u is clamped below 1 (a u of 1 would pass the cdf's last node), and the position in a bin stays below 1 by
# far more than rounding, so that what is placed by it stays inside the bin.
_U_BELOW_ONE = 1.0 - 2.0**-53
_T_BELOW_ONE = 1.0 - 2.0**-30


@shared
def cdf_bin(cdf, start, bins, u):
    """The bin k (0 ≤ k < bins) of a cdf stored as cdf[start], …, cdf[start + bins] (rising from 0 to exactly 1)
    in which a uniform u falls, cdf[start + k] ≤ u < cdf[start + k + 1] (by bisection), and u's position in
    it, in [0, 1). A bin of probability 0 is never returned. `start` and `u` may be arrays of paths."""
    u = np.minimum(np.maximum(u, 0.0), _U_BELOW_ONE)
    low = start + np.int64(0.0 * u)
    high = low + bins
    span = bins
    while span > 1:  # each step at least halves high − low, rounding up
        span = (span + 1) // 2
        middle = (low + high) // 2
        below = cdf[middle] <= u
        low, high = select(below, middle, low), select(below, high, middle)
    first = cdf[low]
    position = (u - first) / np.maximum(cdf[low + 1] - first, 1e-300)
    return low - start, np.minimum(np.maximum(position, 0.0), _T_BELOW_ONE)
