"""Numba backend: the spectral null-scattering volume path tracer, one path at a time per thread.

Algorithm (shared with `numpy_backend`; see docs/algorithm.md):
- Each path carries up to four wavelengths: a hero λ₀ drawn from the band's distribution and three
  companions at u + i/4 (stratified inverse CDF). All of them follow the hero's path; spectral MIS
  (balance heuristic over the wavelengths' path pdfs, tracked as pdf ratios `r_u`, `r_l` relative to
  the hero, as in the null-scattering path integral of Miller et al. 2019) keeps chromatic
  extinction, albedo and anisotropy unbiased.
- Free flight by delta tracking against a wavelength-independent majorant σ̄ read from each medium's
  majorant grid (a DDA over coarse blocks); at a tentative collision the hero picks a real collision
  (scattering weighted by the albedo), fluorescent in-scattering or a null collision in proportion
  to its coefficients.
- Fluorescence is traced backwards: the camera wavelength λ_out switches to an excitation wavelength
  λ_in drawn ∝ excitation(λ_in); only the hero continues (companions are dropped, their MIS share
  goes to the hero).
- Next-event estimation at every real scattering vertex with ratio-tracked transmittance, combined
  with phase sampling by MIS for environment and finite suns.
- Thermal emission σ_a·Planck(T) is collected at every tentative collision.
"""

import functools
import math

import numpy as np
from numba import njit, prange

from ..binned import pdf_binned, sample_binned
from ..phase import hg_pdf, hg_sample_cos, rayleigh_pdf, rayleigh_sample_cos, sample_direction
from ..planck import planck_radiance
from .layout import (
    LIGHT_ENVIRONMENT,
    LIGHT_SKY,
    LIGHT_SPOT,
    LIGHT_SUN,
    MAX_WAVELENGTHS_PER_PATH,
    PHASE_RAYLEIGH,
    SHADOW_ROULETTE_BELOW,
    SHADOW_ROULETTE_STOP,
)
from .numba_cache import cached
from .rng import LOW_DISCREPANCY_DIMENSIONS, low_discrepancy, path_key, pixel_key, uniform

# Every kernel function divides as NumPy does (x/0 gives inf or nan, like the NumPy backend) instead of
# Python's model, which checks every divisor for zero to raise ZeroDivisionError: the images are
# identical and the kernel is 1.3–1.4× faster (bench/README.md).
jit = functools.partial(njit, error_model="numpy")

MAX_LAMBDAS = MAX_WAVELENGTHS_PER_PATH
INF = np.inf
EVENT_ESCAPE, EVENT_SCATTER, EVENT_FLUORESCE, EVENT_ABSORB = 0, 1, 2, 3
# Rows of the per-path spectral cache spec[medium, row, wavelength] (filled when wavelengths change).
SPEC_EXTINCTION, SPEC_EXCITATION, SPEC_EMISSION_PDF, SPEC_ANISOTROPY, SPEC_ALBEDO = 0, 1, 2, 3, 4
SPEC_ROWS = 5


# ----------------------------------------------------------------------------- small helpers

@jit(inline="always")
def _next(stream):
    """Next uniform number of the path's stream (stream = path key, counter, pixel key, sample; `rng`)."""
    counter = stream[1]
    if counter < LOW_DISCREPANCY_DIMENSIONS:
        value = low_discrepancy(stream[2], stream[3], counter)
    else:
        value = uniform(stream[0], counter)
    stream[1] += np.uint64(1)
    return value


@jit(inline="always")
def _table(row, lam):
    """Linear interpolation of a per-nanometre table at wavelength `lam` (0 outside the grid)."""
    position = lam - 250.0
    if position < 0.0 or position > row.shape[0] - 1:
        return 0.0
    index = min(int(position), row.shape[0] - 2)
    frac = position - index
    return row[index] * (1.0 - frac) + row[index + 1] * frac


@jit(inline="always")
def _transform_point(m, x, y, z):
    return (m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + m[0, 3],
            m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + m[1, 3],
            m[2, 0] * x + m[2, 1] * y + m[2, 2] * z + m[2, 3])


@jit(inline="always")
def _transform_vector(m, x, y, z):
    return (m[0, 0] * x + m[0, 1] * y + m[0, 2] * z,
            m[1, 0] * x + m[1, 1] * y + m[1, 2] * z,
            m[2, 0] * x + m[2, 1] * y + m[2, 2] * z)


@jit(inline="always")
def _normalize(x, y, z):
    inv = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv


