"""The majorant grid's DDA (Amanatides and Woo), one axis at a time: where a ray runs inside the block
grid, and the state of its walk from block to block once it is in. Each backend keeps the walk's state in
its own layout (`Tracker` slots in the Numba kernel, arrays of rays in the NumPy backend) and steps it.

Plain arithmetic shared by both backends (`shared_math`): one ray's scalars in the Numba kernel, arrays of
rays in the NumPy backend; choices on a ray's values go through `select`. Coordinates are the medium's
padded index space, where block b along an axis spans [b·B, (b+1)·B) (`majorant`). Part of the kernel
cache's key (`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..shared_math import absolute, floor, select, shared_inline


@shared_inline
def axis_span(o, d, upper, t0, t1):
    """[t0, t1] narrowed to where the ray o + t·d (one axis) lies in [0, upper): a ray parallel to the axis
    keeps [t0, t1] when it is inside and gets t1 = −1 (an empty span) when it is outside."""
    parallel = d == 0.0
    ta, tb = (0.0 - o) / d, (upper - o) / d
    near, far = np.minimum(ta, tb), np.maximum(ta, tb)
    outside = (o < 0.0) | (o >= upper)
    return select(parallel, t0, np.maximum(t0, near)), select(parallel, select(outside, -1.0, t1), np.minimum(t1, far))


@shared_inline
def axis_entry(o, d, t, block, cells):
    """The walk's state on one axis where the ray o + t·d enters the block grid: (block index clamped into
    the `cells` blocks, step ±1 or 0, ray parameter of the next block boundary, spacing of boundaries)."""
    cell = np.minimum(np.maximum(np.int64(floor((o + t * d) / block)), 0), cells - 1)
    moving = d != 0.0
    step = select(d > 0.0, 1, select(d < 0.0, -1, 0))
    boundary = ((cell + (d > 0.0)) * block - o) / d
    return cell, step, select(moving, boundary, np.inf), select(moving, absolute(block / d), np.inf)
