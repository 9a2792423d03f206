"""The "Render to Image" operator: renders the scene into a float Image (and optionally a multilayer
EXR) without the Render window.

The render is the render job the Render settings choose (addon/jobs/). Run from the UI (invoke) it
renders in the background (the job starts, then steps on each timer tick: the Cycles emulation makes one
Cycles render per tick on the main thread), shows progress and stops on Esc; run from a script (execute)
it renders in place. The film goes to the image and the file through addon/output.py. Only a finished
render writes anything: a cancelled or failed one leaves the image and the file as they were.
"""

import bpy

from ..jobs.kinds import render_job
from ..jobs.protocol import Job
from ..output import denoising, placement, write_outputs, write_spectral_exr
from ..export.rendered import export_rendered
from ..tracer.errors import SpectralError

TIMER_SECONDS = 0.25


class SPECTRAL_OT_render_image(bpy.types.Operator):
    """Render spectrally into an image (Esc cancels)"""

    bl_idname = "spectral.render_image"
    bl_label = "Render to Image"

    image_name: bpy.props.StringProperty(name="Image", default="Spectral Render",
                                         description="Float image to render into (created when missing)")
    exr_path: bpy.props.StringProperty(name="EXR File", subtype="FILE_PATH",
                                       description="Also write a multilayer EXR with F12's passes (Combined, XYZ, "
                                                   "XYZ Variance); empty: none")

    _job = None
    _timer = None
    _warnings_shown = 0
    _message = None
    _region = None  # where the film goes in the image (output.placement), as exported
    _tracer_scene = None  # the exported scene (the spectral EXR's units)

    def _start(self, context) -> Job | None:
        try:
            export = export_rendered(context.scene, context.view_layer)
            self._region = placement(context.scene)
            self._tracer_scene = export.scene
            job = render_job(context.scene, export)
        except SpectralError as problem:
            self.report({"ERROR"}, f"Nothing rendered: {problem}")
            return None
        self._warnings_shown = 0
        self.report({"INFO"}, f"Rendering with the {job.describe()}")
        self._report_warnings(job)
        return job

    def _report_warnings(self, job: Job) -> None:
        """The job's warnings not shown yet: the emulation finds some while it renders (textured surfaces)."""
        for warning in job.warnings[self._warnings_shown:]:
            self.report({"WARNING"}, warning)
        self._warnings_shown = len(job.warnings)

    def _show_message(self, context, message: str | None) -> None:
        """Show what the render waits for (the kernel compiling) in the status bar; None restores it."""
        if message != self._message:
            context.workspace.status_text_set(message)
            self._message = message

    def _finish(self, context, job: Job) -> set:
        self._report_warnings(job)
        if job.error is not None:
            self.report({"ERROR"}, f"Render failed, nothing written: {job.error}")
            return {"CANCELLED"}
        if not job.succeeded:
            self.report({"WARNING"}, "Render cancelled, nothing written")
            return {"CANCELLED"}
        denoised, skipped = denoising(context.scene.spectral)
        if skipped:
            self.report({"WARNING"}, skipped)
        try:
            image = write_outputs(job.result.film, self.image_name, self.exr_path, context.view_layer.name,
                                  self._region, denoised, job.result.passes)
            if job.result.film.bins:
                path = write_spectral_exr(context.scene, job.result.film, self._tracer_scene,
                                          region=self._region)
                self.report({"INFO"}, f"Spectral EXR written: {path}")
        except SpectralError as problem:
            self.report({"ERROR"}, f"Render not saved: {problem}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Rendered into image {image.name!r} in {job.result.seconds:.1f} s")
        return {"FINISHED"}

    def execute(self, context):
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        job.run()
        return self._finish(context, job)

    def invoke(self, context, event):
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        self._job = job
        job.start()
        manager = context.window_manager
        self._timer = manager.event_timer_add(TIMER_SECONDS, window=context.window)
        manager.progress_begin(0.0, 1.0)
        manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._job.cancel()
        elif event.type != "TIMER":
            return {"PASS_THROUGH"}
        self._job.step()
        context.window_manager.progress_update(self._job.fraction)
        self._show_message(context, self._job.message)
        if self._job.running:
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self._timer)
        context.window_manager.progress_end()
        self._show_message(context, None)
        return self._finish(context, self._job)


CLASSES = (SPECTRAL_OT_render_image,)