@jit(inline="always")
def _mean(values, n):
    total = 0.0
    for i in range(n):
        total += values[i]
    return total / n


# ----------------------------------------------------------------------------- volume look-ups

@jit(inline="always")
def _trilinear(data, offset, nx, ny, nz, x, y, z):
    """Trilinear interpolation of cell-centre samples at index-space point (x, y, z), zero outside."""
    fx, fy, fz = math.floor(x), math.floor(y), math.floor(z)
    ix, iy, iz = int(fx), int(fy), int(fz)
    tx, ty, tz = x - fx, y - fy, z - fz
    total = 0.0
    for corner in range(8):
        cx = ix + (corner & 1)
        cy = iy + ((corner >> 1) & 1)
        cz = iz + ((corner >> 2) & 1)
        if cx < 0 or cy < 0 or cz < 0 or cx >= nx or cy >= ny or cz >= nz:
            continue
        wx = tx if corner & 1 else 1.0 - tx
        wy = ty if (corner >> 1) & 1 else 1.0 - ty
        wz = tz if (corner >> 2) & 1 else 1.0 - tz
        total += wx * wy * wz * data[offset + (cx * ny + cy) * nz + cz]
    return total


@jit(inline="always")
def _density(ks, m, px, py, pz):
    qx, qy, qz = _transform_point(ks.world_to_padded[m], px, py, pz)
    shape = ks.density_shape[m]
    return _trilinear(ks.density_data, ks.density_offset[m], shape[0], shape[1], shape[2],
                      qx - 1.0, qy - 1.0, qz - 1.0)


@jit(inline="always")
def _temperature(ks, m, px, py, pz):
    qx, qy, qz = _transform_point(ks.temperature_world_to_padded[m], px, py, pz)
    shape = ks.temperature_shape[m]
    raw = _trilinear(ks.temperature_data, ks.temperature_offset[m], shape[0], shape[1], shape[2],
                     qx - 1.0, qy - 1.0, qz - 1.0)
    return raw * ks.temperature_map[m, 0] + ks.temperature_map[m, 1]


@jit(inline="always")
def _albedo(ks, m, density, lam):
    count = ks.albedo_count[m]
    levels = ks.albedo_densities[m]
    if count == 1 or density <= levels[0]:
        return _table(ks.albedo_table[m, 0], lam)
    if density >= levels[count - 1]:
        return _table(ks.albedo_table[m, count - 1], lam)
    upper = 1
    while levels[upper] < density:
        upper += 1
    t = (density - levels[upper - 1]) / (levels[upper] - levels[upper - 1])
    return (1.0 - t) * _table(ks.albedo_table[m, upper - 1], lam) + t * _table(ks.albedo_table[m, upper], lam)


@jit(inline="always")
def _fill_spectral_cache(ks, lams, n, spec):
    """Tabulated spectra of every medium at the path's current wavelengths (looked up once per path
    and after a fluorescent wavelength change, instead of at every collision)."""
    for m in range(ks.density_scale.shape[0]):
        for i in range(n):
            lam = lams[i]
            spec[m, SPEC_EXTINCTION, i] = _table(ks.extinction[m], lam)
            spec[m, SPEC_EXCITATION, i] = _table(ks.excitation[m], lam)
            spec[m, SPEC_EMISSION_PDF, i] = _table(ks.emission_pdf[m], lam)
            spec[m, SPEC_ANISOTROPY, i] = _table(ks.anisotropy[m], lam)
            spec[m, SPEC_ALBEDO, i] = _table(ks.albedo_table[m, 0], lam)


@jit(inline="always")
def _coefficients(ks, px, py, pz, lams, spec, n, sigma_a, sigma_s, sigma_fl, emission, medium_s, medium_fl):
    """Medium coefficients at a point for each path wavelength (summed over media), per-medium
    scattering / fluorescence coefficients (for choosing which medium scatters), and emission."""
    for i in range(n):
        sigma_a[i] = 0.0
        sigma_s[i] = 0.0
        sigma_fl[i] = 0.0
        emission[i] = 0.0
    for m in range(ks.density_scale.shape[0]):
        rho = _density(ks, m, px, py, pz) * ks.density_scale[m]
        temperature = _temperature(ks, m, px, py, pz) if ks.temperature_offset[m] >= 0 and rho > 0 else 0.0
        for i in range(n):
            if rho <= 0.0:
                medium_s[m, i] = 0.0
                medium_fl[m, i] = 0.0
                continue
            sigma_t = rho * spec[m, SPEC_EXTINCTION, i]
            albedo = (spec[m, SPEC_ALBEDO, i] if ks.albedo_count[m] == 1
                      else _albedo(ks, m, rho / ks.density_scale[m], lams[i]))
            scattering = sigma_t * albedo
            plain_absorption = sigma_t - scattering
            medium_s[m, i] = scattering
            medium_fl[m, i] = rho * ks.fluor_strength[m] * spec[m, SPEC_EMISSION_PDF, i]
            sigma_s[i] += scattering
            sigma_a[i] += plain_absorption + rho * spec[m, SPEC_EXCITATION, i]
            sigma_fl[i] += medium_fl[m, i]
            if temperature > 0.0:
                emission[i] += plain_absorption * ks.temperature_map[m, 2] * planck_radiance(lams[i], temperature)


