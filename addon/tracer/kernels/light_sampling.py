"""Lights at a point: the choice of a light for next-event estimation by its selection pmf
(`KernelScene.lights.pmf`), a direction sampled towards it with its pdf and the radiance arriving along it,
the radiance and sampling pdf of the infinite lights along a direction that a path escapes in, and where a ray
meets an area light's emitting face with the pdf the sampler gives that direction (`area_light_hit`).

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend (points and directions as components x, y, z; wavelengths located by
`lookups.on_grid`, a direction's components then being columns (paths, 1) against (paths, wavelengths)).
They branch on a light's own parameters, never on a path's values. Part of the kernel cache's key
(`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..phase import INV_FOUR_PI, sample_direction
from ..shared_math import absolute, copysign, select, shared, shared_inline, sqrt
from .envmap import envmap_pdf, envmap_radiance, envmap_sample
from .layout import (
    AREA_ELLIPSE, LIGHT_AREA, LIGHT_ENVIRONMENT, LIGHT_ENVMAP, LIGHT_MESH, LIGHT_POINT, LIGHT_SKY, LIGHT_SPOT,
    LIGHT_SUN)
from .lookups import table_at
from .surfaces import emitter_pdf, emitter_point

# The solid angles within which a rectangle light is sampled by solid angle (pbrt-v4's bounds): a smaller one
# is the sum of four angles less 2π, lost to rounding; a larger one, close to the light, loses precision too.
SOLID_ANGLE_SAMPLED = (3e-4, 6.22)
ONE_BELOW = np.nextafter(1.0, 0.0)  # the largest float64 below 1


@shared
def choose_light(pmf, u):
    """The light drawn from the selection pmf with a uniform u (walking the pmf: the first light whose
    cumulative probability exceeds u, the last one for u beyond all)."""
    chosen = np.int64(u * 0.0)
    for light in range(pmf.shape[0] - 1):
        further = (chosen == light) & (u >= pmf[light])
        u = u - pmf[light] * further
        chosen = chosen + further
    return chosen


@shared_inline
def is_delta(ks, light):
    """Whether the light is a delta light (a sun of no angle, a point, a spot): sampled, never hit, so no MIS
    weighs its samples. Area lights and emissive surfaces are not: paths hit them."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_SUN:
        return ks.lights.cos[light] >= 1.0
    return kind == LIGHT_POINT or kind == LIGHT_SPOT


@shared_inline
def sun_solid_angle(ks, light):
    """Solid angle 2π(1 − cos θ) of a finite sun's cone."""
    return 2.0 * np.pi * (1.0 - ks.lights.cos[light])


@shared_inline
def in_sun_cone(ks, light, dx, dy, dz):
    """Whether direction(s) (dx, dy, dz) lie in the sun's cone."""
    to_sun = ks.lights.dir[light]
    return dx * to_sun[0] + dy * to_sun[1] + dz * to_sun[2] >= ks.lights.cos[light]


@shared_inline
def infinite_radiance(ks, light, at, dx, dy, dz):
    """Radiance of a non-delta infinite light along direction(s) (dx, dy, dz) at the wavelengths located
    by `at` (0 for other lights): an environment's spectrum; a sky's zenith and horizon spectra blended by
    the direction's elevation sine; an envmap's texel (`envmap.envmap_radiance`); a finite sun's spectrum (its
    irradiance) over π sin²θ in its cone."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_ENVIRONMENT:
        return table_at(ks.lights.spd, light, at)
    if kind == LIGHT_ENVMAP:
        return envmap_radiance(ks, light, at, dx, dy, dz)
    if kind == LIGHT_SKY:
        t = np.minimum(np.maximum(dz, 0.0), 1.0)
        return t * table_at(ks.lights.spd, light, at) + (1.0 - t) * table_at(ks.lights.spd_horizon, light, at)
    if kind == LIGHT_SUN and ks.lights.cos[light] < 1.0:
        sin2 = 1.0 - ks.lights.cos[light] ** 2
        return table_at(ks.lights.spd, light, at) * in_sun_cone(ks, light, dx, dy, dz) / (np.pi * sin2)
    return 0.0


@shared_inline
def infinite_pdf(ks, light, dx, dy, dz):
    """Solid-angle pdf of `sample_light` drawing direction(s) (dx, dy, dz) of a non-delta infinite light
    (0 for other lights)."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_ENVIRONMENT or kind == LIGHT_SKY:
        return INV_FOUR_PI
    if kind == LIGHT_ENVMAP:
        return envmap_pdf(ks, light, dx, dy, dz)
    if kind == LIGHT_SUN and ks.lights.cos[light] < 1.0:
        return in_sun_cone(ks, light, dx, dy, dz) / sun_solid_angle(ks, light)
    return 0.0


