"""Surfaces at a point: a ray's distance to a triangle, the Lambertian reflector's cosine-weighted sampling and
pdf, the side of a triangle a ray arrives on, the point leaving a surface, and the emissive surfaces' points
and pdfs for next-event estimation.

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel (which
walks the triangles' hierarchy), arrays of paths (and of triangles, for the NumPy backend's brute-force
intersection) in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).

A Lambertian surface of albedo ρ(λ) has the BRDF ρ/π: light arriving along a direction at cos θ to the
normal on the side the path is on reflects ρ cos θ / π of its radiance per unit solid angle, and none
through (the surface is opaque, and both of its sides reflect). Directions are drawn with pdf cos θ / π,
so a sampled direction's throughput is ρ, the same pdf at every wavelength.
"""

import numpy as np

from ..shared_math import absolute, select, shared, shared_inline, sqrt
from .layout import SURFACE_OFFSET
from .lookups import cdf_bin

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
