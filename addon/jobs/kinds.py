"""The job kind the Render settings choose: the only place that reads the settings' `renderer`."""

from ..cycles_emulation.job import EmulationJob
from ..export.scene import Export
from .protocol import Job
from .tracer_job import TracerJob


def kind(settings) -> type[Job]:
    """The job kind the Render settings (`scene.spectral`) choose."""
    if settings.renderer == "CYCLES":
        return EmulationJob
    return TracerJob


def render_job(scene, export: Export, *, spp: int | None = None, scheduler: str | None = None) -> Job:
    """The job of the kind the Render settings of the Blender `scene` choose; see `Job.for_export`."""
    return kind(scene.spectral).for_export(scene, export, spp=spp, scheduler=scheduler)
