"""Fluid (smoke and fire) domains → grids, read from the domain's OpenVDB cache files.

Blender writes one file per frame, `<cache directory>/data/fluid_data_<frame:04>.vdb`, holding the
grids "density", "temperature" (the simulation's heat), "flame", "fuel", "react", "color_r/g/b";
with noise, `noise/fluid_noise_<frame:04>.vdb` holds "density_noise" and "flame_noise" at
`noise_scale` times the resolution. The frame read is the scene frame minus `cache_frame_offset`.

Cell (i, j, k) of the simulation is VDB voxel (i, j, k). The grid spans the domain mesh's bounding
box: the longest side gets `resolution_max` cells, the others proportionally (at least 4), and the
box is divided evenly along each axis, as Blender maps the cache onto the domain. Adaptive domains
are not supported. The domain is recognised by its modifier whether or not the modifier is shown,
so the simulation need not be evaluated (which would start Mantaflow) to render its cache.
"""

from pathlib import Path

import bpy
import numpy as np

from ..tracer.errors import SpectralError
from ..tracer.grids import load_grid
from ..tracer.scene import Grid

# What artists may type as a grid name → the name Blender's cache uses.
ALIASES = {"heat": "temperature", "fire": "flame", "smoke": "density"}
MIN_CELLS = 4


def fluid_domain(obj):
    """The FluidDomainSettings of a smoke/fire domain object, or None."""
    for modifier in obj.original.modifiers:
        if modifier.type == "FLUID" and modifier.fluid_type == "DOMAIN":
            return modifier.domain_settings
    return None


def base_resolution(size, resolution_max: int) -> np.ndarray:
    """Cells per axis of a domain box of world `size`: the longest axis gets `resolution_max`."""
    size = np.asarray(size, dtype=np.float64)
    cell = size.max() / resolution_max
    return np.maximum((size / cell + 0.5).astype(int), MIN_CELLS)


def _cache_file(obj, domain, frame: int) -> Path:
    folder = Path(bpy.path.abspath(domain.cache_directory, library=obj.original.library))
    kind, stem = ("noise", "fluid_noise") if domain.use_noise else ("data", "fluid_data")
    path = folder / kind / f"{stem}_{frame:04d}.vdb"
    if not path.is_file():
        raise SpectralError(f"fluid domain {obj.name!r}: no baked cache for frame {frame}: {path} does not exist "
                            "(bake the simulation, or check its cache directory)")
    return path


def _check(obj, domain) -> None:
    if domain.domain_type != "GAS":
        raise SpectralError(f"fluid domain {obj.name!r} is a liquid: only smoke and fire domains are volumes")
    if domain.use_adaptive_domain:
        raise SpectralError(f"fluid domain {obj.name!r} uses an adaptive domain, which is not supported: "
                            "turn Adaptive Domain off and bake again")
    if domain.cache_data_format != "OPENVDB":
        raise SpectralError(f"fluid domain {obj.name!r} caches in {domain.cache_data_format} format: "
                            "set its cache format to OpenVDB and bake again")


def cell_to_world(obj, domain, matrix) -> np.ndarray:
    """Index-to-world matrix of the domain's cells (cell centres at integer indices); `matrix` places
    the domain object in the world."""
    corners = np.array([corner[:] for corner in obj.original.bound_box])
    low, high = corners.min(axis=0), corners.max(axis=0)
    scale = np.abs(np.array(matrix.to_scale()))
    cells = base_resolution((high - low) * scale, domain.resolution_max)
    if domain.use_noise:
        cells = cells * domain.noise_scale
    step = (high - low) / cells
    cell_to_local = np.diag(np.append(step, 1.0))
    cell_to_local[:3, 3] = low + 0.5 * step
    return np.array(matrix, dtype=np.float64) @ cell_to_local


def cache_grid_name(name: str, noise: bool) -> str:
    name = ALIASES.get(name, name)
    return f"{name}_noise" if noise and name in ("density", "flame") else name


def fluid_grids(obj, depsgraph, names, matrix) -> list[Grid]:
    """The grids called `names` (aliases allowed: heat, fire, smoke) of a domain's cache, in world space
    (the domain object at `matrix`)."""
    domain = fluid_domain(obj)
    _check(obj, domain)
    path = _cache_file(obj, domain, depsgraph.scene.frame_current - domain.cache_frame_offset)
    to_world = cell_to_world(obj, domain, matrix)
    try:
        return [load_grid(path, cache_grid_name(name, domain.use_noise), to_world) for name in names]
    except SpectralError as problem:
        raise SpectralError(f"fluid domain {obj.name!r}: {problem}") from None