# ----------------------------------------------------------------------------- majorant tracking

@jit(inline="always")
def _tracker_start(ks, ox, oy, oz, dx, dy, dz, t_min, t_max, state_i, state_f):
    """Initialise one DDA per medium over its majorant blocks, in padded index space.

    state_i[m] = (phase 0 before entry / 1 inside / 2 done, cell x, y, z, step x, y, z)
    state_f[m] = (t_entry, t_exit, t_next x, y, z, t_delta x, y, z, local o x, y, z, local d x, y, z)
    """
    for m in range(ks.density_scale.shape[0]):
        w2p = ks.world_to_padded[m]
        lox, loy, loz = _transform_point(w2p, ox, oy, oz)
        ldx, ldy, ldz = _transform_vector(w2p, dx, dy, dz)
        block = ks.majorant_block[m]
        shape = ks.majorant_shape[m]
        t0, t1 = t_min, t_max
        for axis in range(3):
            o = lox if axis == 0 else (loy if axis == 1 else loz)
            d = ldx if axis == 0 else (ldy if axis == 1 else ldz)
            upper = shape[axis] * block
            if d == 0.0:
                if o < 0.0 or o >= upper:
                    t1 = -1.0
                continue
            ta, tb = (0.0 - o) / d, (upper - o) / d
            if ta > tb:
                ta, tb = tb, ta
            t0, t1 = max(t0, ta), min(t1, tb)
        state_i[m, 0] = 2 if t0 >= t1 else 0
        state_f[m, 0], state_f[m, 1] = t0, t1
        state_f[m, 11], state_f[m, 12], state_f[m, 13] = lox, loy, loz
        state_f[m, 14], state_f[m, 15], state_f[m, 16] = ldx, ldy, ldz


@jit(inline="always")
def _tracker_enter(ks, m, state_i, state_f):
    t = state_f[m, 0]
    block = ks.majorant_block[m]
    shape = ks.majorant_shape[m]
    for axis in range(3):
        o = state_f[m, 11 + axis]
        d = state_f[m, 14 + axis]
        q = o + t * d
        cell = min(max(int(math.floor(q / block)), 0), shape[axis] - 1)
        state_i[m, 1 + axis] = cell
        if d > 0.0:
            state_i[m, 4 + axis] = 1
            state_f[m, 2 + axis] = ((cell + 1) * block - o) / d
            state_f[m, 5 + axis] = block / d
        elif d < 0.0:
            state_i[m, 4 + axis] = -1
            state_f[m, 2 + axis] = (cell * block - o) / d
            state_f[m, 5 + axis] = -block / d
        else:
            state_i[m, 4 + axis] = 0
            state_f[m, 2 + axis] = INF
            state_f[m, 5 + axis] = INF
    state_i[m, 0] = 1


@jit(inline="always")
def _tracker_boundary(state_i, state_f, m):
    """The ray parameter where medium m's current majorant changes next."""
    phase = state_i[m, 0]
    if phase == 0:
        return state_f[m, 0]
    if phase == 1:
        return min(state_f[m, 1], state_f[m, 2], state_f[m, 3], state_f[m, 4])
    return INF


@jit(inline="always")
def _tracker_segment(ks, state_i, state_f):
    """(end of the current segment, combined majorant σ̄ on it)."""
    t_end = INF
    sigma = 0.0
    for m in range(ks.density_scale.shape[0]):
        t_end = min(t_end, _tracker_boundary(state_i, state_f, m))
        if state_i[m, 0] == 1:
            shape = ks.majorant_shape[m]
            index = (state_i[m, 1] * shape[1] + state_i[m, 2]) * shape[2] + state_i[m, 3]
            sigma += ks.majorant_data[ks.majorant_offset[m] + index] * ks.majorant_coeff[m]
    return t_end, sigma


