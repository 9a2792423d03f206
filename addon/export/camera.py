"""Blender camera and render resolution → tracer Camera, for the whole frame or its Render Region.

Our Camera follows Blender's conventions, so most fields copy over: it looks down its local −Z with +Y
up, `fov` / `ortho_scale` span the sensor-fit axis (AUTO: the larger axis of the frame, whose aspect is
resolution × pixel aspect), and shifts are in units of that span. The camera object's scale is dropped (Blender ignores it too).

With Render Region on, the camera sees only the region: its frustum is the part of the frame's frustum
behind the region's pixels (a narrower span and a shift), so its image is those pixels of the full frame.
The region's pixels are Blender's own: border × size, rounded down.
"""

import dataclasses
import math

import numpy as np
from mathutils import Matrix

from ..tracer.lowering import camera_extent
from ..tracer.errors import SpectralError
from ..tracer.scene import Camera


@dataclasses.dataclass(frozen=True)
class Region:
    """The pixels a Render Region covers: `x`, `y` of its lower-left pixel in the full frame of
    `full_width` × `full_height`. (Blender itself crops the image to it, or places it in the frame.)"""

    x: int
    y: int
    width: int
    height: int
    full_width: int
    full_height: int


def resolution(scene) -> tuple[int, int]:
    """Output size in pixels: resolution × percentage, as Blender renders it (integer arithmetic)."""
    render = scene.render
    return (max(1, render.resolution_x * render.resolution_percentage // 100),
            max(1, render.resolution_y * render.resolution_percentage // 100))


def render_region(scene) -> Region | None:
    """The scene's Render Region, or None when it is off or covers the whole frame."""
    render = scene.render
    if not render.use_border:
        return None
    width, height = resolution(scene)
    # Blender multiplies in single precision and truncates.
    x0, x1 = (int(np.float32(border) * np.float32(width)) for border in (render.border_min_x, render.border_max_x))
    y0, y1 = (int(np.float32(border) * np.float32(height)) for border in (render.border_min_y, render.border_max_y))
    if x1 - x0 < 1 or y1 - y0 < 1:
        raise SpectralError("the Render Region is empty: draw a larger region (Ctrl B) or turn it off")
    if (x0, y0, x1, y1) == (0, 0, width, height):
        return None
    return Region(x0, y0, x1 - x0, y1 - y0, width, height)


def camera_to_world(matrix_world) -> np.ndarray:
    """C-ordered (NumPy makes Fortran-ordered arrays of mathutils matrices, and the Numba kernel would
    compile a second specialisation for them)."""
    location, rotation, _scale = matrix_world.decompose()
    return np.ascontiguousarray(np.array(Matrix.LocRotScale(location, rotation, None), dtype=np.float64))


def region_camera(camera: Camera, region: Region) -> Camera:
    """The camera that sees `region` of the frame `camera` sees."""
    extent_x, extent_y, offset_x, offset_y = camera_extent(camera)
    centre_x = offset_x + ((region.x + region.width / 2) / region.full_width - 0.5) * extent_x
    centre_y = offset_y + ((region.y + region.height / 2) / region.full_height - 0.5) * extent_y
    span = extent_x * region.width / region.full_width
    return dataclasses.replace(camera, width=region.width, height=region.height, sensor_fit="HORIZONTAL",
                               fov=2.0 * math.atan(span / 2.0), ortho_scale=span,
                               shift_x=centre_x / span, shift_y=centre_y / span)


def export_camera(scene, camera_object=None) -> Camera:
    """The (evaluated) scene's camera for its whole frame, or for its Render Region when that is on."""
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
    camera = Camera(
        to_world=camera_to_world(camera_object.matrix_world),
        width=width,
        height=height,
        kind="perspective" if data.type == "PERSP" else "orthographic",
        fov=2.0 * math.atan(sensor / (2.0 * data.lens)),
        ortho_scale=data.ortho_scale,
        sensor_fit=data.sensor_fit,
        shift_x=data.shift_x,
        shift_y=data.shift_y,
        pixel_aspect=scene.render.pixel_aspect_x / scene.render.pixel_aspect_y,
    )
    region = render_region(scene)
    return camera if region is None else region_camera(camera, region)
