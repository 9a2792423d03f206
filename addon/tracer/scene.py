"""The in-memory scene: camera, media, lights and render settings as plain dataclasses.

This is what the scene file (`scene_io`, docs/scene-format.md) loads into and what the add-on's
exporter builds; the kernels never see it directly (`lowering` lowers it to `KernelScene`, arrays grouped
by concept). Conventions (docs/architecture.md, "Data flow"): lengths in Blender units, wavelengths in nm,
matrices are 4×4 row-major NumPy arrays acting on column vectors (world = M @ [x, y, z, 1]).

Whoever built a scene, `validation.validate` checks it (called by `scene_io.load_scene` and `save_scene`,
by `lowering.compile_scene` and by the exporter). The enumerations of the format are defined here, once, except those the kernels switch on (kinds of camera and light, phase
functions, wavelengths per path), which `kernels/layout.py` defines beside their codes.
"""

from dataclasses import dataclass, field

import numpy as np

from .spectra import Spectrum, constant

SENSOR_FITS = ("AUTO", "HORIZONTAL", "VERTICAL")
# What a light's strength measures: "luminous", its luminance Y (with the render's colour matching
# functions); "radiant", its radiometric quantity integrated over the whole grid (250–830 nm).
LIGHT_UNITS = ("luminous", "radiant")
# The radiant unit of each light kind's strength.
RADIANT_UNITS = {"sun": "W·m⁻²", "environment": "W·m⁻²·sr⁻¹", "sky": "W·m⁻²·sr⁻¹", "point": "W·sr⁻¹",
                 "spot": "W·sr⁻¹", "area": "W", "envmap": "× its map"}
WAVELENGTH_SAMPLINGS = ("uniform", "d65_rejection", "uv", "light", "visible", "colour")
SEED_MAX = 2**64 - 1  # seeds are unsigned 64-bit integers in the kernels' random streams
SPP_MAX = 2**32  # a pixel's samples are points of a Sobol sequence of 2³² points (kernels/rng.py)
# Scattering events of a path: Russian roulette ends paths long before; beyond, a value is a mistake.
DEPTH_MAX = 2**20


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
class Texture:
    """An image on a surface's triangles through UVs, as Blender's Image Texture node reads it: a texel's colour
    is the Lambertian albedo's colour (its spectrum: `texel_spectra`), replacing the surface's `reflectance`.
    `image[row, column]` is a colour in [0, 1] (linear Rec.709, or sRGB-encoded: `srgb`) with row 0 at the top (v = 1) and column 0 at u = 0; `uv`
    holds each of the surface's triangles' corners' (u, v), in the order of `Surface.triangles`. `extension`
    (Repeat, Extend, Clip: black outside) and `interpolation` (Linear, Closest) have Blender's meanings. With `srgb`
    the texels are sRGB-encoded (an 8-bit sRGB image's) and decoded after interpolation, as Cycles reads them."""

    image: np.ndarray  # (H, W, 3) float32
    uv: np.ndarray  # (T, 3, 2) float64
    extension: str = "REPEAT"  # one of kernels.layout.TEXTURE_EXTENSIONS
    interpolation: str = "Linear"  # one of kernels.layout.TEXTURE_INTERPOLATIONS
    srgb: bool = False  # texels sRGB-encoded, decoded after interpolation


@dataclass(frozen=True, eq=False)
class Surface:
    """An opaque triangle mesh in world space: a Lambertian reflector on both sides, and optionally an
    emitter (a mesh light). `reflectance` is the albedo ρ(λ) in [0, 1], the BRDF ρ/π; `emission` the
    radiance leaving both sides in W·m⁻²·sr⁻¹·nm⁻¹ (Cycles' Emission shader on a mesh is two-sided), None
    for a surface that is not a light. Triangles of zero area (repeated or collinear corners) are allowed
    and ignored: they are never hit and emit nothing. A `holdout` surface, as Cycles' Holdout (shader or object
    property), cuts a hole where a camera ray reaches it (directly or through a volume), before any scattering:
    zero colour behind what lies in front, and zero alpha with Film ▸ Transparent (black without); rays after a
    scattering see it as its reflectance and emission say (a Holdout shader's surface: reflectance 0). A surface
    that is not `camera` visible (Cycles' Indirect Only collections, Ray Visibility ▸ Camera off) is passed by camera
    rays (directly or through a volume) and seen by every ray after a scattering, and by shadow rays. A `texture`
    replaces `reflectance` with its texels' colours."""

    name: str
    vertices: np.ndarray  # (V, 3) float64, world space
    triangles: np.ndarray  # (T, 3) integer indices into vertices
    reflectance: Spectrum  # Lambertian albedo over the wavelength grid, in [0, 1]
    emission: Spectrum | None = None  # radiance leaving both sides, None: not a light
    holdout: bool = False  # camera rays see a hole here (Film ▸ Transparent: alpha 0)
    camera: bool = True  # camera rays see it (False: they pass it)
    texture: Texture | None = None  # the albedo's image through UVs (None: `reflectance` everywhere)
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
    backend: str = "numba"  # one of backends.NAMES
    # Adaptive sampling (`adaptive`): a pixel stops once its error is below this (0: every pixel gets `spp`),
    # after `min_samples` (0: chosen from the threshold).
    noise_threshold: float = 0.0
    min_samples: int = 0
    # Film ▸ Transparent: camera rays that reach the background (the infinite lights) see none of it, and the
    # film's alpha is 1 − the share they saw; the infinite lights still light the scene.
    transparent: bool = False
    # Passes written beside the image: data passes (`passes.DATA_PASSES`: Depth, Mist, Normal, CryptoObject,
    # CryptoMaterial) and light passes (`light_passes.LIGHT_PASSES`: Emission, Environment, Volume Direct,
    # Volume Indirect), with
    # World ▸ Mist Pass's start, depth and falloff and Cryptomatte's levels.
    passes: tuple[str, ...] = ()
    mist_start: float = 5.0
    mist_depth: float = 25.0
    mist_falloff: str = "quadratic"  # "quadratic" | "linear" | "inverse_quadratic"
    cryptomatte_depth: int = 6
    # The spectral image (`spectral_film`, the spectral EXR): per pixel, the mean spectral radiance over each bin from
    # spectrum_start to spectrum_end nm in steps of spectrum_step nm.
    spectrum: bool = False
    spectrum_start: float = 380.0
    spectrum_end: float = 780.0
    spectrum_step: float = 10.0
    # Light Paths ▸ Clamping (`kernels/light_split.py`): the most light a sample's direct and indirect parts may
    # bring, in linear Rec.709 (0: no clamping, the default here: unbiased; Blender's are 0 and 10).
    clamp_direct: float = 0.0
    clamp_indirect: float = 0.0
    # The firefly filter (`fireflies`): each pixel's brightest group of samples is scaled down to the group's size ×
    # its neighbourhood's mean + firefly_threshold × their per-sample standard deviation × √samples (0: off, the
    # default here: unbiased).
    firefly_threshold: float = 0.0


@dataclass(frozen=True, eq=False)
class Scene:
    camera: Camera
    media: tuple[Medium, ...] = ()
    lights: tuple[Light, ...] = ()
    surfaces: tuple[Surface, ...] = ()
    settings: RenderSettings = field(default_factory=RenderSettings)
