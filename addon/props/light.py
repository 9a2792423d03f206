"""Light and World spectra.

A light's spectrum replaces its colour; its brightness stays Blender's own Power (point, spot, in W)
or Strength (sun, in W/m²), converted as described in addon/export/lights.py. The World is uniform
environment light or a sky that blends a zenith and a horizon spectrum.
"""

import bpy

from .spectrum import SpectralLightSpectrum


class SpectralLightSettings(bpy.types.PropertyGroup):
    spectrum: bpy.props.PointerProperty(type=SpectralLightSpectrum, name="Spectrum",
                                        description="The light's spectrum, in place of its color")
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
    strength: bpy.props.FloatProperty(name="Strength", description="Luminance of the world light",
                                      default=1.0, min=0.0, soft_max=10.0)
    curve_group: bpy.props.PointerProperty(type=bpy.types.NodeTree, name="Curves",
                                           description="Hidden node group holding the world's spectral curves")


CLASSES = (SpectralLightSettings, SpectralWorldSettings)
