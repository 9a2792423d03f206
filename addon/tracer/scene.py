"""The in-memory scene: camera, media, lights and render settings as plain dataclasses.

This is what the scene file (`scene_io`, docs/scene-format.md) loads into and what the add-on's
exporter builds; the kernels never see it directly (`lowering` lowers it to `KernelScene`, arrays grouped
by concept). Conventions (docs/architecture.md, "Data flow"): lengths in Blender units, wavelengths in nm,
matrices are 4×4 row-major NumPy arrays acting on column vectors (world = M @ [x, y, z, 1]).

A scene checks itself, whoever built it: `Scene.validate()` (called by `scene_io.load_scene` and
`save_scene` and by `lowering.compile_scene`) raises a SpectralError naming the field by its scene-file
path and in the file's units (`media[0].albedo: ...`, `camera.fov` in degrees). The enumerations of the
format are defined here, once, except those the kernels switch on (kinds of camera and light, phase
functions, wavelengths per path), which `kernels/layout.py` defines beside their codes.
"""

from dataclasses import dataclass, field

import numpy as np

from . import checks
from . import colorimetry
from .colorimetry import CMF_NAMES as CMFS
from .errors import SpectralError
from .kernels.layout import AREA_SHAPES, CAMERA_KINDS, LIGHT_KINDS, PHASES, WAVELENGTHS_PER_PATH
from .phase import HG_G_LIMIT
from .spectra import Spectrum, constant
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

SENSOR_FITS = ("AUTO", "HORIZONTAL", "VERTICAL")
# What a light's strength measures: "luminous", its luminance Y (with the render's colour matching
# functions); "radiant", its radiometric quantity integrated over the whole grid (250–830 nm).
LIGHT_UNITS = ("luminous", "radiant")
# The radiant unit of each light kind's strength.
RADIANT_UNITS = {"sun": "W·m⁻²", "environment": "W·m⁻²·sr⁻¹", "sky": "W·m⁻²·sr⁻¹", "point": "W·sr⁻¹",
                 "spot": "W·sr⁻¹", "area": "W", "envmap": "× its map"}
# An area light's axes (the columns of `Light.area_axes`) may be this far from orthogonal (the cosine of
# their angle): Blender's float32 matrices are orthogonal to about 1e-7.
AREA_AXES_ORTHOGONAL_TO = 1e-5
# An envmap's `to_world` may be this far from orthonormal (its columns' lengths from 1, their cosines from 0).
ENVMAP_ORTHONORMAL_TO = 1e-5
WAVELENGTH_SAMPLINGS = ("uniform", "d65_rejection", "uv", "light", "visible", "colour")
BACKENDS = ("numba", "numpy")
SEED_MAX = 2**64 - 1  # seeds are unsigned 64-bit integers in the kernels' random streams
SPP_MAX = 2**32  # a pixel's samples are points of a Sobol sequence of 2³² points (kernels/rng.py)
# Scattering events of a path: Russian roulette ends paths long before; beyond, a value is a mistake.
DEPTH_MAX = 2**20
# Delta and ratio tracking take about one step per unit of optical depth (through the majorant) along a
# ray, so a medium far thicker than this renders for hours and cannot be interrupted mid-ray. It is also
# far beyond anything visible: light through optical depth 30 is dimmed by e⁻³⁰ ≈ 1e-13.
MAX_OPTICAL_DEPTH = 1e5
# The most a light may emit per nm (its spectrum × strength in the unit of RADIANT_UNITS per nm, at its peak; an
# envmap's brightest texel): a pixel's samples of brighter light, and their squares (the variance), overflow
# the float32 of the image files (3.4e38). The Sun at noon gives about 1.9 W·m⁻²·nm⁻¹.
MAX_LIGHT_PEAK = 1e15


