"""Operators that apply a light-spectrum or material preset."""

import bpy

from .. import presets
from .targets import TargetProperties, resolve


def _items(table):
    return [(key, label, f"Apply the {label} preset") for key, (label, _values) in table.items()]


class SPECTRAL_OT_apply_light_preset(TargetProperties, bpy.types.Operator):
    """Set this light spectrum from a preset"""

    bl_idname = "spectral.apply_light_preset"
    bl_label = "Apply Light Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: bpy.props.EnumProperty(name="Preset", description="The light spectrum to apply",
                                   items=_items(presets.LIGHT_PRESETS))

    def execute(self, context):
        settings = resolve(self)
        if settings is None:
            self.report({"ERROR"}, "The light spectrum no longer exists")
            return {"CANCELLED"}
        presets.apply(settings, presets.LIGHT_PRESETS[self.preset][1])
        return {"FINISHED"}


class SPECTRAL_OT_apply_material_preset(bpy.types.Operator):
    """Set the active material's spectral volume settings from a preset"""

    bl_idname = "spectral.apply_material_preset"
    bl_label = "Apply Material Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: bpy.props.EnumProperty(name="Preset", description="The volume material to apply",
                                   items=_items(presets.MATERIAL_PRESETS))

    @classmethod
    def poll(cls, context):
        return getattr(context, "material", None) is not None

    def execute(self, context):
        settings = context.material.spectral
        presets.apply(settings, presets.MATERIAL_PRESETS[self.preset][1])
        settings.enabled = True
        return {"FINISHED"}


CLASSES = (SPECTRAL_OT_apply_light_preset, SPECTRAL_OT_apply_material_preset)
