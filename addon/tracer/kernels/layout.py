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
LIGHT_KINDS = ("sun", "environment", "sky", "point", "spot")
WAVELENGTHS_PER_PATH = (1, 4)  # the hero alone, or the hero and 3 rotated wavelengths (spectral MIS)

CAMERA_PERSPECTIVE = CAMERA_KINDS.index("perspective")
PHASE_RAYLEIGH = PHASES.index("rayleigh")
LIGHT_SUN = LIGHT_KINDS.index("sun")
LIGHT_ENVIRONMENT = LIGHT_KINDS.index("environment")
LIGHT_SKY = LIGHT_KINDS.index("sky")
LIGHT_SPOT = LIGHT_KINDS.index("spot")
MAX_WAVELENGTHS_PER_PATH = max(WAVELENGTHS_PER_PATH)
# Shadow rays whose every transmittance is below this play Russian roulette, stopping with this probability.
SHADOW_ROULETTE_BELOW, SHADOW_ROULETTE_STOP = 0.05, 0.75
# A path is grey when its attenuation per unit density spreads over its wavelengths by less than this
# (relative; interpolating a flat spectrum rounds differently at each wavelength).
GREY_SPREAD = 1e-9


class KernelScene(NamedTuple):
    """The flat arrays the kernels read, for one wavelength band (`lowering.compile_scene` builds it).

    Its fields are part of the compiled kernel: Numba keys a cached kernel by this class and its fields'
    types, not by their names, so the fields are defined here, in the kernel cache's key."""

    # camera
    cam_to_world: np.ndarray  # (4, 4)
    cam_kind: int
    width: int
    height: int
    cam_extent: np.ndarray  # (4,): film extent x, y and shift x, y (camera-space units at z = -1 or ortho)
    # media (M); grids flattened into one array each with offsets and shapes
    density_data: np.ndarray
    density_offset: np.ndarray
    density_shape: np.ndarray  # (M, 3)
    world_to_padded: np.ndarray  # (M, 4, 4): world → padded index space of the density grid
    majorant_data: np.ndarray
    majorant_offset: np.ndarray
    majorant_shape: np.ndarray  # (M, 3)
    majorant_block: np.ndarray  # (M,) cells per block
    majorant_coeff: np.ndarray  # (M,) density_scale · max over λ of (extinction + excitation)
    minorant_data: np.ndarray  # the blocks' minimum density, laid out as majorant_data
    density_scale: np.ndarray  # (M,)
    extinction: np.ndarray  # (M, GRID)
    excitation: np.ndarray  # (M, GRID) fluorophore absorption per unit density
    excitation_mean: np.ndarray  # (M,) ∫excitation² / ∫excitation: a typical λ_in's absorption (reservoir guide)
    anisotropy: np.ndarray  # (M, GRID)
    phase_kind: np.ndarray  # (M,)
    albedo_densities: np.ndarray  # (M, Lmax)
    albedo_count: np.ndarray  # (M,)
    albedo_table: np.ndarray  # (M, Lmax, GRID)
    fluor_strength: np.ndarray  # (M,) quantum_yield · ∫excitation dλ
    emission_pdf: np.ndarray  # (M, GRID) fluorescence emission pdf per nm
    excitation_cdf: np.ndarray  # (M, GRID) binned cdf for sampling λ_in ∝ excitation
    excitation_pdf: np.ndarray  # (M, GRID - 1)
    temperature_data: np.ndarray
    temperature_offset: np.ndarray  # (M,) -1 when the medium has no emission
    temperature_shape: np.ndarray  # (M, 3)
    temperature_world_to_padded: np.ndarray  # (M, 4, 4)
    temperature_map: np.ndarray  # (M, 3): scale, offset, intensity
    # lights (NL)
    light_kind: np.ndarray
    light_spd: np.ndarray  # (NL, GRID) radiometric: irradiance (sun), radiance (env/sky), intensity (point/spot)
    light_spd_horizon: np.ndarray  # (NL, GRID) sky only
    light_dir: np.ndarray  # (NL, 3) towards the sun; spot axis for spots
    light_pos: np.ndarray  # (NL, 3)
    light_cos: np.ndarray  # (NL,) sun: cos of the half-angle (1: delta); spot: cos of the half cone
    light_smooth: np.ndarray  # (NL,) spot edge width in cosine
    light_pmf: np.ndarray  # (NL,) selection probability for next-event estimation
    light_power: np.ndarray  # (NL,) selection power (`lights.selection_powers`) that `light_pmf` normalises
    # wavelengths and colour
    lambda_cdf: np.ndarray  # (GRID,) binned cdf of the hero wavelength in this band
    lambda_pdf: np.ndarray  # (GRID - 1,)
    wavelengths_per_path: int
    xyz_weights: np.ndarray  # (3, GRID)
    # path settings
    max_depth: int
    rr_depth: int
