"""The first surface each camera ray meets, for the data passes (Depth, Mist, Normal, Cryptomatte): apart from
the path tracer, whose kernel it leaves untouched.

Each pixel-sample's camera ray is the path tracer's own (`geometry.camera_ray`, its film point drawn from the
same numbers of band 0's stream: `rng.low_discrepancy` dimensions 1 and 2), so the passes cover a pixel as the
image does. For each ray: its camera-space depth and its distance from the camera (`geometry.camera_depths`),
the world-space normal on the side facing the camera, and the triangle hit (-1 where none is, the depths then
inf). Media are not seen: as in Cycles, only surfaces write these passes, and only those camera rays see
(`scene.Surface.camera`).

`first_hits` walks the triangles' hierarchy with the path tracer's `numba_backend._closest_hit` and is cached
with its kernel (`numba_cache`); its oracle is the NumPy backend's `first_hits` (every triangle tested). Both
fill `values` (height, width, samples, FIRST_HIT_VALUES: depth, distance, normal x, y, z) and `triangles`
(height, width, samples).
"""

from collections import namedtuple

import numpy as np
from numba import prange

from .geometry import camera_depths, camera_ray
from .numba_backend import _closest_hit, _new_hit, cpu_jit
from .numba_cache import cached
from .rng import low_discrepancy, pixel_key
from .surfaces import facing_normal

# What `_closest_hit` and `camera_ray` read of the kernel scene: a first hit needs no more.
FirstHitScene = namedtuple("FirstHitScene", "camera surfaces")


@cached
@cpu_jit(parallel=True, nogil=True)
def first_hits(camera, surfaces, x0, y0, width, height, sample_begin, sample_end, seed, values, triangles):
    """Fill `values` and `triangles` (module docstring) for samples [sample_begin, sample_end) of each pixel of
    the tile (x0, y0, width, height), a row per thread. Each row puts the scene together itself: Numba's
    parallel loop hands a tuple to its threads member by member, which fails when a member is a tuple itself."""
    for row in prange(height):
        ks = FirstHitScene(camera, surfaces)
        hit = _new_hit()
        py = y0 + row
        for column in range(width):
            px = x0 + column
            key = pixel_key(seed, 0, py * camera.width + px)
            for index in range(sample_end - sample_begin):
                sample = sample_begin + index
                ox, oy, oz, dx, dy, dz = camera_ray(ks, px, py, low_discrepancy(key, sample, 1),
                                                    low_discrepancy(key, sample, 2))
                t, k = _closest_hit(ks, ox, oy, oz, dx, dy, dz, np.inf, False, True, hit)
                triangles[row, column, index] = k
                out = values[row, column, index]
                if k < 0:
                    out[0], out[1], out[2], out[3], out[4] = np.inf, np.inf, 0.0, 0.0, 0.0
                    continue
                out[0], out[1] = camera_depths(camera.to_world, camera.kind, t, dx, dy, dz)
                out[2], out[3], out[4] = facing_normal(ks, k, dx, dy, dz)
