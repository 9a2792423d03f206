"""The "Spectral" tab in the 3D viewport sidebar (N panel)."""

import bpy


class SPECTRAL_PT_sidebar(bpy.types.Panel):
    bl_label = "Spectral Render"
    bl_idname = "SPECTRAL_PT_sidebar"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Spectral"

    def draw(self, context):
        settings = context.scene.spectral
        layout = self.layout
        layout.prop(settings, "samples")
        layout.prop(settings, "seed")


CLASSES = (SPECTRAL_PT_sidebar,)
