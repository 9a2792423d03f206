"""Light and World spectra and units.

Off by default: a light renders with Blender's Color and Temperature, the World with Blender's World
(addon/export/lights.py, world.py). Turned on, a light's spectrum replaces its colour; its brightness
stays Blender's own Power (point, spot, in W) or Strength (sun, in W/m²), and its Unit says whether that
number is luminous (the visible part sets it, as for Cycles' white light) or radiant (watts over the
whole spectrum, visible or not: a UV lamp). The Spectral World replaces Blender's World with uniform
environment light or a sky that blends a zenith and a horizon spectrum. Turning either on starts its
spectrum from the current colour (`starting_colour`), so the image does not jump.
"""

import bpy

from ..nodes.graph import output_source
from .spectrum import SpectralLightSpectrum

# The tracer's light units (tracer.scene.LIGHT_UNITS), for lights and the World.
UNIT_ITEMS = [
    ("luminous", "Luminous", "Strength sets the luminance: the visible light equals that of a white "
     "light of the same strength; a spectrum with no visible part cannot be scaled this way"),
    ("radiant", "Radiant", "Strength is radiant power in watts over the whole spectrum, visible or not "
     "(W/m² for a sun, W for a point or spot, W/m²/sr for the World): for UV lamps"),
]


def _start_light_from_colour(settings, _context) -> None:
    light = settings.id_data
    if settings.enabled:
        starting_colour(settings.spectrum, light.color)


def _start_world_from_colour(settings, _context) -> None:
    if settings.enabled:
        rgb, strength = world_colour(settings.id_data)
        starting_colour(settings.spectrum, rgb)
        settings.kind, settings.unit = "environment", "luminous"
        settings.strength = strength * (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])  # Rec.709 Y


def world_colour(world) -> tuple[tuple, float]:
    """(RGB, strength) of a World's Background node (its socket values), else its viewport colour."""
    found = output_source(world.node_tree, "Surface")
    node = None if found is None else found[0]
    if node is not None and "Color" in node.inputs and "Strength" in node.inputs:
        return tuple(node.inputs["Color"].default_value[:3]), float(node.inputs["Strength"].default_value)
    return tuple(world.color), 1.0


def starting_colour(spectrum, rgb) -> None:
    """Set a light spectrum setting to the colour `rgb` (scaled into [0, 1]; the strength keeps the size)."""
    peak = max(max(rgb), 1e-9)
    spectrum.source = "COLOR"
    spectrum.color = tuple(min(max(value / peak, 0.0), 1.0) for value in rgb)


class SpectralLightSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(name="Spectral Light", default=False, update=_start_light_from_colour,
                                    description="Light with the spectrum below instead of the light's Color "
                                                "(starts from that color)")
    spectrum: bpy.props.PointerProperty(type=SpectralLightSpectrum, name="Spectrum",
                                        description="The light's spectrum, in place of its color")
    unit: bpy.props.EnumProperty(name="Unit", description="What the light's Strength or Power measures",
                                 items=UNIT_ITEMS, default="luminous")
    curve_group: bpy.props.PointerProperty(type=bpy.types.NodeTree, name="Curves",
                                           description="Hidden node group holding this light's spectral curves")


class SpectralWorldSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(name="Spectral World", default=False, update=_start_world_from_colour,
                                    description="Light the scene with the spectral world below instead of "
                                                "Blender's World (starts from the World's color)")
    kind: bpy.props.EnumProperty(name="Type", description="How the world light varies with direction", items=[
        ("environment", "Uniform", "The same light from every direction"),
        ("sky", "Sky", "Zenith spectrum overhead, blending into the horizon spectrum")], default="environment")
    spectrum: bpy.props.PointerProperty(type=SpectralLightSpectrum, name="Spectrum",
                                        description="The world light's spectrum (the zenith's, for a sky)")
    horizon: bpy.props.PointerProperty(type=SpectralLightSpectrum, name="Horizon",
                                       description="The sky's spectrum at the horizon")
    strength: bpy.props.FloatProperty(name="Strength", description="Brightness of the world light in its "
                                      "Unit: luminance Y (Luminous) or radiance in W/m²/sr over the whole "
                                      "spectrum (Radiant)", default=1.0, min=0.0, soft_max=10.0)
    unit: bpy.props.EnumProperty(name="Unit", description="What the world light's Strength measures",
                                 items=UNIT_ITEMS, default="luminous")
    curve_group: bpy.props.PointerProperty(type=bpy.types.NodeTree, name="Curves",
                                           description="Hidden node group holding the world's spectral curves")


CLASSES = (SpectralLightSettings, SpectralWorldSettings)
