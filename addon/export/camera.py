"""Blender camera and render resolution → tracer Camera.

Our Camera follows Blender's conventions, so most fields copy over: it looks down its local −Z with +Y
up, `fov` / `ortho_scale` span the sensor-fit axis (AUTO: the larger image axis), and shifts are in
units of that span. The camera object's scale is dropped (Blender ignores it too).
"""

import math

import numpy as np
from mathutils import Matrix

from ..tracer.errors import SpectralError
from ..tracer.scene import Camera


def resolution(scene) -> tuple[int, int]:
    """Output size in pixels: resolution × percentage, as Blender renders it."""
    render = scene.render
    scale = render.resolution_percentage / 100.0
    return max(1, int(render.resolution_x * scale)), max(1, int(render.resolution_y * scale))


def camera_to_world(matrix_world) -> np.ndarray:
    """C-ordered (NumPy makes Fortran-ordered arrays of mathutils matrices, and the Numba kernel would
    compile a second specialisation for them)."""
    location, rotation, _scale = matrix_world.decompose()
    return np.ascontiguousarray(np.array(Matrix.LocRotScale(location, rotation, None), dtype=np.float64))


def export_camera(scene, camera_object=None) -> Camera:
    camera_object = camera_object or scene.camera
    if camera_object is None:
        raise SpectralError(f"scene {scene.name!r} has no camera: add one and make it the active camera")
    if camera_object.type != "CAMERA":
        raise SpectralError(f"the scene camera {camera_object.name!r} is not a camera object")
    data = camera_object.data
    if data.type not in ("PERSP", "ORTHO"):
        raise SpectralError(f"camera {camera_object.name!r}: {data.type.lower()} cameras are not supported "
                            "(use perspective or orthographic)")
    width, height = resolution(scene)
    sensor = data.sensor_height if data.sensor_fit == "VERTICAL" else data.sensor_width
    return Camera(
        to_world=camera_to_world(camera_object.matrix_world),
        width=width,
        height=height,
        kind="perspective" if data.type == "PERSP" else "orthographic",
        fov=2.0 * math.atan(sensor / (2.0 * data.lens)),
        ortho_scale=data.ortho_scale,
        sensor_fit=data.sensor_fit,
        shift_x=data.shift_x,
        shift_y=data.shift_y,
    )
