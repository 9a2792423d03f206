"""The emulation driver: one Cycles render after another, each set up on the user's scene and undone, their
R, G, B composited into an XYZ film: a render job (addon/jobs/) of the Cycles emulation.

Each planned render (up to three bands, `parameters.plan`) is made twice, with seeds 2·seed and 2·seed + 1
and half the samples each, so the film has a variance estimate (`composite`); Cycles keeps its scene
between the two (persistent data), so the second costs no scene preparation (Cycles 5 spends seconds
building the octree of a volume whose density comes through shader nodes). `step()` makes one planned
render and can be called from a modal operator between UI events (Cycles runs on Blender's main thread,
so nothing renders in the background; it cannot run inside another render engine's render, so F12 and
the Rendered viewport cannot run it); `run()` makes them all. Between steps the scene is
the user's own, and every step restores it even when Cycles fails. Cycles' images and the fluid domains'
grids (`fluids`, written once) go to a temporary folder, removed when the job ends. The data passes (Depth,
Mist, Normal, Cryptomatte) are the tracer's own, from the camera rays' first hits after the last render
(`tracer.render.first_hit_passes`): they depend on no band.
"""

import dataclasses
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

from ..export.passes import without_light_passes
from ..export.scene import Export
from ..jobs.protocol import Job
from ..tracer import image_io
from ..tracer.errors import SpectralError
from ..tracer.render import RenderResult, band_scenes, first_hit_passes
from ..tracer.scene import Scene
from . import fluids, setup
from .band_plan import DEFAULT_MAX_RENDERS, plan_bands
from .composite import CompositeFilm
from .parameters import plan as make_plan
from .state import Borrowed