@dataclass(frozen=True, eq=False)
class Grid:
    """A dense voxel grid. `values[i, j, k]` is the value at the centre of cell (i, j, k) (x, y, z order);
    `index_to_world` maps index-space points (cell centres at integer coordinates) to world space."""

    values: np.ndarray  # float32, shape (nx, ny, nz)
    index_to_world: np.ndarray  # (4, 4) float64
    name: str = "density"

    def world_diagonal(self) -> float:
        """The length of the world-space diagonal of the box its cells fill."""
        shape = np.array(self.values.shape, dtype=np.float64)
        return float(np.linalg.norm(np.asarray(self.index_to_world, dtype=np.float64)[:3, :3] @ shape))


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
class Glow:
    """Emission that does not depend on absorption, as Blender's Cycles defines it, per unit length:
    density(x) · density_scale · [spectrum(λ) + blackbody · tint(λ) · Lbb(λ, T(x))] in W·m⁻²·sr⁻¹·nm⁻¹ per
    Blender unit, where Lbb is Planck's law scaled to luminance σT⁴/π (Cycles' black body; `glow.py`).
    T(x) = temperature(x) · temperature_scale + temperature_offset in kelvin, where a missing grid (and a
    grid outside its box) reads 0: without a grid the temperature is `temperature_offset` everywhere."""

    spectrum: Spectrum | None = None  # radiance per unit length per unit scaled density (None: 0)
    blackbody: float = 0.0  # weight of the normalised black body (Cycles' Blackbody Intensity × 1e-6)
    tint: Spectrum = field(default_factory=lambda: constant(1.0))
    temperature: Grid | None = None
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
    glow: Glow | None = None

    def emits(self) -> bool:
        """Whether the medium is a source of light: thermal emission or a glow."""
        return self.emission is not None or self.glow is not None


