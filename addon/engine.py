"""The "Spectral Volume" render engine: F12, bpy.ops.render.render and animation renders.

Each frame is exported from the render depsgraph and rendered, here or on the Dask farm of the Render
settings' scheduler address, in passes of doubling sample counts cut into units of about a quarter of
a second. After every unit, progress (by samples) and the time left are reported and Esc (`test_break`)
is honoured. The Render Result's Combined pass (linear Rec.709) is updated as often as that stays cheap;
at the end the XYZ and XYZ Variance passes, which the compositor and multilayer EXR output see, are
written too. While the kernel compiles (the first render), the stats line says so. Bad input is
reported as an error and renders nothing, so Blender writes no output file. With the Cycles emulation
chosen as renderer, F12 reports an error instead: Cycles cannot render from inside another engine's
render (Blender crashes). While `render_export` asks for an export (Render to Image, Export Scene, the
CLI), a render exports its depsgraph for it and renders nothing.

While it is the engine, those of Blender's generic panels (offered for every engine) that change what it
renders stay visible: camera, lights, volume file and grids, mesh data, output and colour management,
fluid smoke and fire, force fields and rigid bodies, particles (they instance volumes), animation and
custom properties. Those for what it does not render are left out (`NOT_RENDERED`): cloth, soft bodies,
dynamic paint, liquids, legacy textures, Freestyle, Grease Pencil, light probes, stereoscopy. The
viewport's Material Preview uses EEVEE.
"""

import bpy

from . import dispatch, render_export
from .export.scene import export_scene
from .pixels import blender_rows, with_alpha
from .props.render import ENGINE_ID
from .tracer.errors import SpectralError
from .tracer.image_io import COMBINED, PASSES, VARIANCE, XYZ
from .tracer.progress import Throttle, TimeLeft

# The Render Result is rewritten at most every RESULT_SECONDS, and less often when writing it costs more
# than 1/RESULT_COST_RATIO of the time between writes (a 1920×1080 film takes a while to convert).
RESULT_SECONDS = 1.0
RESULT_COST_RATIO = 10


class SpectralVolumeEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Spectral Volume"
    bl_use_preview = False
    bl_use_eevee_viewport = True

    def update_render_passes(self, scene=None, renderlayer=None):
        for name, channels in PASSES.items():  # the tracer's EXR names, so every EXR of a render reads alike
            self.register_pass(scene, renderlayer, name, len(channels), channels, "COLOR")

    def render(self, depsgraph):
        if render_export.capture(depsgraph):  # Render to Image, Export Scene, the CLI: export only
            return
        if depsgraph.scene.original.spectral.renderer == "CYCLES":
            self.report({"ERROR"}, "the Cycles emulation cannot run inside a render engine's render: use Render to "
                        "Image (Spectral sidebar tab) or the command line, or choose the Tracer renderer")
            return
        try:
            export = export_scene(depsgraph)
        except SpectralError as problem:
            self.report({"ERROR"}, str(problem))
            return
        for warning in export.warnings:
            self.report({"WARNING"}, warning)
        camera = export.scene.camera  # with Render Region on, it sees the region: Blender crops or places it
        result = self.begin_result(0, 0, camera.width, camera.height)
        spp = export.scene.settings.spp
        time_left = TimeLeft()
        throttle = Throttle(RESULT_SECONDS, RESULT_COST_RATIO)

        def progress(film, fraction):
            self.update_progress(fraction)
            left = time_left(fraction)
            self._show_stats(f"{int(fraction * spp)}/{spp} samples"
                             + ("" if left is None else f" | about {left:.0f} s left"))
            if throttle.due() and not self.test_break():  # after Esc, stop at once: the full result is written below
                with throttle.timed():
                    self._write(result, film, preview=True)

        try:
            rendered = dispatch.run(export.scene, depsgraph.scene.original.spectral.scheduler_address,
                                    progress=progress, cancel=self.test_break, notice=self._show_stats)
            self._write(result, rendered.film)
        except SpectralError as problem:
            self.report({"ERROR"}, str(problem))
        self.end_result(result)

    def _show_stats(self, text: str) -> None:
        self.update_stats("", f"Spectral Volume | {text}")

    def _write(self, result, film, preview: bool = False) -> None:
        """Film → Render Result: Combined, and unless this is a preview the XYZ and XYZ Variance passes
        (the variance costs most to convert: 0.2–0.5 s at 1920×1080, time a cancel would wait). Pixels go
        in with `foreach_set`: assigning `rect` took 7–10 s per pass at 1920×1080."""
        passes = result.layers[0].passes
        passes[COMBINED].rect.foreach_set(blender_rows(with_alpha(film.rgb())).ravel())
        if not preview:
            passes[XYZ].rect.foreach_set(blender_rows(film.xyz).ravel())
            passes[VARIANCE].rect.foreach_set(blender_rows(film.variance).ravel())
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