@shared_inline
def uniform_area_point(ks, light, u1, u2):
    """A point (qx, qy, qz) of an area light for uniforms u1, u2, uniform over its area: over the rectangle,
    or over the ellipse in polar coordinates (radius √u1 of its half-axes, angle 2π u2)."""
    if ks.lights.area_shape[light] == AREA_ELLIPSE:
        radius, angle = sqrt(u1), 2.0 * np.pi * u2
        a, b = radius * np.cos(angle), radius * np.sin(angle)
    else:
        a, b = 2.0 * u1 - 1.0, 2.0 * u2 - 1.0
    centre, span = ks.lights.pos[light], ks.lights.area_span[light]
    return (centre[0] + a * span[0, 0] + b * span[1, 0], centre[1] + a * span[0, 1] + b * span[1, 1],
            centre[2] + a * span[0, 2] + b * span[1, 2])


@shared_inline
def _angle(cosine):
    """The angle of a cosine, clamped to [−1, 1] against rounding."""
    return np.arccos(np.minimum(np.maximum(cosine, -1.0), 1.0))


@shared_inline
def _rectangle_frame(ks, light, px, py, pz):
    """A rectangle light seen from point(s) (px, py, pz): its unit axes ex, ey, ez = ex × ey (9 components),
    and in that frame with origin p its corners' coordinates x0 < x1, y0 < y1 and its plane's z."""
    span, centre = ks.lights.area_span[light], ks.lights.pos[light]
    half_x = sqrt(span[0, 0] * span[0, 0] + span[0, 1] * span[0, 1] + span[0, 2] * span[0, 2])
    half_y = sqrt(span[1, 0] * span[1, 0] + span[1, 1] * span[1, 1] + span[1, 2] * span[1, 2])
    exx, exy, exz = span[0, 0] / half_x, span[0, 1] / half_x, span[0, 2] / half_x
    eyx, eyy, eyz = span[1, 0] / half_y, span[1, 1] / half_y, span[1, 2] / half_y
    ezx, ezy, ezz = exy * eyz - exz * eyy, exz * eyx - exx * eyz, exx * eyy - exy * eyx
    cx = centre[0] - span[0, 0] - span[1, 0] - px
    cy = centre[1] - span[0, 1] - span[1, 1] - py
    cz = centre[2] - span[0, 2] - span[1, 2] - pz
    x0, y0, z = cx * exx + cy * exy + cz * exz, cx * eyx + cy * eyy + cz * eyz, cx * ezx + cy * ezy + cz * ezz
    return (exx, exy, exz, eyx, eyy, eyz, ezx, ezy, ezz, x0, y0, x0 + 2.0 * half_x, y0 + 2.0 * half_y, z)


@shared_inline
def _rectangle_angles(x0, y0, x1, y1, z0):
    """The z components of the normals of the planes through the origin and each edge of the rectangle with
    corners (x0 or x1, y0 or y1, z0), z0 ≤ 0 (the others cancel in the products), two of its angles on the
    sphere between consecutive planes (g2, g3), and its solid angle, the sum of the four angles less 2π."""
    n0z, n1z = -y0 / sqrt(z0 * z0 + y0 * y0), x1 / sqrt(z0 * z0 + x1 * x1)
    n2z, n3z = y1 / sqrt(z0 * z0 + y1 * y1), -x0 / sqrt(z0 * z0 + x0 * x0)
    g0, g1, g2, g3 = _angle(-n0z * n1z), _angle(-n1z * n2z), _angle(-n2z * n3z), _angle(-n3z * n0z)
    return n0z, n2z, g2, g3, g0 + g1 + g2 + g3 - 2.0 * np.pi


