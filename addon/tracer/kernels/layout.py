"""The kernels' data layout: `KernelScene`, the integer codes of the scene's enumerations and the
constants the kernels are compiled with.

The enumerations of the scene format that the kernels switch on are defined here (`scene` imports them):
a name's code in the kernels is its index in its tuple. This module is part of the kernel cache's key
(`numba_cache.KERNEL_SOURCES`), so it holds only what the compiled kernel depends on and imports nothing
from the tracer: the lowering (`lowering`) and the light and wavelength policies (`lights`,
`wavelength_modes`) change without recompiling the kernel.
"""

from typing import NamedTuple

import numpy as np

CAMERA_KINDS = ("perspective", "orthographic")
PHASES = ("hg", "rayleigh")
LIGHT_KINDS = ("sun", "environment", "sky", "point", "spot", "area", "envmap")
AREA_SHAPES = ("rectangle", "ellipse")  # an area light's shape (a square and a disk are their equal-sided cases)
WAVELENGTHS_PER_PATH = (1, 4)  # the hero alone, or the hero and 3 rotated wavelengths (spectral MIS)
# A surface texture's reading outside [0, 1] of UV and between its texels, by Blender's names (Image Texture node).
TEXTURE_EXTENSIONS = ("REPEAT", "EXTEND", "CLIP")
TEXTURE_INTERPOLATIONS = ("Linear", "Closest")

CAMERA_PERSPECTIVE = CAMERA_KINDS.index("perspective")
PHASE_RAYLEIGH = PHASES.index("rayleigh")
LIGHT_SUN = LIGHT_KINDS.index("sun")
LIGHT_ENVIRONMENT = LIGHT_KINDS.index("environment")
LIGHT_SKY = LIGHT_KINDS.index("sky")
LIGHT_POINT = LIGHT_KINDS.index("point")
LIGHT_SPOT = LIGHT_KINDS.index("spot")
LIGHT_AREA = LIGHT_KINDS.index("area")
LIGHT_ENVMAP = LIGHT_KINDS.index("envmap")
# A kernel light that no scene file names: an emissive surface (`scene.Surface.emission`), lowered to one light.
LIGHT_MESH = len(LIGHT_KINDS)
AREA_ELLIPSE = AREA_SHAPES.index("ellipse")
TEXTURE_REPEAT = TEXTURE_EXTENSIONS.index("REPEAT")
TEXTURE_CLIP = TEXTURE_EXTENSIONS.index("CLIP")
TEXTURE_LINEAR = TEXTURE_INTERPOLATIONS.index("Linear")
# Nodes per axis of the RGB lattice whose reflectance spectra a texel's colour is interpolated between
# (`texel_spectra`, `surfaces.rgb_reflectance`): 0, 1/8, ..., 1.
RGB_LATTICE = 9
MAX_WAVELENGTHS_PER_PATH = max(WAVELENGTHS_PER_PATH)
# Shadow rays whose every transmittance is below this play Russian roulette, stopping with this probability.
SHADOW_ROULETTE_BELOW, SHADOW_ROULETTE_STOP = 0.05, 0.75
# A path is grey when its attenuation per unit density spreads over its wavelengths by less than this
# (relative; interpolating a flat spectrum rounds differently at each wavelength).
GREY_SPREAD = 1e-9
# A ray leaving a surface starts this far off it along its normal, relative to 1 + the largest |coordinate| of
# the point (float64 rounding puts a computed hit point ~1e-16 of that off the plane), and a shadow ray
# towards a point of an emissive surface stops as far short of it: neither finds the surface it started from
# or ends on.
SURFACE_OFFSET = 1e-9
# The deepest a BVH gets (`bvh.build` falls back to median splits to stay within it), so traversal's stack.
BVH_MAX_DEPTH = 96
# The hierarchy walk's stack of nodes (`numba_backend._closest_hit`), a name: a CUDA local array's shape must be a
# literal, not an expression.
BVH_STACK = 2 * BVH_MAX_DEPTH
# The media one CUDA thread's path state holds (`cuda_backend`; the CPU kernel holds any number): the backend
# refuses a scene with more.
MAX_MEDIA = 4
# A camera ray's first hit, for the data passes (`first_hit`): depth, distance, normal x, y, z.
FIRST_HIT_VALUES = 5