@jit(inline="always")
def _tracker_advance(ks, state_i, state_f, t_end):
    """Move every medium whose boundary is at `t_end` into its next block (or out)."""
    for m in range(ks.density_scale.shape[0]):
        if _tracker_boundary(state_i, state_f, m) > t_end:
            continue
        if state_i[m, 0] == 0:
            _tracker_enter(ks, m, state_i, state_f)
            continue
        if state_f[m, 1] <= t_end:
            state_i[m, 0] = 2
            continue
        axis = 0
        if state_f[m, 3] < state_f[m, 2 + axis]:
            axis = 1
        if state_f[m, 4] < state_f[m, 2 + axis]:
            axis = 2
        state_i[m, 1 + axis] += state_i[m, 4 + axis]
        state_f[m, 2 + axis] += state_f[m, 5 + axis]
        cell = state_i[m, 1 + axis]
        if cell < 0 or cell >= ks.majorant_shape[m, axis]:
            state_i[m, 0] = 2


@jit(inline="always")
def _tentative_collision(ks, stream, state_i, state_f, t):
    """Delta tracking from ray parameter t: the next tentative collision (t, σ̄ there), or (INF, 0)
    when the ray leaves every medium (or passes the tracker's t_max)."""
    while True:
        t_end, sigma_bar = _tracker_segment(ks, state_i, state_f)
        if t_end == INF:
            return INF, 0.0
        if sigma_bar > 0.0:
            step = -math.log(1.0 - _next(stream)) / sigma_bar
            if t + step < t_end:
                return t + step, sigma_bar
        t = t_end
        _tracker_advance(ks, state_i, state_f, t_end)


# ----------------------------------------------------------------------------- phase functions

@jit(inline="always")
def _phase_pdf(ks, m, g, cos_theta):
    if ks.phase_kind[m] == PHASE_RAYLEIGH:
        return rayleigh_pdf(cos_theta)
    return hg_pdf(g, cos_theta)


@jit(inline="always")
def _mixture_phase(ks, medium_s, spec, n, cos_theta, out):
    """Phase pdf (= value) at each wavelength: the σ_s-weighted mixture of the media's phases."""
    for i in range(n):
        total = 0.0
        weighted = 0.0
        for m in range(ks.density_scale.shape[0]):
            if medium_s[m, i] > 0.0:
                total += medium_s[m, i]
                weighted += medium_s[m, i] * _phase_pdf(ks, m, spec[m, SPEC_ANISOTROPY, i], cos_theta)
        out[i] = weighted / total if total > 0.0 else 0.0


@jit(inline="always")
def _pick_medium(weights, i, u):
    total = 0.0
    for m in range(weights.shape[0]):
        total += weights[m, i]
    target = u * total
    for m in range(weights.shape[0]):
        target -= weights[m, i]
        if target < 0.0:
            return m
    return weights.shape[0] - 1


# ----------------------------------------------------------------------------- lights

@jit(inline="always")
def _sky_radiance(ks, light, lam, dz):
    t = min(max(dz, 0.0), 1.0)
    return t * _table(ks.light_spd[light], lam) + (1.0 - t) * _table(ks.light_spd_horizon[light], lam)


@jit(inline="always")
def _sun_solid_angle(ks, light):
    return 2.0 * math.pi * (1.0 - ks.light_cos[light])


@jit(inline="always")
def _infinite_radiance(ks, light, lam, dx, dy, dz):
    """Radiance of a non-delta infinite light seen along direction (dx, dy, dz) (0 for others)."""
    kind = ks.light_kind[light]
    if kind == LIGHT_ENVIRONMENT:
        return _table(ks.light_spd[light], lam)
    if kind == LIGHT_SKY:
        return _sky_radiance(ks, light, lam, dz)
    if kind == LIGHT_SUN and ks.light_cos[light] < 1.0:
        to_sun = ks.light_dir[light]
        if dx * to_sun[0] + dy * to_sun[1] + dz * to_sun[2] >= ks.light_cos[light]:
            sin2 = 1.0 - ks.light_cos[light] ** 2
            return _table(ks.light_spd[light], lam) / (math.pi * sin2)
    return 0.0


