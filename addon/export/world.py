"""The scene's World → a tracer light: Blender's own World as Cycles lights with it, or the Spectral World.

With the World's Spectral World on, its spectral settings (a uniform environment or a sky, in their
unit) replace Blender's World. Otherwise the World's node tree is read: a Background (or Emission) node
on the active output gives a uniform environment of radiance Color × Strength (the colour as an emission
spectrum, `tracer.spectra.emission_from_rgb`), or, with an Environment Texture as its Color, an envmap
light: the image (equirectangular, nearest texel, at most MAX_MAP_WIDTH wide), each texel's RGB on the
emission spectra of pure R, G and B, turned by a Mapping node's rotation, importance-sampled. With a Sky
Texture as its Color, its Nishita models (Single and Multiple Scattering) are evaluated as Cycles evaluates
them (`tracer.sky_model`), and its Preetham model too: the sky as such an envmap (SKY_MAP_WIDTH wide) and its
sun disc as a sun light of the disc's irradiance and angular size; a Hosek / Wilkie sky is named in the
render report as not rendered.
"""

from functools import lru_cache

import numpy as np
from mathutils import Euler

from ..props.spectrum_values import to_spectrum
from ..tracer import spectra
from ..tracer.scene import Light
from ..tracer.sky_model import MODELS as SKY_MODELS, Sky, SkyParameters
from ..nodes.graph import colour, emission_spectrum, number, output_source, source

BACKGROUNDS = ("ShaderNodeBackground", "ShaderNodeEmission")


def _spectral_world(world) -> Light:
    settings = world.spectral
    horizon = to_spectrum(settings.horizon) if settings.kind == "sky" else None
    return Light(kind=settings.kind, spectrum=to_spectrum(settings.spectrum), strength=settings.strength,
                 horizon_spectrum=horizon, name=world.name, unit=settings.unit)


def _srgb_to_linear(values: np.ndarray) -> np.ndarray:
    return np.where(values <= 0.04045, values / 12.92, ((values + 0.055) / 1.055) ** 2.4)


MAX_MAP_WIDTH = 2048  # wider HDRIs are averaged down (by whole texel blocks) to at most this width


def srgb_bytes(image) -> bool:
    """Whether an image's pixels are 8-bit sRGB-encoded (what `image_rgb` linearises)."""
    return not image.is_float and image.colorspace_settings.name == "sRGB"


