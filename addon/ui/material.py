"""Material panels (Properties editor ▸ Material: Spectral Volume, Spectral Surface) and the drawing the sidebar shares."""

import bpy

from .panel import SpectralPanel
from .presets import SPECTRAL_PT_material_presets
from .spectrum import draw_spectrum


def draw_material_main(layout, material) -> None:
    """Density scale, phase, extinction and base albedo: the controls an artist reaches for first."""
    settings = material.spectral
    row = layout.row(align=True)
    row.use_property_split = False
    row.prop(settings, "enabled")
    body = layout.column()
    body.active = settings.enabled
    body.prop(settings, "density_scale")
    body.prop(settings, "phase")
    if settings.phase == "hg":
        draw_spectrum(body, settings.anisotropy, "Anisotropy")
    draw_spectrum(body, settings.extinction, "Extinction")
    draw_spectrum(body, settings.albedo, "Albedo")


def draw_material_surface(layout, material) -> None:
    """The surface's reflectance spectrum (Spectral Surface on), else what it renders from."""
    settings = material.spectral
    if settings.use_surface:
        draw_spectrum(layout, settings.reflectance, "Reflectance")
    else:
        layout.label(text="Diffuse color from the Surface nodes", icon="NODETREE")


def draw_albedo_levels(layout, material) -> None:
    settings = material.spectral
    row = layout.row()
    row.use_property_split = False
    row.template_list("SPECTRAL_UL_albedo_levels", "", settings, "albedo_levels", settings, "albedo_index", rows=2)
    buttons = row.column(align=True)
    buttons.operator("spectral.albedo_level_add", text="", icon="ADD")
    buttons.operator("spectral.albedo_level_remove", text="", icon="REMOVE")
    if 0 <= settings.albedo_index < len(settings.albedo_levels):
        level = settings.albedo_levels[settings.albedo_index]
        layout.prop(level, "density")
        draw_spectrum(layout, level.spectrum, "Albedo at this density")


def draw_fluorescence(layout, material, renderer: str = "TRACER") -> None:
    settings = material.spectral
    layout.active = settings.use_fluorescence
    if renderer == "CYCLES":
        layout.label(text="Cycles emulation: excitation absorbs, nothing is re-emitted", icon="ERROR")
    draw_spectrum(layout, settings.excitation, "Excitation")
    draw_spectrum(layout, settings.emission, "Emission")
    layout.prop(settings, "quantum_yield")


def draw_blackbody(layout, material, renderer: str = "TRACER") -> None:
    settings = material.spectral
    layout.active = settings.use_blackbody
    if renderer == "CYCLES":
        layout.label(text="Cycles emulation: Nodes shader only (not OSL)", icon="INFO")
    layout.prop(settings, "temperature_grid")
    layout.prop(settings, "blackbody_intensity")
    column = layout.column(align=True)
    column.prop(settings, "temperature_scale", text="Temperature Scale")
    column.prop(settings, "temperature_offset", text="Offset")


class SPECTRAL_UL_albedo_levels(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_property, index=0, flt_flag=0):
        row = layout.row(align=True)
        row.prop(item.spectrum, "preview", text="")
        row.prop(item, "density", emboss=False)


class MaterialPanel(SpectralPanel):
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "material", None) is not None


class SPECTRAL_PT_material(MaterialPanel, bpy.types.Panel):
    bl_label = "Spectral Volume"
    bl_idname = "SPECTRAL_PT_material"

    def draw_header_preset(self, context):
        SPECTRAL_PT_material_presets.draw_panel_header(self.layout)

    def draw_settings(self, layout, context):
        draw_material_main(layout, context.material)


class SPECTRAL_PT_material_surface(MaterialPanel, bpy.types.Panel):
    bl_label = "Spectral Surface"
    bl_idname = "SPECTRAL_PT_material_surface"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.material.spectral, "use_surface", text="")

    def draw_settings(self, layout, context):
        draw_material_surface(layout, context.material)


class SPECTRAL_PT_material_albedo(MaterialPanel, bpy.types.Panel):
    bl_label = "Albedo by Density"
    bl_idname = "SPECTRAL_PT_material_albedo"
    bl_parent_id = "SPECTRAL_PT_material"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_settings(self, layout, context):
        draw_albedo_levels(layout, context.material)


class SPECTRAL_PT_material_fluorescence(MaterialPanel, bpy.types.Panel):
    bl_label = "Fluorescence"
    bl_idname = "SPECTRAL_PT_material_fluorescence"
    bl_parent_id = "SPECTRAL_PT_material"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.material.spectral, "use_fluorescence", text="")

    def draw_settings(self, layout, context):
        draw_fluorescence(layout, context.material, context.scene.spectral.renderer)


class SPECTRAL_PT_material_blackbody(MaterialPanel, bpy.types.Panel):
    bl_label = "Blackbody Emission"
    bl_idname = "SPECTRAL_PT_material_blackbody"
    bl_parent_id = "SPECTRAL_PT_material"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.material.spectral, "use_blackbody", text="")

    def draw_settings(self, layout, context):
        draw_blackbody(layout, context.material, context.scene.spectral.renderer)


CLASSES = (SPECTRAL_UL_albedo_levels, SPECTRAL_PT_material, SPECTRAL_PT_material_albedo,
           SPECTRAL_PT_material_fluorescence, SPECTRAL_PT_material_blackbody, SPECTRAL_PT_material_surface)