@jit(inline="always")
def _infinite_pdf(ks, light, dx, dy, dz):
    """Solid-angle pdf of `_sample_light` producing this direction for a non-delta infinite light."""
    kind = ks.light_kind[light]
    if kind == LIGHT_ENVIRONMENT or kind == LIGHT_SKY:
        return 1.0 / (4.0 * math.pi)
    if kind == LIGHT_SUN and ks.light_cos[light] < 1.0:
        to_sun = ks.light_dir[light]
        if dx * to_sun[0] + dy * to_sun[1] + dz * to_sun[2] >= ks.light_cos[light]:
            return 1.0 / _sun_solid_angle(ks, light)
    return 0.0


@jit(inline="always")
def _sample_light(ks, light, px, py, pz, u1, u2, lams, n, radiance):
    """Direction to the light, its solid-angle pdf (1 for delta lights), distance, delta flag;
    fills `radiance` with the incident radiance (irradiance / intensity / d² for delta lights)."""
    kind = ks.light_kind[light]
    if kind == LIGHT_SUN:
        to_sun = ks.light_dir[light]
        if ks.light_cos[light] >= 1.0:
            for i in range(n):
                radiance[i] = _table(ks.light_spd[light], lams[i])
            return to_sun[0], to_sun[1], to_sun[2], 1.0, INF, True
        cos_theta = 1.0 - u1 * (1.0 - ks.light_cos[light])
        wx, wy, wz = sample_direction((to_sun[0], to_sun[1], to_sun[2]), cos_theta, u2)
        for i in range(n):
            radiance[i] = _infinite_radiance(ks, light, lams[i], wx, wy, wz)
        return wx, wy, wz, 1.0 / _sun_solid_angle(ks, light), INF, False
    if kind == LIGHT_ENVIRONMENT or kind == LIGHT_SKY:
        wz = 1.0 - 2.0 * u1
        r = math.sqrt(max(0.0, 1.0 - wz * wz))
        wx, wy = r * math.cos(2.0 * math.pi * u2), r * math.sin(2.0 * math.pi * u2)
        for i in range(n):
            radiance[i] = _infinite_radiance(ks, light, lams[i], wx, wy, wz)
        return wx, wy, wz, 1.0 / (4.0 * math.pi), INF, False
    position = ks.light_pos[light]
    vx, vy, vz = position[0] - px, position[1] - py, position[2] - pz
    distance = math.sqrt(vx * vx + vy * vy + vz * vz)
    wx, wy, wz = vx / distance, vy / distance, vz / distance
    falloff = 1.0 / (distance * distance)
    if kind == LIGHT_SPOT:
        axis = ks.light_dir[light]
        cos_angle = -(wx * axis[0] + wy * axis[1] + wz * axis[2])
        smooth = ks.light_smooth[light]
        if smooth > 0.0:
            t = min(max((cos_angle - ks.light_cos[light]) / smooth, 0.0), 1.0)
            falloff *= t * t * (3.0 - 2.0 * t)
        elif cos_angle < ks.light_cos[light]:
            falloff = 0.0
    for i in range(n):
        radiance[i] = _table(ks.light_spd[light], lams[i]) * falloff
    return wx, wy, wz, 1.0, distance, True


# ----------------------------------------------------------------------------- transport

@jit(inline="always")
def _medium_scratch_s(medium_s):
    """Second half of the per-medium σ_s buffer: shadow rays write there, keeping the vertex's values."""
    return medium_s[:, MAX_LAMBDAS:]


@jit(inline="always")
def _medium_scratch_fl(medium_fl):
    return medium_fl[:, MAX_LAMBDAS:]


@jit(inline="always")
def _transmittance(ks, ox, oy, oz, dx, dy, dz, t_max, lams, spec, n, stream, transmittance, null_ratio,
                   state_i, state_f, sigma_a, sigma_s, sigma_fl, emission, medium_s, medium_fl):
    """Ratio tracking along a shadow ray: fills `transmittance` (per λ) and `null_ratio`, the product
    of the unidirectional null-event probabilities σ_n/(σ̄ + σ_fl) per λ (for MIS)."""
    for i in range(n):
        transmittance[i] = 1.0
        null_ratio[i] = 1.0
    _tracker_start(ks, ox, oy, oz, dx, dy, dz, 0.0, t_max, state_i, state_f)
    t = 0.0
    while True:
        t, sigma_bar = _tentative_collision(ks, stream, state_i, state_f, t)
        if t == INF:
            return
        _coefficients(ks, ox + t * dx, oy + t * dy, oz + t * dz, lams, spec, n,
                      sigma_a, sigma_s, sigma_fl, emission, medium_s, medium_fl)
        largest = 0.0
        for i in range(n):
            sigma_n = max(0.0, sigma_bar - sigma_a[i] - sigma_s[i])
            transmittance[i] *= sigma_n / sigma_bar
            null_ratio[i] *= sigma_n / (sigma_bar + sigma_fl[i])
            largest = max(largest, transmittance[i])
        if largest == 0.0:
            return
        if largest < SHADOW_ROULETTE_BELOW:
            # Russian roulette on faint shadow rays: unbiased, and stops long walks through dense media.
            if _next(stream) < SHADOW_ROULETTE_STOP:
                for i in range(n):
                    transmittance[i] = 0.0
                return
            for i in range(n):
                transmittance[i] /= 1.0 - SHADOW_ROULETTE_STOP


