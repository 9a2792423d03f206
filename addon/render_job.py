"""A tracer render (here or on a Dask farm) on a background thread, polled from Blender's main thread.

The Numba kernel releases the GIL, so Blender stays responsive. The thread never touches `bpy`: it
gets a finished tracer Scene and leaves a RenderResult (or an error message) behind.
"""

import threading

from . import dispatch
from .tracer.errors import SpectralError
from .tracer.scene import Scene


class RenderJob:
    def __init__(self, scene: Scene, scheduler: str = ""):
        self.scene, self.scheduler = scene, scheduler
        self.fraction = 0.0
        self.message = None  # what the render waits for before it starts (the kernel compiling), if anything
        self.result = None
        self.error = None
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self.run, name="spectral-render", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def step(self) -> None:
        """Nothing to do on the main thread: the render runs on its own (the Cycles emulation's job steps)."""

    def run(self) -> None:
        """Render in the calling thread (what the background thread runs)."""
        try:
            self.result = dispatch.run(self.scene, self.scheduler, progress=self._progress, cancel=self._cancel.is_set,
                                       notice=self._notice)
        except SpectralError as problem:
            self.error = str(problem)
        except Exception as problem:  # noqa: BLE001 - reported to the user instead of dying silently
            self.error = f"the render failed unexpectedly: {problem!r}"

    def _progress(self, _film, fraction: float) -> None:
        self.fraction = fraction
        self.message = None

    def _notice(self, text: str) -> None:
        self.message = text

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    @property
    def succeeded(self) -> bool:
        return self.error is None and self.result is not None and not self.result.cancelled
