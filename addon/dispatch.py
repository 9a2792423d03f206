"""Runs a tracer render on this computer, or on the Dask farm whose scheduler the Render settings name.

Both give the same RenderResult (the distributed film is bit-identical, docs/distributed.md) and call
`progress(film, fraction)` and `cancel()` alike, so the engine, Render to Image and the CLI show the
cluster's progress and stop it the same way. Dask comes with the extension's wheels; where it is
missing anyway (the add-on run from a source checkout) the tracer reports what to install.
"""

from .tracer import render as local
from .tracer.render import RenderResult
from .tracer.scene import Scene


def run(scene: Scene, scheduler: str = "", *, spp: int | None = None, progress=None, cancel=None,
        notice=None, unit_seconds: float = local.UNIT_SECONDS) -> RenderResult:
    """`notice(text)` is told what a local render waits for before it starts (the kernel compiling); the
    farm's workers compile their own kernels. A local render works in units of about `unit_seconds` (the
    most a cancel waits); the farm's units are its tiles."""
    if not scheduler:
        return local.render(scene, spp=spp, progress=progress, cancel=cancel, notice=notice,
                            unit_seconds=unit_seconds)
    from .tracer import distributed

    return distributed.render(scene, scheduler=scheduler, spp=spp, progress=progress, cancel=cancel)
