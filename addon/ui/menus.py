"""Preset menus: light spectra (for the spectrum in `context.spectral_spectrum`) and materials."""

import bpy

from .. import presets
from ..operators.targets import point_at


class SPECTRAL_MT_light_presets(bpy.types.Menu):
    bl_label = "Light Spectrum Presets"
    bl_idname = "SPECTRAL_MT_light_presets"

    def draw(self, context):
        settings = getattr(context, "spectral_spectrum", None)
        if settings is None:
            self.layout.label(text="No light spectrum here")
            return
        for key, (label, _values) in presets.LIGHT_PRESETS.items():
            operator = self.layout.operator("spectral.apply_light_preset", text=label)
            operator.preset = key
            point_at(operator, settings)


class SPECTRAL_MT_material_presets(bpy.types.Menu):
    bl_label = "Spectral Material Presets"
    bl_idname = "SPECTRAL_MT_material_presets"

    def draw(self, context):
        for key, (label, _values) in presets.MATERIAL_PRESETS.items():
            self.layout.operator("spectral.apply_material_preset", text=label).preset = key


CLASSES = (SPECTRAL_MT_light_presets, SPECTRAL_MT_material_presets)
