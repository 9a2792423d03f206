"""An object's volume fields as Cycles' volume shaders see them: its attribute grids by name, and the
region its shader fills (where a constant Density or an emission applies), all in world space.

- Volume objects: the VDB's grids; the region is where the object's Density Grid (or its first grid)
  exceeds the volume's Clipping, as Cycles bounds a volume by its voxels above it. With the volume's
  Space set to Object (Blender's default), Cycles scales its shader's density and emission by the
  object's scale: 1 / |M (1, 1, 1)/√3| (`density_scale`).
- Fluid domains: the cache's `density`, `flame` and `heat` grids, and `temperature` as Cycles reads it
  from the flame (ignition + flame × (maximum − ignition) where flame > 0.01, else 0: 0..1 is 0..1000 K
  for the Temperature input); the region is the whole domain.
- Meshes: no attributes; the region is the inside of the evaluated mesh, voxelised at the object's
  Voxel Size (`meshes.voxelise`).
Grids are read once per object and export.
"""

import numpy as np

from ..tracer.errors import SpectralError
from ..tracer.scene import Grid
from .fluids import fluid_domain, fluid_grids
from .meshes import voxelise
from .volumes import volume_grids

FLUID_ATTRIBUTES = ("density", "flame", "heat", "temperature")
FLAME_THRESHOLD = 0.01


class VolumeFields:
    """The fields of one evaluated object (an instance at world `matrix`)."""

    def __init__(self, obj, depsgraph, matrix):
        self.obj, self.depsgraph, self.matrix = obj, depsgraph, matrix
        self.domain = fluid_domain(obj) if obj.type == "MESH" else None
        self._grids: dict = {}
        self.density_scale = 1.0
        if obj.type == "VOLUME" and obj.data.render.space == "OBJECT":
            diagonal = np.array(matrix.to_3x3(), dtype=np.float64) @ np.full(3, 1.0 / np.sqrt(3.0))
            self.density_scale = 1.0 / float(np.linalg.norm(diagonal))
        if obj.type == "VOLUME":
            self.names = tuple(grid.name for grid in obj.data.grids)
        elif self.domain is not None:
            self.names = FLUID_ATTRIBUTES
        else:
            self.names = ()

    def has(self, name: str) -> bool:
        return name in self.names

    def grid(self, name: str | None) -> Grid:
        """The grid of attribute `name`, or the region (a 0/1 grid) for None."""
        if name not in self._grids:
            self._grids[name] = self._region() if name is None else self._read(name)
        return self._grids[name]

    def _read(self, name: str) -> Grid:
        if self.domain is None:
            return volume_grids(self.obj, self.depsgraph, [name], self.matrix)[0]
        if name == "temperature":
            flame = self.grid("flame")
            ignition, hottest = self.domain.flame_ignition, self.domain.flame_max_temp
            values = np.where(flame.values > FLAME_THRESHOLD, ignition + flame.values * (hottest - ignition), 0.0)
            return Grid(values.astype(np.float32), flame.index_to_world, "temperature")
        return fluid_grids(self.obj, self.depsgraph, [name], self.matrix)[0]  # its aliases: "heat" is the cache's heat

    def _region(self) -> Grid:
        if self.obj.type == "VOLUME":
            if not self.names:
                raise SpectralError(f"Volume {self.obj.name!r} has no grids at this frame")
            wanted = self.obj.original.spectral.density_grid
            grid = self.grid(wanted if wanted in self.names else self.names[0])
            inside = grid.values > self.obj.data.render.clipping
        elif self.domain is not None:
            grid = self.grid("density")
            inside = np.ones_like(grid.values, dtype=bool)
        else:
            return voxelise(self.obj, self.obj.original.spectral.voxel_size, self.matrix)
        return Grid(inside.astype(np.float32), grid.index_to_world, "region")
