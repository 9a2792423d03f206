"""Meshes with a spectral volume material → a density grid: 1 inside the evaluated mesh, 0 outside.

Voxel centres lie on a world-axis-aligned lattice of the object's `voxel_size` around its bounds.
Inside is decided per column of voxels: a ray cast upwards through the column's centre collects every
crossing of the surface (mathutils BVH tree), and a voxel is inside when an odd number of crossings
lies below it. Open meshes give columns with an odd number of crossings; those are left empty.
"""

import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

from ..tracer.errors import SpectralError
from ..tracer.scene import Grid

MAX_VOXELS = 512**3
_EPSILON = 1e-6
_FIT_TOLERANCE = 1e-4  # fraction of a voxel by which a mesh may exceed a whole number of voxels


def _world_triangles(obj, matrix):
    mesh = obj.to_mesh()
    try:
        mesh.calc_loop_triangles()
        vertices = np.empty(len(mesh.vertices) * 3)
        mesh.vertices.foreach_get("co", vertices)
        triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", triangles)
    finally:
        obj.to_mesh_clear()
    matrix = np.array(matrix, dtype=np.float64)
    vertices = vertices.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    return vertices, triangles.reshape(-1, 3)


def _crossings(tree, x: float, y: float, z0: float, z1: float) -> list[float]:
    hits, z = [], z0
    while True:
        location, _normal, _index, distance = tree.ray_cast(Vector((x, y, z)), Vector((0.0, 0.0, 1.0)), z1 - z)
        if location is None:
            return hits
        hits.append(location.z)
        z = location.z + max(_EPSILON, distance * _EPSILON)


def voxelise(obj, voxel_size: float, matrix) -> Grid:
    """Density grid of an evaluated mesh object placed at world `matrix` (world space, `voxel_size`
    world units per voxel)."""
    vertices, triangles = _world_triangles(obj, matrix)
    if len(triangles) == 0:
        raise SpectralError(f"mesh {obj.name!r} has no faces to fill with its volume material")
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    # Vertices are float32: a box 1 unit wide at x = 0.85 spans 1.0000000x, which must stay 1 / voxel_size voxels.
    spans = np.ceil((high - low) / voxel_size - _FIT_TOLERANCE)
    cells = np.maximum(spans.astype(int), 1) + 2  # an empty voxel on every side
    if np.prod(cells.astype(np.float64)) > MAX_VOXELS:
        raise SpectralError(f"mesh {obj.name!r}: voxel size {voxel_size:g} gives {' × '.join(map(str, cells))} "
                            "voxels, too many: increase the object's Voxel Size")
    origin = (low + high) / 2 - (cells - 1) / 2 * voxel_size  # centre of voxel (0, 0, 0)
    tree = BVHTree.FromPolygons([Vector(v) for v in vertices], triangles.tolist(), all_triangles=True)
    z_centres = origin[2] + np.arange(cells[2]) * voxel_size
    start, end = low[2] - voxel_size, high[2] + voxel_size
    values = np.zeros(tuple(cells), dtype=np.float32)
    for i in range(cells[0]):
        x = origin[0] + i * voxel_size
        for j in range(cells[1]):
            hits = _crossings(tree, x, origin[1] + j * voxel_size, start, end)
            if hits and len(hits) % 2 == 0:
                values[i, j] = np.searchsorted(np.sort(hits), z_centres) % 2
    index_to_world = np.diag([voxel_size, voxel_size, voxel_size, 1.0])
    index_to_world[:3, 3] = origin
    return Grid(values=values, index_to_world=index_to_world, name="density")