@jit(inline="always")
def _next_event(ks, ox, oy, oz, dx, dy, dz, isotropic, lams, spec, n, stream, beta, r_u, radiance,
                scratch, medium_s, medium_fl, state_i, state_f):
    """Next-event estimation from a scattering vertex: one light chosen by its pmf, ratio-tracked
    transmittance, MIS against phase sampling (balance heuristic over wavelengths and strategies)."""
    light_radiance, phase_values, transmittance, null_ratio = scratch[4], scratch[5], scratch[6], scratch[7]
    r_l_light, r_u_light = scratch[8], scratch[9]
    n_lights = ks.light_kind.shape[0]
    light = 0
    choice = _next(stream)
    while light < n_lights - 1 and choice >= ks.light_pmf[light]:
        choice -= ks.light_pmf[light]
        light += 1
    u1, u2 = _next(stream), _next(stream)
    wx, wy, wz, direction_pdf, distance, delta = _sample_light(ks, light, ox, oy, oz, u1, u2, lams, n,
                                                               light_radiance)
    cos_theta = dx * wx + dy * wy + dz * wz
    if isotropic:
        for i in range(n):
            phase_values[i] = 0.25 / math.pi
    else:
        _mixture_phase(ks, medium_s, spec, n, cos_theta, phase_values)
    any_light = False
    for i in range(n):
        if light_radiance[i] > 0.0 and phase_values[i] > 0.0 and beta[i] > 0.0:
            any_light = True
    if any_light:
        _transmittance(ks, ox, oy, oz, wx, wy, wz, distance, lams, spec, n, stream, transmittance, null_ratio,
                       state_i, state_f, scratch[10], scratch[11], scratch[12], scratch[13],
                       _medium_scratch_s(medium_s), _medium_scratch_fl(medium_fl))
        light_pdf = ks.light_pmf[light] * direction_pdf
        for i in range(n):
            r_l_light[i] = r_u[i] * light_pdf
            r_u_light[i] = 0.0 if delta else r_u[i] * phase_values[i] * null_ratio[i]
        for i in range(n):
            r_l_light[i] += r_u_light[i]
        mean_r = _mean(r_l_light, n)
        if mean_r > 0.0:
            for i in range(n):
                radiance[i] += beta[i] * phase_values[i] * transmittance[i] * light_radiance[i] / mean_r


