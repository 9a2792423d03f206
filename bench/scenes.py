"""The benchmark scenes, built in code and shared by every script in bench/.

One family of scenes (issue 3, Performance): the procedural heterogeneous cloud of
`addon.tracer.procedural.cloud_grid` (edge 2 world units, at the origin), single-scattering albedo 0.8,
Henyey–Greenstein anisotropy g, lit by a D65 sun and a constant equal-energy environment, seen by a 40°
perspective camera. The sun is a delta light (angle 0) so that Mitsuba's `directional` emitter is the
same light. `grid="sphere"` swaps the cloud for a smooth soft sphere (optical depth about 8 through its
centre). Extinction, albedo and anisotropy can each vary with wavelength (`CHROMATIC` sets all three:
the seminar report's Rayleigh-like setting, g rising towards the red, for the colour benchmark).

Grids of 256³ and more take minutes and gigabytes of temporaries to generate, so `cloud_density` keeps
every grid it made as a .npy file in a cache folder (default out/bench-cache/, ignored by git).
"""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from addon.tracer import spectra
from addon.tracer.builders import environment, medium, perspective, scene, smooth_ramp, sun
from addon.tracer.procedural import cloud_grid
from addon.tracer.scene import Camera, Grid, Light, Medium, Scene

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / "out" / "bench-cache"

CLOUD_SIZE = 2.0  # world units, edge of the grid's cube
CLOUD_SEED = 7
SUN_DIRECTION = (0.5, -0.4, 0.75)  # towards the sun
EYE, TARGET = (0.0, -3.6, 0.5), (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class CloudSpec:
    """Everything that varies between benchmark scenes (defaults: issue 3's settings)."""

    resolution: int = 64
    g: float = 0.0
    albedo: float = 0.8
    density_scale: float = 30.0  # σ_t = 30 per world unit where the density is 1
    width: int = 256
    height: int = 256
    fov_degrees: float = 40.0
    sun_strength: float = 3.0  # irradiance luminance Y on a plane facing the sun
    environment_strength: float = 0.5  # radiance luminance Y
    grid: str = "cloud"  # "cloud": procedural.cloud_grid; "sphere": sphere_density
    extinction_varies: bool = False  # extinction 1.4 → 0.7 from 380 to 700 nm instead of 1
    albedo_varies: bool = False  # albedo 0.6 → 0.95 instead of `albedo`
    g_varies: bool = False  # g 0 → 0.8 instead of `g`

    def label(self) -> str:
        varying = [name for name, flag in (("extinction", self.extinction_varies), ("albedo", self.albedo_varies),
                                           ("g", self.g_varies)) if flag]
        g = "" if self.g_varies else f" g={self.g:g}"
        spectral = f" varying {'+'.join(varying)}" if varying else ""
        return f"{self.grid} {self.resolution}³{g}{spectral} {self.width}×{self.height}"

    def with_(self, **changes) -> "CloudSpec":
        return replace(self, **changes)


CHROMATIC = {"extinction_varies": True, "albedo_varies": True, "g_varies": True}
SPHERE_DENSITY_SCALE = 7.5  # σ_t of the soft sphere's centre: optical depth 7.5 · 16/15 = 8 along a diameter


def cloud_transform(resolution: int) -> np.ndarray:
    """Index-to-world matrix of the cloud grid: `procedural.cloud_grid`'s cube of edge CLOUD_SIZE."""
    step = CLOUD_SIZE / resolution
    index_to_world = np.diag([step, step, step, 1.0])
    index_to_world[:3, 3] = -CLOUD_SIZE / 2 + 0.5 * step
    return index_to_world


def cloud_density(resolution: int, cache: Path | None = CACHE) -> tuple[Grid, bool]:
    """`procedural.cloud_grid(resolution, CLOUD_SIZE, seed=CLOUD_SEED)` and whether it came from the cache
    folder `cache` (None: no cache)."""
    path = None if cache is None else Path(cache) / f"cloud-{resolution}-seed{CLOUD_SEED}.npy"
    if path is not None and path.exists():
        values = np.load(path)
        if values.shape == (resolution,) * 3 and values.dtype == np.float32:
            return Grid(values, cloud_transform(resolution), name="density"), True
    grid = cloud_grid(resolution=resolution, size=CLOUD_SIZE, seed=CLOUD_SEED)
    assert np.allclose(grid.index_to_world, cloud_transform(resolution))
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, grid.values)
    return grid, False


def sphere_density(resolution: int) -> Grid:
    """A smooth soft sphere filling the cloud's cube: density (1 − r²)² at distance r from the centre in
    units of the half-edge (1 at the centre, 0 from the faces' centres outwards); ∫(1 − x²)² dx = 16/15
    along a diameter."""
    index_to_world = cloud_transform(resolution)
    centres = (np.arange(resolution) * index_to_world[0, 0] + index_to_world[0, 3]) / (CLOUD_SIZE / 2)
    x, y, z = np.meshgrid(centres, centres, centres, indexing="ij")
    values = np.clip(1.0 - (x**2 + y**2 + z**2), 0.0, None) ** 2
    return Grid(values.astype(np.float32), index_to_world, name="density")


def density_grid(spec: CloudSpec) -> Grid:
    """The density grid `spec` names (the cloud from the cache folder where it is there)."""
    if spec.grid == "sphere":
        return sphere_density(spec.resolution)
    if spec.grid == "cloud":
        return cloud_density(spec.resolution)[0]
    raise ValueError(f"unknown grid {spec.grid!r}")


def _smooth(lo_value: float, hi_value: float) -> spectra.Spectrum:
    """A spectrum going smoothly from `lo_value` at 380 nm to `hi_value` at 700 nm (flat beyond)."""
    return smooth_ramp(lo_value, hi_value, 380.0, 700.0)


def cloud_medium(spec: CloudSpec, density: Grid) -> Medium:
    return medium(density, spec.density_scale, name="cloud",
                  extinction=_smooth(1.4, 0.7) if spec.extinction_varies else 1.0,
                  albedo=_smooth(0.6, 0.95) if spec.albedo_varies else spec.albedo,
                  g=_smooth(0.0, 0.8) if spec.g_varies else spec.g)


def lights(spec: CloudSpec) -> tuple[Light, ...]:
    both = (sun(SUN_DIRECTION, spec.sun_strength, spectrum=spectra.illuminant("D65"), name="sun"),
            environment(spec.environment_strength, name="environment"))
    return tuple(light for light in both if light.strength > 0)


def camera(spec: CloudSpec) -> Camera:
    return perspective(EYE, TARGET, spec.width, spec.height, spec.fov_degrees)


def cloud_scene(spec: CloudSpec, density: Grid | None = None, **settings) -> Scene:
    """The benchmark scene for `spec`; `settings` are RenderSettings fields (wavelengths_per_path, …)."""
    if density is None:
        density = density_grid(spec)
    return scene(camera(spec), (cloud_medium(spec, density),), lights(spec), **settings)


def orientation_grid(cells: int = 8) -> Grid:
    """An asymmetric grid for orientation checks: a dense slab near −x, +y, +z corner, thinner
    elsewhere, so that a swap or flip of any axis moves its image."""
    values = np.zeros((cells,) * 3, dtype=np.float32)
    values[1:cells // 3 + 1, cells // 2:cells - 1, cells // 2 + 1:cells - 1] = 1.0
    values[cells // 2:cells - 1, 1:cells // 4 + 1, 1:cells // 2] = 0.3
    return Grid(values, cloud_transform(cells), name="density")
