"""The "Spectral Volume" render engine: F12, bpy.ops.render.render and animation renders, material,
light and World previews (thumbnails, addon/engine/thumbnails.py), and the Rendered viewport.

Each frame is exported from the render depsgraph and rendered, here or on the Dask farm of the Render
settings' scheduler address, in passes of doubling sample counts cut into units of about a quarter of
a second. After every unit, progress (by samples) and the time left are reported and Esc (`test_break`)
is honoured. The Render Result's Combined pass (linear Rec.709) is updated as often as that stays cheap;
at the end the XYZ and XYZ Variance passes, which the compositor and multilayer EXR output see, are
written too, and with Denoise on, Combined is replaced by the denoised image (addon/tracer/denoise.py;
the updates during the render stay raw). While the kernel compiles (the first render), the stats line
says so. The render is a render job (addon/jobs/) and its film goes to the Render Result through
addon/output.py. Bad input is reported as an error and renders nothing, so Blender writes no output
file. A renderer that cannot run inside a render engine's render (the Cycles emulation: Blender crashes)
is refused with an error (its job kind's `engine_refusal`). While `export.rendered` asks for an export
(Render to Image, Export Scene, the CLI), a render exports its depsgraph for it and renders nothing. A
preview renders Blender's preview scene as a render does, lit as `preview_scene` says, and reports nothing.

While it is the engine, those of Blender's generic panels (offered for every engine) that change what it
renders stay visible: camera, lights, volume file and grids, mesh data, output and colour management,
fluid smoke and fire, force fields and rigid bodies, particles (they instance volumes), animation and
custom properties. Those for what it does not render are left out (`NOT_RENDERED`): cloth, soft bodies,
dynamic paint, liquids, legacy textures, Freestyle, Grease Pencil, light probes, stereoscopy. The
viewport's Material Preview uses EEVEE, with each spectral material's preview nodes (`addon/eevee_stand_in.py`).

The Rendered viewport: `view_update` (Blender changed the scene) exports it through the view's camera (built
from the 3D view's matrices, `region_camera`) at the Viewport Samples (denoised with Viewport Denoise on)
and hands it to the engine's `ViewportRenderer` (addon/engine/viewport_render.py), which restarts its background
render; `view_draw` restarts it when the view moved or was resized, draws the latest image through the
scene's colour management (`bind_display_space_shader`, addon/engine/viewport_draw.py) and, while a render is in
flight, asks for the next redraw (`tag_redraw`, as Blender's own engine template does; no timers). Bad input
stops the render and its message shows in the viewport's stats line.
"""

import dataclasses

import bpy
import gpu

from .. import output
from ..export import rendered
from ..jobs import kinds
from ..export.passes import pass_settings
from ..export.scene import export_scene
from .thumbnails import preview_scene
from ..props.render import ENGINE_ID
from ..tracer.denoise import available as denoise_available, denoised_rgb
from ..tracer.errors import SpectralError
from ..tracer.fireflies import as_finished
from ..tracer.image_io import PASSES
from ..tracer.passes import DEPTH, MIST, NORMAL, pass_channels
from ..tracer.scene import RenderSettings
from ..tracer.progress import Throttle, TimeLeft
from .viewport_draw import ViewportImage
from .viewport_render import ViewportRenderer, view_camera

# The Render Result is rewritten at most every RESULT_SECONDS, and less often when writing it costs more
# than 1/RESULT_COST_RATIO of the time between writes (a 1920×1080 film takes a while to convert).
RESULT_SECONDS = 1.0
RESULT_COST_RATIO = 10
PASS_TYPES = {DEPTH: "VALUE", MIST: "VALUE", NORMAL: "VECTOR"}  # the data passes' kinds, as Cycles' (else COLOR)


class SpectralVolumeEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Spectral Volume"
    bl_use_preview = True
    bl_use_eevee_viewport = True

    def update_render_passes(self, scene=None, renderlayer=None):
        for name, channels in PASSES.items():  # the tracer's EXR names, so every EXR of a render reads alike
            self.register_pass(scene, renderlayer, name, len(channels), channels, "COLOR")
        # the View Layer's data passes, as Cycles registers them (exactly those the engine writes)
        settings = RenderSettings(**pass_settings(renderlayer, scene.world))
        for name, channels in pass_channels(settings).items():
            self.register_pass(scene, renderlayer, name, len(channels), channels, PASS_TYPES.get(name, "COLOR"))

    def render(self, depsgraph):
        if rendered.capture(depsgraph):  # Render to Image, Export Scene, the CLI: export only
            return
        original = depsgraph.scene.original
        settings = original.spectral
        refusal = kinds.kind(settings).engine_refusal
        if refusal is not None:
            self.report({"ERROR"}, refusal)
            return
        try:
            export = export_scene(depsgraph)
        except SpectralError as problem:
            self._report_unless_preview({"ERROR"}, str(problem))
            return
        if self.is_preview:
            export = dataclasses.replace(export, scene=preview_scene(export.scene, settings.preview_samples))
        job = kinds.render_job(original, export)
        for warning in job.warnings:
            self._report_unless_preview({"WARNING"}, warning)
        scene = export.scene
        camera = scene.camera  # with Render Region on, it sees the region: Blender crops or places it
        result = self.begin_result(0, 0, camera.width, camera.height)
        spp = scene.settings.spp
        time_left = TimeLeft()
        throttle = Throttle(RESULT_SECONDS, RESULT_COST_RATIO)

        def progress(film, fraction):
            self.update_progress(fraction)
            left = time_left(fraction)
            self._show_stats(f"{int(fraction * spp)}/{spp} samples"
                             + ("" if left is None else f" | about {left:.0f} s left"))
            if throttle.due() and not self.test_break():  # after Esc, stop at once: the full result is written below
                with throttle.timed():
                    self._write(result, as_finished(film, scene.settings.firefly_threshold), preview=True)

        job.run(progress=progress, notice=self._show_stats, cancel=self.test_break)
        problem = job.error
        if problem is None:
            try:
                self._write(result, job.result.film)
                output.render_data_passes(result, job.result.passes)
                output.stamp_metadata(self.get_result(), job.result.passes, depsgraph.view_layer.name)
                self.update_result(result)
                self._denoise(result, job.result.film, settings)
                if job.result.film.bins and not self.is_preview:
                    path = output.write_spectral_exr(original, job.result.film, scene, self.is_animation,
                                                     output.placement(original))
                    self.report({"INFO"}, f"Spectral EXR written: {path}")
            except SpectralError as error:  # Open Image Denoise failed, or the spectral EXR could not be written
                problem = str(error)
        if problem is not None:
            self._report_unless_preview({"ERROR"}, problem)
        self.end_result(result)

    def _report_unless_preview(self, kind: set, message: str) -> None:
        """Report to the user, except from a preview (a thumbnail of Blender's preview scene: its area lights,
        say, are nothing the user can act on, and each thumbnail would repeat them)."""
        if not self.is_preview:
            self.report(kind, message)

    def view_update(self, context, depsgraph):
        """Blender changed something (objects, materials, lights, World, settings): export the scene
        through the view's camera and render it again. Blender is evaluating the depsgraph meanwhile."""
        viewport = self._viewport()
        settings = depsgraph.scene.spectral
        try:
            export = export_scene(depsgraph, view=region_camera(context))
        except SpectralError as problem:
            self.viewport_notes = []
            viewport.fail(str(problem))
            return
        note = kinds.kind(settings).viewport_note
        self.viewport_notes = export.warnings + ([] if note is None else [note])
        scene = export.scene
        scene = dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, spp=settings.preview_samples,
                                                                        noise_threshold=0.0))
        viewport.render(scene, settings.scheduler_address, settings.viewport_denoise and denoise_available())

    def view_draw(self, context, depsgraph):
        """Draw the latest image, after restarting the render if the view moved or was resized; while a
        render is in flight, ask for another redraw to show its progress."""
        viewport = self._viewport()
        viewport.look_through(region_camera(context))
        frame = viewport.frame
        if frame is not None:
            gpu.state.blend_set("ALPHA_PREMULT")
            self.bind_display_space_shader(depsgraph.scene)
            self.viewport_image.draw(frame.pixels, context.region.width, context.region.height)
            self.unbind_display_space_shader()
            gpu.state.blend_set("NONE")
        self._show_stats(" | ".join(["Viewport: " + viewport.status, *self.viewport_notes]))
        if viewport.busy:
            self.tag_redraw()

    def _viewport(self) -> ViewportRenderer:
        """This engine's viewport renderer (an engine draws one 3D view), made on first use."""
        if getattr(self, "viewport", None) is None:
            self.viewport, self.viewport_image, self.viewport_notes = ViewportRenderer(), ViewportImage(), []
        return self.viewport

    def __del__(self):
        try:
            viewport = getattr(self, "viewport", None)
        except ReferenceError:  # Blender freed the engine first
            return
        if viewport is not None:
            viewport.close()

    def _show_stats(self, text: str) -> None:
        self.update_stats("", f"Spectral Volume | {text}")

    def _denoise(self, result, film, settings) -> None:
        """With Denoise on (not in previews), rewrite Combined with the denoised image (the XYZ and XYZ
        Variance passes stay as rendered). Runs after the raw result is written, so a failure loses nothing."""
        denoised, skipped = output.denoising(settings)
        if skipped:
            self._report_unless_preview({"WARNING"}, skipped)
        if not denoised or self.is_preview or self.test_break():
            return
        self._show_stats("Denoising")
        output.render_combined(result, denoised_rgb(film), film.alpha)
        self.update_result(result)

    def _write(self, result, film, preview: bool = False) -> None:
        """Film → Render Result (`output.render_result`), shown."""
        output.render_result(result, film, preview)
        self.update_result(result)


