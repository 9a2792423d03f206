"""The "Spectral Volume" render engine (F12, bpy.ops.render.render, animation renders)."""

import bpy

from .props.render import ENGINE_ID


class SpectralVolumeEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Spectral Volume"
    bl_use_preview = False

    def render(self, depsgraph):
        self.report({"ERROR"}, "Spectral Volume: rendering is not implemented yet")


CLASSES = (SpectralVolumeEngine,)
