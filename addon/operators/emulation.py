"""The "Estimate Bands" operator: the Cycles emulation's automatic bands for the scene as it is now, and
their estimated colour error, shown in the Render settings (`band_plan`; nothing renders)."""

import bpy

from ..cycles_emulation.band_plan import plan_bands
from ..export.rendered import export_rendered
from ..tracer.errors import SpectralError

# Scene name → the last estimate's summary, for the panel (not saved with the file: it describes the
# scene at the moment the estimate was made).
ESTIMATES: dict[str, str] = {}


class SPECTRAL_OT_estimate_emulation_bands(bpy.types.Operator):
    """Choose the Cycles emulation's bands for the scene as it is now and estimate their color error"""

    bl_idname = "spectral.estimate_emulation_bands"
    bl_label = "Estimate Bands"

    def execute(self, context):
        settings = context.scene.spectral
        try:
            export = export_rendered(context.scene, context.view_layer)
            plan = plan_bands(export.scene, max_renders=settings.emulation_max_renders)
        except SpectralError as problem:
            self.report({"ERROR"}, f"No estimate: {problem}")
            return {"CANCELLED"}
        ESTIMATES[context.scene.name] = plan.summary()
        self.report({"WARNING"} if plan.warning else {"INFO"}, plan.warning or plan.summary())
        return {"FINISHED"}


CLASSES = (SPECTRAL_OT_estimate_emulation_bands,)
