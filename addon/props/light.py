"""Light and World spectra and units.

A light's spectrum replaces its colour; its brightness stays Blender's own Power (point, spot, in W)
or Strength (sun, in W/m²), converted as described in addon/export/lights.py, and its Unit says whether
that number is luminous (the visible part sets it, as for Cycles' white light) or radiant (watts over
the whole spectrum, visible or not: a UV lamp). The World is uniform environment light or a sky that
blends a zenith and a horizon spectrum.
"""

import bpy

from .spectrum import SpectralLightSpectrum

# The tracer's light units (tracer.scene.LIGHT_UNITS), for lights and the World.
UNIT_ITEMS = [
    ("luminous", "Luminous", "Strength sets the luminance: the visible light equals that of a white "
     "light of the same strength; a spectrum with no visible part cannot be scaled this way"),
    ("radiant", "Radiant", "Strength is radiant power in watts over the whole spectrum, visible or not "
     "(W/m² for a sun, W for a point or spot, W/m²/sr for the World): for UV lamps"),
]


class SpectralLightSettings(bpy.types.PropertyGroup):
    spectrum: bpy.props.PointerProperty(type=SpectralLightSpectrum, name="Spectrum",
                                        description="The light's spectrum, in place of its color")
    unit: bpy.props.EnumProperty(name="Unit", description="What the light's Strength or Power measures",
                                 items=UNIT_ITEMS, default="luminous")
    curve_group: bpy.props.PointerProperty(type=bpy.types.NodeTree, name="Curves",
                                           description="Hidden node group holding this light's spectral curves")


class SpectralWorldSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(name="Spectral World", description="Light the scene from the world",
                                    default=True)
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
