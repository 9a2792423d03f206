"""Starts the tracer's kernel compiling in the background (addon/tracer/background_compile.py) as soon as a
scene renders with this engine's local Numba kernel: when a file using it loads, and when a scene switches
to it. The first render then usually finds the kernel compiled instead of compiling it for minutes; right
after installing, it renders with the portable kernel the extension ships meanwhile.
"""

import bpy

from ..props.render import ENGINE_ID, chosen_backend
from ..tracer import background_compile


def uses_local_kernel(scene) -> bool:
    """Whether `scene` renders with this engine's Numba kernel on this computer (not on a Dask farm, whose
    workers compile their own, and not with the NumPy backend or on the GPU)."""
    settings = scene.spectral
    return scene.render.engine == ENGINE_ID and chosen_backend(settings) == "numba" and not settings.scheduler_address


@bpy.app.handlers.persistent
def warm_up_on_switch(scene, _depsgraph=None) -> None:
    """After a change: start the compile once the scene uses the kernel (a cheap check on every update)."""
    if not background_compile.started() and uses_local_kernel(scene):
        background_compile.start()


@bpy.app.handlers.persistent
def warm_up_on_load(_=None) -> None:
    """After a file loads: start the compile if any of its scenes uses the kernel."""
    if not background_compile.started() and any(uses_local_kernel(scene) for scene in bpy.data.scenes):
        background_compile.start()


CLASSES = ()
HANDLERS = ((bpy.app.handlers.depsgraph_update_post, warm_up_on_switch), (bpy.app.handlers.load_post, warm_up_on_load))

