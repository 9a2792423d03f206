"""An envmap light (`KernelEnvmaps`): an equirectangular RGB map of the radiance arriving from every direction,
mapped as Blender's Environment Texture maps it, read at the texel a direction falls in and sampled texel by
texel in proportion to the texels' weights.

A world direction is turned into the map's frame (`to_map`), where (x, y, z) has the map coordinates of
Cycles' `direction_to_equirectangular`:

    u = 0.5 − atan2(y, x) / 2π   across the columns, left to right (+X at the centre, +Y at u = 0.25)
    v = 0.5 + asin(z) / π        v = 1 at the top row, the +Z pole

Texel (r, c), row r from the top of H rows and column c of W, covers u in [c/W, (c+1)/W) and the polar
angle θ = acos z in [π r/H, π (r+1)/H), a solid angle (2π/W)(cos(π r/H) − cos(π (r+1)/H)) (`row_solid_angle`).
Its radiance Σ_c rgb_c · basis_c(λ) is constant over it: the map is not interpolated between texels, so the
sampler's pdf follows it exactly. A row is drawn from the row cdf, a column from that row's column cdf, and
a direction uniformly in the texel's solid angle (uniform in z and in the azimuth): the pdf in solid angle is
the texel's probability over its solid angle, and the estimate is constant over a texel.

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..shared_math import floor, shared, shared_inline, sqrt
from .lookups import cdf_bin, table_at


@shared
def row_solid_angle(rows, columns, row):
    """The solid angle of a texel in row(s) `row` (from the top) of a map of `rows` × `columns` texels."""
    return (2.0 * np.pi / columns) * (np.cos(np.pi * row / rows) - np.cos(np.pi * (row + 1.0) / rows))


@shared_inline
def texel_of(ks, light, dx, dy, dz):
    """The texel (row, column) of the light's map that world direction(s) (dx, dy, dz) fall in."""
    rows, columns = ks.envmaps.shape[light, 0], ks.envmaps.shape[light, 1]
    m = ks.envmaps.to_map[light]
    x = m[0, 0] * dx + m[0, 1] * dy + m[0, 2] * dz
    y = m[1, 0] * dx + m[1, 1] * dy + m[1, 2] * dz
    z = m[2, 0] * dx + m[2, 1] * dy + m[2, 2] * dz
    u = 0.5 - np.arctan2(y, x) * (0.5 / np.pi)
    polar = np.arccos(np.minimum(np.maximum(z, -1.0), 1.0))
    column = np.int64(np.minimum(np.maximum(floor(u * columns), 0.0), columns - 1.0))
    row = np.int64(np.minimum(floor(polar * (rows / np.pi)), rows - 1.0))
    return row, column


@shared_inline
def texel_pdf(ks, light, row, column):
    """The solid-angle pdf of `envmap_sample` in texel(s) (row, column): the probability of its row times that
    of its column in the row, over its solid angle."""
    rows, columns = ks.envmaps.shape[light, 0], ks.envmaps.shape[light, 1]
    row_cdf, column_cdf = ks.envmaps.row_cdf, ks.envmaps.column_cdf
    r = ks.envmaps.row_cdf_offset[light] + row
    c = ks.envmaps.column_cdf_offset[light] + row * (columns + 1) + column
    probability = (row_cdf[r + 1] - row_cdf[r]) * (column_cdf[c + 1] - column_cdf[c])
    return probability / row_solid_angle(rows, columns, row)


@shared_inline
def envmap_radiance(ks, light, at, dx, dy, dz):
    """The radiance Σ_c rgb_c · basis_c arriving along world direction(s) (dx, dy, dz) at the wavelengths
    located by `at`, from the texel they fall in."""
    row, column = texel_of(ks, light, dx, dy, dz)
    texel = ks.envmaps.texel_offset[light] + row * ks.envmaps.shape[light, 1] + column
    rgb, basis = ks.envmaps.rgb, ks.envmaps.basis
    return (rgb[texel, 0] * table_at(basis, 3 * light, at) + rgb[texel, 1] * table_at(basis, 3 * light + 1, at)
            + rgb[texel, 2] * table_at(basis, 3 * light + 2, at))


@shared_inline
def envmap_pdf(ks, light, dx, dy, dz):
    """The solid-angle pdf of `envmap_sample` drawing world direction(s) (dx, dy, dz)."""
    row, column = texel_of(ks, light, dx, dy, dz)
    return texel_pdf(ks, light, row, column)


@shared_inline
def envmap_sample(ks, light, u1, u2):
    """A world direction (wx, wy, wz) drawn for uniforms u1, u2 and its solid-angle pdf: a row by u1, a column
    of it by u2, then a direction uniform in the texel's solid angle (u1's and u2's positions in their bins
    place it in z and in the azimuth)."""
    rows, columns = ks.envmaps.shape[light, 0], ks.envmaps.shape[light, 1]
    row, along_row = cdf_bin(ks.envmaps.row_cdf, ks.envmaps.row_cdf_offset[light], rows, u1)
    start = ks.envmaps.column_cdf_offset[light] + row * (columns + 1)
    column, along_column = cdf_bin(ks.envmaps.column_cdf, start, columns, u2)
    top, bottom = np.cos(np.pi * row / rows), np.cos(np.pi * (row + 1.0) / rows)
    z = top - along_row * (top - bottom)
    azimuth = np.pi * (1.0 - 2.0 * (column + along_column) / columns)  # atan2(y, x) at u = (column + t) / W
    radius = sqrt(np.maximum(1.0 - z * z, 0.0))
    x, y = radius * np.cos(azimuth), radius * np.sin(azimuth)
    m = ks.envmaps.to_map[light]  # orthonormal: its transpose takes the map's frame to the world
    return (m[0, 0] * x + m[1, 0] * y + m[2, 0] * z, m[0, 1] * x + m[1, 1] * y + m[2, 1] * z,
            m[0, 2] * x + m[1, 2] * y + m[2, 2] * z, texel_pdf(ks, light, row, column))
