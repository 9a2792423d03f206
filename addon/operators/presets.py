"""Add and remove the user's own light-spectrum and material presets (Blender's AddPresetBase, as Cycles'
sampling presets). Blender's `script.execute_preset` applies a preset; what a preset stores and how it is
written is `addon.presets`. Built-in presets cannot be removed."""

import os
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase

from .. import presets
from ..tracer.errors import SpectralError


class AddSpectralPreset(AddPresetBase):
    """The shared part: subclasses name the settings (`target`), the line that finds them when the preset
    runs (`define`), and what they are (`what`)."""

    define = ""
    what = ""

    @staticmethod
    def target(context):
        raise NotImplementedError

    def execute(self, context):
        adding = not (self.remove_name or self.remove_active)
        if adding and self.target(context) is None:
            self.report({"ERROR"}, f"No {self.what} here to save as a preset")
            return {"CANCELLED"}
        return super().execute(context)

    def add(self, context, filepath):
        note = f"Spectral Volume {self.what} preset: it sets every setting listed here"
        presets.write(filepath, self.target(context), self.define, note)

    def remove(self, context, filepath):
        if Path(filepath).resolve().is_relative_to(presets.BUILT_IN.resolve()):
            raise SpectralError(f"{bpy.path.display_name(Path(filepath).stem)!r} is a built-in preset: "
                                "it cannot be removed")
        os.remove(filepath)


class SPECTRAL_OT_light_preset_add(AddSpectralPreset, bpy.types.Operator):
    """Save this light spectrum as a preset, or remove one of yours (the wavelength window is not saved)"""

    bl_idname = "spectral.light_preset_add"
    bl_label = "Add Light Spectrum Preset"
    preset_menu = "SPECTRAL_PT_light_presets"
    preset_subdir = presets.LIGHT_SUBDIR
    define = "spectrum = bpy.context.spectral_spectrum"
    what = "light spectrum"

    @staticmethod
    def target(context):
        return getattr(context, "spectral_spectrum", None)


class SPECTRAL_OT_material_preset_add(AddSpectralPreset, bpy.types.Operator):
    """Save this material's spectral volume settings as a preset, or remove one of yours"""

    bl_idname = "spectral.material_preset_add"
    bl_label = "Add Spectral Material Preset"
    preset_menu = "SPECTRAL_PT_material_presets"
    preset_subdir = presets.MATERIAL_SUBDIR
    define = "settings = bpy.context.material.spectral"
    what = "material"

    @staticmethod
    def target(context):
        material = getattr(context, "material", None)
        return None if material is None else material.spectral


CLASSES = (SPECTRAL_OT_light_preset_add, SPECTRAL_OT_material_preset_add)
