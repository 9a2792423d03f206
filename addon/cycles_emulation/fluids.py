"""Fluid domains in the emulation: for each Cycles render a temporary Volume object stands in for every
smoke or fire domain the tracer renders.

Cycles reads a domain's grids only through its evaluated fluid modifier, which needs Mantaflow (which
Blender-as-a-module cannot run) and which scenes may hide to keep Mantaflow from starting, as our demos
do; the tracer reads the cache files itself (`export.fluids`). So the domain is hidden, and the grids the
tracer renders (density, and temperature for blackbody emission), written to a temporary VDB in world
space, fill a Volume object that takes its place. Both engines then read the very same voxels.
"""

from pathlib import Path

import bpy

from ..export.fluids import fluid_domain
from ..tracer.grids import save_grid_vdb
from ..tracer.scene import Grid, Medium

DENSITY, TEMPERATURE = "density", "temperature"  # grid names in the stand-in's file


def _grids(medium: Medium) -> list[Grid]:
    grids = [Grid(medium.density.values, medium.density.index_to_world, DENSITY)]
    if medium.emission is not None:
        temperature = medium.emission.temperature
        grids.append(Grid(temperature.values, temperature.index_to_world, TEMPERATURE))
    return grids


def stand_ins(borrowed, scene, objects, media: dict[str, Medium], folder: Path) -> dict:
    """Domain name → a temporary Volume object holding its medium's grids, linked to `scene`; the domains
    are hidden from the render."""
    result = {}
    for obj in objects:
        medium = media.get(obj.name)
        if medium is None or obj.type != "MESH" or fluid_domain(obj) is None:
            continue
        path = save_grid_vdb(folder / f"fluid_domain_{len(result)}.vdb", *_grids(medium))
        volume = borrowed.keep(bpy.data.volumes.new(f".spectral emulation {obj.name}"))
        volume.filepath = str(path)
        stand_in = borrowed.keep(bpy.data.objects.new(volume.name, volume))
        scene.collection.objects.link(stand_in)
        borrowed.set(obj, "hide_render", True)
        result[obj.name] = stand_in
    return result
