"""The majorant grid's DDA (`kernels.dda`) and the `select` it chooses with: a reference walk by the shared
per-axis arithmetic, checked against brute-force sampling, then each backend's own tracker state machine
against that walk.

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


# ----------------------------------------------------------------------------- the backends' own state machines

def backend_walks():
    """Each backend's DDA state machine (`_tracker_start`, `_tracker_boundary`, `_tracker_advance` of the
    Numba kernel, inlined into a small jitted loop, and of the NumPy backend) walking one medium's majorant
    blocks along a world ray: [(block, t where the ray leaves it)]."""
    from addon.tracer.kernels import numba_backend as nb
    from addon.tracer.kernels import numpy_backend as npb

    @nb.cpu_jit  # the kernel's options (NumPy's error model: a ray parallel to a face divides by zero)
    def numba_walk(ks, origin, direction, cells, leaves):
        tracker = nb._new_tracker(1)
        nb._tracker_start(ks, origin[0], origin[1], origin[2], direction[0], direction[1], direction[2], 0.0,
                          np.inf, tracker)
        count = 0
        while tracker.state_i[0, nb.PHASE] != nb.DONE:
            t_end = nb._tracker_boundary(tracker, 0)
            if tracker.state_i[0, nb.PHASE] == nb.INSIDE:
                for axis in range(3):
                    cells[count, axis] = tracker.state_i[0, nb.CELL + axis]
                leaves[count] = t_end
                count += 1
            nb._tracker_advance(ks, tracker, t_end)
        return count

    def numba(ks, origin, direction):
        cells, leaves = np.zeros((512, 3), dtype=np.int64), np.zeros(512)
        count = numba_walk(ks, origin, direction, cells, leaves)
        return [(tuple(int(c) for c in cells[k]), float(leaves[k])) for k in range(count)]

    @np.errstate(divide="ignore", invalid="ignore")  # as in the backend: a parallel axis divides by zero
    def numpy(ks, origin, direction):
        tracker = npb._tracker_start(ks, origin[None, :], direction[None, :], np.inf)
        visited, moving = [], np.ones(1, dtype=bool)
        while tracker.phase[0, 0] != 2:
            t_end = npb._tracker_boundary(tracker)[:, 0]
            if tracker.phase[0, 0] == 1:
                visited.append((tuple(int(c) for c in tracker.cell[0, 0]), float(t_end[0])))
            npb._tracker_advance(ks, tracker, moving, t_end)
        return visited

    return {"numba": numba, "numpy": numpy}


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_each_backends_tracker_walks_the_blocks_the_reference_walk_does(backend):
    """Random world rays through a medium's majorant blocks (in and out of the grid, some parallel to a
    face): the backend's state machine visits the blocks `walk` visits, leaving each where it does (`walk`
    itself is checked against brute-force sampling above)."""
    from addon.tracer.builders import medium, sampled_grid
    from addon.tracer.lowering import compile_scene
    from tests.support import scenes as s

    grid = sampled_grid(lambda x, y, z: 1.0 + 0.5 * np.sin(3.0 * x) * np.cos(2.0 * y) + 0.2 * z, (37, 29, 23),
                        (-1.0, -0.7, -0.4), (1.2, 0.9, 0.6))
    ks = compile_scene(s.scene(s.perspective_camera(), [medium(grid, 2.0)], [s.environment()]))
    walk_of = backend_walks()[backend]
    w2p, block, cells = ks.density.world_to_padded[0], int(ks.majorant.block[0]), ks.majorant.shape[0]
    assert np.prod(cells) > 8  # several blocks to walk through
    rng = np.random.default_rng(3)
    for _ in range(60):
        origin = rng.uniform((-2.0, -2.0, -2.0), (2.0, 2.0, 2.0))
        direction = rng.normal(size=3)
        if rng.random() < 0.2:
            direction[rng.integers(3)] = 0.0
        direction /= np.linalg.norm(direction)
        visited = walk_of(ks, origin, direction)
        # The reference walks the same ray in the medium's padded index space, where the blocks are a grid.
        index_origin = w2p[:3, :3] @ origin + w2p[:3, 3]
        index_direction = w2p[:3, :3] @ direction
        expected = walk(index_origin, index_direction, block, cells)
        assert [cell for cell, _ in visited] == [cell for cell, _ in expected]
        np.testing.assert_allclose([t for _, t in visited], [t for _, t in expected], rtol=1e-12, atol=1e-12)
