"""Points and directions as components (x, y, z): affine transforms, normalisation, the camera's ray
through a point of the film, and a point's depth and distance along a camera ray (the data passes).

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

from ..shared_math import shared, sqrt
from .layout import CAMERA_PERSPECTIVE


@shared
def transform_point(m, x, y, z):
    """The point (x, y, z) through the 4×4 affine matrix `m`."""
    return (m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + m[0, 3],
            m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + m[1, 3],
            m[2, 0] * x + m[2, 1] * y + m[2, 2] * z + m[2, 3])


@shared
def transform_vector(m, x, y, z):
    """The vector (x, y, z) through the linear part of the 4×4 matrix `m`."""
    return (m[0, 0] * x + m[0, 1] * y + m[0, 2] * z,
            m[1, 0] * x + m[1, 1] * y + m[1, 2] * z,
            m[2, 0] * x + m[2, 1] * y + m[2, 2] * z)


@shared
def normalize(x, y, z):
    """(x, y, z) scaled to unit length."""
    inv = 1.0 / sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv


@shared
def camera_ray(ks, px, py, u1, u2):
    """Origin and unit direction (ox, oy, oz, dx, dy, dz) of the ray through the film point (px + u1, py + u2)
    of pixel (px, py) (a box filter), in Blender's camera conventions: the film spans `camera.extent` at z = −1
    (perspective) or at the camera (orthographic), the camera looking along −z."""
    cx = (-0.5 + (px + u1) / ks.camera.width) * ks.camera.extent[0] + ks.camera.extent[2]
    cy = (0.5 - (py + u2) / ks.camera.height) * ks.camera.extent[1] + ks.camera.extent[3]
    if ks.camera.kind == CAMERA_PERSPECTIVE:
        ox, oy, oz = transform_point(ks.camera.to_world, 0.0, 0.0, 0.0)
        dx, dy, dz = transform_vector(ks.camera.to_world, cx, cy, -1.0)
    else:
        ox, oy, oz = transform_point(ks.camera.to_world, cx, cy, 0.0)
        dx, dy, dz = transform_vector(ks.camera.to_world, 0.0, 0.0, -1.0)
    dx, dy, dz = normalize(dx, dy, dz)
    return ox, oy, oz, dx, dy, dz


@shared
def camera_depths(to_world, kind, t, dx, dy, dz):
    """(camera-space depth, distance from the camera) of the point at t along a camera ray of unit direction d
    (Cycles' `camera_z_depth` and `camera_distance`): the depth is t (d · the view axis); the distance t for a
    perspective camera (its rays start at the camera), the depth for an orthographic one (they start on its
    film plane)."""
    ax, ay, az = -to_world[0, 2], -to_world[1, 2], -to_world[2, 2]
    depth = t * (dx * ax + dy * ay + dz * az) / sqrt(ax * ax + ay * ay + az * az)
    return depth, t if kind == CAMERA_PERSPECTIVE else depth
