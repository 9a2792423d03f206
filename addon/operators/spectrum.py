"""Operators on one spectrum setting: import a CSV file, turn the current spectrum into a curve."""

import bpy
import numpy as np
from bpy_extras.io_utils import ImportHelper

from ..props import curves
from ..props.spectrum_values import to_spectrum
from ..props.spectrum import CSV_UNIT_ITEMS
from ..tracer import spectra
from ..tracer.errors import SpectralError
from ..tracer.wavelengths import GRID
from .targets import TargetProperties, resolve

CURVE_STEP_NM = 20.0


class SPECTRAL_OT_import_spectrum_csv(TargetProperties, bpy.types.Operator, ImportHelper):
    """Use a CSV file of wavelength, value rows as this spectrum"""

    bl_idname = "spectral.import_spectrum_csv"
    bl_label = "Import Spectrum CSV"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".csv"
    filter_glob: bpy.props.StringProperty(default="*.csv;*.txt", options={"HIDDEN"})
    units: bpy.props.EnumProperty(name="Units", description="Wavelength unit of the CSV file",
                                  items=CSV_UNIT_ITEMS, default="nm")

    def execute(self, context):
        settings = resolve(self)
        if settings is None:
            self.report({"ERROR"}, "The spectrum to import into no longer exists")
            return {"CANCELLED"}
        try:
            spectra.from_csv(self.filepath, self.units)
        except SpectralError as problem:
            self.report({"ERROR"}, f"Not imported: {problem}")
            return {"CANCELLED"}
        settings.filepath = bpy.path.relpath(self.filepath) if bpy.data.filepath else self.filepath
        settings.units = self.units
        settings.source = "CSV"
        return {"FINISHED"}


class SPECTRAL_OT_spectrum_to_curve(TargetProperties, bpy.types.Operator):
    """Edit this spectrum as a curve, starting from its current shape"""

    bl_idname = "spectral.spectrum_to_curve"
    bl_label = "Edit as Curve"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        settings = resolve(self)
        if settings is None:
            self.report({"ERROR"}, "The spectrum to edit no longer exists")
            return {"CANCELLED"}
        try:
            values = to_spectrum(settings).values
        except SpectralError as problem:
            self.report({"ERROR"}, str(problem))
            return {"CANCELLED"}
        low, high = settings.Y_RANGE
        if settings.ROLE == "light" and values.max() > 0:
            values = values / values.max()  # a light's curve is its shape
        nodes = np.arange(GRID[0], GRID[-1] + 1.0, CURVE_STEP_NM)
        samples = np.clip(np.interp(nodes, GRID, values), low, high)
        mapping = curves.ensure(settings.curve, settings.Y_RANGE)
        curves.set_points(mapping, nodes, samples)
        settings.source = "CURVE"
        return {"FINISHED"}


class SPECTRAL_OT_curves_single_user(TargetProperties, bpy.types.Operator):
    """Give this data block its own copy of the spectral curves it shares with a copy of itself"""

    bl_idname = "spectral.curves_single_user"
    bl_label = "Make Curves Single-User"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        settings = resolve(self)
        if settings is None:
            self.report({"ERROR"}, "The spectrum no longer exists")
            return {"CANCELLED"}
        curves.make_single_user(settings.id_data)
        return {"FINISHED"}


CLASSES = (SPECTRAL_OT_import_spectrum_csv, SPECTRAL_OT_spectrum_to_curve, SPECTRAL_OT_curves_single_user)
