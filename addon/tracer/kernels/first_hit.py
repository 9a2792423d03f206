"""The first surface each camera ray meets, for the data passes (Depth, Mist, Normal, Cryptomatte): apart from
the path tracer, whose kernel it leaves untouched.

Each pixel-sample's camera ray is the path tracer's own (`geometry.camera_ray`, its film point drawn from the
same numbers of band 0's stream: `rng.low_discrepancy` dimensions 1 and 2), so the passes cover a pixel as the
image does. For each ray: its camera-space depth (distance along the camera's view axis, Cycles'
`camera_z_depth`), its distance from the camera (Cycles' `camera_distance`: the depth for an orthographic camera),
the world-space normal on the side facing the camera, and the triangle hit (-1 where none is, the depths then
inf). Media are not seen: as in Cycles, only surfaces write these passes.

`first_hits` is the Numba kernel (the hierarchy walk `numba_backend._closest_hit`; cached with the path
tracer's kernel, `numba_cache`); `first_hits_numpy` the oracle (every triangle tested, `numpy_backend._closest_hits`). Both fill `values` (height, width, samples, 5:
depth, distance, normal x, y, z) and `triangles` (height, width, samples).
"""

from collections import namedtuple

import numpy as np
from numba import prange

from ..shared_math import shared
from .geometry import camera_ray
from .layout import CAMERA_PERSPECTIVE
from .numba_backend import _closest_hit, _new_hit, jit
from .numba_cache import cached
from .numpy_backend import _closest_hits
from .rng import low_discrepancy, pixel_key
from .surfaces import facing_normal

VALUES = 5  # depth, distance, normal x, y, z
# What `_closest_hit` and `camera_ray` read of the kernel scene: a first hit needs no more.
FirstHitScene = namedtuple("FirstHitScene", "camera surfaces")


@shared
def depths(to_world, kind, t, dx, dy, dz):
    """(camera-space depth, distance from the camera) of the point at t along a camera ray of unit direction d:
    the depth is t (d · the view axis); the distance t for a perspective camera (its rays start at the camera),
    the depth for an orthographic one (they start on its film plane)."""
    ax, ay, az = -to_world[0, 2], -to_world[1, 2], -to_world[2, 2]
    depth = t * (dx * ax + dy * ay + dz * az) / np.sqrt(ax * ax + ay * ay + az * az)
    return depth, t if kind == CAMERA_PERSPECTIVE else depth


@cached
@jit(parallel=True, nogil=True)
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
                t, k = _closest_hit(ks, ox, oy, oz, dx, dy, dz, np.inf, False, hit)
                triangles[row, column, index] = k
                out = values[row, column, index]
                if k < 0:
                    out[0], out[1], out[2], out[3], out[4] = np.inf, np.inf, 0.0, 0.0, 0.0
                    continue
                out[0], out[1] = depths(camera.to_world, camera.kind, t, dx, dy, dz)
                out[2], out[3], out[4] = facing_normal(ks, k, dx, dy, dz)


def first_hits_numpy(camera, surfaces, x0, y0, width, height, sample_begin, sample_end, seed, values, triangles):
    """`first_hits` in NumPy, testing every triangle: the oracle."""
    with np.errstate(over="ignore"):  # the random numbers' hashes wrap around, as they should
        _first_hits_numpy(FirstHitScene(camera, surfaces), x0, y0, width, height, sample_begin, sample_end, seed,
                          values, triangles)


def _first_hits_numpy(ks, x0, y0, width, height, sample_begin, sample_end, seed, values, triangles):
    camera = ks.camera
    samples = sample_end - sample_begin
    rows, columns, index = np.meshgrid(np.arange(height), np.arange(width), np.arange(samples), indexing="ij")
    px, py = (x0 + columns).ravel(), (y0 + rows).ravel()
    keys = pixel_key(seed, 0, (py * camera.width + px).astype(np.uint64))
    sample = (sample_begin + index.ravel()).astype(np.uint64)
    ox, oy, oz, dx, dy, dz = camera_ray(ks, px, py, low_discrepancy(keys, sample, np.uint64(1)),
                                        low_discrepancy(keys, sample, np.uint64(2)))
    ox, oy, oz, dx, dy, dz = np.broadcast_arrays(ox, oy, oz, dx, dy, dz, np.zeros(px.size))[:6]
    t, k = _closest_hits(ks, np.stack((ox, oy, oz), axis=1), np.stack((dx, dy, dz), axis=1), np.inf)
    hit = k >= 0
    depth, distance = depths(camera.to_world, camera.kind, t, dx, dy, dz)
    normal = np.stack(facing_normal(ks, np.maximum(k, 0), dx, dy, dz), axis=1) * hit[:, None]
    out = np.column_stack((np.where(hit, depth, np.inf), np.where(hit, distance, np.inf), normal))
    values[...] = out.reshape(height, width, samples, VALUES)
    triangles[...] = k.reshape(height, width, samples)
