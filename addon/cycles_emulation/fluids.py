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


def write_grids(objects, media: dict[str, Medium], folder: Path) -> dict[str, Path]:
    """Domain name → a VDB in `folder` holding its medium's grids, for every fluid domain the tracer renders
    (written once per emulation, read by every render's stand-in)."""
    files = {}
    for obj in objects:
        medium = media.get(obj.name)
        if medium is not None and obj.type == "MESH" and fluid_domain(obj) is not None:
            files[obj.name] = save_grid_vdb(folder / f"fluid_domain_{len(files)}.vdb", *_grids(medium))
    return files


def stand_ins(borrowed, scene, files: dict[str, Path]) -> dict:
    """Domain name → a temporary Volume object reading its file from `write_grids`, linked to `scene`;
    the domains are hidden from the render."""
    result = {}
    for name, path in files.items():
        volume = borrowed.keep(bpy.data.volumes.new(f".spectral emulation {name}"))
        volume.filepath = str(path)
        stand_in = borrowed.keep(bpy.data.objects.new(volume.name, volume))
        scene.collection.objects.link(stand_in)
        borrowed.set(scene.objects[name], "hide_render", True)
        result[name] = stand_in
    return result