CLASSES = (SpectralVolumeEngine,)
GENERIC_ENGINE = "BLENDER_RENDER"  # Blender marks the panels that suit any engine with this name
# Generic panels of what this engine does not render (by the start of their class names).
NOT_RENDERED = ("TEXTURE_PT_", "NODE_PT_texture", "PHYSICS_PT_cloth", "PHYSICS_PT_softbody",
                "PHYSICS_PT_dp_", "PHYSICS_PT_dynamic_paint", "PHYSICS_PT_collision", "PHYSICS_PT_liquid",
                "PHYSICS_PT_viscosity", "PHYSICS_PT_diffusion", "PHYSICS_PT_mesh", "PHYSICS_PT_particles",
                "RENDER_PT_freestyle", "VIEWLAYER_PT_freestyle", "MATERIAL_PT_freestyle", "RENDER_PT_gpencil",
                "RENDER_PT_grease_pencil", "RENDER_PT_simplify_greasepencil", "DATA_PT_lightprobe",
                "DATA_PT_context_lightprobe", "RENDER_PT_stereoscopy", "RENDER_PT_output_views",
                "DATA_PT_camera_stereoscopy")
_panels_shown = []


def region_camera(context):
    """The tracer Camera of the context's 3D view, at its region's size (in camera view, the view's
    matrices are those of the scene camera, zoomed and offset as the view shows its frame)."""
    view = context.region_data
    return view_camera(view.view_matrix, view.window_matrix, context.region.width, context.region.height)


def _panel_classes(base=bpy.types.Panel):
    for cls in base.__subclasses__():
        yield cls
        yield from _panel_classes(cls)


def register_extras():
    for panel in _panel_classes():
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if (isinstance(engines, set) and GENERIC_ENGINE in engines and ENGINE_ID not in engines
                and not panel.__name__.startswith(NOT_RENDERED)):
            engines.add(ENGINE_ID)
            _panels_shown.append(panel)


def unregister_extras():
    for panel in _panels_shown:
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    _panels_shown.clear()