@shared_inline
def rectangle_solid_angle(ks, light, px, py, pz):
    """The solid angle a rectangle light subtends from point(s) (px, py, pz)."""
    frame = _rectangle_frame(ks, light, px, py, pz)
    return _rectangle_angles(frame[9], frame[10], frame[11], frame[12], -absolute(frame[13]))[4]


@shared_inline
def spherical_rectangle_point(ks, light, px, py, pz, u1, u2):
    """A point (qx, qy, qz) of a rectangle light drawn uniformly in the solid angle it subtends from point(s)
    (px, py, pz) for uniforms u1, u2, and that solid angle (Ureña, Fajardo and King 2013, "An area-preserving
    parametrization for spherical rectangles", as pbrt-v4 writes it). In the rectangle's frame (its unit
    axes ex, ey and ez = ex × ey, origin at p) its corners are (x0 or x1, y0 or y1, z), and the algorithm
    works with z0 = −|z|."""
    exx, exy, exz, eyx, eyy, eyz, ezx, ezy, ezz, x0, y0, x1, y1, z = _rectangle_frame(ks, light, px, py, pz)
    z0 = -absolute(z)
    n0z, n2z, g2, g3, solid_angle = _rectangle_angles(x0, y0, x1, y1, z0)
    # x: invert the solid angle's cdf along the rectangle's x edge.
    au = u1 * solid_angle + (2.0 * np.pi - g2 - g3)
    fu = (np.cos(au) * n0z - n2z) / np.sin(au)
    cu = np.minimum(np.maximum(copysign(1.0 / sqrt(fu * fu + n0z * n0z), fu), -ONE_BELOW), ONE_BELOW)
    xu = np.minimum(np.maximum(-cu * z0 / sqrt(1.0 - cu * cu), x0), x1)
    # y: uniform in the sine of the elevation along the column at xu.
    d = sqrt(xu * xu + z0 * z0)
    h0, h1 = y0 / sqrt(d * d + y0 * y0), y1 / sqrt(d * d + y1 * y1)
    hv = h0 + u2 * (h1 - h0)
    yv = np.minimum(np.maximum(hv * d / sqrt(np.maximum(1.0 - hv * hv, 0.0)), y0), y1)
    return (px + xu * exx + yv * eyx + z * ezx, py + xu * exy + yv * eyy + z * ezy,
            pz + xu * exz + yv * eyz + z * ezz, solid_angle)


@shared_inline
def area_light_area(ks, light):
    """An area light's area: 4 |X| |Y| for a rectangle of half-axes X, Y (`area_span`), π |X| |Y| for an
    ellipse."""
    span = ks.lights.area_span[light]
    product = sqrt((span[0, 0] * span[0, 0] + span[0, 1] * span[0, 1] + span[0, 2] * span[0, 2])
                      * (span[1, 0] * span[1, 0] + span[1, 1] * span[1, 1] + span[1, 2] * span[1, 2]))
    if ks.lights.area_shape[light] == AREA_ELLIPSE:
        return np.pi * product
    return 4.0 * product


@shared_inline
def _by_solid_angle(solid_angle):
    """Whether a rectangle subtending `solid_angle` is sampled in it (within SOLID_ANGLE_SAMPLED), not over its
    area."""
    return (solid_angle >= SOLID_ANGLE_SAMPLED[0]) & (solid_angle <= SOLID_ANGLE_SAMPLED[1])


@shared_inline
def _sampled_pdf(ks, light, solid_angle, distance, cos_light):
    """The solid-angle pdf of a direction to a point of an area light at `distance` whose emitting normal makes
    cosine `cos_light` with the way back, drawn uniformly in `solid_angle` Ω (1/Ω), or over the area A where
    that is 0 (d² / (A cos θ); 0 behind the light or in its plane)."""
    over_area = select(cos_light > 0.0, distance * distance / (area_light_area(ks, light) * cos_light), 0.0)
    return select(solid_angle > 0.0, 1.0 / select(solid_angle > 0.0, solid_angle, 1.0), over_area)


