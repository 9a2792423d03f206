"""Export a scene as F12 renders it, from outside F12: Render to Image, Export Scene, Estimate Bands, the CLI.

What F12 renders is decided by Blender's render depsgraph: objects and collections disabled in renders
(`hide_render`) are left out, objects only hidden in the viewport are in, and modifiers and Geometry Nodes
are evaluated with their render settings (`show_render`, Subdivision's Render levels). The viewport
depsgraph (`Context.evaluated_depsgraph_get`, `ViewLayer.depsgraph`) follows the viewport instead, and
Blender's Python API (5.2) cannot build a render one. So `export_rendered` asks Blender to render the one
view layer (`bpy.ops.render.render`) with this engine: while the request is open, the engine's `render()`
hands its depsgraph to `capture`, which exports it and renders nothing. The export is therefore F12's own,
and what F12 does besides happens too: render handlers run, and the Render Result becomes an empty image.
"""

from dataclasses import dataclass, field

import bpy

from .scene import Export, export_scene
from ..props.render import ENGINE_ID
from ..tracer.errors import SpectralError


@dataclass
class _Request:
    scene: str
    view_layer: str
    outcome: list = field(default_factory=list)  # the Export, or what exporting raised


_request: _Request | None = None


def export_rendered(scene, view_layer) -> Export:
    """Export `view_layer` of `scene` at its current frame, from the depsgraph F12 would render.
    Raises SpectralError on bad input, or when Blender renders nothing of that view layer."""
    global _request
    if _request is not None:
        raise SpectralError("another export for rendering is under way")
    _request = _Request(scene.name, view_layer.name)
    engine = scene.render.engine
    try:
        if engine != ENGINE_ID:
            scene.render.engine = ENGINE_ID  # any engine renders with the render depsgraph; ours exports it
        try:
            bpy.ops.render.render(scene=scene.name, layer=view_layer.name)
        except RuntimeError as problem:  # no camera, a render already running...
            raise SpectralError(f"Blender cannot render the scene: {str(problem).strip().removeprefix('Error: ')}") \
                from None
        outcome = _request.outcome
    finally:
        _request = None
        if scene.render.engine != engine:
            scene.render.engine = engine
    if not outcome:
        raise SpectralError(f"Blender renders nothing of view layer {view_layer.name!r}: its Use for Rendering "
                            "(View Layer Properties) is off, or the Sequencer's strips replace the scene "
                            "(Output Properties ▸ Post Processing)")
    if isinstance(outcome[0], BaseException):
        raise outcome[0]
    return outcome[0]


def capture(depsgraph) -> bool:
    """For the engine's `render()`: True when an export is requested, having exported `depsgraph` for it
    (the render then renders nothing). A depsgraph of another scene or view layer (a Sequencer strip's)
    is not the one asked for: it is skipped."""
    if _request is None:
        return False
    if (depsgraph.scene.name, depsgraph.view_layer.name) == (_request.scene, _request.view_layer):
        try:
            _request.outcome.append(export_scene(depsgraph))
        except Exception as problem:  # re-raised by export_rendered, outside Blender's render
            _request.outcome.append(problem)
    return True
