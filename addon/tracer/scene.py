"""The in-memory scene: camera, media, lights and render settings as plain dataclasses.

This is what the scene file (`scene_io`, docs/scene-format.md) loads into and what the add-on's
exporter builds; the kernels never see it directly (`compile` lowers it to flat arrays).
Conventions (DESIGN.md): lengths in Blender units, wavelengths in nm, matrices are 4×4 row-major
NumPy arrays acting on column vectors (world = M @ [x, y, z, 1]).
"""

from dataclasses import dataclass, field

import numpy as np

from .spectra import Spectrum


@dataclass(frozen=True, eq=False)
class Grid:
    """A dense voxel grid. `values[i, j, k]` is the value at the centre of cell (i, j, k) (x, y, z order);
    `index_to_world` maps index-space points (cell centres at integer coordinates) to world space."""

    values: np.ndarray  # float32, shape (nx, ny, nz)
    index_to_world: np.ndarray  # (4, 4) float64
    name: str = "density"


@dataclass(frozen=True, eq=False)
class Fluorescence:
    """Fluorophore in a medium. Its absorption coefficient is density · density_scale · excitation(λ)
    (added to the extinction); a fraction `quantum_yield` of the absorbed energy is re-emitted
    isotropically at a wavelength drawn from `emission` (normalised to a pdf over λ when compiled)."""

    excitation: Spectrum
    emission: Spectrum
    quantum_yield: float


@dataclass(frozen=True, eq=False)
class BlackbodyEmission:
    """Thermal emission: σ_a(λ) · intensity · Planck(λ, T(x)) / Planck-luminance normalisation, with T from
    `temperature` (kelvin, after `temperature_scale` and `temperature_offset`, as Blender fire grids
    store normalised values)."""

    temperature: Grid
    intensity: float = 1.0
    temperature_scale: float = 1.0
    temperature_offset: float = 0.0


@dataclass(frozen=True, eq=False)
class Medium:
    """A heterogeneous participating medium.

    σ_t(x, λ) = density(x) · density_scale · extinction(λ). The single-scattering albedo is a table
    over density levels (rows) and the wavelength grid (columns), linearly interpolated in density and
    clamped outside the listed levels. Anisotropy is Henyey–Greenstein g(λ), or the Rayleigh phase
    function when `phase` is "rayleigh"."""

    name: str
    density: Grid
    density_scale: float
    extinction: Spectrum
    albedo_densities: np.ndarray  # (L,), increasing
    albedo_table: np.ndarray  # (L, GRID.size) in [0, 1]
    anisotropy: Spectrum
    phase: str = "hg"  # "hg" | "rayleigh"
    fluorescence: Fluorescence | None = None
    emission: BlackbodyEmission | None = None


@dataclass(frozen=True, eq=False)
class Light:
    """One light. `spectrum` is a shape; `strength` sets its luminance Y:
    sun: irradiance Y on a plane facing it; environment: radiance Y; sky: radiance Y of both its zenith
    colour (`spectrum`) and its horizon colour, blended linearly by the elevation's sine;
    point/spot: intensity Y (per steradian)."""

    kind: str  # "sun" | "environment" | "sky" | "point" | "spot"
    spectrum: Spectrum
    strength: float = 1.0
    direction: np.ndarray | None = None  # sun: unit vector pointing from the scene towards the sun
    angle: float = 0.0  # sun: angular diameter (radians)
    position: np.ndarray | None = None  # point/spot
    spot_direction: np.ndarray | None = None  # spot: unit vector the spot points along
    spot_size: float = np.pi / 4  # spot: full cone angle (radians)
    spot_blend: float = 0.15  # spot: Blender's smooth edge fraction
    horizon_spectrum: Spectrum | None = None  # sky: colour at the horizon (zenith colour is `spectrum`)
    name: str = ""


@dataclass(frozen=True, eq=False)
class Camera:
    """Blender's camera model: looks down its local -Z with +Y up; `to_world` is its world matrix.
    `fov` (radians, perspective) or `ortho_scale` (orthographic) spans the `sensor_fit` axis
    ("AUTO": the larger image axis, "HORIZONTAL", "VERTICAL"); shifts are in units of that span."""

    to_world: np.ndarray
    width: int
    height: int
    kind: str = "perspective"  # "perspective" | "orthographic"
    fov: float = np.radians(39.6)  # Blender's default 50 mm lens on a 36 mm sensor
    ortho_scale: float = 6.0
    sensor_fit: str = "AUTO"
    shift_x: float = 0.0
    shift_y: float = 0.0


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """A camera's `to_world` in Blender's convention (looks along its local −z, +y up) at `eye`,
    looking at `target`, with `up` pointing up in the image."""
    eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = right, np.cross(back, right), back, eye
    return matrix


@dataclass(frozen=True)
class RenderSettings:
    spp: int = 16
    seed: int = 0
    max_depth: int = 64
    rr_depth: int = 5  # Russian roulette starts after this many scattering events
    # pdf of the hero λ: "colour" | "visible" | "light" | "uniform" | "d65_rejection" | "uv"
    wavelength_sampling: str = "colour"
    wavelengths_per_path: int = 4  # 1, or 4 (hero + 3 rotated, spectral MIS)
    lambda_min: float = 360.0
    lambda_max: float = 830.0
    bands: int = 1  # per-wavelength passes: the λ range split into this many equal bands
    cmf: str = "cie1931"  # "cie1931" | "wyman1" | "wyman3"
    backend: str = "numba"  # "numba" | "numpy"


@dataclass(frozen=True, eq=False)
class Scene:
    camera: Camera
    media: tuple[Medium, ...] = ()
    lights: tuple[Light, ...] = ()
    settings: RenderSettings = field(default_factory=RenderSettings)