class KernelCamera(NamedTuple):
    """The camera: its pose, kind and film (Film ▸ Transparent: `kernels/transparency.py`)."""

    to_world: np.ndarray  # (4, 4)
    kind: int
    width: int
    height: int
    extent: np.ndarray  # (4,): film extent x, y and shift x, y (camera-space units at z = -1 or ortho)
    transparent: bool  # camera rays that reach the background see none of it (they count as transparency)
    white_y: float  # Y of a unit equal-energy radiance over the camera's wavelengths (the transparency's scale)


class KernelDensity(NamedTuple):
    """The media's (M) density grids, flattened into one array with each grid's offset and shape."""

    data: np.ndarray
    offset: np.ndarray
    shape: np.ndarray  # (M, 3)
    world_to_padded: np.ndarray  # (M, 4, 4): world → padded index space of the density grid


class KernelMajorant(NamedTuple):
    """The media's majorant grids (each block's maximum density), flattened like `KernelDensity`, and the
    minorant grids (each block's minimum density), laid out as the majorant grids."""

    data: np.ndarray
    offset: np.ndarray
    shape: np.ndarray  # (M, 3)
    block: np.ndarray  # (M,) cells per block
    coeff: np.ndarray  # (M,) density_scale · max over λ of (extinction + excitation)
    minorant: np.ndarray  # the blocks' minimum density, laid out as `data`


class KernelTemperature(NamedTuple):
    """The temperature grids of the media that emit a black body (thermally or as a glow), flattened like
    `KernelDensity`, and how each maps to kelvin and thermal emission."""

    data: np.ndarray
    offset: np.ndarray  # (M,) -1 when the medium has no temperature
    shape: np.ndarray  # (M, 3)
    world_to_padded: np.ndarray  # (M, 4, 4)
    map: np.ndarray  # (M, 3): scale, offset, thermal intensity (0 for a glow)


class KernelGlow(NamedTuple):
    """Each medium's glow, emission per unit scaled density that does not depend on absorption (all zero
    without one), and the black body's normalisation to luminance σT⁴/π, tabulated over log T."""

    glowing: np.ndarray  # (M,) bool: the medium has a glow
    spectrum: np.ndarray  # (M, GRID) radiance per unit length per unit scaled density
    blackbody: np.ndarray  # (M, GRID) blackbody · tint: the weight of the normalised black body
    log_kelvin: np.ndarray  # (2,) log T of the table's first node and the spacing of its nodes
    log_normalisation: np.ndarray  # (K,) log((σT⁴/π) / Y(Planck(·, T))) at the nodes


class KernelMedia(NamedTuple):
    """Each medium's density scale, extinction, phase function and albedo, tabulated on the grid."""

    density_scale: np.ndarray  # (M,)
    extinction: np.ndarray  # (M, GRID)
    anisotropy: np.ndarray  # (M, GRID)
    phase_kind: np.ndarray  # (M,)
    albedo_densities: np.ndarray  # (M, Lmax)
    albedo_count: np.ndarray  # (M,)
    albedo_table: np.ndarray  # (M, Lmax, GRID)


class KernelFluorescence(NamedTuple):
    """Each medium's fluorophore (all zero without one): its absorption, strength and emission, and the
    distribution of the excitation wavelength λ_in."""

    excitation: np.ndarray  # (M, GRID) fluorophore absorption per unit density
    excitation_mean: np.ndarray  # (M,) ∫excitation² / ∫excitation: a typical λ_in's absorption (reservoir guide)
    strength: np.ndarray  # (M,) quantum_yield · ∫excitation dλ
    emission_pdf: np.ndarray  # (M, GRID) fluorescence emission pdf per nm
    excitation_cdf: np.ndarray  # (M, GRID) binned cdf for sampling λ_in ∝ excitation
    excitation_pdf: np.ndarray  # (M, GRID - 1)


