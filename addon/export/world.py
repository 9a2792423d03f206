"""The scene's World → a tracer light: Blender's own World as Cycles lights with it, or the Spectral World.

With the World's Spectral World on, its spectral settings (a uniform environment or a sky, in their
unit) replace Blender's World. Otherwise the World's node tree is read: a Background (or Emission) node
on the active output gives a uniform environment of radiance Color × Strength (the colour as an emission
spectrum, `tracer.spectra.emission_from_rgb`). Not yet rendered as set, and named in the render report:
an Environment Texture (rendered uniform, at the image's mean colour over the sphere) and a Sky Texture
(not rendered).
"""

import numpy as np

from ..props.spectrum_values import to_spectrum
from ..tracer import spectra
from ..tracer.scene import Light
from ..nodes.graph import Blackbody, colour, number, output_source, source

BACKGROUNDS = ("ShaderNodeBackground", "ShaderNodeEmission")


def _spectral_world(world) -> Light:
    settings = world.spectral
    horizon = to_spectrum(settings.horizon) if settings.kind == "sky" else None
    return Light(kind=settings.kind, spectrum=to_spectrum(settings.spectrum), strength=settings.strength,
                 horizon_spectrum=horizon, name=world.name, unit=settings.unit)


def _srgb_to_linear(values: np.ndarray) -> np.ndarray:
    return np.where(values <= 0.04045, values / 12.92, ((values + 0.055) / 1.055) ** 2.4)


MAX_MAP_WIDTH = 2048  # wider HDRIs are averaged down (by whole texel blocks) to at most this width


def image_rgb(image) -> np.ndarray | None:
    """An image's linear Rec.709 pixels (height, width, 3), top row first, at most MAX_MAP_WIDTH wide
    (blocks of texels averaged); None when it has no pixels. 8-bit sRGB images are linearised."""
    width, height = image.size
    if width == 0 or height == 0:
        return None
    pixels = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, width, image.channels)[::-1, :, :3]  # Blender stores the bottom row first
    if not image.is_float and image.colorspace_settings.name == "sRGB":
        rgb = _srgb_to_linear(rgb.astype(np.float64)).astype(np.float32)
    step = -(-width // MAX_MAP_WIDTH)
    if step > 1:
        rows, columns = height // step * step, width // step * step
        rgb = rgb[:rows, :columns].reshape(rows // step, step, columns // step, step, 3).mean(axis=(1, 3))
    return np.ascontiguousarray(np.maximum(rgb, 0.0), dtype=np.float32)


def image_mean_colour(image) -> tuple[float, float, float] | None:
    """The mean linear RGB of an equirectangular image over the sphere (rows weighted by the cosine of
    their latitude), or None when it has no pixels."""
    rgb = image_rgb(image)
    if rgb is None:
        return None
    height, width = rgb.shape[:2]
    latitude = (np.arange(height) + 0.5) / height * np.pi - np.pi / 2
    weights = np.cos(latitude)[:, None, None]
    return tuple((rgb.astype(np.float64) * weights).sum(axis=(0, 1)) / (weights.sum() * width))


def _background_colour(node, owner: str, notes):
    """The background's colour as RGB or Blackbody, or None when it is not rendered."""
    found = source(node.inputs["Color"])
    if found is not None and found[0].bl_idname == "ShaderNodeTexEnvironment":
        texture = found[0]
        mean = None if texture.image is None else image_mean_colour(texture.image)
        if mean is None:
            notes.leave_out("World texture", f"{texture.name} of {owner}, no image")
            return None
        notes.add(f"{owner} ▸ {texture.name}: the HDRI is rendered as a uniform World of its mean colour "
                  f"({', '.join(f'{value:.3g}' for value in mean)})")
        return mean
    if found is not None and found[0].bl_idname == "ShaderNodeTexSky":
        notes.leave_out("World texture", f"{found[0].name} of {owner}")
        return None
    return colour(node, "Color", owner, notes)


def _emission_spectrum(value) -> spectra.Spectrum:
    if isinstance(value, Blackbody):
        return spectra.blackbody_of_luminance_one(max(value.temperature, 1.0))
    return spectra.emission_from_rgb(np.maximum(value, 0.0))


def export_world(world, notes) -> Light | None:
    """The light of the scene's World, or None when it gives none (no World, black, or not rendered)."""
    if world is None:
        return None
    if world.spectral.enabled:
        return _spectral_world(world)
    owner = f"World {world.name!r}"
    found = output_source(world.node_tree, "Surface")
    if found is None:
        return None
    node = found[0]
    if node.bl_idname not in BACKGROUNDS:
        notes.leave_out("World shader", f"{owner} ▸ {node.name}")
        return None
    value = _background_colour(node, owner, notes)
    strength = max(float(number(node, "Strength", owner, notes)), 0.0)
    if value is None or strength == 0.0:
        return None
    return radiant_light("environment", _emission_spectrum(value), strength, name=world.name)


def radiant_light(kind: str, spectrum: spectra.Spectrum, factor: float, **fields) -> Light | None:
    """A light whose radiometric spectrum is `factor` × `spectrum` exactly, whatever the render's colour
    matching functions (the radiant unit: strength is the integral), or None when that is zero."""
    integral = spectrum.integral()
    if not integral > 0 or not factor > 0:
        return None
    return Light(kind=kind, spectrum=spectrum, strength=factor * integral, unit="radiant", **fields)
