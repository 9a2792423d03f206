"""Building blocks for tracer scenes written in code: grids sampled from a field, media whose optics are
numbers or spectra, surfaces (a subdivided parallelogram), suns, environments, envmaps, cameras and smooth
spectra.

The demos (demo_blends/scenes.py), the tests (tests/support/scenes.py) and the benchmarks
(bench/scenes.py) build their scenes with these, so a scene written in Python reads the same everywhere.
World conventions are Blender's: z up, lengths in Blender units, cameras looking along their local −z.
"""

import numpy as np

from . import spectra
from .scene import Camera, Grid, Light, Medium, RenderSettings, Scene, Surface, Texture, look_at
from .wavelengths import GRID


def cell_centres(cells, lo, hi):
    """Coordinates (x, y, z as broadcastable arrays) of the centres of `cells` cells filling the box
    [lo, hi], and the grid's index-to-world matrix."""
    cells, lo, hi = np.asarray(cells), np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    step = (hi - lo) / cells
    axes = [lo[i] + (np.arange(cells[i]) + 0.5) * step[i] for i in range(3)]
    index_to_world = np.diag(np.append(step, 1.0))
    index_to_world[:3, 3] = lo + 0.5 * step
    return np.meshgrid(*axes, indexing="ij", sparse=True), index_to_world


def sampled_grid(field, cells, lo, hi, name: str = "density") -> Grid:
    """A grid of `field(x, y, z)` (NumPy-broadcasting) at the centres of `cells` cells filling [lo, hi]."""
    (x, y, z), index_to_world = cell_centres(cells, lo, hi)
    values = np.broadcast_to(field(x, y, z), tuple(cells)).astype(np.float32)
    return Grid(np.ascontiguousarray(values), index_to_world, name=name)


def box_grid(cells=(8, 8, 8), size=(2.0, 2.0, 2.0), centre=(0.0, 0.0, 0.0), density=1.0) -> Grid:
    """A constant-density box: `cells` cell centres spanning `size` world units around `centre`.

    With zero padding outside the array, the optical depth of a ray crossing the box along an axis
    (away from the other faces) is exactly density · size along that axis."""
    half = np.asarray(size, dtype=np.float64) / 2
    return sampled_grid(lambda x, y, z: np.full(np.broadcast_shapes(x.shape, y.shape, z.shape), density),
                        cells, np.asarray(centre) - half, np.asarray(centre) + half)


def as_spectrum(value) -> spectra.Spectrum:
    """A Spectrum as it is, a number as the constant spectrum of that value."""
    return value if isinstance(value, spectra.Spectrum) else spectra.constant(value)


def medium(density: Grid, scale: float = 1.0, *, name: str = "medium", extinction=1.0, albedo=1.0, g=0.0,
           phase: str = "hg", fluorescence=None, emission=None, glow=None) -> Medium:
    """A medium whose extinction, albedo (the same at every density) and anisotropy are numbers or spectra;
    σ_t = density · `scale` · extinction."""
    return Medium(name=name, density=density, density_scale=float(scale), extinction=as_spectrum(extinction),
                  albedo_densities=np.array([0.0]), albedo_table=as_spectrum(albedo).values[None, :],
                  anisotropy=as_spectrum(g), phase=phase, fluorescence=fluorescence, emission=emission,
                  glow=glow)