@shared_inline
def area_direction_pdf(ks, light, px, py, pz, distance, cos_light):
    """The solid-angle pdf with which `sample_light` draws, from point(s) (px, py, pz), the direction to a point
    of an area light at `distance` whose emitting normal makes cosine `cos_light` with the way back: 1/Ω for a
    rectangle it samples in its solid angle Ω (`area_point`), else over the area."""
    solid_angle = 0.0 * distance
    if ks.lights.area_shape[light] != AREA_ELLIPSE:
        solid_angle = rectangle_solid_angle(ks, light, px, py, pz)
        solid_angle = select(_by_solid_angle(solid_angle), solid_angle, 0.0)
    return _sampled_pdf(ks, light, solid_angle, distance, cos_light)


@shared_inline
def area_light_hit(ks, light, ox, oy, oz, dx, dy, dz, t_max):
    """Where the ray(s) o + t d (d a unit vector) meet the emitting face of area light `light` (one facing back
    along the ray, so the light emits towards o) with 0 < t < t_max: t, or inf where it does not. Behind the
    light, in its plane and beyond its edge the ray passes by: a light is no obstacle."""
    normal, centre, span = ks.lights.dir[light], ks.lights.pos[light], ks.lights.area_span[light]
    facing = -(dx * normal[0] + dy * normal[1] + dz * normal[2])
    height = (ox - centre[0]) * normal[0] + (oy - centre[1]) * normal[1] + (oz - centre[2]) * normal[2]
    t = select(facing > 0.0, height / select(facing > 0.0, facing, 1.0), -1.0)
    rx, ry, rz = ox + t * dx - centre[0], oy + t * dy - centre[1], oz + t * dz - centre[2]
    a = (rx * span[0, 0] + ry * span[0, 1] + rz * span[0, 2]) / (
        span[0, 0] * span[0, 0] + span[0, 1] * span[0, 1] + span[0, 2] * span[0, 2])
    b = (rx * span[1, 0] + ry * span[1, 1] + rz * span[1, 2]) / (
        span[1, 0] * span[1, 0] + span[1, 1] * span[1, 1] + span[1, 2] * span[1, 2])
    if ks.lights.area_shape[light] == AREA_ELLIPSE:
        inside = a * a + b * b <= 1.0
    else:
        inside = (absolute(a) <= 1.0) & (absolute(b) <= 1.0)
    return select(inside & (t > 0.0) & (t < t_max), t, np.inf)


@shared_inline
def area_radiance(ks, light, at):
    """An area light's radiance on its emitting side at the wavelengths located by `at`: its spectrum (its
    intensity along its normal, P/π) over its area."""
    return table_at(ks.lights.spd, light, at) / area_light_area(ks, light)


@shared_inline
def area_point(ks, light, px, py, pz, u1, u2):
    """A point (qx, qy, qz) of an area light seen from point(s) (px, py, pz), drawn for uniforms u1, u2, with
    the solid angle it was drawn uniformly in (`spherical_rectangle_point`: a rectangle subtending a solid
    angle within SOLID_ANGLE_SAMPLED), or 0 where it was drawn uniformly over the area (`uniform_area_point`:
    an ellipse, and a rectangle outside those bounds)."""
    qx, qy, qz = uniform_area_point(ks, light, u1, u2)
    if ks.lights.area_shape[light] == AREA_ELLIPSE:
        return qx, qy, qz, 0.0 * u1
    sx, sy, sz, solid_angle = spherical_rectangle_point(ks, light, px, py, pz, u1, u2)
    by_solid_angle = _by_solid_angle(solid_angle)
    return (select(by_solid_angle, sx, qx), select(by_solid_angle, sy, qy), select(by_solid_angle, sz, qz),
            select(by_solid_angle, solid_angle, 0.0))


