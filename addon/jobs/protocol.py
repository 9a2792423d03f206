"""The render job protocol (`Job`): what every kind of render job offers its callers (addon/jobs/__init__.py)."""

from abc import ABC, abstractmethod

from ..export.scene import Export
from ..tracer.render import RenderResult


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
        and `cancel()`, when given, is asked between units, as `tracer_job.render_tracer` does. Bad input ends the
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