@jit(inline="always")
def _trace_path(ks, px, py, stream, n, lam_cam, pdf_cam, lams, spec, beta, r_u, r_l, radiance,
                scratch, medium_s, medium_fl, state_i, state_f, xyz):
    """Trace one camera path; adds its XYZ estimate to `xyz`."""
    sigma_a, sigma_s, sigma_fl, emission = scratch[0], scratch[1], scratch[2], scratch[3]
    light_radiance, phase_values, r_l_light = scratch[4], scratch[5], scratch[8]

    # Wavelengths: hero and stratified companions.
    u = _next(stream)
    for i in range(n):
        ui = u + i / n
        ui -= math.floor(ui)
        lam_cam[i] = sample_binned(ks.lambda_cdf, ui)
        pdf_cam[i] = pdf_binned(ks.lambda_pdf, lam_cam[i])
        lams[i] = lam_cam[i]
        beta[i] = 1.0
        r_u[i] = 1.0
        r_l[i] = 1.0
        radiance[i] = 0.0
    _fill_spectral_cache(ks, lams, n, spec)

    # Camera ray through the pixel (box filter), Blender camera conventions.
    ex, ey = ks.cam_extent[0], ks.cam_extent[1]
    cx = (-0.5 + (px + _next(stream)) / ks.width) * ex + ks.cam_extent[2]
    cy = (0.5 - (py + _next(stream)) / ks.height) * ey + ks.cam_extent[3]
    if ks.cam_kind == 0:
        ox, oy, oz = _transform_point(ks.cam_to_world, 0.0, 0.0, 0.0)
        dx, dy, dz = _transform_vector(ks.cam_to_world, cx, cy, -1.0)
    else:
        ox, oy, oz = _transform_point(ks.cam_to_world, cx, cy, 0.0)
        dx, dy, dz = _transform_vector(ks.cam_to_world, 0.0, 0.0, -1.0)
    dx, dy, dz = _normalize(dx, dy, dz)

    depth = 0
    scattered = False
    n_lights = ks.light_kind.shape[0]
    while True:
        # Free flight to the next real event (or escape), null collisions handled inline.
        event = EVENT_ESCAPE
        _tracker_start(ks, ox, oy, oz, dx, dy, dz, 0.0, INF, state_i, state_f)
        t = 0.0
        while True:
            t, sigma_bar = _tentative_collision(ks, stream, state_i, state_f, t)
            if t == INF:
                break
            qx, qy, qz = ox + t * dx, oy + t * dy, oz + t * dz
            _coefficients(ks, qx, qy, qz, lams, spec, n, sigma_a, sigma_s, sigma_fl, emission, medium_s, medium_fl)
            mean_r_u = _mean(r_u, n)
            for i in range(n):
                if emission[i] > 0.0:
                    radiance[i] += beta[i] * emission[i] / (sigma_bar * mean_r_u)
            total = sigma_bar + sigma_fl[0]
            sigma_n0 = max(0.0, sigma_bar - sigma_a[0] - sigma_s[0])
            choice = _next(stream) * total
            if choice < sigma_a[0] + sigma_s[0]:
                # A real collision scatters, weighted by the albedo: absorption lowers the throughput
                # instead of ending the path (Russian roulette ends faint paths).
                probability0 = (sigma_a[0] + sigma_s[0]) / total
                alive = False
                for i in range(n):
                    beta[i] *= sigma_s[i] / sigma_bar / probability0
                    r_u[i] *= (sigma_a[i] + sigma_s[i]) / (sigma_bar + sigma_fl[i]) / probability0
                    if beta[i] > 0.0:
                        alive = True
                event = EVENT_SCATTER if alive else EVENT_ABSORB
                break
            if choice < sigma_a[0] + sigma_s[0] + sigma_fl[0]:
                event = EVENT_FLUORESCE
                break
            probability0 = sigma_n0 / total
            alive = False
            for i in range(n):
                sigma_n = max(0.0, sigma_bar - sigma_a[i] - sigma_s[i])
                beta[i] *= sigma_n / sigma_bar / probability0
                r_u[i] *= sigma_n / (sigma_bar + sigma_fl[i]) / probability0
                r_l[i] /= probability0
                if beta[i] > 0.0:
                    alive = True
            if not alive:
                event = EVENT_ABSORB
                break

        if event == EVENT_ABSORB:
            break
        if event == EVENT_ESCAPE:
            for light in range(n_lights):
                for i in range(n):
                    le = _infinite_radiance(ks, light, lams[i], dx, dy, dz)
                    light_radiance[i] = le
                if not scattered:
                    mean_r = _mean(r_u, n)
                    for i in range(n):
                        radiance[i] += beta[i] * light_radiance[i] / mean_r
                else:
                    light_pdf = ks.light_pmf[light] * _infinite_pdf(ks, light, dx, dy, dz)
                    for i in range(n):
                        r_l_light[i] = r_u[i] + r_l[i] * light_pdf
                    mean_r = _mean(r_l_light, n)
                    for i in range(n):
                        radiance[i] += beta[i] * light_radiance[i] / mean_r
            break

        # A real scattering (or fluorescent) vertex at q.
        depth += 1
        if depth > ks.max_depth:
            break
        ox, oy, oz = qx, qy, qz
        isotropic = False
        if event == EVENT_FLUORESCE:
            medium = _pick_medium(medium_fl, 0, _next(stream))
            beta[0] *= (sigma_bar + sigma_fl[0]) / sigma_bar
            lams[0] = sample_binned(ks.excitation_cdf[medium], _next(stream))
            for i in range(1, n):
                beta[i] = 0.0
                r_u[i] = 0.0
                r_l[i] = 0.0
            _fill_spectral_cache(ks, lams, n, spec)
            isotropic = True

        if n_lights > 0:
            _next_event(ks, ox, oy, oz, dx, dy, dz, isotropic, lams, spec, n, stream, beta, r_u, radiance,
                        scratch, medium_s, medium_fl, state_i, state_f)

        # Phase sampling for the next direction (hero's phase; MIS pdfs at every wavelength).
        u1, u2 = _next(stream), _next(stream)
        if isotropic:
            new_cos = 1.0 - 2.0 * u1
        else:
            medium = _pick_medium(medium_s, 0, _next(stream))
            if ks.phase_kind[medium] == PHASE_RAYLEIGH:
                new_cos = rayleigh_sample_cos(u1)
            else:
                new_cos = hg_sample_cos(spec[medium, SPEC_ANISOTROPY, 0], u1)
        nx, ny, nz = sample_direction((dx, dy, dz), new_cos, u2)
        if isotropic:
            for i in range(n):
                phase_values[i] = 0.25 / math.pi
        else:
            _mixture_phase(ks, medium_s, spec, n, new_cos, phase_values)
        pdf0 = phase_values[0]
        if pdf0 <= 0.0:
            break
        for i in range(n):
            r_l[i] = r_u[i] / pdf0
            beta[i] *= phase_values[i] / pdf0
            r_u[i] *= phase_values[i] / pdf0
        dx, dy, dz = _normalize(nx, ny, nz)
        scattered = True

        # Russian roulette on the MIS-weighted throughput.
        if depth >= ks.rr_depth:
            mean_r = _mean(r_u, n)
            largest = 0.0
            for i in range(n):
                largest = max(largest, beta[i] / mean_r)
            if largest < 1.0:
                survive = max(largest, 0.05)
                if _next(stream) >= survive:
                    break
                for i in range(n):
                    beta[i] /= survive

    for i in range(n):
        if radiance[i] == 0.0 or pdf_cam[i] <= 0.0:
            continue
        scale = radiance[i] / (pdf_cam[i] * n)
        xyz[0] += scale * _table(ks.xyz_weights[0], lam_cam[i])
        xyz[1] += scale * _table(ks.xyz_weights[1], lam_cam[i])
        xyz[2] += scale * _table(ks.xyz_weights[2], lam_cam[i])


