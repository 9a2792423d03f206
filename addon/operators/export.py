"""The "Export Scene" operator: writes the tracer scene folder (scene.json + grids) for the CLI or a farm."""

from pathlib import Path

import bpy
from bpy_extras.io_utils import ExportHelper

from ..export.rendered import export_rendered
from ..tracer.errors import SpectralError
from ..tracer.scene_io import SCENE_FILE, save_scene


class SPECTRAL_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the scene as a tracer scene folder (scene.json and its grids)"""

    bl_idname = "spectral.export_scene"
    bl_label = "Export Spectral Scene"

    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        self.filepath = str(Path(bpy.path.abspath("//") or ".") / "spectral_scene" / SCENE_FILE)
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            result = export_rendered(context.scene, context.view_layer)
        except SpectralError as problem:
            self.report({"ERROR"}, f"Nothing exported: {problem}")
            return {"CANCELLED"}
        for warning in result.warnings:
            self.report({"WARNING"}, warning)
        path = save_scene(result.scene, Path(self.filepath).parent)
        self.report({"INFO"}, f"Exported {path}")
        return {"FINISHED"}


CLASSES = (SPECTRAL_OT_export_scene,)