@dataclass(frozen=True, eq=False)
class Light:
    """One light. `spectrum` is a shape; `strength` sets its size in `unit` (LIGHT_UNITS): "luminous",
    the luminance Y of its sun irradiance on a plane facing it, environment radiance, point/spot
    intensity (per steradian), area light power (all it emits); "radiant", the same quantities in watts
    over the whole spectrum (RADIANT_UNITS). A sky's zenith colour (`spectrum`) and horizon colour each
    have that strength, blended linearly by the elevation's sine.

    An area light is a flat one-sided Lambertian emitter (Blender's area light at Spread 180°): a
    rectangle of size_x × size_y, or an ellipse of those diameters, centred at `position` in the plane of
    its local X and Y axes (the columns of `area_axes`, normalised when compiled, so their lengths are
    ignored), emitting along its local −Z (the third column) with radiance P / (π · area) on that side
    and none behind, P being its power (`strength`). Next-event estimation samples it and rays that meet
    its emitting face add its radiance (weighted by MIS after scattering), as Cycles does; it blocks
    nothing. Camera rays see it where `camera_visible` is on (Blender's Object ▸ Visibility ▸ Ray
    Visibility ▸ Camera, off by default for a light object, as in Cycles; off for scene files that do not
    say, which camera rays then pass through as before).

    An envmap is an equirectangular image around the scene (Blender's Environment Texture), with no
    `spectrum`: the radiance arriving from world direction ω is, in W·m⁻²·sr⁻¹·nm⁻¹,

        L(ω, λ) = strength · Σ_c image[row, column, c] · basis[c](λ)     (c = R, G, B)

    at the texel that ω falls in (nearest texel: no interpolation). `strength` is a plain factor (Blender's
    Background Strength), so `unit` must be "radiant"; `basis` holds the radiance of a texel of unit R, G and B
    (`spectra.emission_from_rgb((1, 0, 0))` etc. give each texel the XYZ of its linear Rec.709 RGB, with white
    (1, 1, 1) of luminance Y = 1). `image` is (H, W, 3), H ≥ 1, W ≥ 2, row 0 at the top (Blender's image
    pixels are stored bottom row first: flip them). With (x, y, z) = to_worldᵀ ω, the direction in the map's
    frame, ω falls at Cycles' `direction_to_equirectangular` coordinates u = 0.5 − atan2(y, x) / 2π (across the
    columns, from the left: +X at the centre, +Y at u = 0.25) and v = 0.5 + asin(z) / π (v = 1 at the top row),
    i.e. column ⌊u W⌋ and row ⌊(1 − v) H⌋ = ⌊acos(z) H / π⌋. `to_world` (3 × 3, orthonormal, default the
    identity) takes the map's frame to world directions: the rotation of the Environment Texture's Mapping
    node (Vector type "Point" or "Vector"; it rotates the lookup direction, so pass its inverse, the transpose
    of that rotation)."""

    kind: str  # "sun" | "environment" | "sky" | "point" | "spot" | "area" | "envmap"
    spectrum: Spectrum | None = None  # every kind but "envmap"
    strength: float = 1.0
    direction: np.ndarray | None = None  # sun: unit vector pointing from the scene towards the sun
    angle: float = 0.0  # sun: angular diameter (radians)
    position: np.ndarray | None = None  # point/spot; area: its centre
    spot_direction: np.ndarray | None = None  # spot: unit vector the spot points along
    spot_size: float = np.pi / 4  # spot: full cone angle (radians)
    spot_blend: float = 0.15  # spot: Blender's smooth edge fraction
    horizon_spectrum: Spectrum | None = None  # sky: colour at the horizon (zenith colour is `spectrum`)
    area_axes: np.ndarray | None = None  # area: (3, 3), columns its local X, Y, Z in world space (matrix_world's)
    area_shape: str = "rectangle"  # area: "rectangle" | "ellipse"
    size_x: float = 1.0  # area: width along its local X (the ellipse's diameter), in world units
    size_y: float = 1.0  # area: height along its local Y
    camera_visible: bool = False  # area: whether camera rays see its emitting face
    image: np.ndarray | None = None  # envmap: (H, W, 3) linear Rec.709 texels, row 0 at the top (+Z)
    basis: np.ndarray | tuple[Spectrum, ...] | None = None  # envmap: (3, GRID) or 3 spectra, per unit R, G, B
    to_world: np.ndarray | None = None  # envmap: (3, 3) the map's frame → world directions (None: identity)
    name: str = ""
    unit: str = "luminous"  # "luminous" | "radiant"

    def basis_values(self) -> np.ndarray:
        """An envmap's basis as an array (3, GRID): it may be given as one or as three spectra."""
        basis = self.basis
        if isinstance(basis, (list, tuple)) and all(isinstance(item, Spectrum) for item in basis):
            basis = [item.values for item in basis]
        return np.asarray(basis, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class Surface:
    """An opaque triangle mesh in world space: a Lambertian reflector on both sides, and optionally an
    emitter (a mesh light). `reflectance` is the albedo ρ(λ) in [0, 1], the BRDF ρ/π; `emission` the
    radiance leaving both sides in W·m⁻²·sr⁻¹·nm⁻¹ (Cycles' Emission shader on a mesh is two-sided), None
    for a surface that is not a light. Triangles of zero area (repeated or collinear corners) are allowed
    and ignored: they are never hit and emit nothing. A `holdout` surface, as Cycles' Holdout (shader or object
    property), cuts a hole where a camera ray reaches it (directly or through a volume), before any scattering:
    zero colour behind what lies in front, and zero alpha with Film ▸ Transparent (black without); rays after a
    scattering see it as its reflectance and emission say (a Holdout shader's surface: reflectance 0)."""

    name: str
    vertices: np.ndarray  # (V, 3) float64, world space
    triangles: np.ndarray  # (T, 3) integer indices into vertices
    reflectance: Spectrum  # Lambertian albedo over the wavelength grid, in [0, 1]
    emission: Spectrum | None = None  # radiance leaving both sides, None: not a light
    holdout: bool = False  # camera rays see a hole here (Film ▸ Transparent: alpha 0)
    object: str = ""  # its Blender object's name, for Cryptomatte ("": the surface's name)
    material: str = ""  # its material's name, for Cryptomatte ("": the surface's name)


@dataclass(frozen=True, eq=False)
class Camera:
    """Blender's camera model: looks down its local -Z with +Y up; `to_world` is its world matrix.
    `fov` (radians, perspective) or `ortho_scale` (orthographic) spans the `sensor_fit` axis
    ("AUTO": the larger axis of the frame, "HORIZONTAL", "VERTICAL"); shifts are in units of that span.
    `pixel_aspect` is a pixel's width ÷ its height (Blender's pixel_aspect_x / pixel_aspect_y): the frame
    is width · pixel_aspect wide for height tall."""

    to_world: np.ndarray
    width: int
    height: int
    kind: str = "perspective"  # "perspective" | "orthographic"
    fov: float = np.radians(39.6)  # Blender's default 50 mm lens on a 36 mm sensor
    ortho_scale: float = 6.0
    sensor_fit: str = "AUTO"
    shift_x: float = 0.0
    shift_y: float = 0.0
    pixel_aspect: float = 1.0


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
    # Adaptive sampling (`adaptive`): a pixel stops once its error is below this (0: every pixel gets `spp`),
    # after `min_samples` (0: chosen from the threshold).
    noise_threshold: float = 0.0
    min_samples: int = 0
    # Film ▸ Transparent: camera rays that reach the background (the infinite lights) see none of it, and the
    # film's alpha is 1 − the share they saw; the infinite lights still light the scene.
    transparent: bool = False
    # Data passes written beside the image (`passes.DATA_PASSES`: Depth, Mist, Normal, CryptoObject,
    # CryptoMaterial), with World ▸ Mist Pass's start, depth and falloff and Cryptomatte's levels.
    passes: tuple[str, ...] = ()
    mist_start: float = 5.0
    mist_depth: float = 25.0
    mist_falloff: str = "quadratic"  # "quadratic" | "linear" | "inverse_quadratic"
    cryptomatte_depth: int = 6


@dataclass(frozen=True, eq=False)
class Scene:
    camera: Camera
    media: tuple[Medium, ...] = ()
    lights: tuple[Light, ...] = ()
    surfaces: tuple[Surface, ...] = ()
    settings: RenderSettings = field(default_factory=RenderSettings)

    def validate(self) -> "Scene":
        """This scene, or a SpectralError naming the first invalid field (see the module docstring)."""
        check_settings(self.settings, "render")  # first: the lights' check uses its colour matching functions
        _check_camera(self.camera, "camera")
        for index, medium in enumerate(self.media):
            _check_medium(medium, f"media[{index}]")
        for index, light in enumerate(self.lights):
            _check_light(light, f"lights[{index}]", self.settings.cmf)
        for index, surface in enumerate(self.surfaces):
            _check_surface(surface, f"surfaces[{index}]")
        emitters = any(medium.emits() for medium in self.media) or any(s.emission is not None for s in self.surfaces)
        if not self.lights and not emitters:
            raise SpectralError("lights: the scene has no lights: add a sun, environment, sky, envmap, point, spot "
                                "or area light (or an emitting medium or surface)")
        if self.lights and not any(light.strength > 0 for light in self.lights):
            raise SpectralError("lights: every light has strength 0, so nothing is lit")
        return self


def _check_camera(camera: Camera, where: str) -> None:
    checks.whole_within(camera.width, f"{where}.width", 1)
    checks.whole_within(camera.height, f"{where}.height", 1)
    checks.one_of(camera.kind, f"{where}.kind", CAMERA_KINDS)
    checks.within(np.degrees(checks.number(camera.fov, f"{where}.fov")), f"{where}.fov", 0.0, 180.0, closed=False)
    checks.positive(checks.number(camera.ortho_scale, f"{where}.ortho_scale"), f"{where}.ortho_scale")
    checks.one_of(camera.sensor_fit, f"{where}.sensor_fit", SENSOR_FITS)
    checks.number(camera.shift_x, f"{where}.shift_x")
    checks.number(camera.shift_y, f"{where}.shift_y")
    checks.positive(checks.number(camera.pixel_aspect, f"{where}.pixel_aspect"), f"{where}.pixel_aspect")
    checks.affine_matrix(camera.to_world, f"{where}.to_world")


def _check_grid(grid: Grid, where: str, nonnegative: bool = True) -> None:
    checks.grid_values(np.asarray(grid.values), f"{where}: grid {grid.name!r}", nonnegative)
    checks.affine_matrix(grid.index_to_world, f"{where}.index_to_world")


def _check_medium(medium: Medium, where: str) -> None:
    if not isinstance(medium.name, str):
        raise SpectralError(f"{where}.name: expected a string, found {checks.shown(medium.name)}")
    _check_grid(medium.density, f"{where}.density")
    checks.positive(checks.number(medium.density_scale, f"{where}.density_scale"), f"{where}.density_scale")
    checks.spectrum_within(medium.extinction.values, f"{where}.extinction", "extinction must not be negative",
                           0.0, np.inf)
    _check_albedo(medium.albedo_densities, medium.albedo_table, f"{where}.albedo")
    checks.spectrum_within(medium.anisotropy.values, f"{where}.anisotropy",
                           f"|g| must be at most {HG_G_LIMIT!r} (sharper lobes are not resolved by float64 directions)",
                           -HG_G_LIMIT, HG_G_LIMIT)
    checks.one_of(medium.phase, f"{where}.phase", PHASES)
    _check_optical_depth(medium, where)
    if medium.fluorescence is not None:
        _check_fluorescence(medium.fluorescence, f"{where}.fluorescence")
    if medium.emission is not None:
        _check_emission(medium.emission, f"{where}.emission")
    if medium.glow is not None:
        if medium.emission is not None:
            raise SpectralError(f"{where}.glow: a medium has one temperature, so it takes either \"emission\" "
                                "(thermal) or \"glow\", not both")
        _check_glow(medium.glow, f"{where}.glow")


def _check_surface(surface: Surface, where: str) -> None:
    for key in ("name", "object", "material"):
        if not isinstance(getattr(surface, key), str):
            raise SpectralError(f"{where}.{key}: expected a string, found {checks.shown(getattr(surface, key))}")
    _check_boolean(surface.holdout, f"{where}.holdout")
    vertices = _float_array(lambda: surface.vertices, f"{where}.vertices")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise SpectralError(f"{where}.vertices: expected a list of [x, y, z] points, found an array of shape "
                            f"{vertices.shape}")
    finite = np.isfinite(vertices)
    if not finite.all():
        at = tuple(int(i) for i in np.argwhere(~finite)[0])
        raise SpectralError(f"{where}.vertices: must be finite, found {vertices[at]:g} at index {list(at)}")
    triangles = np.asarray(surface.triangles)
    if triangles.ndim != 2 or triangles.shape[1] != 3 or triangles.shape[0] == 0:
        raise SpectralError(f"{where}.triangles: expected a non-empty list of [i, j, k] vertex indices, found an "
                            f"array of shape {triangles.shape}")
    if not np.issubdtype(triangles.dtype, np.integer):
        raise SpectralError(f"{where}.triangles: expected whole numbers (vertex indices), found {triangles.dtype}")
    outside = (triangles < 0) | (triangles >= vertices.shape[0])
    if outside.any():
        at = tuple(int(i) for i in np.argwhere(outside)[0])
        raise SpectralError(f"{where}.triangles: vertex index {int(triangles[at])} at {list(at)} is outside the "
                            f"{vertices.shape[0]} vertices (indices count from 0)")
    checks.spectrum_within(surface.reflectance.values, f"{where}.reflectance", "a reflectance must be within [0, 1]",
                           0.0, 1.0)
    if surface.emission is not None:
        checks.spectrum_within(surface.emission.values, f"{where}.emission", "an emission must not be negative",
                               0.0, np.inf)


def optical_depth(medium: Medium) -> float:
    """An upper bound of the optical depth along any straight path through the medium: its largest
    extinction coefficient (with fluorescent absorption) times the diagonal of its grid's world box."""
    extinction = medium.extinction.values
    if medium.fluorescence is not None:
        extinction = extinction + medium.fluorescence.excitation.values
    diagonal = medium.density.world_diagonal()
    return float(medium.density_scale * extinction.max() * medium.density.values.max()) * diagonal


def _check_optical_depth(medium: Medium, where: str) -> None:
    depth = optical_depth(medium)
    if not depth <= MAX_OPTICAL_DEPTH:
        raise SpectralError(
            f"{where}: the optical depth through the medium reaches {depth:.3g} (density_scale × extinction × "
            f"density × size), more than the {MAX_OPTICAL_DEPTH:g} the tracer accepts: tracking would take about "
            f"that many steps per ray, and nothing shows through beyond ~30; lower density_scale or extinction")


def _check_albedo(densities, table, where: str) -> None:
    """The table's rows are written as `where` when it is one level at density 0 (the scene file's single
    spectrum), else as `where.spectra[i]` with their levels `where.densities[i]`."""
    densities, table = np.asarray(densities, dtype=np.float64), np.asarray(table, dtype=np.float64)
    if densities.ndim != 1 or densities.size == 0 or table.shape != (densities.size, GRID.size):
        raise SpectralError(f"{where}: expected L density levels and an L × {GRID.size} table, found shapes "
                            f"{densities.shape} and {table.shape}")
    single = densities.size == 1 and densities[0] == 0
    for index, density in enumerate(densities):
        checks.within(checks.number(density, f"{where}.densities[{index}]"), f"{where}.densities[{index}]", 0.0)
    if np.any(np.diff(densities) <= 0):
        raise SpectralError(f"{where}.densities: density levels must increase strictly, found {densities.tolist()}")
    for index, row in enumerate(table):
        row_where = where if single else f"{where}.spectra[{index}]"
        if not np.all(np.isfinite(row)):
            raise SpectralError(f"{row_where}: the albedo contains NaN or infinite values")
        checks.spectrum_within(row, row_where, "albedo must be within [0, 1]", 0.0, 1.0)


def _check_fluorescence(fluorescence: Fluorescence, where: str) -> None:
    for part in ("excitation", "emission"):
        values = getattr(fluorescence, part).values
        checks.spectrum_within(values, f"{where}.{part}", f"{part} must not be negative", 0.0, np.inf)
        if not values.any():
            raise SpectralError(f"{where}.{part}: the {part} spectrum is zero everywhere"
                                + (", so it cannot be a pdf" if part == "emission" else ""))
    checks.within(checks.number(fluorescence.quantum_yield, f"{where}.quantum_yield"), f"{where}.quantum_yield",
                  0.0, 1.0)


def _check_emission(emission: BlackbodyEmission, where: str) -> None:
    checks.within(checks.number(emission.intensity, f"{where}.intensity"), f"{where}.intensity", 0.0)
    _check_temperature(emission.temperature, emission.temperature_scale, emission.temperature_offset, where)


def _check_glow(glow: Glow, where: str) -> None:
    if glow.spectrum is not None:
        checks.spectrum_within(glow.spectrum.values, f"{where}.spectrum", "a glow must not be negative", 0.0, np.inf)
    blackbody = checks.within(checks.number(glow.blackbody, f"{where}.blackbody"), f"{where}.blackbody", 0.0)
    checks.spectrum_within(glow.tint.values, f"{where}.tint", "a tint must not be negative", 0.0, np.inf)
    _check_temperature(glow.temperature, glow.temperature_scale, glow.temperature_offset, where)
    if blackbody > 0 and glow.temperature is None and glow.temperature_offset == 0:
        raise SpectralError(f"{where}.temperature: a black-body glow needs a temperature: a grid, or a constant "
                            "temperature_offset in kelvin")


def _check_temperature(grid: Grid | None, scale, offset, where: str) -> None:
    """Temperature = grid value × scale + offset (a missing grid reads 0) must be non-negative kelvin."""
    if grid is not None:
        _check_grid(grid, f"{where}.temperature", nonnegative=False)
    scale = checks.number(scale, f"{where}.temperature_scale")
    offset = checks.number(offset, f"{where}.temperature_offset")
    coldest = offset
    if grid is not None:
        coldest += min(float(grid.values.min()) * scale, float(grid.values.max()) * scale)
    if coldest < 0:
        raise SpectralError(f"{where}: temperatures (grid value × temperature_scale + temperature_offset) must be "
                            f"non-negative kelvin, found {coldest:g} K")


def _check_light(light: Light, where: str, cmf: str) -> None:
    kind = checks.one_of(light.kind, f"{where}.kind", LIGHT_KINDS)
    unit = checks.one_of(light.unit, f"{where}.unit", LIGHT_UNITS)
    if kind == "envmap":
        _check_envmap(light, where)
    elif light.spectrum is None:
        raise SpectralError(f"{where}.spectrum: a {kind} light needs a spectrum")
    else:
        _check_light_spectrum(light.spectrum, f"{where}.spectrum", unit, cmf)
    checks.within(checks.number(light.strength, f"{where}.strength"), f"{where}.strength", 0.0)
    if not isinstance(light.name, str):
        raise SpectralError(f"{where}.name: expected a string, found {checks.shown(light.name)}")
    if kind == "sun":
        checks.direction(light.direction, f"{where}.direction")
        checks.within(np.degrees(checks.number(light.angle, f"{where}.angle")), f"{where}.angle", 0.0, 180.0)
    if kind == "sky" and light.horizon_spectrum is not None:
        _check_light_spectrum(light.horizon_spectrum, f"{where}.horizon_spectrum", unit, cmf)
    if kind in ("point", "spot", "area"):
        checks.vector(light.position, f"{where}.position")
    if kind == "spot":
        checks.direction(light.spot_direction, f"{where}.spot_direction")
        checks.within(np.degrees(checks.number(light.spot_size, f"{where}.spot_size")), f"{where}.spot_size",
                      0.0, 180.0, closed=False)
        checks.within(checks.number(light.spot_blend, f"{where}.spot_blend"), f"{where}.spot_blend", 0.0, 1.0)
    if kind == "area":
        _check_area_axes(light.area_axes, f"{where}.area_axes")
        checks.one_of(light.area_shape, f"{where}.area_shape", AREA_SHAPES)
        for key in ("size_x", "size_y"):
            checks.positive(checks.number(getattr(light, key), f"{where}.{key}"), f"{where}.{key}")
        if not isinstance(light.camera_visible, (bool, np.bool_)):
            raise SpectralError(f"{where}.camera_visible: expected true or false, found {checks.shown(light.camera_visible)}")
    _check_light_peak(light, where, cmf)


def _check_light_peak(light: Light, where: str, cmf: str) -> None:
    from .lights import peak_emission  # lights reads this module's Light

    peak = peak_emission(light, cmf)
    if not peak <= MAX_LIGHT_PEAK:
        raise SpectralError(f"{where}.strength: the light's spectrum × strength peaks at {peak:.3g} "
                            f"{RADIANT_UNITS[light.kind]} per nm, more than the {MAX_LIGHT_PEAK:g} the tracer "
                            "accepts (its samples' squares, the variance, would overflow the float32 of the image "
                            "files): lower the strength")


def _check_envmap(light: Light, where: str) -> None:
    """An envmap's image, basis and rotation (its spectrum is its image and basis; its strength a factor)."""
    if light.spectrum is not None:
        raise SpectralError(f"{where}.spectrum: an envmap's colour is its image and basis: give it no spectrum")
    if light.unit != "radiant":
        raise SpectralError(f"{where}.unit: an envmap's strength multiplies its map (radiance = strength × Σ rgb · "
                            f"basis): its unit must be \"radiant\", found {checks.shown(light.unit)}")
    image = _float_array(lambda: light.image, f"{where}.image")
    if image.ndim != 3 or image.shape[0] < 1 or image.shape[1] < 2 or image.shape[2] != 3:
        raise SpectralError(f"{where}.image: expected an array of H ≥ 1 rows, W ≥ 2 columns and 3 channels (R, G, "
                            f"B), found shape {image.shape}")
    with np.errstate(over="ignore"):  # the kernels read it as float32: a value beyond float32 is inf, refused
        _check_finite_nonnegative(image.astype(np.float32), f"{where}.image", "texel [row, column, channel]")
    basis = _float_array(light.basis_values, f"{where}.basis")
    if basis.shape != (3, GRID.size):
        raise SpectralError(f"{where}.basis: expected 3 spectra (R, G, B) on the {GRID.size}-node grid, found shape "
                            f"{basis.shape}")
    _check_finite_nonnegative(basis, f"{where}.basis", "[channel, wavelength index]")
    if not (image.sum(axis=(0, 1)) @ basis).any():
        raise SpectralError(f"{where}.image: the map is black (every texel's radiance Σ rgb · basis is zero)")
    if light.to_world is not None:
        to_world = checks.matrix3(light.to_world, f"{where}.to_world")
        error = np.abs(to_world.T @ to_world - np.eye(3)).max()
        if error > ENVMAP_ORTHONORMAL_TO:
            raise SpectralError(f"{where}.to_world: must be orthonormal (a rotation), found its columns' lengths and "
                                f"cosines off by up to {error:.3g}")


def _float_array(values, where: str) -> np.ndarray:
    """The float64 array that `values()` gives, or an error naming `where`."""
    try:
        return np.asarray(values(), dtype=np.float64)
    except (TypeError, ValueError):
        raise SpectralError(f"{where}: expected an array of numbers") from None


def _check_finite_nonnegative(values: np.ndarray, where: str, index: str) -> None:
    bad = ~np.isfinite(values) | (values < 0)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise SpectralError(f"{where}: must be finite and non-negative, found {values[at]:g} at {index} "
                            f"{list(at)}")


def _check_area_axes(axes, where: str) -> None:
    """Three mutually orthogonal columns (to AREA_AXES_ORTHOGONAL_TO) of finite, non-zero length."""
    columns = checks.matrix3(axes, where).T
    for index, column in enumerate(columns):
        if not np.abs(column).max() > 0:
            raise SpectralError(f"{where}: its column {index} (local {'XYZ'[index]}) must have a non-zero length")
    unit = checks.unit(columns)
    for first, second in ((0, 1), (0, 2), (1, 2)):
        cosine = float(unit[first] @ unit[second])
        if abs(cosine) > AREA_AXES_ORTHOGONAL_TO:
            raise SpectralError(f"{where}: its columns (local X, Y, Z) must be orthogonal, found local "
                                f"{'XYZ'[first]} and {'XYZ'[second]} at cosine {cosine:.3g}")


def _check_light_spectrum(spectrum: Spectrum, where: str, unit: str, cmf: str) -> None:
    checks.spectrum_within(spectrum.values, where, "a light spectrum must not be negative", 0.0, np.inf)
    if not spectrum.values.any():
        raise SpectralError(f"{where}: the light's spectrum is zero everywhere")
    if unit == "luminous" and not colorimetry.spectrum_to_xyz(spectrum.values, cmf)[1] > 0:
        raise SpectralError(f"{where}: the spectrum has no visible part (luminance Y = 0), so a luminous "
                            "strength cannot scale it: give the light \"unit\": \"radiant\" (watts)")


def check_settings(settings: RenderSettings, where: str = "render") -> None:
    """The render settings' part of `Scene.validate` (also for settings overridden after loading)."""
    checks.whole_within(settings.spp, f"{where}.spp", 1, SPP_MAX)
    checks.whole_within(settings.seed, f"{where}.seed", 0, SEED_MAX)
    checks.whole_within(settings.max_depth, f"{where}.max_depth", 1, DEPTH_MAX)
    checks.whole_within(settings.rr_depth, f"{where}.rr_depth", 0, DEPTH_MAX)
    checks.one_of(settings.wavelength_sampling, f"{where}.wavelength_sampling", WAVELENGTH_SAMPLINGS)
    per_path = checks.whole(settings.wavelengths_per_path, f"{where}.wavelengths_per_path")
    if per_path not in WAVELENGTHS_PER_PATH:
        raise SpectralError(f"{where}.wavelengths_per_path: must be "
                            f"{' or '.join(map(str, WAVELENGTHS_PER_PATH))}, found {per_path}")
    lambda_min, lambda_max = (
        checks.within(checks.number(getattr(settings, key), f"{where}.{key}"), f"{where}.{key}", LAMBDA_MIN, LAMBDA_MAX)
        for key in ("lambda_min", "lambda_max"))
    if lambda_min >= lambda_max:
        raise SpectralError(f"{where}: the wavelength range {lambda_min:g}–{lambda_max:g} nm is empty "
                            "(lambda_min must be below lambda_max)")
    if checks.whole_within(settings.bands, f"{where}.bands", 1) > 1:
        from .sampling import band_ranges  # the rule of bands, where they are made
        from .wavelength_modes import default_band

        try:
            band_ranges(*default_band(settings), settings.bands)
        except SpectralError as problem:
            raise SpectralError(f"{where}.bands: {problem}") from None
    checks.one_of(settings.cmf, f"{where}.cmf", CMFS)
    checks.one_of(settings.backend, f"{where}.backend", BACKENDS)
    checks.within(checks.number(settings.noise_threshold, f"{where}.noise_threshold"), f"{where}.noise_threshold",
                  0.0, 1.0)
    checks.whole_within(settings.min_samples, f"{where}.min_samples", 0)
    _check_boolean(settings.transparent, f"{where}.transparent")
    from .passes import check_passes  # the passes' rules, where they are made

    check_passes(settings, where)


def _check_boolean(value, where: str) -> None:
    if not isinstance(value, (bool, np.bool_)):
        raise SpectralError(f"{where}: expected true or false, found {checks.shown(value)}")
