"""Where a render's film goes in Blender: the Render Result's passes (F12), a float Image datablock (linear
Rec.709) and multilayer EXR files (Render to Image, the command line), all named and laid out alike; and its spectral
image, a file of its own next to the render output (`spectral_exr_path`), at the film's size.

Pixels go to Blender bottom row first, one flat float32 array per image (`blender_rows`). A Render Result
is the size of the film (with Render Region on, Blender crops or places it); an image and an EXR are each
the size Blender's own render would have: with Render Region on and Crop to Render Region off, the film
(the region) is placed in the full frame, empty (alpha 0) outside, as Blender places it (`placement`).
"""

import os
from typing import NamedTuple

import bpy
import numpy as np

from .export.camera import Region, render_region
from .tracer import denoise, image_io, spectral_film
from .tracer.image_io import COMBINED, VARIANCE, XYZ
from .tracer.passes import DEPTH, NO_HIT_DEPTH, PassImages

COLORSPACE = "Linear Rec.709"


class Passes(NamedTuple):
    """A render's passes as images (height, width, channels; top row first); alpha has no channel axis."""

    xyz: np.ndarray
    rgb: np.ndarray
    variance: np.ndarray
    alpha: np.ndarray


def blender_rows(image: np.ndarray) -> np.ndarray:
    """(height, width, channels), top row first → (height · width, channels), bottom row first, float32."""
    height, width, channels = image.shape
    return np.ascontiguousarray(image[::-1].reshape(height * width, channels), dtype=np.float32)


