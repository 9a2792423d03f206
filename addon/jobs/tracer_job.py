"""The tracer's render job (`TracerJob`), and `render_tracer`, which renders a tracer Scene on this computer or on
the Dask farm whose scheduler the Render settings name.

Both give the same RenderResult (the distributed film is bit-identical, docs/distributed.md) and call
`progress(film, fraction)` and `cancel()` alike, so the engine, Render to Image and the CLI show the
cluster's progress and stop it the same way. Dask comes with the extension's wheels; where it is
missing anyway (the add-on run from a source checkout) the tracer reports what to install.
"""

import threading

from ..export.scene import Export
from ..tracer import render as local
from ..tracer.errors import SpectralError
from ..tracer.render import RenderResult
from ..tracer.scene import Scene
from .protocol import Job


def render_tracer(scene: Scene, scheduler: str = "", *, spp: int | None = None, progress=None, cancel=None,
                  notice=None, unit_seconds: float = local.UNIT_SECONDS) -> RenderResult:
    """`notice(text)` is told what a local render waits for before it starts (the kernel compiling); the
    farm's workers compile their own kernels. A local render works in units of about `unit_seconds` (the
    most a cancel waits); the farm's units are its tiles."""
    if not scheduler:
        return local.render(scene, spp=spp, progress=progress, cancel=cancel, notice=notice,
                            unit_seconds=unit_seconds)
    from ..tracer import farm  # Dask: imported only for a farm

    return farm.render(scene, scheduler=scheduler, spp=spp, progress=progress, cancel=cancel)


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
            self.result = render_tracer(self.scene, self.scheduler, spp=self.spp, progress=progressed,
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