class KernelLights(NamedTuple):
    """The lights (NL): their kind, spectra and geometry, and how next-event estimation selects them."""

    kind: np.ndarray
    # (NL, GRID) radiometric: irradiance (sun), radiance (env/sky; envmap: its mean; an emissive surface, LIGHT_MESH),
    # intensity (point/spot; area: along its normal)
    spd: np.ndarray
    spd_horizon: np.ndarray  # (NL, GRID) sky only
    dir: np.ndarray  # (NL, 3) towards the sun; spot axis for spots; the direction an area light emits along
    pos: np.ndarray  # (NL, 3) point, spot; the centre of an area light
    area_span: np.ndarray  # (NL, 2, 3) half its size along its local X and Y, as world vectors
    area_shape: np.ndarray  # (NL,) its index in AREA_SHAPES
    camera_visible: np.ndarray  # (NL,) bool: camera rays see an area light's face
    cos: np.ndarray  # (NL,) sun: cos of the half-angle (1: delta); spot: cos of the half cone
    smooth: np.ndarray  # (NL,) spot edge width in cosine
    pmf: np.ndarray  # (NL,) selection probability for next-event estimation
    power: np.ndarray  # (NL,) selection power (`lights.selection_powers`) that `pmf` normalises
    # The sunward probe (`probe_grid`, docs/algorithm.md): the sun it aims at ((1,), -1: no probe), the chance of a
    # probe at a medium vertex per cell of a grid over the media's box (N, N, N), and that box ((2, 3): its lower
    # corner, then cells per unit length along each axis)
    probe: np.ndarray
    probe_chance: np.ndarray
    probe_box: np.ndarray


class KernelEnvmaps(NamedTuple):
    """The envmap lights' equirectangular maps (`kernels/envmap.py`) and their sampling distributions, every
    map's back to back in flat arrays from its light's offsets (a light without a map has shape (0, 0))."""

    rgb: np.ndarray  # (texels, 3) float32: each map's texels row by row, row 0 at the top (the map's +Z pole)
    basis: np.ndarray  # (3 NL, GRID) rows 3 · light + c: the radiance of a texel of unit channel c (R, G, B)
    to_map: np.ndarray  # (NL, 3, 3) world directions to the map's frame (the transpose of its `to_world`)
    shape: np.ndarray  # (NL, 2) rows H and columns W
    texel_offset: np.ndarray  # (NL,) the map's first texel in `rgb`
    row_cdf: np.ndarray  # (H + 1 per map) the cdf over the rows, 0 … 1
    row_cdf_offset: np.ndarray  # (NL,)
    column_cdf: np.ndarray  # (H (W + 1) per map) each row's cdf over its columns, 0 … 1
    column_cdf_offset: np.ndarray  # (NL,)


