"""Surfaces at a point: a ray's distance to a triangle, the Lambertian reflector's cosine-weighted sampling and
pdf, the side of a triangle a ray arrives on, the point leaving a surface, a textured surface's albedo at a
point (its UV, the texels as Blender's Image Texture node reads them, and the colour's reflectance between
the RGB lattice's spectra: `texel_spectra`), and the emissive surfaces' points and pdfs for next-event
estimation.

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel (which
walks the triangles' hierarchy), arrays of paths (and of triangles, for the NumPy backend's brute-force
intersection) in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).

A Lambertian surface of albedo ρ(λ) has the BRDF ρ/π: light arriving along a direction at cos θ to the
normal on the side the path is on reflects ρ cos θ / π of its radiance per unit solid angle, and none
through (the surface is opaque, and both of its sides reflect). Directions are drawn with pdf cos θ / π,
so a sampled direction's throughput is ρ, the same pdf at every wavelength.
"""

import numpy as np

from ..shared_math import absolute, exp, floor, select, shared, shared_inline, sqrt
from .layout import RGB_LATTICE, SURFACE_OFFSET, TEXTURE_CLIP, TEXTURE_LINEAR, TEXTURE_REPEAT
from .lookups import cdf_bin, table_at

INV_PI = 1.0 / np.pi


@shared_inline
def triangle_distance(ks, k, ox, oy, oz, dx, dy, dz):
    """The ray parameter t > 0 at which the ray(s) o + t d meet triangle(s) k (Möller and Trumbore 1997, on
    the lowered corner and edges), inf where they miss it (a ray in its plane misses it). Rays and triangles
    broadcast: columns of rays against a row of triangles in the NumPy backend."""
    corner, edge1, edge2 = ks.surfaces.corner, ks.surfaces.edge1, ks.surfaces.edge2
    e1x, e1y, e1z = edge1[k, 0], edge1[k, 1], edge1[k, 2]
    e2x, e2y, e2z = edge2[k, 0], edge2[k, 1], edge2[k, 2]
    px, py, pz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
    determinant = e1x * px + e1y * py + e1z * pz
    inverse = 1.0 / determinant
    tx, ty, tz = ox - corner[k, 0], oy - corner[k, 1], oz - corner[k, 2]
    u = (tx * px + ty * py + tz * pz) * inverse
    qx, qy, qz = ty * e1z - tz * e1y, tz * e1x - tx * e1z, tx * e1y - ty * e1x
    v = (dx * qx + dy * qy + dz * qz) * inverse
    t = (e2x * qx + e2y * qy + e2z * qz) * inverse
    hit = (determinant != 0.0) & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > 0.0)
    return select(hit, t, np.inf)


@shared_inline
def facing_normal(ks, k, dx, dy, dz):
    """Triangle(s) k's unit normal on the side that ray direction(s) (dx, dy, dz) arrive from (against d)."""
    normal = ks.surfaces.normal
    nx, ny, nz = normal[k, 0], normal[k, 1], normal[k, 2]
    side = select(nx * dx + ny * dy + nz * dz > 0.0, -1.0, 1.0)
    return nx * side, ny * side, nz * side


@shared_inline
def barycentrics(ks, k, px, py, pz):
    """The weights (b1, b2) of triangle(s) k's second and third corners at point(s) p in its plane: p = corner +
    b1 · edge1 + b2 · edge2."""
    corner, edge1, edge2 = ks.surfaces.corner, ks.surfaces.edge1, ks.surfaces.edge2
    e1x, e1y, e1z = edge1[k, 0], edge1[k, 1], edge1[k, 2]
    e2x, e2y, e2z = edge2[k, 0], edge2[k, 1], edge2[k, 2]
    vx, vy, vz = px - corner[k, 0], py - corner[k, 1], pz - corner[k, 2]
    d11, d22 = e1x * e1x + e1y * e1y + e1z * e1z, e2x * e2x + e2y * e2y + e2z * e2z
    d12 = e1x * e2x + e1y * e2y + e1z * e2z
    v1, v2 = vx * e1x + vy * e1y + vz * e1z, vx * e2x + vy * e2y + vz * e2z
    inverse = 1.0 / (d11 * d22 - d12 * d12)
    return (d22 * v1 - d12 * v2) * inverse, (d11 * v2 - d12 * v1) * inverse


