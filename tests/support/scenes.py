"""Small scenes built in code for tracer tests (no files): boxes of medium, cameras, lights."""

import numpy as np

from addon.tracer import spectra
from addon.tracer.scene import Camera, Grid, Light, Medium, RenderSettings, Scene
from addon.tracer.wavelengths import GRID


def box_grid(cells=(8, 8, 8), size=(2.0, 2.0, 2.0), centre=(0.0, 0.0, 0.0), density=1.0) -> Grid:
    """A constant-density box: `cells` cell centres spanning `size` world units around `centre`.

    With zero padding outside the array, the optical depth of a ray crossing the box along an axis
    (away from the other faces) is exactly density · size along that axis."""
    cells = np.asarray(cells)
    step = np.asarray(size, dtype=np.float64) / cells
    index_to_world = np.diag(np.append(step, 1.0))
    index_to_world[:3, 3] = np.asarray(centre) - np.asarray(size) / 2 + 0.5 * step
    return Grid(np.full(tuple(cells), density, dtype=np.float32), index_to_world)


def look_down_z(height=6.0) -> np.ndarray:
    """Camera matrix at (0, 0, height) looking down −z (Blender cameras look along local −z)."""
    matrix = np.eye(4)
    matrix[2, 3] = height
    return matrix


def ortho_camera(width=8, height=8, scale=0.5, distance=6.0) -> Camera:
    return Camera(to_world=look_down_z(distance), width=width, height=height, kind="orthographic",
                  ortho_scale=scale)


def perspective_camera(width=16, height=16, fov_degrees=30.0, distance=6.0) -> Camera:
    return Camera(to_world=look_down_z(distance), width=width, height=height, fov=np.radians(fov_degrees))


def medium(grid: Grid, *, scale=1.0, extinction=1.0, albedo=1.0, g=0.0, phase="hg", name="medium",
           fluorescence=None, emission=None) -> Medium:
    """A medium with constant-or-Spectrum extinction, albedo (same at every density) and g."""
    as_spectrum = lambda value: value if isinstance(value, spectra.Spectrum) else spectra.constant(value)
    return Medium(name=name, density=grid, density_scale=scale, extinction=as_spectrum(extinction),
                  albedo_densities=np.array([0.0]), albedo_table=as_spectrum(albedo).values[None, :],
                  anisotropy=as_spectrum(g), phase=phase, fluorescence=fluorescence, emission=emission)


def environment(strength=1.0, spectrum=None) -> Light:
    return Light(kind="environment", spectrum=spectrum or spectra.constant(1.0), strength=strength)


def sun(direction, strength=1.0, angle=0.0, spectrum=None) -> Light:
    direction = np.asarray(direction, dtype=np.float64)
    return Light(kind="sun", spectrum=spectrum or spectra.constant(1.0), strength=strength,
                 direction=direction / np.linalg.norm(direction), angle=angle)


def scene(camera, media=(), lights=(), **settings) -> Scene:
    return Scene(camera=camera, media=tuple(media), lights=tuple(lights), settings=RenderSettings(**settings))


def smooth_spectrum(lo_value, hi_value) -> spectra.Spectrum:
    """A spectrum varying smoothly from `lo_value` at 360 nm to `hi_value` at 830 nm."""
    t = np.clip((GRID - 360.0) / 470.0, 0.0, 1.0)
    return spectra.Spectrum(lo_value + (hi_value - lo_value) * (3 * t**2 - 2 * t**3))
