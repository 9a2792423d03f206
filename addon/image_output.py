"""Where a finished render goes: a float Image datablock (linear Rec.709) and a multilayer EXR."""

import bpy

from .pixels import blender_rows, with_alpha
from .tracer import image_io

COLORSPACE = "Linear Rec.709"


def store_image(name: str, rgb):
    """Put linear Rec.709 pixels (height, width, 3; top row first) into the float Image `name`."""
    height, width = rgb.shape[:2]
    image = bpy.data.images.get(name)
    if image is None or not image.is_float or image.source != "GENERATED":
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    image.colorspace_settings.name = COLORSPACE
    image.pixels.foreach_set(blender_rows(with_alpha(rgb)).ravel())
    image.update()
    return image


def write_outputs(film, image_name: str, exr_path: str = "", layer: str = image_io.VIEW_LAYER):
    """The EXR (its passes in the render layer `layer`, as F12 names them) first, written to a temporary
    name and renamed, so a failure leaves the old file; then the image. Returns the image."""
    if exr_path:
        image_io.write_exr(bpy.path.abspath(exr_path), film.xyz, film.rgb(), film.variance, layer=layer)
    return store_image(image_name, film.rgb())
