"""The "Import Spectral Scene" operator (File ▸ Import ▸ Spectral Scene): a tracer scene folder
(`scene.json`, docs/scene-format.md) opened as a new Blender scene, made the window's scene."""

from pathlib import Path

import bpy
from bpy_extras.io_utils import ImportHelper

from ..importer import import_scene
from ..tracer.errors import SpectralError
from ..tracer.scene_io import SCENE_FILE, load_scene

DATA_FOLDER = "blender_data"  # default: beside scene.json


class SPECTRAL_OT_import_scene(bpy.types.Operator, ImportHelper):
    """Open a tracer scene (scene.json and its grids) as a new Blender scene"""

    bl_idname = "spectral.import_scene"
    bl_label = "Import Spectral Scene"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})
    data_folder: bpy.props.StringProperty(
        name="Data Folder", subtype="DIR_PATH", options={"PATH_SUPPORTS_BLEND_RELATIVE"},
        description="Where the VDB files of the volumes (and spectra no curve can hold, as CSV) are written; "
                    f"empty: a folder '{DATA_FOLDER}' beside scene.json")

    def execute(self, context):
        path = Path(self.filepath)
        path = path / SCENE_FILE if path.is_dir() else path  # the folder itself chosen
        folder = Path(bpy.path.abspath(self.data_folder)) if self.data_folder else path.parent / DATA_FOLDER
        try:
            scene = load_scene(path)
            blender_scene, warnings = import_scene(scene, path.parent.name or path.stem, folder)
        except SpectralError as problem:
            self.report({"ERROR"}, f"Nothing imported: {problem}")
            return {"CANCELLED"}
        for warning in warnings:
            self.report({"WARNING"}, warning)
        context.window.scene = blender_scene
        self.report({"INFO"}, f"Imported {path} as scene {blender_scene.name!r}")
        return {"FINISHED"}


def menu_entry(menu, _context):
    menu.layout.operator(SPECTRAL_OT_import_scene.bl_idname, text="Spectral Scene (.json)")


def register_extras():
    bpy.types.TOPBAR_MT_file_import.append(menu_entry)


def unregister_extras():
    bpy.types.TOPBAR_MT_file_import.remove(menu_entry)


CLASSES = (SPECTRAL_OT_import_scene,)
