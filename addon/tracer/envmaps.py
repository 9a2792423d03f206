"""An envmap light's map as the kernels take it (`kernels/envmap.py`, `KernelEnvmaps`): its basis spectra at its
strength, the solid angles of its texels, its mean radiance and the row and column cdfs that its texels are
drawn from.
"""

import numpy as np

from .kernels.envmap import row_solid_angle
from .scene import Light


def kernel_basis(light: Light) -> np.ndarray:
    """(3, GRID): the radiance of a texel of unit R, G and B: the light's basis times its strength."""
    return light.strength * light.basis_values()


def texel_solid_angles(light: Light) -> np.ndarray:
    """(H, 1): the solid angle of a texel in each row of the light's map (the same along a row)."""
    rows, columns = light.image.shape[:2]
    return row_solid_angle(rows, columns, np.arange(rows, dtype=np.float64))[:, None]


def mean_radiance(light: Light) -> np.ndarray:
    """(GRID,): the map's radiance averaged over the sphere, Σ_c (∫ rgb_c dω / 4π) · basis_c."""
    rgb = np.asarray(light.image, dtype=np.float64)
    mean_rgb = (rgb * texel_solid_angles(light)[:, :, None]).sum(axis=(0, 1)) / (4.0 * np.pi)
    return mean_rgb @ kernel_basis(light)


def cdfs(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cdf over the rows of non-negative texel `weights` (H, W) (H + 1 values) and each row's cdf over its
    columns (H × (W + 1) values, row by row), each from exactly 0 to exactly 1; a row of weight 0, never
    drawn, gets a uniform one."""
    rows, columns = weights.shape
    row_weights = weights.sum(axis=1)
    row_cdf = np.concatenate([[0.0], np.cumsum(row_weights)]) / row_weights.sum()
    row_cdf[-1] = 1.0
    column_cdf = np.zeros((rows, columns + 1))
    column_cdf[:, 1:] = np.cumsum(np.where(row_weights[:, None] > 0, weights, 1.0), axis=1)
    column_cdf /= column_cdf[:, -1:]
    column_cdf[:, -1] = 1.0
    return row_cdf, column_cdf.ravel()
