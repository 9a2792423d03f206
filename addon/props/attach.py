"""Attaches the settings to Blender's types as `.spectral` pointers (and removes them again)."""

import bpy

from .light import SpectralLightSettings, SpectralWorldSettings
from .material import SpectralMaterialSettings
from .render import SpectralObjectSettings, SpectralRenderSettings

CLASSES = ()
ATTACHMENTS = (
    (bpy.types.Scene, SpectralRenderSettings),
    (bpy.types.Material, SpectralMaterialSettings),
    (bpy.types.Light, SpectralLightSettings),
    (bpy.types.World, SpectralWorldSettings),
    (bpy.types.Object, SpectralObjectSettings),
)


def register_extras():
    for owner, settings in ATTACHMENTS:
        owner.spectral = bpy.props.PointerProperty(type=settings, name="Spectral")


def unregister_extras():
    for owner, _settings in ATTACHMENTS:
        del owner.spectral
