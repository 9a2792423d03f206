"""Attaches the settings to Blender's types as `.spectral` pointers (and removes them again)."""

import bpy

from .light import LightSettings, WorldSettings
from .material import VolumeMaterialSettings
from .render import ObjectVolumeSettings, SpectralRenderSettings

CLASSES = ()
ATTACHMENTS = (
    (bpy.types.Scene, SpectralRenderSettings),
    (bpy.types.Material, VolumeMaterialSettings),
    (bpy.types.Light, LightSettings),
    (bpy.types.World, WorldSettings),
    (bpy.types.Object, ObjectVolumeSettings),
)


def register_extras():
    for owner, settings in ATTACHMENTS:
        owner.spectral = bpy.props.PointerProperty(type=settings, name="Spectral")


def unregister_extras():
    for owner, _settings in ATTACHMENTS:
        del owner.spectral