class EmulationJob(Job):
    """`band_count` equal bands, or (None) the bands `band_plan` chooses within `max_renders` Cycles renders."""

    engine_refusal = ("the Cycles emulation cannot run inside a render engine's render: use Render to Image "
                      "(Spectral sidebar tab) or the command line, or choose the Tracer renderer")
    viewport_note = "the viewport shows the tracer (Cycles emulation: Render to Image)"

    def __init__(self, scene, tracer_scene: Scene, warnings=(), *, band_count: int | None = None,
                 max_renders: int = DEFAULT_MAX_RENDERS, shader: str = "SVM", spp: int | None = None):
        super().__init__(warnings)
        self.scene, self._tracer_scene = scene, tracer_scene
        self.band_plan = None if band_count is not None else plan_bands(tracer_scene, max_renders=max_renders)
        self.plan = make_plan(tracer_scene, band_count if self.band_plan is None else self.band_plan.bands)
        self._media = {medium.name: medium for medium in tracer_scene.media}
        self._scratch = tempfile.TemporaryDirectory(prefix="spectral_emulation_")  # removed when the job ends
        self._fluid_files = None  # written by the first render
        self.shader = shader
        settings = tracer_scene.settings
        self.samples = max(1, (settings.spp if spp is None else int(spp)) // 2)
        self.seed, self.max_bounces = settings.seed, settings.max_depth
        self.warnings += self.plan.warnings
        if self.band_plan is not None and self.band_plan.warning:
            self.warnings.append(self.band_plan.warning)
        self.film = CompositeFilm(tracer_scene.camera.width, tracer_scene.camera.height)
        self._queue = list(self.plan.renders)
        self._total = len(self._queue)
        self._cancel = False
        self._seconds = 0.0

    @classmethod
    def for_export(cls, scene, export: Export, *, spp: int | None = None,
                   scheduler: str | None = None) -> "EmulationJob":
        """With the Render settings' bands and shader (Cycles renders here: `scheduler` is not asked)."""
        settings = scene.spectral
        band_count = settings.emulation_bands if settings.emulation_band_mode == "FIXED" else None
        export = without_light_passes(export, "the Cycles emulation")
        tracer_settings = export.scene.settings
        if tracer_settings.clamp_direct > 0 or tracer_settings.clamp_indirect > 0:
            # Cycles' clamp would act on each render's three bands as if they were R, G and B: not the tracer's
            export = dataclasses.replace(export, warnings=[
                *export.warnings, f"the Cycles emulation does not clamp: Light Paths ▸ Clamping (Direct "
                f"{tracer_settings.clamp_direct:g}, Indirect {tracer_settings.clamp_indirect:g}) left out of the render"])
        if tracer_settings.firefly_threshold > 0:
            export = dataclasses.replace(export, warnings=[
                *export.warnings, "the Cycles emulation does not filter fireflies: Light Paths ▸ Clamping ▸ Firefly "
                "Filter left out of the render"])
        return cls(scene, export.scene, export.warnings, band_count=band_count,
                   max_renders=settings.emulation_max_renders, shader=settings.emulation_shader, spp=spp)

    @property
    def cycles_renders(self) -> int:
        """Planned Cycles renders (band groups), each made twice (two seeds)."""
        return len(self.plan.renders)

    def describe(self) -> str:
        """The bands and what they cost (with the estimated colour error when planned)."""
        if self.band_plan is not None:
            bands = self.band_plan.summary()
        else:
            bands = f"{self.plan.bands.count} equal bands in {self.cycles_renders} Cycles render(s)"
        return f"Cycles emulation: {bands}, each made twice"

    @property
    def fraction(self) -> float:
        return 1.0 - len(self._queue) / self._total

    @property
    def running(self) -> bool:
        return self.result is None and self.error is None

    def cancel(self) -> None:
        self._cancel = True

    def step(self) -> None:
        """Make the next Cycles render, or finish (cancelled, failed or done)."""
        if not self.running:
            return
        if self._cancel or not self._queue:
            cancelled = bool(self._queue)
            passes = None if cancelled else self._data_passes()
            self.result = RenderResult(film=self.film, cancelled=cancelled or passes is None, seconds=self._seconds,
                                       **({"passes": passes} if passes is not None else {}))
            self._scratch.cleanup()
            return
        start = time.perf_counter()
        members = self._queue.pop(0)
        try:
            first, second = self._render(members)
        except SpectralError as problem:
            self.error = str(problem)
            self._scratch.cleanup()
            return
        finally:
            self._seconds += time.perf_counter() - start
        self.film.add(first, second, self.plan.weights[list(members)])

    def run(self, progress=None, notice=None, cancel=None) -> RenderResult | None:
        """All renders in this thread; `progress` follows each, `cancel()` is asked between them (the
        emulation never waits: `notice` is not called)."""
        while self.running:
            if cancel is not None and cancel():
                self.cancel()
            self.step()
            if progress is not None and self.running:
                progress(self.film, self.fraction)
        return self.result

    def _data_passes(self):
        """The data passes the scene asks for, as the tracer makes them (geometry only: no band to emulate)."""
        start = time.perf_counter()
        scene = self._tracer_scene
        try:
            return first_hit_passes(scene, band_scenes(scene)[0], 2 * self.samples, self.seed, scene.settings.backend)
        finally:
            self._seconds += time.perf_counter() - start

    def _render(self, members) -> tuple[np.ndarray, np.ndarray]:
        """The two halves of one planned render, (height, width, 3) each, top row first."""
        scene, folder = self.scene, Path(self._scratch.name)
        objects = list(scene.objects)
        if self._fluid_files is None:
            self._fluid_files = fluids.write_grids(objects, self._media, folder)
        with Borrowed() as borrowed:
            setup.cycles_settings(borrowed, scene, samples=self.samples, max_bounces=self.max_bounces,
                                  shader=self.shader)
            setup.camera(borrowed, scene)
            setup.lights(borrowed, objects, self.plan, members)
            setup.world(borrowed, scene, self.plan, members)
            stand_ins = fluids.stand_ins(borrowed, scene, self._fluid_files)
            setup.materials(borrowed, objects, self.plan, members, self.shader, self.warnings, stand_ins)
            return tuple(self._cycles(borrowed, members, 2 * self.seed + half, folder / f"half{half}.exr")
                         for half in (0, 1))

    def _cycles(self, borrowed, members, seed: int, path: Path) -> np.ndarray:
        scene = self.scene
        borrowed.set(scene.cycles, "seed", seed)
        borrowed.set(scene.render, "filepath", str(path))
        path.unlink(missing_ok=True)  # the previous render's half: never read it as this one's
        try:
            bpy.ops.render.render(write_still=True, scene=scene.name)
        except RuntimeError as problem:
            raise SpectralError(f"Cycles failed on bands {self._bands(members)}: {problem}") from None
        if not path.is_file():
            raise SpectralError(f"Cycles wrote no image for bands {self._bands(members)}")
        channels = image_io.read_exr(path)
        return np.stack([channels[name] for name in "RGB"], axis=-1).astype(np.float64)

    def _bands(self, members) -> str:
        return ", ".join(self.plan.bands.label(k) for k in members)