def parallelogram(corner, edge_u, edge_v, subdivisions: int = 1, *, reflectance=1.0, emission=None,
                  name: str = "surface", holdout: bool = False, camera: bool = True, image=None,
                  extension: str = "REPEAT", interpolation: str = "Linear", srgb: bool = False) -> Surface:
    """A flat surface spanning corner + a·edge_u + b·edge_v for a, b in [0, 1], cut into `subdivisions`² cells
    of two triangles each; `reflectance` and `emission` (None: not a light) are numbers or spectra; `holdout`
    and `camera` as `Surface`'s; an `image` (H, W, 3) is its texture (`Texture`, with `extension`, `interpolation`
    and `srgb`) at UV (a, b)."""
    n = int(subdivisions)
    a, b = np.meshgrid(np.linspace(0.0, 1.0, n + 1), np.linspace(0.0, 1.0, n + 1), indexing="ij")
    vertices = (np.asarray(corner, dtype=np.float64) + a.reshape(-1, 1) * np.asarray(edge_u, dtype=np.float64)
                + b.reshape(-1, 1) * np.asarray(edge_v, dtype=np.float64))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    first = (i * (n + 1) + j).ravel()
    triangles = np.concatenate([np.stack([first, first + n + 1, first + n + 2], axis=1),
                                np.stack([first, first + n + 2, first + 1], axis=1)])
    texture = None if image is None else Texture(
        image=np.asarray(image, dtype=np.float32), uv=np.stack([a.ravel(), b.ravel()], axis=1)[triangles],
        extension=extension, interpolation=interpolation, srgb=srgb)
    return Surface(name=name, vertices=vertices, triangles=triangles, reflectance=as_spectrum(reflectance),
                   emission=None if emission is None else as_spectrum(emission), holdout=holdout, camera=camera,
                   texture=texture)


def direction(elevation: float, azimuth: float = 0.0) -> np.ndarray:
    """Unit vector `elevation` degrees above the horizon, `azimuth` degrees from +y towards +x."""
    e, a = np.radians(elevation), np.radians(azimuth)
    return np.array([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)])


def sun(towards, strength: float = 1.0, *, angle: float = 0.0, spectrum=None, name: str = "") -> Light:
    """A sun shining from the direction `towards` (any length), `strength` its irradiance Y, `angle` its
    angular diameter in radians, `spectrum` its shape (default equal energy)."""
    towards = np.asarray(towards, dtype=np.float64)
    return Light(kind="sun", spectrum=spectrum or spectra.constant(1.0), strength=strength,
                 direction=towards / np.linalg.norm(towards), angle=angle, name=name)


def environment(strength: float = 1.0, spectrum=None, name: str = "") -> Light:
    """Light from every direction, `strength` its radiance Y, `spectrum` its shape (default equal energy)."""
    return Light(kind="environment", spectrum=spectrum or spectra.constant(1.0), strength=strength, name=name)


def envmap(image, strength: float = 1.0, *, basis=None, to_world=None, name: str = "") -> Light:
    """An envmap of linear Rec.709 `image` (H, W, 3, row 0 at the top), radiance strength × Σ rgb · basis, the
    basis by default the emission spectra of pure R, G and B (`spectra.emission_from_rgb`)."""
    if basis is None:
        basis = tuple(spectra.emission_from_rgb(rgb) for rgb in np.eye(3))
    return Light(kind="envmap", image=np.asarray(image, dtype=np.float32), basis=basis, to_world=to_world,
                 strength=strength, unit="radiant", name=name)


def perspective(eye, target, width: int, height: int, fov_degrees: float) -> Camera:
    """A perspective camera at `eye` looking at `target`; `fov_degrees` spans the image's wider axis."""
    return Camera(to_world=look_at(eye, target), width=width, height=height, fov=np.radians(fov_degrees))


def scene(camera: Camera, media=(), lights=(), surfaces=(), **settings) -> Scene:
    """A Scene; `settings` are RenderSettings fields (spp, seed, …)."""
    return Scene(camera=camera, media=tuple(media), lights=tuple(lights), surfaces=tuple(surfaces),
                 settings=RenderSettings(**settings))


def smooth_ramp(lo_value: float, hi_value: float, lo_nm: float = 360.0, hi_nm: float = 830.0) -> spectra.Spectrum:
    """A spectrum going smoothly (smoothstep) from `lo_value` at `lo_nm` to `hi_value` at `hi_nm`, flat
    beyond."""
    t = np.clip((GRID - lo_nm) / (hi_nm - lo_nm), 0.0, 1.0)
    return spectra.Spectrum(lo_value + (hi_value - lo_value) * (3 * t**2 - 2 * t**3))


def smooth_step(edge_nm: float, width_nm: float) -> np.ndarray:
    """0 well below `edge_nm`, 1 well above, a logistic step of about `width_nm` (values on GRID)."""
    return 1.0 / (1.0 + np.exp(-(GRID - edge_nm) / (0.25 * width_nm)))
