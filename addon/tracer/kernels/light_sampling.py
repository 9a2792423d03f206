"""Lights at a point: the choice of a light for next-event estimation by its selection pmf
(`KernelScene.lights.pmf`), a direction sampled towards it with its pdf and the radiance arriving along it,
and the radiance and sampling pdf of the infinite lights along a direction that a path escapes in.

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend (points and directions as components x, y, z; wavelengths located by
`lookups.on_grid`, a direction's components then being columns (paths, 1) against (paths, wavelengths)).
They branch on a light's own parameters, never on a path's values. Part of the kernel cache's key
(`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..phase import INV_FOUR_PI, sample_direction
from ..shared_math import shared, shared_inline
from .layout import AREA_ELLIPSE, LIGHT_AREA, LIGHT_ENVIRONMENT, LIGHT_SKY, LIGHT_SPOT, LIGHT_SUN
from .lookups import table_at


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
    """Whether the light is a delta light (a sun of no angle, a point, a spot), or an area light, which is
    treated as one: sampled, never hit (paths do not see its surface, so no MIS weighs its samples)."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_SUN:
        return ks.lights.cos[light] >= 1.0
    return kind != LIGHT_ENVIRONMENT and kind != LIGHT_SKY


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
    the direction's elevation sine; a finite sun's spectrum (its irradiance) over π sin²θ in its cone."""
    kind = ks.lights.kind[light]
    if kind == LIGHT_ENVIRONMENT:
        return table_at(ks.lights.spd, light, at)
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
    if kind == LIGHT_SUN and ks.lights.cos[light] < 1.0:
        return in_sun_cone(ks, light, dx, dy, dz) / sun_solid_angle(ks, light)
    return 0.0


@shared_inline
def area_point(ks, light, u1, u2):
    """A point (qx, qy, qz) of an area light for uniforms u1, u2, uniform over its area: over the rectangle,
    or over the ellipse in polar coordinates (radius √u1 of its half-axes, angle 2π u2)."""
    if ks.lights.area_shape[light] == AREA_ELLIPSE:
        radius, angle = np.sqrt(u1), 2.0 * np.pi * u2
        a, b = radius * np.cos(angle), radius * np.sin(angle)
    else:
        a, b = 2.0 * u1 - 1.0, 2.0 * u2 - 1.0
    centre, span = ks.lights.pos[light], ks.lights.area_span[light]
    return (centre[0] + a * span[0, 0] + b * span[1, 0], centre[1] + a * span[0, 1] + b * span[1, 1],
            centre[2] + a * span[0, 2] + b * span[1, 2])


@shared_inline
def sample_light(ks, light, px, py, pz, u1, u2):
    """A direction (wx, wy, wz) from point(s) (px, py, pz) towards the light for uniforms u1, u2: uniform in
    a finite sun's cone or over the sphere for an environment or a sky, towards a point of an area light
    drawn uniformly over its area (`area_point`). Returns it with its solid-angle pdf (1 for a delta light
    and an area light), the distance to the light (inf for suns and the sphere) and the falloff of a point
    or spot light: 1/d², times a spot's cone (smoothed over its blend); of an area light, cos θ / d² with θ
    the angle from its emitting side's normal (0 behind it): its spectrum is its intensity P/π along the
    normal, so radiance P/(πA) · cos θ / d² over the pdf 1/A of the point is the estimate."""
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
        r = np.sqrt(np.maximum(0.0, 1.0 - wz * wz))
        return r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2), wz, INV_FOUR_PI, np.inf, 1.0
    position = ks.lights.pos[light]
    qx, qy, qz = position[0], position[1], position[2]
    if kind == LIGHT_AREA:
        qx, qy, qz = area_point(ks, light, u1, u2)
    vx, vy, vz = qx - px, qy - py, qz - pz
    distance = np.sqrt(vx * vx + vy * vy + vz * vz)
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
        falloff = falloff * np.maximum(-(wx * normal[0] + wy * normal[1] + wz * normal[2]), 0.0)
    return wx, wy, wz, 1.0, distance, falloff


@shared_inline
def incident_radiance(ks, light, at, wx, wy, wz, falloff):
    """Radiance arriving along a direction that `sample_light` drew, at the wavelengths located by `at`: a
    delta or area light's spectrum (irradiance or intensity) times the sample's falloff, else
    `infinite_radiance`."""
    if is_delta(ks, light):
        return table_at(ks.lights.spd, light, at) * falloff
    return infinite_radiance(ks, light, at, wx, wy, wz)