@cached
@jit(parallel=True, nogil=True)
def render_tile(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq):
    """Add samples [sample_begin, sample_end) of every pixel of a tile to the accumulators
    `sum_xyz` and `sum_sq` (shape (tile_height, tile_width, 3): Σ XYZ and Σ XYZ² per pixel)."""
    media = max(ks.density_scale.shape[0], 1)
    n = ks.wavelengths_per_path
    for index in prange(tile_width * tile_height):
        row, column = index // tile_width, index % tile_width
        px, py = x0 + column, y0 + row
        pixel = py * ks.width + px
        lam_cam = np.empty(MAX_LAMBDAS)
        pdf_cam = np.empty(MAX_LAMBDAS)
        lams = np.empty(MAX_LAMBDAS)
        spec = np.empty((media, SPEC_ROWS, MAX_LAMBDAS))
        beta = np.empty(MAX_LAMBDAS)
        r_u = np.empty(MAX_LAMBDAS)
        r_l = np.empty(MAX_LAMBDAS)
        radiance = np.empty(MAX_LAMBDAS)
        scratch = np.empty((14, MAX_LAMBDAS))
        medium_s = np.zeros((media, 2 * MAX_LAMBDAS))
        medium_fl = np.zeros((media, 2 * MAX_LAMBDAS))
        state_i = np.zeros((media, 7), dtype=np.int64)
        state_f = np.zeros((media, 17))
        stream = np.zeros(4, dtype=np.uint64)
        stream[2] = pixel_key(seed, band, pixel)
        xyz = np.zeros(3)
        for sample in range(sample_begin, sample_end):
            stream[0] = path_key(stream[2], sample)
            stream[1] = 0
            stream[3] = sample
            xyz[:] = 0.0
            _trace_path(ks, px, py, stream, n, lam_cam, pdf_cam, lams, spec, beta, r_u, r_l, radiance,
                        scratch, medium_s, medium_fl, state_i, state_f, xyz)
            for c in range(3):
                sum_xyz[row, column, c] += xyz[c]
                sum_sq[row, column, c] += xyz[c] * xyz[c]


def set_threads(count: int) -> None:
    """Use `count` threads (at most the number Numba was started with)."""
    import numba

    numba.set_num_threads(max(1, min(count, numba.config.NUMBA_NUM_THREADS)))
