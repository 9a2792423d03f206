"""The majorant grid's DDA (`kernels.dda`) and the `select` it chooses with.

The walk must visit exactly the blocks that the ray passes through, in order, with the boundaries where
the ray leaves each: free flights and shadow rays take each block's majorant (and minorant) only between
those boundaries, so a missed or extra block is a wrong majorant.
"""

import numpy as np
import pytest
from numba import njit

from addon.tracer.kernels.dda import axis_entry, axis_span
from addon.tracer.shared_math import select


@np.errstate(divide="ignore", invalid="ignore")  # a parallel axis divides by zero, as in the backends
def walk(origin, direction, block, cells, t_max=np.inf):
    """(block, t where the ray leaves it) along the ray, by the shared per-axis arithmetic, as NumPy scalars."""
    t0, t1 = 0.0, t_max
    for axis in range(3):
        t0, t1 = axis_span(origin[axis], direction[axis], cells[axis] * block, t0, t1)
    if t0 >= t1:
        return []
    state = [axis_entry(origin[axis], direction[axis], t0, block, cells[axis]) for axis in range(3)]
    cell = [int(s[0]) for s in state]
    step = [int(s[1]) for s in state]
    t_next = [float(s[2]) for s in state]
    t_delta = [float(s[3]) for s in state]
    visited = []
    while True:
        leave = min(t1, *t_next)
        visited.append((tuple(cell), leave))
        if leave >= t1:
            return visited
        axis = int(np.argmin(t_next))
        cell[axis] += step[axis]
        t_next[axis] += t_delta[axis]
        if not 0 <= cell[axis] < cells[axis]:
            return visited


@pytest.mark.parametrize("seed", range(5))
def test_walk_visits_the_blocks_the_ray_passes_through(seed):
    rng = np.random.default_rng(seed)
    block, cells = 3, np.array([4, 5, 6])
    upper = cells * block
    for _ in range(200):
        origin = rng.uniform(-4.0, upper + 4.0)
        direction = rng.normal(size=3)
        if rng.random() < 0.2:
            direction[rng.integers(3)] = 0.0  # parallel to a face: the span and step of that axis
        direction /= np.linalg.norm(direction)
        visited = walk(origin, direction, block, cells)
        # Brute force: the block of every point on a fine sampling of the ray inside the grid.
        t = np.linspace(0.0, 40.0, 200_001)
        points = origin + t[:, None] * direction
        inside = np.all((points >= 0.0) & (points < upper), axis=1)
        expected = []
        for index in np.floor(points[inside] / block).astype(int):
            if not expected or expected[-1] != tuple(index):
                expected.append(tuple(index))
        blocks = [cell for cell, _ in visited]
        # A sample may skip a block the ray only grazes (shorter than the sampling step): those are
        # allowed in the walk, never the reverse.
        assert all(cell in blocks for cell in expected)
        assert (blocks[0] == expected[0] and blocks[-1] == expected[-1]) if expected else blocks == []
        positions = [blocks.index(cell) for cell in expected]
        assert positions == sorted(positions)
        for (cell, leave), next_cell in zip(visited, blocks[1:]):
            point = origin + leave * direction  # where the ray leaves a block it enters the next one
            assert np.all(np.abs(point / block - np.clip(point / block, next_cell, np.add(next_cell, 1))) < 1e-9)


@np.errstate(divide="ignore", invalid="ignore")
def test_a_parallel_ray_outside_the_grid_has_no_span():
    zero = np.float64(0.0)
    t0, t1 = axis_span(np.float64(-1.0), zero, 12, 0.0, np.inf)
    assert t1 < t0
    t0, t1 = axis_span(np.float64(5.0), zero, 12, 0.0, np.inf)
    assert (t0, t1) == (0.0, np.inf)


def test_select_gives_scalars_in_kernels_and_arrays_in_numpy():
    @njit
    def kernel(x):
        return select(x > 0.0, x * 2.0, -1.0)

    assert kernel(2.0) == 4.0 and kernel(-3.0) == -1.0
    assert isinstance(kernel(2.0), float)  # np.where would give a 0-d array: an allocation per call
    np.testing.assert_array_equal(select(np.array([1.0, -1.0]) > 0.0, 5.0, np.array([7.0, 8.0])), [5.0, 8.0])