def image_rgb(image, decode: bool = True) -> np.ndarray | None:
    """An image's linear Rec.709 pixels (height, width, 3), top row first, at most MAX_MAP_WIDTH wide
    (blocks of texels averaged); None when it has no pixels. 8-bit sRGB images are linearised (`decode`), or,
    without `decode`, left encoded."""
    width, height = image.size
    if width == 0 or height == 0:
        return None
    pixels = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, width, image.channels)[::-1, :, :3]  # Blender stores the bottom row first
    if decode and srgb_bytes(image):
        rgb = _srgb_to_linear(rgb.astype(np.float64)).astype(np.float32)
    step = -(-width // MAX_MAP_WIDTH)
    if step > 1:
        rows, columns = height // step * step, width // step * step
        rgb = rgb[:rows, :columns].reshape(rows // step, step, columns // step, step, 3).mean(axis=(1, 3))
    return np.ascontiguousarray(np.maximum(rgb, 0.0), dtype=np.float32)


def _map_to_world(texture, owner: str, notes) -> np.ndarray:
    """The envmap's `to_world` from a Mapping node feeding the texture's Vector (identity without one): Cycles
    reads the map at R·ω for a Point or Vector mapping, at R⁻¹·ω for a Texture one, so the map's frame turns
    to the world by Rᵀ or R. Location and scale, which do not turn directions, are noted when set."""
    vector = next(socket for socket in texture.inputs if socket.identifier == "Vector")  # by name only if shown
    found = source(vector)
    if found is None:
        return np.eye(3)
    mapping = found[0]
    if mapping.bl_idname != "ShaderNodeMapping":
        notes.add(f"{owner} ▸ {texture.name} ▸ Vector is driven by {mapping.name!r}, which cannot be converted: "
                  "the map is not turned")
        return np.eye(3)
    rotation = np.array(Euler(mapping.inputs["Rotation"].default_value).to_matrix(), dtype=np.float64)
    if mapping.inputs["Location"].is_linked or mapping.inputs["Rotation"].is_linked \
            or mapping.inputs["Scale"].is_linked or np.ptp(mapping.inputs["Scale"].default_value) > 1e-6:
        notes.add(f"{owner} ▸ {mapping.name}: only a constant rotation turns the map (driven inputs or an "
                  "unequal scale are not rendered)")
    return rotation if mapping.vector_type == "TEXTURE" else rotation.T


def _environment_map(texture, strength: float, world, owner: str, notes) -> Light | None:
    """The envmap light of an Environment Texture (equirectangular), or None (named) without an image."""
    rgb = None if texture.image is None else image_rgb(texture.image)
    if rgb is None:
        notes.leave_out("World texture", f"{texture.name} of {owner}, no image")
        return None
    if texture.projection != "EQUIRECTANGULAR":
        notes.add(f"{owner} ▸ {texture.name}: {texture.projection.replace('_', ' ').title()} projection rendered "
                  "as Equirectangular")
    if texture.interpolation != "Closest":
        notes.add(f"{owner} ▸ {texture.name}: {texture.interpolation} interpolation rendered as Closest")
    return _rgb_envmap(rgb, _map_to_world(texture, owner, notes), strength, world)


def _rgb_envmap(rgb: np.ndarray, to_world: np.ndarray, strength: float, world) -> Light:
    """An envmap of linear Rec.709 texels, each on the emission spectra of pure R, G and B."""
    basis = tuple(spectra.emission_from_rgb(primary) for primary in np.eye(3))
    return Light(kind="envmap", image=rgb, basis=basis, to_world=to_world, strength=strength, unit="radiant",
                 name=world.name)


SKY_MAP_WIDTH = 1024  # texels around the horizon of a Sky Texture's envmap (Cycles tabulates 512)


def _sky(texture, strength: float, world, owner: str, notes) -> list[Light]:
    """A Sky Texture's lights: the sky as an envmap and its sun disc as a sun light (`tracer.sky_model`), both
    turned by a Mapping node as an HDRI is; none (named) for a model the tracer does not evaluate."""
    if texture.sky_type not in SKY_MODELS:
        model = texture.bl_rna.properties["sky_type"].enum_items[texture.sky_type].name
        notes.leave_out("World texture", f"{texture.name} of {owner}, {model} model")
        return []
    image, irradiance, sun, sun_size = _evaluated_sky(SkyParameters(
        model=texture.sky_type, sun_elevation=texture.sun_elevation, sun_rotation=texture.sun_rotation,
        altitude=texture.altitude, air=texture.air_density, aerosol=texture.aerosol_density,
        ozone=texture.ozone_density, sun_disc=texture.sun_disc, sun_size=texture.sun_size,
        sun_intensity=texture.sun_intensity, sun_direction=tuple(texture.sun_direction),
        turbidity=texture.turbidity))
    to_world = _map_to_world(texture, owner, notes)
    lights = [_rgb_envmap(image, to_world, strength, world)]
    sun = radiant_light("sun", spectra.emission_from_rgb(irradiance), strength, direction=to_world @ sun,
                        angle=sun_size, name=f"{world.name} sun")
    return lights if sun is None else [*lights, sun]


@lru_cache(maxsize=4)
def _evaluated_sky(parameters: SkyParameters) -> tuple:
    """(the sky's envmap texels, read-only; the disc's irradiance RGB; the sun's direction; its angular
    diameter): a few seconds' work, kept for re-exports of the same sky (the viewport's)."""
    sky = Sky(parameters)
    image = sky.sky_map(SKY_MAP_WIDTH)
    image.flags.writeable = False
    return image, sky.sun_irradiance_rgb(), sky.sun, sky.sun_size


def _background(node, strength: float, world, owner: str, notes) -> list[Light]:
    """The lights of a background node (Background or Emission): an envmap from an Environment Texture, a sky
    and its sun from a Sky Texture, else a uniform environment of its colour; none when it gives none (named
    when not rendered)."""
    found = source(node.inputs["Color"])
    if found is not None and found[0].bl_idname == "ShaderNodeTexEnvironment":
        light = _environment_map(found[0], strength, world, owner, notes)
    elif found is not None and found[0].bl_idname == "ShaderNodeTexSky":
        return _sky(found[0], strength, world, owner, notes)
    else:
        value = colour(node, "Color", owner, notes)
        light = radiant_light("environment", emission_spectrum(value), strength, name=world.name)
    return [] if light is None else [light]


def export_world(world, notes) -> list[Light]:
    """The lights of the scene's World: none when it gives none (no World, black, or not rendered), else one,
    or a sky and its sun."""
    if world is None:
        return []
    if world.spectral.enabled:
        return [_spectral_world(world)]
    owner = f"World {world.name!r}"
    found = output_source(world.node_tree, "Surface")
    if found is None:
        return []
    node = found[0]
    if node.bl_idname not in BACKGROUNDS:
        notes.leave_out("World shader", f"{owner} ▸ {node.name}")
        return []
    strength = max(float(number(node, "Strength", owner, notes)), 0.0)
    return _background(node, strength, world, owner, notes) if strength > 0 else []


def radiant_light(kind: str, spectrum: spectra.Spectrum, factor: float, **fields) -> Light | None:
    """A light whose radiometric spectrum is `factor` × `spectrum` exactly, whatever the render's colour
    matching functions (the radiant unit: strength is the integral), or None when that is zero."""
    integral = spectrum.integral()
    if not integral > 0 or not factor > 0:
        return None
    return Light(kind=kind, spectrum=spectrum, strength=factor * integral, unit="radiant", **fields)
