"""Procedural density grids (clouds, blobs) for demos, benchmarks and tests; no files needed.

Values are float32 in [0, 1], indexed [x, y, z]; `cloud_grid` places them in a world box.
"""

import numpy as np

from .errors import SpectralError
from .scene import Grid


def _value_noise(resolution: int, cells: int, rng: np.random.Generator) -> np.ndarray:
    """Smooth random field: random values on a coarse lattice, upsampled with smoothstep weights."""
    lattice = rng.random((cells + 1,) * 3, dtype=np.float32)
    position = np.linspace(0.0, cells, resolution, endpoint=False, dtype=np.float32)
    index = np.minimum(position.astype(np.int64), cells - 1)
    t = position - index
    t = t * t * (3 - 2 * t)
    field = np.zeros((resolution,) * 3, dtype=np.float32)
    for corner in np.ndindex(2, 2, 2):
        weights = [tt if c else 1 - tt for c, tt in zip(corner, (t, t, t))]
        values = lattice[np.ix_(index + corner[0], index + corner[1], index + corner[2])]
        field += values * weights[0][:, None, None] * weights[1][None, :, None] * weights[2][None, None, :]
    return field


def cloud(resolution: int = 64, seed: int = 0, octaves: int = 4, coverage: float = 0.45) -> np.ndarray:
    """A cumulus-like density: fractal value noise inside a soft ellipsoid; `coverage` in (0, 1) grows it."""
    if resolution < 4:
        raise SpectralError(f"a procedural cloud needs a resolution of at least 4, got {resolution}")
    rng = np.random.default_rng(seed)
    noise = np.zeros((resolution,) * 3, dtype=np.float32)
    amplitude, total = 1.0, 0.0
    for octave in range(octaves):
        noise += amplitude * _value_noise(resolution, 2 ** (octave + 2), rng)
        total += amplitude
        amplitude *= 0.5
    noise /= total
    axis = np.linspace(-1.0, 1.0, resolution, dtype=np.float32)
    x, y, z = np.meshgrid(axis, axis, axis * 1.4, indexing="ij", sparse=True)
    # The noise must exceed a threshold that rises towards the ellipsoid's surface.
    threshold = (1.0 - coverage) * 0.75 + 0.3 * (x * x + y * y + z * z)
    density = np.clip((noise - threshold) * 4.0, 0.0, 1.0)
    return density.astype(np.float32)


def cloud_grid(resolution: int = 64, size: float = 2.0, centre=(0.0, 0.0, 0.0), seed: int = 0) -> Grid:
    """`cloud` in a cube of edge `size` world units around `centre`."""
    step = size / resolution
    index_to_world = np.diag([step, step, step, 1.0])
    index_to_world[:3, 3] = np.asarray(centre, dtype=np.float64) - size / 2 + 0.5 * step
    return Grid(cloud(resolution, seed), index_to_world, name="density")