@shared
def _texel_index(i, count, extension):
    """A texel's column (or row from the bottom) i of `count` under the texture's extension (Repeat wraps,
    Extend and Clip clamp) and whether it is read (Clip: black outside the image)."""
    wrapped = i - np.int64(floor(i / count)) * count
    clamped = np.minimum(np.maximum(i, 0), count - 1)
    return (select(extension == TEXTURE_REPEAT, wrapped, clamped),
            (extension != TEXTURE_CLIP) | ((i >= 0) & (i < count)))


@shared_inline
def texel_colour(ks, s, k, px, py, pz):
    """The linear Rec.709 colour of textured surface(s) s at point(s) p of their triangle(s) k: the UV of p
    between the triangle's corners, read as Blender reads an image (Linear: the 4 texels around it weighted
    bilinearly, texel centres at (i + ½) / W; Closest: the texel it falls in), with the texture's extension, and
    decoded from sRGB after interpolation where its texels are encoded so (as Cycles reads 8-bit sRGB images)."""
    b1, b2 = barycentrics(ks, k, px, py, pz)
    uv = ks.surfaces.uv
    u = uv[k, 0] + b1 * (uv[k, 2] - uv[k, 0]) + b2 * (uv[k, 4] - uv[k, 0])
    v = uv[k, 1] + b1 * (uv[k, 3] - uv[k, 1]) + b2 * (uv[k, 5] - uv[k, 1])
    offset = ks.surfaces.texture_offset[s]
    rows, columns = ks.surfaces.texture_shape[s, 0], ks.surfaces.texture_shape[s, 1]
    extension, linear = ks.surfaces.texture_mode[s, 0], ks.surfaces.texture_mode[s, 1] == TEXTURE_LINEAR
    x = select(linear, u * columns - 0.5, floor(u * columns))
    y = select(linear, v * rows - 0.5, floor(v * rows))
    x0, y0 = floor(x), floor(y)
    fx, fy = x - x0, y - y0
    i0, j0 = np.int64(x0), np.int64(y0)
    r, g, b = 0.0 * u, 0.0 * u, 0.0 * u
    for corner in range(4):
        dx, dy = corner % 2, corner // 2
        column, inside_x = _texel_index(i0 + dx, columns, extension)
        row, inside_y = _texel_index(j0 + dy, rows, extension)
        weight = (fx if dx else 1.0 - fx) * (fy if dy else 1.0 - fy) * (inside_x & inside_y)
        texel = offset + (rows - 1 - row) * columns + column  # rows stored top first
        r = r + weight * ks.surfaces.texels[texel, 0]
        g = g + weight * ks.surfaces.texels[texel, 1]
        b = b + weight * ks.surfaces.texels[texel, 2]
    srgb = ks.surfaces.texture_mode[s, 2] == 1
    return _srgb_decoded(r, srgb), _srgb_decoded(g, srgb), _srgb_decoded(b, srgb)


@shared
def _srgb_decoded(value, srgb):
    """A colour component in [0, 1] decoded from the sRGB transfer function where `srgb`, else as it is."""
    curve = exp(2.4 * np.log(np.maximum((value + 0.055) / 1.055, 1e-300)))
    return select(srgb, select(value <= 0.04045, value / 12.92, curve), value)


@shared
def _lattice(value):
    """A colour component in [0, 1] on the RGB lattice: its cell's lower node and its position in the cell."""
    position = np.minimum(np.maximum(value, 0.0), 1.0) * (RGB_LATTICE - 1)
    node = np.int64(np.minimum(floor(position), RGB_LATTICE - 2.0))
    return node, position - node


