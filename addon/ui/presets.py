"""Preset popovers (Blender's PresetPanel, as Cycles' sampling presets): light spectra, next to each light
and World spectrum (which they find as `context.spectral_spectrum`), and volume materials, in the header
of the Spectral Volume panels (`context.material`). Choosing a preset runs Blender's script.execute_preset;
the field and + below the list save the settings as a new preset, − removes one (operators/presets.py).
Registering makes the built-in presets (addon/presets) visible to Blender's preset search."""

import bpy
from bl_ui.utils import PresetPanel

from .. import presets


class SPECTRAL_PT_light_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Light Spectrum Presets"
    bl_idname = "SPECTRAL_PT_light_presets"
    preset_subdir = presets.LIGHT_SUBDIR
    preset_operator = "script.execute_preset"
    preset_add_operator = "spectral.light_preset_add"


class SPECTRAL_PT_material_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Spectral Material Presets"
    bl_idname = "SPECTRAL_PT_material_presets"
    preset_subdir = presets.MATERIAL_SUBDIR
    preset_operator = "script.execute_preset"
    preset_add_operator = "spectral.material_preset_add"


CLASSES = (SPECTRAL_PT_light_presets, SPECTRAL_PT_material_presets)


def register_extras():
    bpy.utils.register_preset_path(str(presets.SEARCH_PATH))


def unregister_extras():
    bpy.utils.unregister_preset_path(str(presets.SEARCH_PATH))
