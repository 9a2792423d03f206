"""The "Spectral" tab in the 3D viewport sidebar (N panel): the artist's main controls in one place."""

import bpy

from .lighting import draw_light, draw_world
from .material import draw_material_main
from .panel import SpectralPanel
from .presets import SPECTRAL_PT_material_presets


class SidebarPanel(SpectralPanel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Spectral"


class SPECTRAL_PT_sidebar(SidebarPanel, bpy.types.Panel):
    bl_label = "Spectral Render"
    bl_idname = "SPECTRAL_PT_sidebar"

    def draw_settings(self, layout, context):
        scene = context.scene
        layout.operator("spectral.render_image", text="Render", icon="RENDER_STILL")
        layout.operator("spectral.export_scene", text="Export Scene", icon="EXPORT")
        layout.prop(scene.spectral, "renderer")
        layout.prop(scene.spectral, "samples")
        layout.prop(scene.spectral, "wavelength_sampling")


def _active_material(context):
    obj = context.active_object
    return obj.active_material if obj is not None else None


class SPECTRAL_PT_sidebar_volume(SidebarPanel, bpy.types.Panel):
    bl_label = "Volume"
    bl_idname = "SPECTRAL_PT_sidebar_volume"
    bl_parent_id = "SPECTRAL_PT_sidebar"

    def draw_header_preset(self, context):
        material = _active_material(context)
        if material is not None:
            self.layout.context_pointer_set("material", material)  # the presets' target, as in Properties
            SPECTRAL_PT_material_presets.draw_panel_header(self.layout)

    def draw_settings(self, layout, context):
        material = _active_material(context)
        if material is None:
            layout.label(text="Select an object with a material", icon="INFO")
            return
        layout.label(text=material.name, icon="MATERIAL")
        draw_material_main(layout, material)


class SPECTRAL_PT_sidebar_lighting(SidebarPanel, bpy.types.Panel):
    bl_label = "Lighting"
    bl_idname = "SPECTRAL_PT_sidebar_lighting"
    bl_parent_id = "SPECTRAL_PT_sidebar"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_settings(self, layout, context):
        obj = context.active_object
        if obj is not None and obj.type == "LIGHT":
            layout.label(text=obj.name, icon="LIGHT")
            draw_light(layout, obj.data)
        world = context.scene.world
        if world is not None:
            row = layout.row()
            row.use_property_split = False
            row.label(text=world.name, icon="WORLD")
            row.prop(world.spectral, "enabled", text="")
            draw_world(layout, world)


CLASSES = (SPECTRAL_PT_sidebar, SPECTRAL_PT_sidebar_volume, SPECTRAL_PT_sidebar_lighting)
