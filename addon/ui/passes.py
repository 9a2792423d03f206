"""The View Layer's passes this engine makes (Properties ▸ View Layer ▸ Passes), and the World's Mist Pass settings
(Properties ▸ World ▸ Mist Pass): the engine's own panels, as Cycles has, so that only the passes it writes are
offered (Blender's generic pass panels name only EEVEE and Workbench in their COMPAT_ENGINES, and stay hidden)."""

import bpy

from ..export.passes import LIGHT_TOGGLES, TOGGLES
from ..tracer.light_passes import EMIT, ENV, VOLUME_DIR, VOLUME_IND
from ..tracer.passes import CRYPTO_MATERIAL, CRYPTO_OBJECT, DEPTH, MIST, NORMAL
from .panel import SpectralPanel

LABELS = {DEPTH: "Z", MIST: "Mist", NORMAL: "Normal", CRYPTO_OBJECT: "Object", CRYPTO_MATERIAL: "Material",
          EMIT: "Emission", ENV: "Environment", VOLUME_DIR: "Volume Direct", VOLUME_IND: "Volume Indirect"}


class SPECTRAL_PT_view_layer_passes(SpectralPanel, bpy.types.Panel):
    bl_label = "Passes"
    bl_idname = "SPECTRAL_PT_view_layer_passes"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "view_layer"

    def draw_settings(self, layout, context):
        view_layer = context.view_layer
        column = layout.column(heading="Include", align=True)
        column.prop(view_layer, "use_pass_combined")
        column = layout.column(heading="Data", align=True)
        for name in (DEPTH, MIST, NORMAL):
            column.prop(view_layer, TOGGLES[name], text=LABELS[name])
        column = layout.column(heading="Light", align=True)
        for name, (owner, toggle) in LIGHT_TOGGLES.items():
            settings = getattr(view_layer, owner, None) if owner else view_layer
            if settings is not None:  # Cycles' toggles exist where the Cycles add-on is enabled
                column.prop(settings, toggle, text=LABELS[name])
        column = layout.column(heading="Cryptomatte", align=True)
        for name in (CRYPTO_OBJECT, CRYPTO_MATERIAL):
            column.prop(view_layer, TOGGLES[name], text=LABELS[name])
        layout.prop(view_layer, "pass_cryptomatte_depth", text="Levels")
        draw_spectral_exr(layout, context.scene.spectral)


def draw_spectral_exr(layout, settings) -> None:
    """The Spectral EXR: on or off, and its bins. A file next to the render output, not a Render Result pass: a pass
    holds at most 8 channels, each named by one letter, where the spectral layout names a channel by its wavelength."""
    layout.prop(settings, "spectral_exr")
    column = layout.column(align=True)
    column.active = settings.spectral_exr
    column.prop(settings, "spectral_exr_start")
    column.prop(settings, "spectral_exr_end")
    column.prop(settings, "spectral_exr_step")


class SPECTRAL_PT_world_mist(SpectralPanel, bpy.types.Panel):
    bl_label = "Mist Pass"
    bl_idname = "SPECTRAL_PT_world_mist"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.world is not None

    def draw_settings(self, layout, context):
        mist = context.world.mist_settings
        layout.prop(mist, "start")
        layout.prop(mist, "depth")
        layout.prop(mist, "falloff")


CLASSES = (SPECTRAL_PT_view_layer_passes, SPECTRAL_PT_world_mist)
