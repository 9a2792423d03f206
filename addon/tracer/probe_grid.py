"""The sunward probe's grid: where a path's medium vertex sends a probe towards the sun, and how often.

A sunlit cloud of forward-scattering droplets is bright where a path's next vertex scatters the sun's light
through the phase function's peak: the path must arrive heading almost straight at the sun. Phase sampling
about the path's direction seldom draws such a direction, and the few paths that do bring a large sun estimate
at their next vertex: the speckles of a sunlit cloud at low sample counts. The probe (docs/algorithm.md,
"The sunward probe") draws an extra direction about the sun's at a medium vertex, with a chance a(x) = A ×
the sun's transmittance to x (where the sun reaches, its light is worth probing), and the two strategies are
weighed by the balance heuristic.

The chance must be a function of the position alone (the MIS weights depend on it): a grid of
`PROBE_CELLS`³ cells over the media's box, each cell's sun transmittance marched once through the density
grids at the media's mean extinction over the wavelength grid. Built once per scene by `lowering.compile_scene`;
the kernels look it up (`kernels/lookups.probe_chance`). No sun, no medium, or no medium that scatters forward
(Henyey–Greenstein g of at least `FORWARD_G` somewhere on the grid): no probe. Where the phase function has no
peak the probe's directions are the path's own kind of sample, at a vertex's cost: on the isotropic sunlit
scenes of `bench/vs_mitsuba.py` it gained nothing (efficiency 0.96–1.13×, bench/README.md).
"""

import numpy as np

from .kernels.layout import LIGHT_SUN, PHASE_RAYLEIGH, KernelScene
from .kernels.media import attenuation, density
from .kernels.geometry import transform_point

PROBE_CELLS = 32  # cells along each axis of the grid
# A: the chance of a probe where the sun shines unattenuated. 0.5 and 1 lowered the variance of a sunlit cloud
# alike (1.9× and 2.1×, bench/README.md "Denoise and a sunward probe"); 0.5 at half the cost.
PROBE_STRENGTH = 0.5
_STEPS_PER_CELL = 2  # the transmittance's march: steps per cell diagonal
FORWARD_G = 0.3  # the least anisotropy that sends probes


def no_probe() -> dict:
    """`KernelLights`' probe fields of a scene without a probe (the same types as with one)."""
    return {"probe": np.full(1, -1, dtype=np.int64), "probe_chance": np.zeros((1, 1, 1)),
            "probe_box": np.zeros((2, 3))}


def with_probe(ks: KernelScene) -> KernelScene:
    """`ks` with its probe: towards the sun chosen most often by next-event estimation, with the chance of a
    probe in each cell of the media's box; `no_probe` without a sun or without a forward-scattering medium."""
    suns = np.flatnonzero(ks.lights.kind == LIGHT_SUN)
    forward = [ks.media.phase_kind[m] != PHASE_RAYLEIGH and ks.media.anisotropy[m].max() >= FORWARD_G
               for m in range(ks.media.density_scale.shape[0])]
    if suns.size == 0 or not any(forward):
        return ks._replace(lights=ks.lights._replace(**no_probe()))
    sun = suns[np.argmax(ks.lights.pmf[suns])]
    lower, upper = _media_box(ks)
    size = np.maximum(upper - lower, 1e-12)
    chance = PROBE_STRENGTH * _sun_transmittance(ks, lower, size, ks.lights.dir[sun])
    return ks._replace(lights=ks.lights._replace(
        probe=np.full(1, sun, dtype=np.int64), probe_chance=np.minimum(chance, 1.0),
        probe_box=np.array([lower, PROBE_CELLS / size])))


def _media_box(ks: KernelScene) -> tuple[np.ndarray, np.ndarray]:
    """The world box around every medium's majorant grid (where the tracker tracks it)."""
    corners = []
    for m in range(ks.media.density_scale.shape[0]):
        extent = ks.majorant.shape[m] * ks.majorant.block[m]
        to_world = np.linalg.inv(ks.density.world_to_padded[m])
        for index in np.ndindex(2, 2, 2):
            corners.append(transform_point(to_world, *(np.array(index) * extent)))
    corners = np.array(corners, dtype=np.float64)
    return corners.min(axis=0), corners.max(axis=0)


def _sun_transmittance(ks: KernelScene, lower: np.ndarray, size: np.ndarray, towards_sun: np.ndarray) -> np.ndarray:
    """The sun's transmittance at each cell's centre (N, N, N): the density marched towards the sun to the box's
    edge, at each medium's mean extinction over the wavelength grid (its dye's absorption included)."""
    cells = (np.arange(PROBE_CELLS) + 0.5) / PROBE_CELLS
    grid = np.stack(np.meshgrid(cells, cells, cells, indexing="ij"), axis=-1).reshape(-1, 3)
    points = lower + grid * size
    with np.errstate(divide="ignore", invalid="ignore"):  # the box's exit along the sun's direction
        exits = np.where(towards_sun > 0.0, (lower + size - points) / towards_sun,
                         np.where(towards_sun < 0.0, (lower - points) / towards_sun, np.inf))
    exit = exits.min(axis=1)
    step = np.linalg.norm(size / PROBE_CELLS) / _STEPS_PER_CELL
    sigma = [ks.media.density_scale[m] * np.mean(attenuation(1.0, ks.media.extinction[m],
                                                               ks.fluorescence.excitation[m]))
             for m in range(ks.media.density_scale.shape[0])]
    depth = np.zeros(points.shape[0])
    for k in range(int(np.ceil(exit.max() / step))):
        t = (k + 0.5) * step
        inside = t < exit
        if not inside.any():
            break
        x, y, z = (points[inside] + t * towards_sun).T
        for m, coefficient in enumerate(sigma):
            depth[inside] += coefficient * density(ks, m, x, y, z) * np.minimum(step, exit[inside] - k * step)
    return np.exp(-depth).reshape(PROBE_CELLS, PROBE_CELLS, PROBE_CELLS)
