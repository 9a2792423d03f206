"""Render jobs: one exported frame rendered by the renderer the Render settings choose, the same way for every
caller (F12, Render to Image, the command line).

`kind(settings)` is the only place that reads the settings' `renderer` to choose: the tracer (`TracerJob`,
here or on the Dask farm, `dispatch`) or the Cycles emulation (`cycles_emulation.job.EmulationJob`).
`render_job` builds the chosen kind's job. Every kind is a `Job` and offers the same things, so a caller
never asks which kind it holds: `start()` then `step()` on every UI timer tick until it is no longer
`running` (a modal operator), or `run()` in the calling thread; `cancel()`; `fraction`, `message`,
`warnings`, `describe()` while it renders; `result`, `error` and `succeeded` when it has ended. Where a kind
cannot run, it says so (`engine_refusal`, `viewport_note`). The Rendered viewport renders the tracer
through its own restartable renderer (addon/viewport_render.py) and asks here only for its note.
"""

import threading
from abc import ABC, abstractmethod

from . import dispatch
from .export.scene import Export
from .tracer.errors import SpectralError
from .tracer.render import RenderResult
from .tracer.scene import Scene


class Job(ABC):
    """One render. `fraction` (0–1) is how much is done; `message` what the render waits for before it
    starts (the kernel compiling), else None; `warnings` are for the user (a job may find more while it
    renders); `result` is the RenderResult once the render ended (cancelled or not), `error` why it failed."""

    engine_refusal: str | None = None  # why a render engine's render (F12) cannot run this kind; None: it can
    viewport_note: str | None = None  # what the Rendered viewport shows instead of this kind, if not this kind

    def __init__(self, warnings=()):
        self.warnings = list(warnings)
        self.message = None
        self.result = None
        self.error = None

    @classmethod
    @abstractmethod
    def for_export(cls, scene, export: Export, *, spp: int | None = None, scheduler: str | None = None) -> "Job":
        """The job that renders `export` of the Blender `scene` with its Render settings, at `spp` samples
        (None: the settings'), on the Dask farm at `scheduler` (None: the settings'; "": this computer)."""

    def start(self) -> None:
        """Start what renders in the background, where the kind renders there (the tracer); nothing otherwise."""

    def step(self) -> None:
        """Do the next piece of the work that must run on Blender's main thread, where the kind has such work
        (the emulation's Cycles renders); nothing otherwise. Called between UI events."""

    @abstractmethod
    def run(self, progress=None, notice=None, cancel=None) -> RenderResult | None:
        """The whole render in the calling thread; returns `result`. `progress(film, fraction)` is called
        after each unit of work, `notice(text)` when the render waits for something (as `message` says),
        and `cancel()`, when given, is asked between units, as `dispatch.run` does. Bad input ends the
        job with `error` set; anything else raises (a bug)."""

    @abstractmethod
    def cancel(self) -> None:
        """Stop at the end of the unit of work in flight; the result is then marked cancelled."""

    @property
    @abstractmethod
    def running(self) -> bool:
        """Whether the render has yet to end."""

    @abstractmethod
    def describe(self) -> str:
        """What renders, for the user (`Rendering with the …`, the command line's summary)."""

    @property
    def succeeded(self) -> bool:
        """Whether the render ended with a complete result."""
        return self.error is None and self.result is not None and not self.result.cancelled


class TracerJob(Job):
    """The tracer, here or on the Dask farm: on a background thread (`start`), polled from Blender's main
    thread, or in the calling thread (`run`). The Numba kernel releases the GIL, so Blender stays
    responsive. The thread never touches `bpy`: it gets a finished tracer Scene."""

    def __init__(self, scene: Scene, scheduler: str = "", *, spp: int | None = None, warnings=()):
        super().__init__(warnings)
        self.scene, self.scheduler, self.spp = scene, scheduler, spp
        self.fraction = 0.0
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._work, name="spectral-render", daemon=True)

    @classmethod
    def for_export(cls, scene, export: Export, *, spp: int | None = None,
                   scheduler: str | None = None) -> "TracerJob":
        address = scene.spectral.scheduler_address if scheduler is None else scheduler
        return cls(export.scene, address, spp=spp, warnings=export.warnings)

    def start(self) -> None:
        self._thread.start()

    def run(self, progress=None, notice=None, cancel=None) -> RenderResult | None:
        def progressed(film, fraction):
            self.fraction, self.message = fraction, None
            if progress is not None:
                progress(film, fraction)

        def noticed(text):
            self.message = text
            if notice is not None:
                notice(text)

        try:
            self.result = dispatch.run(self.scene, self.scheduler, spp=self.spp, progress=progressed,
                                       cancel=lambda: self._cancel.is_set() or (cancel is not None and cancel()),
                                       notice=noticed)
        except SpectralError as problem:
            self.error = str(problem)
        return self.result

    def _work(self) -> None:
        """What the background thread runs: `run`, with every failure kept for the main thread to report."""
        try:
            self.run()
        except Exception as problem:  # noqa: BLE001 - reported to the user instead of dying silently
            self.error = f"the render failed unexpectedly: {problem!r}"

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    def describe(self) -> str:
        return f"tracer on the Dask farm at {self.scheduler}" if self.scheduler else "tracer"


def kind(settings) -> type[Job]:
    """The job kind the Render settings (`scene.spectral`) choose."""
    if settings.renderer == "CYCLES":
        from .cycles_emulation.job import EmulationJob  # here, not above: it is a Job, defined in this module

        return EmulationJob
    return TracerJob


def render_job(scene, export: Export, *, spp: int | None = None, scheduler: str | None = None) -> Job:
    """The job of the kind the Render settings of the Blender `scene` choose; see `Job.for_export`."""
    return kind(scene.spectral).for_export(scene, export, spp=spp, scheduler=scheduler)
