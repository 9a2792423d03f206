"""Operators that add or remove a material's albedo levels (the albedo at higher densities)."""

import bpy

from ..props import curves


class SPECTRAL_OT_albedo_level_add(bpy.types.Operator):
    """Add an albedo spectrum at a higher density"""

    bl_idname = "spectral.albedo_level_add"
    bl_label = "Add Albedo Level"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return getattr(context, "material", None) is not None

    def execute(self, context):
        settings = context.material.spectral
        highest = max((level.density for level in settings.albedo_levels), default=0.0)
        level = settings.albedo_levels.add()
        level.density = highest + 1.0
        settings.albedo_index = len(settings.albedo_levels) - 1
        return {"FINISHED"}


class SPECTRAL_OT_albedo_level_remove(bpy.types.Operator):
    """Remove the active albedo level"""

    bl_idname = "spectral.albedo_level_remove"
    bl_label = "Remove Albedo Level"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        material = getattr(context, "material", None)
        return material is not None and len(material.spectral.albedo_levels) > 0

    def execute(self, context):
        settings = context.material.spectral
        curves.discard(settings.albedo_levels[settings.albedo_index].spectrum.curve)
        settings.albedo_levels.remove(settings.albedo_index)
        settings.albedo_index = max(0, min(settings.albedo_index, len(settings.albedo_levels) - 1))
        return {"FINISHED"}


CLASSES = (SPECTRAL_OT_albedo_level_add, SPECTRAL_OT_albedo_level_remove)