def with_alpha(rgb: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """RGB → RGBA; `alpha` (height, width) defaults to 1 (the film's alpha is 1 everywhere unless Film ▸
    Transparent is on or a holdout is seen, `Film.alpha`)."""
    alpha = np.ones(rgb.shape[:2]) if alpha is None else alpha
    return np.concatenate([rgb, alpha[..., None]], axis=2)


def placement(scene) -> Region | None:
    """Where the film of the scene's render goes in its image: the Render Region when the region is placed
    in the full frame, None when the film is the whole image (no region, or cropped to it). Ask before
    rendering: it describes the render as exported."""
    return None if scene.render.use_crop_to_border else render_region(scene)


def denoising(settings) -> tuple[bool, str]:
    """Whether the final image is denoised (the Render settings' Denoise, where Open Image Denoise loads),
    and a warning for the user when Denoise is on but cannot run here ("" otherwise)."""
    if not settings.denoise:
        return False, ""
    if denoise.available():
        return True, ""
    return False, f"Denoise skipped: {denoise.unavailable_reason()}"


def passes(film, region: Region | None = None, denoised: bool = False) -> Passes:
    """The film's passes, placed at `region` in a frame of zeros when one is given; with `denoised`, the RGB
    (Combined) image is denoised (addon/tracer/denoise.py) while XYZ and variance stay as rendered."""
    rgb = denoise.denoised_rgb(film) if denoised else film.rgb()
    rendered = Passes(film.xyz, rgb, film.variance, film.alpha)
    if region is None:
        return rendered
    return Passes(*(placed(image, region) for image in rendered))


def placed(image: np.ndarray, region: Region | None, fill: float = 0.0) -> np.ndarray:
    """`image` (the film's rows and columns first) placed at `region` in a frame of `fill`, as Blender places a
    Render Region that is not cropped; `image` itself without a region."""
    if region is None:
        return image
    top = region.full_height - region.y - region.height  # Region counts rows from the bottom
    frame = np.full((region.full_height, region.full_width) + image.shape[2:], fill, dtype=image.dtype)
    frame[top:top + region.height, region.x:region.x + region.width] = image
    return frame


def render_result(result, film, preview: bool = False) -> None:
    """Film → the passes of a Render Result (`RenderEngine.begin_result`'s): Combined, and unless this is a
    preview (an update during the render) XYZ and XYZ Variance (the variance costs most to convert:
    0.2–0.5 s at 1920×1080, time a cancel would wait). Pixels go in with `foreach_set`: assigning `rect`
    took 7–10 s per pass at 1920×1080. The engine then calls `update_result`."""
    render_combined(result, film.rgb(), film.alpha)
    if not preview:
        _render_pass(result, XYZ, film.xyz)
        _render_pass(result, VARIANCE, film.variance)


def render_combined(result, rgb: np.ndarray, alpha: np.ndarray) -> None:
    """Linear Rec.709 `rgb` (height, width, 3; top row first), premultiplied by `alpha` (height, width) → the
    Render Result's Combined pass (RGBA: the Render Layers node's Image and Alpha)."""
    _render_pass(result, COMBINED, with_alpha(rgb, alpha))


def _render_pass(result, name: str, image: np.ndarray) -> None:
    result.layers[0].passes[name].rect.foreach_set(blender_rows(image).ravel())


def exr(path, images: Passes, layer: str, data: PassImages | None = None) -> image_io.Output:
    """The multilayer EXR of `images` and the data passes `data`, its channels in the render layer `layer`, as
    F12 names them."""
    return image_io.exr(path, images.xyz, images.rgb, images.variance, images.alpha, layer, data)


SPECTRAL_SUFFIX = "_spectral.exr"


def spectral_exr_path(scene, frame: int, animation: bool = False) -> str:
    """Where a frame's spectral EXR goes: the render output's path (Output Properties ▸ Output) as Blender saves the
    image, its file extension replaced by `_spectral.exr`: for an animation, the path of `frame` (its number
    added, or put in place of its `#`s); for a still, the path as it is (a folder: the frame's file in it)."""
    path = bpy.path.abspath(scene.render.filepath)
    if animation or not os.path.basename(path):
        path = bpy.path.abspath(scene.render.frame_path(frame=frame))
    return os.path.splitext(path)[0] + SPECTRAL_SUFFIX


def write_spectral_exr(scene, film, tracer_scene, animation: bool = False, region: Region | None = None) -> str:
    """Render ▸ Passes ▸ Spectral EXR: the film's spectral image written next to the render output of the scene's
    current frame (`spectral_exr_path`), placed at `region` as the image is (`placement`); returns its path."""
    path = spectral_exr_path(scene, scene.frame_current, animation)
    image_io.write_all([spectral_exr(path, film, tracer_scene, region)])
    return path


def spectral_exr(path, film, tracer_scene, region: Region | None = None) -> image_io.Output:
    """The film's spectral image (`Film.spectrum`) as an EXR in the layout of Fichet et al. 2021, with its linear
    Rec.709 RGB and alpha beside it, in the radiance units of `tracer_scene`'s sources (`spectral_film`); placed at
    `region` in a frame of zeros (alpha 0) as the render's image is (`placement`)."""
    return image_io.spectral_exr(bpy.path.abspath(str(path)), placed(film.spectrum, region),
                                 film.spectrum_edges, spectral_film.radiance_units(tracer_scene),
                                 placed(film.rgb(), region), placed(film.alpha, region))


def data_passes(data: PassImages, region: Region | None = None) -> PassImages:
    """The data passes, placed at `region` in a frame as `passes` places the image, with F12's values outside:
    Depth 1e10 (no surface), every other pass 0."""
    if region is None:
        return data
    images = {name: placed(image, region, NO_HIT_DEPTH if name == DEPTH else 0.0) for name, image in data.images.items()}
    return PassImages(images, data.mattes)


def render_data_passes(result, data: PassImages) -> None:
    """The data passes → the Render Result's passes of the same names (registered by the engine)."""
    for name, image in data.images.items():
        _render_pass(result, name, image)


def stamp_metadata(full_result, data: PassImages, layer: str) -> None:
    """Cryptomatte's manifests of render layer `layer` into the metadata (stamp data) of the whole Render Result
    (`RenderEngine.get_result()`, as Cycles stamps it): F12's EXR header, which the Cryptomatte node reads."""
    for key, value in data.metadata(layer).items():
        full_result.stamp_data_add_field(key, value)


def store_image(name: str, rgb, alpha=None):
    """Put linear Rec.709 pixels (height, width, 3; top row first) and `alpha` (default 1) into the float
    Image `name`."""
    height, width = rgb.shape[:2]
    image = bpy.data.images.get(name)
    if image is None or not image.is_float or image.source != "GENERATED":
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    image.colorspace_settings.name = COLORSPACE
    image.pixels.foreach_set(blender_rows(with_alpha(rgb, alpha)).ravel())
    image.update()
    return image


def write_outputs(film, image_name: str, exr_path: str = "", layer: str = image_io.VIEW_LAYER,
                  region: Region | None = None, denoised: bool = False, data: PassImages | None = None):
    """The EXR (see `exr`, with the data passes `data`) first, written to a temporary name and renamed, so a
    failure leaves the old file; then the image. `region`: see `placement`; `denoised`: see `passes`. Returns
    the image."""
    images = passes(film, region, denoised)
    if exr_path:
        placed = None if data is None else data_passes(data, region)
        image_io.write_all([exr(bpy.path.abspath(exr_path), images, layer, placed)])
    return store_image(image_name, images.rgb, images.alpha)
