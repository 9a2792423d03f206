"""Small scenes built in code for tracer tests (no files): the shared builders (addon.tracer.builders)
and the tests' cameras, which look straight down the z axis at the origin."""

import numpy as np

from addon.tracer.builders import (  # noqa: F401 (the tests' scenes)
    box_grid, environment, envmap, medium, parallelogram, sampled_grid, scene, smooth_ramp, sun)
from addon.tracer.scene import Camera


def look_down_z(height=6.0) -> np.ndarray:
    """Camera matrix at (0, 0, height) looking down −z (Blender cameras look along local −z)."""
    matrix = np.eye(4)
    matrix[2, 3] = height
    return matrix


def ortho_camera(width=8, height=8, scale=0.5, distance=6.0) -> Camera:
    return Camera(to_world=look_down_z(distance), width=width, height=height, kind="orthographic",
                  ortho_scale=scale)


def perspective_camera(width=16, height=16, fov_degrees=30.0, distance=6.0) -> Camera:
    return Camera(to_world=look_down_z(distance), width=width, height=height, fov=np.radians(fov_degrees))
