"""A surface texture's image as the tracer reads it (`tracer.scene.Texture.image` and `srgb`): Blender's pixels,
clipped to the albedo's [0, 1], as Cycles reads them: an 8-bit sRGB image's bytes left encoded (Cycles decodes
them after interpolating, and so does the tracer: `Texture.srgb`), float and Non-Color images in linear Rec.709
(Cycles' scene-linear) as they are.

The pixels come from `world.image_rgb`, as an envmap's do: packed and generated images alike, images wider than
`world.MAX_MAP_WIDTH` averaged down by whole blocks of texels. An image without pixels (a missing file) and texels
above 1 are named in the render report.
"""

import numpy as np

from ..nodes.notes import Notes
from .world import MAX_MAP_WIDTH, image_rgb, srgb_bytes


def texture_image(image, where: str, notes: Notes) -> tuple[np.ndarray, bool] | None:
    """The (H, W, 3) float32 texels in [0, 1] of a Blender image, top row first, and whether they are sRGB-encoded;
    None (named) where it has no pixels."""
    encoded = srgb_bytes(image)
    rgb = image_rgb(image, decode=not encoded)
    if rgb is None:
        notes.add(f"{where}: image {image.name!r} has no pixels (is its file {image.filepath!r} missing?): "
                  "the texture is not rendered (its socket's value is)")
        return None
    if image.size[0] > MAX_MAP_WIDTH:
        notes.add(f"{where}: image {image.name!r} averaged down to {rgb.shape[1]} texels wide")
    if rgb.max() > 1.0:
        notes.add(f"{where}: image {image.name!r} has texels above 1, rendered as 1 (an albedo)")
    return np.minimum(rgb, 1.0), encoded