@shared_inline
def sample_light(ks, light, px, py, pz, u1, u2):
    """A direction (wx, wy, wz) from point(s) (px, py, pz) towards the light for uniforms u1, u2: uniform in
    a finite sun's cone or over the sphere for an environment or a sky, texel by texel for an envmap
    (`envmap.envmap_sample`), towards a point of an area light
    (`area_point`). Returns it with its solid-angle pdf (1 for a delta light; for an area light
    `area_direction_pdf`), the distance to the light (inf for suns and the sphere) and the falloff of a point
    or spot light: 1/d², times a spot's cone (smoothed over its blend). An area light's spectrum is its
    intensity P/π along its normal, its radiance L = P/(πA) times its area A, so its falloff is 1/A on its
    emitting side (0 behind it): radiance over pdf is then L Ω for a point drawn uniformly in the solid angle
    Ω, L A cos θ / d² for one drawn with pdf 1/A over the area, θ the angle from the light's emitting
    normal."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_SUN:
        to_sun = ks.lights.dir[light]
        if ks.lights.cos[light] >= 1.0:
            return to_sun[0], to_sun[1], to_sun[2], 1.0, np.inf, 1.0
        cos_theta = 1.0 - u1 * (1.0 - ks.lights.cos[light])
        wx, wy, wz = sample_direction((to_sun[0], to_sun[1], to_sun[2]), cos_theta, u2)
        return wx, wy, wz, 1.0 / sun_solid_angle(ks, light), np.inf, 1.0
    if kind == LIGHT_ENVIRONMENT or kind == LIGHT_SKY:
        wz = 1.0 - 2.0 * u1
        r = sqrt(np.maximum(0.0, 1.0 - wz * wz))
        return r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2), wz, INV_FOUR_PI, np.inf, 1.0
    if kind == LIGHT_ENVMAP:
        wx, wy, wz, direction_pdf = envmap_sample(ks, light, u1, u2)
        return wx, wy, wz, direction_pdf, np.inf, 1.0
    if kind == LIGHT_MESH:
        qx, qy, qz, nx, ny, nz = emitter_point(ks, light, u1, u2)
        vx, vy, vz = qx - px, qy - py, qz - pz
        distance = sqrt(vx * vx + vy * vy + vz * vz)
        wx, wy, wz = vx / distance, vy / distance, vz / distance
        cos_light = absolute(wx * nx + wy * ny + wz * nz)
        area = ks.surfaces.area[ks.surfaces.of_light[light]]
        return wx, wy, wz, emitter_pdf(area, distance, cos_light), distance, 1.0
    position = ks.lights.pos[light]
    qx, qy, qz, solid_angle = position[0], position[1], position[2], 0.0
    if kind == LIGHT_AREA:
        qx, qy, qz, solid_angle = area_point(ks, light, px, py, pz, u1, u2)
    vx, vy, vz = qx - px, qy - py, qz - pz
    distance = sqrt(vx * vx + vy * vy + vz * vz)
    wx, wy, wz = vx / distance, vy / distance, vz / distance
    falloff = 1.0 / (distance * distance)
    if kind == LIGHT_SPOT:
        axis = ks.lights.dir[light]
        cos_angle = -(wx * axis[0] + wy * axis[1] + wz * axis[2])
        smooth = ks.lights.smooth[light]
        if smooth > 0.0:
            t = np.minimum(np.maximum((cos_angle - ks.lights.cos[light]) / smooth, 0.0), 1.0)
            falloff = falloff * (t * t * (3.0 - 2.0 * t))
        else:
            falloff = falloff * (cos_angle >= ks.lights.cos[light])
    if kind == LIGHT_AREA:
        normal = ks.lights.dir[light]
        cos_light = -(wx * normal[0] + wy * normal[1] + wz * normal[2])
        return (wx, wy, wz, _sampled_pdf(ks, light, solid_angle, distance, cos_light), distance,
                (cos_light > 0.0) / area_light_area(ks, light))
    return wx, wy, wz, 1.0, distance, falloff


@shared_inline
def incident_radiance(ks, light, at, wx, wy, wz, falloff):
    """Radiance arriving along a direction that `sample_light` drew, at the wavelengths located by `at`: a
    delta or area light's spectrum (irradiance, intensity) times the sample's falloff, an emissive
    surface's radiance (the same on both sides), else `infinite_radiance`."""
    if is_delta(ks, light) or ks.lights.kind[light] == LIGHT_AREA:
        return table_at(ks.lights.spd, light, at) * falloff
    if ks.lights.kind[light] == LIGHT_MESH:
        return table_at(ks.lights.spd, light, at)
    return infinite_radiance(ks, light, at, wx, wy, wz)