class KernelSurfaces(NamedTuple):
    """The surfaces' (S) triangles (T, zero-area ones dropped) in the order of their bounding volume hierarchy
    (`bvh.build`), its nodes (N), the surfaces' spectra, and the emissive surfaces' triangle distributions."""

    corner: np.ndarray  # (T, 3) each triangle's first vertex
    edge1: np.ndarray  # (T, 3) its second vertex less the first
    edge2: np.ndarray  # (T, 3) its third vertex less the first
    normal: np.ndarray  # (T, 3) unit normal, edge1 × edge2 normalised
    surface: np.ndarray  # (T,) the surface each belongs to
    node_bounds: np.ndarray  # (N, 6) each node's box: lower x, y, z, upper x, y, z
    node_first: np.ndarray  # (N,) an inner node's left child (its right one follows it); a leaf's first triangle
    node_count: np.ndarray  # (N,) a leaf's number of triangles, 0 for an inner node
    reflectance: np.ndarray  # (S, GRID) Lambertian albedo
    light: np.ndarray  # (S,) the kernel light (LIGHT_MESH) of an emissive surface, -1 for the others
    holdout: np.ndarray  # (S,) bool: camera rays that reach it see a hole (`kernels/transparency.py`)
    camera: np.ndarray  # (S,) bool: camera rays see it (False: Indirect Only, Ray Visibility ▸ Camera off)
    uv: np.ndarray  # (T, 6) each triangle's corners' u, v (zeros on a surface without a texture)
    texture_offset: np.ndarray  # (S,) a textured surface's first texel in `texels`, -1 for a surface without one
    texture_shape: np.ndarray  # (S, 2) its texture's rows and columns
    # (S, 3) its extension (TEXTURE_EXTENSIONS), interpolation (TEXTURE_INTERPOLATIONS), and 1 where its texels are
    # sRGB-encoded (decoded after interpolation, as Cycles decodes 8-bit sRGB images), else 0
    texture_mode: np.ndarray
    texels: np.ndarray  # (texels, 3) float32 in [0, 1], each texture's rows back to back, top row first
    rgb_spectra: np.ndarray  # (RGB_LATTICE³ or 0, GRID) the reflectance of each RGB lattice node (`texel_spectra`)
    of_light: np.ndarray  # (NL,) the surface of each kernel light, -1 for lights that are not surfaces
    area: np.ndarray  # (S,) total area
    emitter_cdf: np.ndarray  # each emissive surface's cdf over its triangles by area, from 0 to 1, back to back
    emitter_triangle: np.ndarray  # each bin's triangle, at its cdf node's index (each surface's last entry -1)
    emitter_offset: np.ndarray  # (S,) where each surface's cdf starts in emitter_cdf (and its bins in emitter_triangle)
    emitter_count: np.ndarray  # (S,) its number of triangles (0: not emissive)


class KernelWavelengths(NamedTuple):
    """The camera's wavelengths and colour: the hero wavelength's distribution in this band, the
    wavelengths per path, the XYZ weights and the spectral film's bins."""

    cdf: np.ndarray  # (GRID,) binned cdf of the hero wavelength in this band
    pdf: np.ndarray  # (GRID - 1,)
    per_path: int
    xyz_weights: np.ndarray  # (3, GRID)
    spectrum_edges: np.ndarray  # (B + 1,) edges of the spectral film's uniform bins, nm (`spectrum_bins`); (0,): none


class KernelTermination(NamedTuple):
    """When a path ends: its greatest depth and the depth from which it plays Russian roulette; and how much
    light one sample may bring (Light Paths ▸ Clamping, `light_split`: each part's limit, 0 for none, and the
    XYZ → linear Rec.709 matrix the limits are measured in)."""

    max_depth: int
    rr_depth: int
    clamp_direct: float
    clamp_indirect: float
    xyz_to_rgb: np.ndarray  # (3, 3)


class KernelScene(NamedTuple):
    """The arrays the kernels read, for one wavelength band (`lowering.compile_scene` builds it), grouped
    by concept in the NamedTuples above (`ks.camera.width`, `ks.majorant.data`, `ks.lights.pmf`, ...).

    Its classes are part of the compiled kernel: Numba keys a cached kernel by these classes and their
    fields' types, not by their names, so they are defined here, in the kernel cache's key."""

    camera: KernelCamera
    density: KernelDensity
    majorant: KernelMajorant
    temperature: KernelTemperature
    glow: KernelGlow
    media: KernelMedia
    fluorescence: KernelFluorescence
    lights: KernelLights
    envmaps: KernelEnvmaps
    surfaces: KernelSurfaces
    wavelengths: KernelWavelengths
    termination: KernelTermination