@shared
def rgb_reflectance(spectra, r, g, b, at):
    """The reflectance at the wavelength(s) located by `at` (`lookups.on_grid`) of colour(s) (r, g, b) in [0, 1]:
    the lattice nodes' `spectra` (`texel_spectra`) of the tetrahedron around the colour, weighted so that they
    sum to the colour (module docstring of `texel_spectra`)."""
    ir, fr = _lattice(r)
    ig, fg = _lattice(g)
    ib, fb = _lattice(b)
    strides = (RGB_LATTICE * RGB_LATTICE, RGB_LATTICE, 1)
    base = ir * strides[0] + ig * strides[1] + ib
    high = np.maximum(np.maximum(fr, fg), fb)
    low = np.minimum(np.minimum(fr, fg), fb)
    r_high = (fr >= fg) & (fr >= fb)
    step_high = select(r_high, strides[0], select(fg >= fb, strides[1], strides[2]))
    b_low = (fb <= fg) & (fb <= fr)
    step_low = select(b_low, strides[2], select(fg <= fr, strides[1], strides[0]))
    middle = fr + fg + fb - high - low
    step_middle = strides[0] + strides[1] + strides[2] - step_high - step_low
    return ((1.0 - high) * table_at(spectra, base, at) + (high - middle) * table_at(spectra, base + step_high, at)
            + (middle - low) * table_at(spectra, base + step_high + step_middle, at)
            + low * table_at(spectra, base + strides[0] + strides[1] + strides[2], at))


@shared
def offset_point(px, py, pz, nx, ny, nz):
    """Point(s) on a surface moved off it along the unit normal (nx, ny, nz) by SURFACE_OFFSET relative to
    their size, where rays leaving the surface on that side start (and do not find it again)."""
    scale = SURFACE_OFFSET * (1.0 + np.maximum(np.maximum(absolute(px), absolute(py)), absolute(pz)))
    return px + scale * nx, py + scale * ny, pz + scale * nz


@shared
def lambert_pdf(cos_theta):
    """The pdf (per solid angle) of a cosine-weighted direction at cos θ to the normal: cos θ / π, 0 below."""
    return np.maximum(cos_theta, 0.0) * INV_PI


@shared
def lambert_sample_cos(u):
    """cos θ of a cosine-weighted direction for a uniform u (the azimuth is uniform: `phase.sample_direction`)."""
    return sqrt(u)


@shared_inline
def emitter_point(ks, light, u1, u2):
    """A point (qx, qy, qz) of emissive surface light `light` (LIGHT_MESH) for uniforms u1, u2, uniform over its
    area (a triangle drawn by area, `u1`'s position in its bin and `u2` placing the point in it), with its
    triangle's unit normal (nx, ny, nz)."""
    s = ks.surfaces.of_light[light]
    offset = ks.surfaces.emitter_offset[s]
    bin_, position = cdf_bin(ks.surfaces.emitter_cdf, offset, ks.surfaces.emitter_count[s], u1)
    k = ks.surfaces.emitter_triangle[offset + bin_]
    root = sqrt(position)
    b1, b2 = root * (1.0 - u2), root * u2
    corner, edge1, edge2, normal = ks.surfaces.corner, ks.surfaces.edge1, ks.surfaces.edge2, ks.surfaces.normal
    return (corner[k, 0] + b1 * edge1[k, 0] + b2 * edge2[k, 0], corner[k, 1] + b1 * edge1[k, 1] + b2 * edge2[k, 1],
            corner[k, 2] + b1 * edge1[k, 2] + b2 * edge2[k, 2], normal[k, 0], normal[k, 1], normal[k, 2])


@shared
def emitter_pdf(area, distance, cos_light):
    """The solid-angle pdf of a point drawn uniformly over an emitter of `area`, at `distance` and at |cos θ|
    `cos_light` to its normal: d² / (A |cos θ|) (inf edge-on: such a point adds nothing)."""
    return distance * distance / (area * cos_light)
