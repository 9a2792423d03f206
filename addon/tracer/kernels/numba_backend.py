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
- Fluorescence is traced backwards, by branching: every tentative collision offers its fluorescent
  source (σ_fl at each camera wavelength) to three weighted one-slot reservoirs (`Fluorescent`, guided
  by the dye's optical depth: `fluorescent_reservoir`), and the path carries on by plain delta tracking,
  so no weight grows with the dye's density. When the path ends, a fluorescent sub-path starts at one
  reservoir's collision: one wavelength λ_in drawn ∝ excitation(λ_in), an isotropic direction; its
  radiance, times the collision's weight ÷ its mixture probability and each camera wavelength's share,
  is added to the path's. The sub-path's own reservoirs give the next (cascades, no recursion).
- Next-event estimation at every real scattering vertex with ratio-tracked transmittance (residual
  ratio tracking towards delta lights and on grey paths), combined with phase sampling by MIS for
  environment, sky, envmaps, finite suns and area lights (on grey paths weighed by the controls' transmittance,
  `_is_grey`). A free flight adds the area lights whose emitting faces it passes (`_area_light_seen`).
- Under a sun, in a forward-scattering medium: sunward probes (`_probe_from`, chance from `probe_grid`), an extra
  direction drawn about the sun's at a medium vertex, tracked to its next collision for the sun's estimate there,
  weighed against the path's own phase sampling by the balance heuristic.
- Thermal emission σ_a·Planck(T) and glow (emission that does not depend on absorption) are collected at every
  tentative collision.
- Surfaces (opaque Lambertian triangles, some emissive) end free flights: the closest hit along a ray
  (`_closest_hit`, a walk of the triangles' hierarchy) is the tracking's far end, and a path that gets there
  collects the surface's emission (MIS-weighted against light sampling after a scattering vertex,
  `_surface_emission`), then reflects: next-event estimation with the Lambertian BRDF and cosine-weighted
  sampling (`_sample_lambert`). Shadow rays that meet a surface carry nothing (`_shadow_blocked`).
- Film ▸ Transparent and holdouts (`transparency`): a camera path that reaches the background (transparent) or a
  holdout surface before any scattering adds its throughput to its transparency instead of light (`_see_through`).

Structure: `render_tile` runs runs of pixels in parallel (`_render_runs`); `_render_pixels` makes a run's buffers once
(each allocation updates Numba's global counters atomically) and `_render_samples` runs a pixel's samples, each through
the same stages as the NumPy backend's wavefront: `_sample_wavelengths` and `geometry.camera_ray`, then transport
(`_trace`: `_transport` with `_closest_hit`, `_free_flight`, `_offer_fluorescence`, `_escape`, `_surface_emission`,
`_next_event`, `_sample_phase` or `_sample_lambert`, `_survives_roulette`; then `_start_fluorescent_branch` for each
fluorescent sub-path), then `_path_xyz`. A path's state is named (`Path`, `Coefficients`, `LightSample`, `Tracker`,
`Fluorescent`, `Hit`). The physics at a point (look-ups, coefficients, phase functions, lights, surfaces, free paths,
the DDA's arithmetic) and the estimator's per-wavelength arithmetic (`estimator`: weight and MIS-ratio updates,
collision estimates, contributions, roulettes) are the shared arithmetic that the NumPy backend calls on arrays
(docs/algorithm.md); this module holds the path's loops, masks and state, and one tracking loop,
`_tentative_collision`, which free flights and shadow rays share. Every function below `_render_samples`, shared ones
included, is inlined into it,
and the kernel scene's arrays are borrowed (`_borrowed`): a call that takes the scene costs nothing, where Numba would
otherwise update the reference count of each of its ~40 arrays (atomic operations that threads contend for) on every
call. The arrays sit in the scene's nested groups (`layout.KernelScene`), all of which `_borrowed` borrows.

Two targets: `_render_samples` and everything it calls are `shared_math`'s (`shared`, and `shared_inline` for what
Numba inlines before typing on the CPU, where they are device functions on CUDA), so they compile for Numba's CPU
target here and for CUDA in `cuda_backend`, which runs `_render_samples` for one sample per GPU thread. The state's buffers (`local_empty`, `local_zeros`) and the
per-pixel sums of light passes and spectral bins (`accumulate`) go through `shared_math`'s per-target shims.
`render_tile`, `_render_runs` and `_render_pixels` are the CPU's alone (`cpu_jit`).
"""

import functools
from collections import namedtuple

import numpy as np
from numba import njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from ..binned import linear_over_binned, pdf_binned, sample_binned
from ..phase import INV_FOUR_PI, hg_sample_cos, rayleigh_sample_cos, sample_direction
from ..planck import planck_radiance
from .fluorescent_reservoir import RESERVOIRS, back_guide, chosen_reservoir, front_guide, mixture_weight
from .dda import axis_entry, axis_span
from .estimator import (
    attenuates_alike, camera_estimate, collision_estimate, companion_uniform, controls_transmittance,
    hit_light_contribution, hit_light_ratio, lambert_sampled, light_sample_ratio, next_event_contribution,
    null_collision, phase_sampled, probe_sampled, probe_weight, ratio_tracked, real_collision, real_probability,
    residual_tracked, roulette_survival, shadow_bound, shadow_roulette)
from .geometry import camera_ray, normalize, transform_point, transform_vector
from .layout import (
    BVH_STACK,
    LIGHT_AREA,
    MAX_WAVELENGTHS_PER_PATH,
    PHASE_RAYLEIGH,
    SHADOW_ROULETTE_BELOW,
    SURFACE_OFFSET,
    KernelScene,
)
from .light_sampling import (
    area_direction_pdf,
    area_light_hit,
    area_radiance,
    choose_light,
    incident_radiance,
    infinite_pdf,
    infinite_radiance,
    is_delta,
    sample_light,
)
from .light_split import (
    AFTER_NEE, BACKGROUND, EMISSION, ENVIRONMENT, FIRST, MARKS, MEDIUM, NOTHING, SECOND, SURFACE, clamp_factor,
    clamped_mark, direct_slot)
from .lookups import on_grid, probe_chance, table_at
from .media import (
    albedo,
    attenuation,
    blackbody_normalisation,
    collision_coefficients,
    density,
    free_path,
    glow_emission,
    null_fraction,
    phase_pdf,
    temperature,
    thermal_emission,
)
from ..shared_math import accumulate, local_empty, local_zeros, shared, shared_inline, shared_inline_always
from .numba_cache import cached
from .rng import LOW_DISCREPANCY_DIMENSIONS, low_discrepancy, path_key, pixel_key, uniform
from .spectrum_bins import spectrum_bin, spectrum_weight
from .surfaces import (emitter_pdf, facing_normal, lambert_pdf, lambert_sample_cos, offset_point, rgb_reflectance,
                       texel_colour, triangle_distance)
from .transparency import transparency_weight

# Every kernel function divides as NumPy does (x/0 gives inf or nan, like the NumPy backend) instead of
# Python's model, which checks every divisor for zero to raise ZeroDivisionError: the images are
# identical and the kernel is 1.3–1.4× faster (bench/README.md). The shared functions the CPU-only ones call
# inherit their error model (Numba's flag inheritance); numba-cuda's kernels divide as NumPy does anyway.
cpu_jit = functools.partial(njit, error_model="numpy")

MAX_LAMBDAS = MAX_WAVELENGTHS_PER_PATH
INF = np.inf
EVENT_ESCAPE, EVENT_SCATTER, EVENT_ABSORB = 0, 1, 2
# Rows of the per-path spectral cache spec[medium, row, wavelength] (filled when wavelengths change).
SPEC_EXTINCTION, SPEC_EXCITATION, SPEC_EMISSION_PDF, SPEC_ANISOTROPY, SPEC_ALBEDO, SPEC_GLOW, SPEC_GLOW_BLACKBODY = (
    0, 1, 2, 3, 4, 5, 6)
SPEC_ROWS = 7
# Rows of a path's sunward probe state path.probe[row, wavelength] (`_probe_from`): the path's β and r_u at its
# vertex before it drew its direction; its β, r_u and r_l while a probe is traced; the factor of r_u in its next
# sun estimate (`estimator.probe_weight`); the probe's pdf at a direction; and the light a probe from the camera
# path's first vertex brought, which counts as indirect (`_mark`).
START_BETA, START_R_U, SAVED_BETA, SAVED_R_U, SAVED_R_L, WEIGHT, SUN_PHASE, HELD, BACK = range(9)
PROBE_ROWS = 10  # BACK and the row after it: the path's vertex and direction while a probe is traced


# ----------------------------------------------------------------------------- small helpers

def _borrowed(scene):
    """The kernel scene (or a tuple of buffers) with its arrays borrowed, at any depth of nested tuples: the
    same data, without the reference counts that Numba's CPU target updates whenever an array is passed to a
    function or sliced. Those updates are atomic operations on counters that every thread shares; the caller
    keeps the arrays alive for the whole render. In Python (numba-cuda's simulator) and on CUDA
    (`cuda_backend`), whose arrays carry no reference counts, the scene itself."""
    return scene


@overload(_borrowed, target="cpu")  # a function of its own, as `shared_math`'s CPU overloads are (they say why)
def _borrowed_on_cpu(scene):
    return lambda scene: _borrow_arrays(scene)


@intrinsic(target="cpu")
def _borrow_arrays(typingctx, scene):
    """`_borrowed`'s CPU code."""

    def codegen(context, builder, signature, args):
        return _borrow(context, builder, signature.args[0], args[0])

    return scene(scene), codegen


def _borrow(context, builder, kind, value):
    """`_borrowed`'s code for a `value` of Numba type `kind`: an array with null reference-count (`meminfo`)
    and owner (`parent`) pointers, or a tuple with each of its arrays and tuples borrowed. Every array must be:
    Numba takes the result for a new reference and releases it, so an array still counted would be released
    once too often (freed while in use)."""
    if isinstance(kind, types.Array):
        array = context.make_array(kind)(context, builder, value)
        array.meminfo = cgutils.get_null_value(array.meminfo.type)
        array.parent = cgutils.get_null_value(array.parent.type)
        return array._getvalue()
    if isinstance(kind, types.BaseTuple):
        for index, member in enumerate(kind):
            if isinstance(member, (types.Array, types.BaseTuple)):
                borrowed = _borrow(context, builder, member, builder.extract_value(value, index))
                value = builder.insert_value(value, borrowed, index)
    return value



@shared_inline
def _next(stream):
    """Next uniform number of the path's stream (stream = path key, counter, pixel key, sample; `rng`)."""
    counter = stream[1]
    if counter < LOW_DISCREPANCY_DIMENSIONS:
        value = low_discrepancy(stream[2], stream[3], counter)
    else:
        value = uniform(stream[0], counter)
    stream[1] += np.uint64(1)
    return value


@shared_inline
def _mean(values, n):
    total = 0.0
    for i in range(n):
        total += values[i]
    return total / n


# ----------------------------------------------------------------------------- volume look-ups

@shared_inline
def _fill_spectral_cache(ks, lams, n, spec):
    """Tabulated spectra of every medium at the path's current wavelengths (looked up once per path
    and after a fluorescent wavelength change, instead of at every collision)."""
    for m in range(ks.media.density_scale.shape[0]):
        for i in range(n):
            at = on_grid(lams[i])
            spec[m, SPEC_EXTINCTION, i] = table_at(ks.media.extinction, m, at)
            spec[m, SPEC_EXCITATION, i] = table_at(ks.fluorescence.excitation, m, at)
            spec[m, SPEC_EMISSION_PDF, i] = table_at(ks.fluorescence.emission_pdf, m, at)
            spec[m, SPEC_ANISOTROPY, i] = table_at(ks.media.anisotropy, m, at)
            spec[m, SPEC_ALBEDO, i] = table_at(ks.media.albedo_table[m], 0, at)
            spec[m, SPEC_GLOW, i] = table_at(ks.glow.spectrum, m, at)
            spec[m, SPEC_GLOW_BLACKBODY, i] = table_at(ks.glow.blackbody, m, at)


@shared_inline
def _coefficients(ks, px, py, pz, lams, spec, n, c):
    """Medium coefficients at a point for each path wavelength (summed over media), per-medium
    scattering / fluorescence coefficients (for choosing which medium scatters), and emission, into the
    `Coefficients` c."""
    sigma_a, sigma_s, emission, medium_s, medium_fl, dye = c
    for i in range(n):
        sigma_a[i] = 0.0
        sigma_s[i] = 0.0
        emission[i] = 0.0
    dye[0] = 0.0
    for m in range(ks.media.density_scale.shape[0]):
        rho = density(ks, m, px, py, pz) * ks.media.density_scale[m]
        if rho > 0.0 and ks.fluorescence.strength[m] > 0.0:
            dye[0] += rho * ks.fluorescence.excitation_mean[m]
        kelvin = temperature(ks, m, px, py, pz) if ks.temperature.offset[m] >= 0 and rho > 0 else 0.0
        glowing = ks.glow.glowing[m]
        normalisation = blackbody_normalisation(ks, kelvin) if glowing and kelvin > 0.0 else 0.0
        for i in range(n):
            if rho <= 0.0:
                medium_s[m, i] = 0.0
                medium_fl[m, i] = 0.0
                continue
            albedo_value = (spec[m, SPEC_ALBEDO, i] if ks.media.albedo_count[m] == 1
                            else albedo(ks, m, rho / ks.media.density_scale[m], on_grid(lams[i])))
            scattering, absorption, plain_absorption, medium_fl[m, i] = collision_coefficients(
                rho, spec[m, SPEC_EXTINCTION, i], albedo_value, spec[m, SPEC_EXCITATION, i],
                ks.fluorescence.strength[m], spec[m, SPEC_EMISSION_PDF, i])
            medium_s[m, i] = scattering
            sigma_s[i] += scattering
            sigma_a[i] += absorption
            planck = planck_radiance(lams[i], kelvin) if kelvin > 0.0 else 0.0  # costly: skipped where it is 0
            if kelvin > 0.0:
                emission[i] += thermal_emission(plain_absorption, ks.temperature.map[m, 2], planck)
            if glowing:
                emission[i] += glow_emission(rho, spec[m, SPEC_GLOW, i], spec[m, SPEC_GLOW_BLACKBODY, i], planck,
                                             normalisation)


# ----------------------------------------------------------------------------- majorant tracking

# One DDA per medium over its majorant blocks, in the medium's padded index space (`Tracker`): slots of
# state_i[m] (the phase, then the cell and the step per axis) and of state_f[m] (the ray's span in the
# block grid, the next boundary and the spacing of boundaries per axis, the ray in index space; for
# residual ratio tracking, the control density on the current segment, its integral along the ray so
# far, and the density above the control at a tentative collision).
PHASE, CELL, STEP, TRACKER_INTS = 0, 1, 4, 7
BEFORE, INSIDE, DONE = 0, 1, 2  # phases: the ray has not entered the block grid yet, is in it, has left
T_ENTRY, T_EXIT, T_NEXT, T_DELTA, ORIGIN, DIRECTION, CONTROL, DEPTH, EXCESS, TRACKER_FLOATS = (
    0, 1, 2, 5, 11, 14, 17, 18, 19, 20)
STALE = -1.0  # the end of a ray's segment that `_tentative_collision` has yet to look up


@shared_inline
def _tracker_start(ks, ox, oy, oz, dx, dy, dz, t_min, t_max, tracker):
    """Start every medium's DDA for the ray o + t·d, t in [t_min, t_max]."""
    state_i, state_f = tracker.state_i, tracker.state_f
    for m in range(ks.media.density_scale.shape[0]):
        w2p = ks.density.world_to_padded[m]
        lox, loy, loz = transform_point(w2p, ox, oy, oz)
        ldx, ldy, ldz = transform_vector(w2p, dx, dy, dz)
        block = ks.majorant.block[m]
        shape = ks.majorant.shape[m]
        t0, t1 = axis_span(lox, ldx, shape[0] * block, t_min, t_max)
        t0, t1 = axis_span(loy, ldy, shape[1] * block, t0, t1)
        t0, t1 = axis_span(loz, ldz, shape[2] * block, t0, t1)
        state_i[m, PHASE] = DONE if t0 >= t1 else BEFORE
        state_f[m, T_ENTRY], state_f[m, T_EXIT] = t0, t1
        state_f[m, ORIGIN], state_f[m, ORIGIN + 1], state_f[m, ORIGIN + 2] = lox, loy, loz
        state_f[m, DIRECTION], state_f[m, DIRECTION + 1], state_f[m, DIRECTION + 2] = ldx, ldy, ldz


@shared_inline
def _tracker_enter(ks, m, tracker):
    state_i, state_f = tracker.state_i, tracker.state_f
    for axis in range(3):
        cell, step, t_next, t_delta = axis_entry(state_f[m, ORIGIN + axis], state_f[m, DIRECTION + axis],
                                                 state_f[m, T_ENTRY], ks.majorant.block[m], ks.majorant.shape[m, axis])
        state_i[m, CELL + axis], state_i[m, STEP + axis] = cell, step
        state_f[m, T_NEXT + axis], state_f[m, T_DELTA + axis] = t_next, t_delta
    state_i[m, PHASE] = INSIDE


@shared_inline
def _tracker_boundary(tracker, m):
    """The ray parameter where medium m's current majorant changes next."""
    state_f = tracker.state_f
    phase = tracker.state_i[m, PHASE]
    if phase == BEFORE:
        return state_f[m, T_ENTRY]
    if phase == INSIDE:
        return min(state_f[m, T_EXIT], state_f[m, T_NEXT], state_f[m, T_NEXT + 1], state_f[m, T_NEXT + 2])
    return INF


@shared_inline
def _block(ks, tracker, m):
    """Where medium m's current block is in `majorant.data` (and `majorant.minorant`)."""
    state_i = tracker.state_i
    shape = ks.majorant.shape[m]
    index = (state_i[m, CELL] * shape[1] + state_i[m, CELL + 1]) * shape[2] + state_i[m, CELL + 2]
    return ks.majorant.offset[m] + index


@shared_inline
def _tracker_segment(ks, tracker, controls):
    """(end of the current segment, the combined majorant σ̄ on it, the controls' share of σ̄). With
    `controls`, each medium's control σ_c (its block's minorant, scaled density; 0 outside its blocks) goes
    to its CONTROL slot and the share is Σ σ_c·coeff: σ̄ less it is the residual majorant of residual ratio
    tracking. Without, the share is 0."""
    t_end = INF
    sigma_bar = 0.0
    control_rate = 0.0
    for m in range(ks.media.density_scale.shape[0]):
        t_end = min(t_end, _tracker_boundary(tracker, m))
        if tracker.state_i[m, PHASE] == INSIDE:
            block = _block(ks, tracker, m)
            sigma_bar += np.float64(ks.majorant.data[block]) * ks.majorant.coeff[m]
            if controls:
                control = np.float64(ks.majorant.minorant[block])
                tracker.state_f[m, CONTROL] = control * ks.media.density_scale[m]
                control_rate += control * ks.majorant.coeff[m]
        elif controls:
            tracker.state_f[m, CONTROL] = 0.0
    return t_end, sigma_bar, control_rate


@shared_inline
def _integrate_controls(ks, tracker, dt):
    """Each medium's control integrated over dt more of the ray (its DEPTH slot)."""
    for m in range(ks.media.density_scale.shape[0]):
        tracker.state_f[m, DEPTH] += tracker.state_f[m, CONTROL] * dt


@shared_inline
def _tracker_advance(ks, tracker, t_end):
    """Move every medium whose boundary is at `t_end` into its next block (or out)."""
    state_i, state_f = tracker.state_i, tracker.state_f
    for m in range(ks.media.density_scale.shape[0]):
        if _tracker_boundary(tracker, m) > t_end:
            continue
        if state_i[m, PHASE] == BEFORE:
            _tracker_enter(ks, m, tracker)
            continue
        if state_f[m, T_EXIT] <= t_end:
            state_i[m, PHASE] = DONE
            continue
        axis = 0
        if state_f[m, T_NEXT + 1] < state_f[m, T_NEXT + axis]:
            axis = 1
        if state_f[m, T_NEXT + 2] < state_f[m, T_NEXT + axis]:
            axis = 2
        state_i[m, CELL + axis] += state_i[m, STEP + axis]
        state_f[m, T_NEXT + axis] += state_f[m, T_DELTA + axis]
        cell = state_i[m, CELL + axis]
        if cell < 0 or cell >= ks.majorant.shape[m, axis]:
            state_i[m, PHASE] = DONE


@shared_inline
def _tentative_collision(ks, stream, tracker, t, t_end, rate, controls, residual):
    """The one tracking loop, of free flights (`_free_flight`) and shadow rays (`_transmittance`): from ray
    parameter t on the current segment (ending at t_end, tentative collisions drawn at `rate` on it; t_end
    STALE: not looked up yet) to the next tentative collision. Returns (t, t_end, rate) there, for the next
    call to go on from, or (INF, INF, 0) when the ray leaves every medium (or passes the tracker's t_max).
    The rate is the majorant σ̄, or with `residual` σ̄ less the controls' share (the residual majorant of residual
    ratio tracking). With `controls`, the controls are integrated along the way (`_integrate_controls`). Each
    segment is looked up once (`_tracker_segment`), and its end and rate stay in the caller's variables."""
    while True:
        if t_end == STALE:
            t_end, sigma_bar, control_rate = _tracker_segment(ks, tracker, controls)
            rate = sigma_bar - control_rate if residual else sigma_bar
        if t_end == INF:
            return INF, INF, 0.0
        t_next = t_end
        if rate > 0.0:
            t_next = min(t + free_path(_next(stream), rate), t_end)
        if controls:
            _integrate_controls(ks, tracker, t_next - t)
        if t_next < t_end:
            return t_next, t_end, rate
        t = t_end
        _tracker_advance(ks, tracker, t_end)
        t_end = STALE


# ----------------------------------------------------------------------------- phase functions

@shared_inline
def _mixture_phase(ks, medium_s, spec, n, cos_theta, out):
    """Phase pdf (= value) at each wavelength: the σ_s-weighted mixture of the media's phases."""
    for i in range(n):
        total = 0.0
        weighted = 0.0
        for m in range(ks.media.density_scale.shape[0]):
            if medium_s[m, i] > 0.0:
                total += medium_s[m, i]
                weighted += medium_s[m, i] * phase_pdf(ks, m, spec[m, SPEC_ANISOTROPY, i], cos_theta)
        out[i] = weighted / total if total > 0.0 else 0.0


@shared_inline
def _pick_medium(ks, weights, i, u):
    """A medium drawn in proportion to its `weights[m, i]` (rows beyond the scene's media are not looked at)."""
    media = ks.media.density_scale.shape[0]
    total = 0.0
    for m in range(media):
        total += weights[m, i]
    target = u * total
    for m in range(media):
        target -= weights[m, i]
        if target < 0.0:
            return m
    return media - 1


# ----------------------------------------------------------------------------- lights

@shared_inline
def _sample_light(ks, light, px, py, pz, u1, u2, lams, n, radiance):
    """`light_sampling.sample_light` from (px, py, pz): direction, solid-angle pdf, distance and whether the
    light is a delta light; fills `radiance` with the radiance arriving at each wavelength."""
    wx, wy, wz, direction_pdf, distance, falloff = sample_light(ks, light, px, py, pz, u1, u2)
    for i in range(n):
        radiance[i] = incident_radiance(ks, light, on_grid(lams[i]), wx, wy, wz, falloff)
    return wx, wy, wz, direction_pdf, distance, is_delta(ks, light)


@shared_inline
def _next_area_light(ks, ox, oy, oz, dx, dy, dz, after, after_light, t_max):
    """The next area light face that the ray o + t d meets after (after, after_light) (its t, then its
    index, in that order) and before t_max: (t, light), or (INF, -1) where none is."""
    best_t, best = INF, -1
    for chosen in range(ks.lights.kind.shape[0]):
        if ks.lights.kind[chosen] != LIGHT_AREA:
            continue
        t = area_light_hit(ks, chosen, ox, oy, oz, dx, dy, dz, t_max)
        if (t > after or (t == after and chosen > after_light)) and t < best_t:
            best_t, best = t, chosen
    return best_t, best


@shared_inline
def _area_light_seen(ks, chosen, ox, oy, oz, dx, dy, dz, distance, scattered, n, path, light):
    """Radiance of the area light `chosen` whose emitting face a ray from the vertex o along d reaches at
    `distance` (`_free_flight`, with the path's weights there), added by `_add_hit_light` (its light pdf: the
    light's choice times `light_sampling.area_direction_pdf` from o); camera rays see it only where it is
    visible to the camera."""
    if not scattered and not ks.lights.camera_visible[chosen]:
        return
    for i in range(n):
        light.radiance[i] = area_radiance(ks, chosen, on_grid(path.lams[i]))
    light_pdf = 0.0
    if scattered:
        normal = ks.lights.dir[chosen]
        cos_light = -(dx * normal[0] + dy * normal[1] + dz * normal[2])
        light_pdf = ks.lights.pmf[chosen] * area_direction_pdf(ks, chosen, ox, oy, oz, distance, cos_light)
    _add_hit_light(scattered, 1.0, light_pdf, n, path, light)


# ----------------------------------------------------------------------------- surfaces

@shared_inline
def _box_entry(ks, node, ox, oy, oz, ix, iy, iz, t_max):
    """Where the ray o + t d (with inverse direction i) enters the box of node `node` within [0, t_max], or
    INF where it misses it there."""
    bounds = ks.surfaces.node_bounds[node]
    t0, t1 = (bounds[0] - ox) * ix, (bounds[3] - ox) * ix
    near, far = min(t0, t1), max(t0, t1)
    t0, t1 = (bounds[1] - oy) * iy, (bounds[4] - oy) * iy
    near, far = max(near, min(t0, t1)), min(far, max(t0, t1))
    t0, t1 = (bounds[2] - oz) * iz, (bounds[5] - oz) * iz
    near, far = max(near, min(t0, t1), 0.0), min(far, max(t0, t1), t_max)
    return near if near <= far else INF


@shared_inline
def _inverse(d):
    """1/d, a huge number of the same sign for d = 0 (a slab the ray runs along is all or nothing)."""
    return 1.0 / d if d != 0.0 else 1e300


@shared_inline
def _closest_hit(ks, ox, oy, oz, dx, dy, dz, t_max, any_hit, camera, hit):
    """The nearest triangle along the ray o + t d with 0 < t < t_max, walking the hierarchy nearer child
    first: (t, triangle), or (t_max, -1) where none is. With `any_hit`, the first triangle found (a shadow
    ray needs no more); a `camera` ray passes the surfaces camera rays do not see."""
    best_t, best = t_max, -1
    if ks.surfaces.node_count.shape[0] == 0:
        return best_t, best
    ix, iy, iz = _inverse(dx), _inverse(dy), _inverse(dz)
    nodes, entries = hit.nodes, hit.entries
    entry = _box_entry(ks, 0, ox, oy, oz, ix, iy, iz, best_t)
    top = 0
    if entry < INF:
        nodes[0], entries[0], top = 0, entry, 1
    while top > 0:
        top -= 1
        if entries[top] > best_t:
            continue
        node = nodes[top]
        first, count = ks.surfaces.node_first[node], ks.surfaces.node_count[node]
        if count > 0:
            for k in range(first, first + count):
                t = triangle_distance(ks, k, ox, oy, oz, dx, dy, dz)
                if t < best_t and (not camera or ks.surfaces.camera[ks.surfaces.surface[k]]):
                    best_t, best = t, k
                    if any_hit:
                        return best_t, best
            continue
        near = _box_entry(ks, first, ox, oy, oz, ix, iy, iz, best_t)
        far = _box_entry(ks, first + 1, ox, oy, oz, ix, iy, iz, best_t)
        near_node, far_node = first, first + 1
        if far < near:
            near, far, near_node, far_node = far, near, first + 1, first
        if far < INF:
            nodes[top], entries[top], top = far_node, far, top + 1
        if near < INF:
            nodes[top], entries[top], top = near_node, near, top + 1
    return best_t, best


@shared_inline
def _shadow_blocked(ks, ox, oy, oz, wx, wy, wz, distance, hit):
    """Whether a surface lies on the shadow ray from o along w before `distance` (stopping SURFACE_OFFSET short
    of its end, which may lie on an emissive surface)."""
    if ks.surfaces.node_count.shape[0] == 0:
        return False
    t_max = distance
    if distance < INF:
        qx, qy, qz = ox + distance * wx, oy + distance * wy, oz + distance * wz
        t_max = distance - SURFACE_OFFSET * (1.0 + max(abs(qx), abs(qy), abs(qz)))
    _, triangle = _closest_hit(ks, ox, oy, oz, wx, wy, wz, t_max, True, False, hit)
    return triangle >= 0


@shared_inline
def _surface_emission(ks, triangle, distance, dx, dy, dz, scattered, survival, n, path, light):
    """Radiance of an emissive surface that a path hits at `distance` along d, added by `_add_hit_light` (its
    light pdf: the mesh light's choice times its point's pdf in solid angle)."""
    s = ks.surfaces.surface[triangle]
    chosen = ks.surfaces.light[s]
    if chosen < 0:
        return
    for i in range(n):
        light.radiance[i] = table_at(ks.lights.spd, chosen, on_grid(path.lams[i]))
    light_pdf = 0.0
    if scattered:
        normal = ks.surfaces.normal[triangle]
        cos_light = abs(dx * normal[0] + dy * normal[1] + dz * normal[2])
        light_pdf = ks.lights.pmf[chosen] * emitter_pdf(ks.surfaces.area[s], distance, cos_light)
    _add_hit_light(scattered, survival, light_pdf, n, path, light)


@shared_inline
def _add_hit_light(scattered, survival, light_pdf, n, path, light):
    """Add the radiance in `light.radiance` of a light that the path's ray hit: plain for a camera ray; after a
    scattering vertex, MIS-weighted against light sampling of pdf `light_pdf` (the light's choice included),
    with the path's `survival` along the ray as a shadow ray would have given it (`_transmittance`: 1 where
    `r_l` has the null-event probabilities)."""
    for i in range(n):
        light.r_l[i] = hit_light_ratio(path.r_u[i], path.r_l[i], survival, light_pdf, scattered)
    mean_r = _mean(light.r_l, n)
    if mean_r > 0.0:
        for i in range(n):
            path.radiance[i] += hit_light_contribution(path.beta[i], light.radiance[i], survival, scattered, mean_r)


@shared_inline
def _arrive_at_surface(ks, triangle, px, py, pz, dx, dy, dz, n, path, hit):
    """A path reaching triangle `triangle` at p along d: the surface's normal on the path's side and its
    reflectance at the path's wavelengths (a textured surface's at p) into `hit`; returns the point leaving it on
    that side, and whether the surface reflects any of the path's light."""
    nx, ny, nz = facing_normal(ks, triangle, dx, dy, dz)
    hit.normal[0], hit.normal[1], hit.normal[2] = nx, ny, nz
    s = ks.surfaces.surface[triangle]
    reflects = False
    if ks.surfaces.texture_offset[s] < 0:
        for i in range(n):
            hit.reflectance[i] = table_at(ks.surfaces.reflectance, s, on_grid(path.lams[i]))
    else:
        r, g, b = texel_colour(ks, s, triangle, px, py, pz)
        for i in range(n):
            hit.reflectance[i] = rgb_reflectance(ks.surfaces.rgb_spectra, r, g, b, on_grid(path.lams[i]))
    for i in range(n):
        if hit.reflectance[i] > 0.0 and path.beta[i] > 0.0:
            reflects = True
    ox, oy, oz = offset_point(px, py, pz, nx, ny, nz)
    return ox, oy, oz, reflects


@shared_inline
def _sample_lambert(n, path, hit):
    """Cosine-weighted sampling of the direction leaving a surface (the same pdf at every wavelength, so
    the throughput takes the reflectance): the new direction, or a zero vector where its pdf is zero."""
    u1, u2 = _next(path.stream), _next(path.stream)
    cos_theta = lambert_sample_cos(u1)
    pdf0 = lambert_pdf(cos_theta)
    if pdf0 <= 0.0:
        return 0.0, 0.0, 0.0
    nx, ny, nz = sample_direction((hit.normal[0], hit.normal[1], hit.normal[2]), cos_theta, u2)
    for i in range(n):
        path.beta[i], path.r_u[i], path.r_l[i] = lambert_sampled(path.beta[i], path.r_u[i], hit.reflectance[i], pdf0)
    return normalize(nx, ny, nz)


# ----------------------------------------------------------------------------- path state

# One path's state, one slot per wavelength (buffers made once per pixel by `_new_path`, reused by its
# samples): the stream of random numbers (`_next`), camera wavelengths and their pdfs, current
# wavelengths (the hero changes at fluorescence), the media's spectra at them (`_fill_spectral_cache`),
# throughput, the MIS pdf ratios of unidirectional and light sampling, the radiance collected, and the camera
# path's transparency (one value: `_see_through`); for light passes and clamping, the camera path's marks of its
# radiance and what it met first and how many marks it has taken (`light_split`); the sunward probe's rows
# (`_probe_from`, `PROBE_ROWS`).
Path = namedtuple("Path", "stream lam_cam pdf_cam lams spec beta r_u r_l radiance transparent marks first probe")
# Medium coefficients at a point (`_coefficients`): per wavelength summed over media, and per medium;
# `dye` holds the dyes' absorption at their mean excitation (`fluorescent_reservoir`'s optical depth).
Coefficients = namedtuple("Coefficients", "sigma_a sigma_s emission medium_s medium_fl dye")
# Next-event estimation's per-wavelength values: the light's radiance, the phase function, ratio-tracked
# transmittance and the unidirectional strategy's survival along the shadow ray (`_transmittance`), and
# the strategies' ratios summed (`estimator.light_sample_ratio`, `estimator.hit_light_ratio`).
LightSample = namedtuple("LightSample", "radiance phase transmittance survival r_l")
# One majorant DDA per medium (`_tracker_*`): integer and float state per medium.
Tracker = namedtuple("Tracker", "state_i state_f")
# The fluorescent branch (`_offer_fluorescence`, `fluorescent_reservoir`): per reservoir (unguided, front,
# back) its total weight, its collision, each camera wavelength's share of the collision's weight, its
# medium and vertex depth, and its dye optical depth; the dye optical depth along the current segment; the
# radiance collected so far and the factor of each camera wavelength for the sub-path being traced.
Fluorescent = namedtuple("Fluorescent", "total point share medium tau_at tau radiance scale")
# A surface's hierarchy walk (`_closest_hit`: its stack of nodes and where the ray enters them) and the surface
# a path is on (`_arrive_at_surface`: the normal on the path's side, the reflectance at its wavelengths).
Hit = namedtuple("Hit", "nodes entries normal reflectance")


# Each `_new_*` makes one kind of state from `local_empty` / `local_zeros` (`shared_math`): NumPy's arrays in the
# CPU kernel, the thread's local arrays on CUDA, whose shapes must be literal there: `media` is the number of the
# scene's media on the CPU, `MAX_MEDIA` on CUDA (`cuda_backend`). Inlined on both targets (`shared_inline_always`):
# on CUDA the arrays live in the kernel's frame.
@shared_inline_always
def _new_path(media):
    f = np.float64
    return Path(local_zeros(4, np.uint64), local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f),
                local_empty(MAX_LAMBDAS, f), local_empty((media, SPEC_ROWS, MAX_LAMBDAS), f),
                local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f),
                local_empty(MAX_LAMBDAS, f), local_zeros(1, f), local_zeros((MARKS, MAX_LAMBDAS), f),
                local_zeros(2, np.int64), local_zeros((PROBE_ROWS, MAX_LAMBDAS), f))


@shared_inline_always
def _new_coefficients(media):
    f = np.float64
    return Coefficients(local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f),
                        local_zeros((media, MAX_LAMBDAS), f), local_zeros((media, MAX_LAMBDAS), f), local_zeros(1, f))


@shared_inline_always
def _new_light_sample():
    f = np.float64
    return LightSample(local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f),
                       local_empty(MAX_LAMBDAS, f), local_empty(MAX_LAMBDAS, f))


@shared_inline_always
def _new_fluorescent():
    f = np.float64
    return Fluorescent(local_zeros(RESERVOIRS, f), local_zeros((RESERVOIRS, 3), f),
                       local_zeros((RESERVOIRS, MAX_LAMBDAS), f), local_zeros((RESERVOIRS, 2), np.int64),
                       local_zeros(RESERVOIRS, f), local_zeros(1, f), local_zeros(MAX_LAMBDAS, f),
                       local_zeros(MAX_LAMBDAS, f))


@shared_inline_always
def _new_hit():
    f = np.float64
    return Hit(local_zeros(BVH_STACK, np.int64), local_zeros(BVH_STACK, f), local_zeros(3, f),
               local_zeros(MAX_LAMBDAS, f))


@shared_inline_always
def _new_tracker(media):
    return Tracker(local_zeros((media, TRACKER_INTS), np.int64), local_zeros((media, TRACKER_FLOATS), np.float64))


# ----------------------------------------------------------------------------- camera and film

@shared_inline
def _sample_wavelengths(ks, n, path):
    """The path's wavelengths: a hero drawn from the band's distribution and companions at u + i/n
    (stratified inverse CDF), with fresh weights."""
    u = _next(path.stream)
    for i in range(n):
        path.lam_cam[i] = sample_binned(ks.wavelengths.cdf, companion_uniform(u, i, n))
        path.pdf_cam[i] = pdf_binned(ks.wavelengths.pdf, path.lam_cam[i])
        path.lams[i] = path.lam_cam[i]
        path.beta[i] = 1.0
        path.r_u[i] = 1.0
        path.r_l[i] = 1.0
        path.radiance[i] = 0.0
    path.transparent[0] = 0.0
    _fill_spectral_cache(ks, path.lams, n, path.spec)


@shared_inline
def _see_through(ks, n, path):
    """A camera path reaching the background with Film ▸ Transparent on, or a holdout surface: its throughput
    (each wavelength's, as its radiance would have been weighted) into its transparency, as `transparency`
    weighs it; nothing with Film ▸ Transparent off (a holdout is then black)."""
    if not ks.camera.transparent:
        return
    mean_r = _mean(path.r_u, n)
    if mean_r > 0.0:
        for i in range(n):
            path.transparent[0] += path.beta[i] / mean_r * transparency_weight(ks, path.lam_cam[i], path.pdf_cam[i],
                                                                               n)


@shared_inline
def _path_xyz(ks, n, path):
    """The path's XYZ estimate: each camera wavelength's radiance over its pdf, through the XYZ weights."""
    return _spectrum_xyz(ks, n, path, -1)


@shared_inline
def _spectrum_xyz(ks, n, path, mark):
    """XYZ of the path's radiance (`mark` −1) or of one of its marks (`light_split`), as `_path_xyz` weighs it."""
    x, y, z = 0.0, 0.0, 0.0
    for i in range(n):
        value = path.radiance[i] if mark < 0 else path.marks[mark, i]
        if value == 0.0 or path.pdf_cam[i] <= 0.0:
            continue
        scale = camera_estimate(value, path.pdf_cam[i], n)
        at = on_grid(path.lam_cam[i])
        x += scale * table_at(ks.wavelengths.xyz_weights, 0, at)
        y += scale * table_at(ks.wavelengths.xyz_weights, 1, at)
        z += scale * table_at(ks.wavelengths.xyz_weights, 2, at)
    return x, y, z


@shared_inline
def _path_spectrum(ks, n, path, sum_spectrum, row, column):
    """The path's spectral estimate added to its pixel's bins (`spectrum_bins`); nothing without bins."""
    if sum_spectrum.shape[2] == 0:
        return
    edges = ks.wavelengths.spectrum_edges
    for i in range(n):
        if path.radiance[i] == 0.0 or path.pdf_cam[i] <= 0.0:
            continue
        b = int(spectrum_bin(edges, path.lam_cam[i]))
        if b >= 0:
            accumulate(sum_spectrum, (row, column, b), spectrum_weight(edges, path.radiance[i], path.pdf_cam[i], n))


@shared_inline
def _mark(n, path, index):
    """Take the camera path's mark `index` of its radiance (`light_split`): the next one it takes. The second
    leaves out what probes from the first vertex brought (`HELD`): light scattered at a second vertex, indirect."""
    for i in range(n):
        path.marks[index, i] = path.radiance[i] - path.probe[HELD, i] if index == SECOND else path.radiance[i]
    path.first[1] = index + 1


@shared_inline
def _mark_vertex(n, path, on_surface):
    """The camera path reaches a vertex: its first (what it is, and the mark), or its second (the mark)."""
    if path.first[1] == FIRST:
        path.first[0] = SURFACE if on_surface else MEDIUM
        _mark(n, path, FIRST)
    elif path.first[1] == SECOND:
        _mark(n, path, SECOND)


@shared_inline
def _mark_fluorescence(path, i, depth, contribution):
    """A fluorescent sub-path from a collision at vertex `depth` adds `contribution` at camera wavelength i: as a
    medium's emission there, to the marks taken after it (`light_split`)."""
    if depth == 1:
        for index in range(MARKS):
            path.marks[index, i] += contribution
    elif depth == 2:
        path.marks[SECOND, i] += contribution


@shared_inline
def _split_light(ks, n, path, x, y, z, light_sums):
    """The camera path's XYZ (x, y, z) clamped (Light Paths ▸ Clamping, `light_split`), and split by its marks into
    the light categories, added to `light_sums` (slots × XYZ; none: no light passes). Returns the clamped XYZ."""
    x0, y0, z0 = _spectrum_xyz(ks, n, path, FIRST)
    x1, y1, z1 = _spectrum_xyz(ks, n, path, AFTER_NEE)
    x2, y2, z2 = _spectrum_xyz(ks, n, path, SECOND)
    term = ks.termination
    direct = clamp_factor(x1, y1, z1, term.xyz_to_rgb, term.clamp_direct)
    indirect = clamp_factor(x - x1, y - y1, z - z1, term.xyz_to_rgb, term.clamp_indirect)
    if direct < 1.0 or indirect < 1.0:  # else the image stays exactly as unclamped
        x, y, z = (clamped_mark(x, x1, direct, indirect), clamped_mark(y, y1, direct, indirect),
                   clamped_mark(z, z1, direct, indirect))
        x2, y2, z2 = (clamped_mark(x2, x1, direct, indirect), clamped_mark(y2, y1, direct, indirect),
                      clamped_mark(z2, z1, direct, indirect))
        x0, y0, z0 = direct * x0, direct * y0, direct * z0
    if light_sums.shape[0] > 0:
        accumulate(light_sums, (EMISSION, 0), x0)
        accumulate(light_sums, (EMISSION, 1), y0)
        accumulate(light_sums, (EMISSION, 2), z0)
        if path.first[0] == BACKGROUND:
            accumulate(light_sums, (ENVIRONMENT, 0), x - x0)
            accumulate(light_sums, (ENVIRONMENT, 1), y - y0)
            accumulate(light_sums, (ENVIRONMENT, 2), z - z0)
        else:
            slot = direct_slot(path.first[0])
            accumulate(light_sums, (slot, 0), x2 - x0)
            accumulate(light_sums, (slot, 1), y2 - y0)
            accumulate(light_sums, (slot, 2), z2 - z0)
            accumulate(light_sums, (slot + 1, 0), x - x2)
            accumulate(light_sums, (slot + 1, 1), y - y2)
            accumulate(light_sums, (slot + 1, 2), z - z2)
    return x, y, z


# ----------------------------------------------------------------------------- transport

@shared_inline
def _control_depth(ks, tracker, spec, i):
    """The control's optical depth so far along a shadow ray at wavelength i (residual ratio tracking)."""
    depth = 0.0
    for m in range(ks.media.density_scale.shape[0]):
        depth += attenuation(tracker.state_f[m, DEPTH], spec[m, SPEC_EXTINCTION, i], spec[m, SPEC_EXCITATION, i])
    return depth


@shared_inline
def _is_grey(ks, n, spec):
    """Whether the path may weigh light sampling against phase sampling with residual ratio tracking: a
    light is not a delta light, and the path is grey (every medium attenuates its wavelengths alike, to
    GREY_SPREAD). Then the unidirectional strategy's null-event probabilities are the same at every
    wavelength and cancel out of the spectral MIS, so MIS may give both strategies the controls'
    transmittance in their place (docs/algorithm.md, "Lights and next-event estimation"). Never in a scene
    with an area light: a path meets its face inside a free flight, where the controls' transmittance up to
    it is not kept."""
    hit_light = False  # a light that paths may find (not a delta light)
    for light in range(ks.lights.kind.shape[0]):
        if ks.lights.kind[light] == LIGHT_AREA:
            return False  # its hits are weighed with the null-event probabilities in r_l (`_area_light_seen`)
        if not is_delta(ks, light):
            hit_light = True
    if not hit_light:
        return False
    for m in range(ks.media.density_scale.shape[0]):
        first = attenuation(1.0, spec[m, SPEC_EXTINCTION, 0], spec[m, SPEC_EXCITATION, 0])
        for i in range(1, n):
            value = attenuation(1.0, spec[m, SPEC_EXTINCTION, i], spec[m, SPEC_EXCITATION, i])
            if not attenuates_alike(value, first):
                return False
    return True


@shared_inline
def _faint_shadow_survives(ks, n, path, light, tracker, residual):
    """Russian roulette on a faint shadow ray (every transmittance below SHADOW_ROULETTE_BELOW; with
    `residual`, the ratio-tracked factors times the control's transmittance at its least optical depth):
    unbiased, and stops long walks through dense media. False when the ray stops (its transmittance 0)."""
    transmittance = light.transmittance
    largest = 0.0
    for i in range(n):
        largest = max(largest, transmittance[i])
    if largest == 0.0:
        return False
    if residual and largest >= SHADOW_ROULETTE_BELOW:
        least_depth = INF
        for i in range(n):
            least_depth = min(least_depth, _control_depth(ks, tracker, path.spec, i))
        largest = shadow_bound(largest, least_depth)
    if largest >= SHADOW_ROULETTE_BELOW:
        return True
    u = _next(path.stream)
    going_on = False
    for i in range(n):
        transmittance[i] = shadow_roulette(transmittance[i], u)
        if transmittance[i] > 0.0:
            going_on = True
    return going_on


@shared_inline
def _transmittance(ks, ox, oy, oz, dx, dy, dz, t_max, residual, n, path, light, tracker):
    """Ratio tracking along a shadow ray: fills `light.transmittance` (per λ) and `light.survival`, the
    chance MIS gives the unidirectional strategy of passing where the shadow ray passed (per λ).

    Plain ratio tracking: the survival is the product of the unidirectional null-event probabilities
    σ_n/σ̄ at the shadow ray's tentative collisions (the null-scattering path integral's MIS).

    With `residual` (towards delta lights, and for grey paths, `_is_grey`): residual ratio tracking
    (Novák et al. 2014). Each block's minorant, the control, is integrated exactly (`DEPTH`), and only
    the rest is ratio-tracked, against the residual majorant σ̄ − σ_c: in a smooth medium few tentative
    collisions and little variance. The survival is then the controls' transmittance exp(−∫σ_c), which
    `_free_flight` gives escaping paths too (docs/algorithm.md)."""
    transmittance, survival, state_f = light.transmittance, light.survival, tracker.state_f
    for i in range(n):
        transmittance[i] = 1.0
        survival[i] = 1.0
    _tracker_start(ks, ox, oy, oz, dx, dy, dz, 0.0, t_max, tracker)
    for m in range(ks.media.density_scale.shape[0]):
        state_f[m, CONTROL] = 0.0  # no control: plain ratio tracking
        state_f[m, DEPTH] = 0.0
    t, t_end, rate = 0.0, STALE, 0.0
    while True:
        t, t_end, rate = _tentative_collision(ks, path.stream, tracker, t, t_end, rate, residual, residual)
        if t == INF:
            break
        px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
        for m in range(ks.media.density_scale.shape[0]):
            state_f[m, EXCESS] = density(ks, m, px, py, pz) * ks.media.density_scale[m] - state_f[m, CONTROL]
        for i in range(n):
            excess = 0.0
            for m in range(ks.media.density_scale.shape[0]):
                excess += attenuation(state_f[m, EXCESS], path.spec[m, SPEC_EXTINCTION, i],
                                      path.spec[m, SPEC_EXCITATION, i])
            transmittance[i], survival[i] = ratio_tracked(transmittance[i], survival[i], rate, excess, residual)
        if not _faint_shadow_survives(ks, n, path, light, tracker, residual):
            return
    if residual:
        for i in range(n):
            transmittance[i], survival[i] = residual_tracked(transmittance[i],
                                                             _control_depth(ks, tracker, path.spec, i))


@shared_inline
def _next_event(ks, ox, oy, oz, dx, dy, dz, isotropic, on_surface, grey, n, path, vertex, light, tracker, hit,
                probing, weighted, hold):
    """Next-event estimation from a scattering vertex in a medium or on a surface (`on_surface`: the BRDF
    ρ/π, `hit`): one light chosen by its pmf, a shadow ray that a surface stops, ratio-tracked transmittance
    (residual ratio tracking towards delta lights and on `grey` paths), MIS against phase or BRDF sampling
    (balance heuristic over wavelengths and strategies). `light.phase` holds the sampling pdf of the
    direction, which at a medium is also the phase function's value.

    At a sunward probe's vertex (`probing`): the probe's sun, chosen with certainty (its estimate times the
    chance the path's own choice gives it), and with `hold` the light is also held for the marks (`HELD`, which
    only the second mark reads).
    With `weighted` (the path's first vertex after a probing one), the sun's estimate weighs the probe's
    strategy in (`probe.weight`)."""
    chosen = ks.lights.probe[0] if probing else choose_light(ks.lights.pmf, _next(path.stream))
    u1, u2 = _next(path.stream), _next(path.stream)
    wx, wy, wz, direction_pdf, distance, delta = _sample_light(ks, chosen, ox, oy, oz, u1, u2, path.lams, n,
                                                               light.radiance)
    cos_theta = dx * wx + dy * wy + dz * wz
    if on_surface:
        cos_surface = hit.normal[0] * wx + hit.normal[1] * wy + hit.normal[2] * wz
        for i in range(n):
            light.phase[i] = lambert_pdf(cos_surface)
    elif isotropic:
        for i in range(n):
            light.phase[i] = INV_FOUR_PI
    else:
        _mixture_phase(ks, vertex.medium_s, path.spec, n, cos_theta, light.phase)
    any_light = False
    for i in range(n):
        if light.radiance[i] > 0.0 and light.phase[i] > 0.0 and path.beta[i] > 0.0:
            any_light = True
    if not any_light or _shadow_blocked(ks, ox, oy, oz, wx, wy, wz, distance, hit):
        return
    _transmittance(ks, ox, oy, oz, wx, wy, wz, distance, delta or grey, n, path, light, tracker)
    light_pdf = ks.lights.pmf[chosen] * direction_pdf
    weighted = weighted and chosen == ks.lights.probe[0]
    for i in range(n):
        r_u = path.r_u[i] * path.probe[WEIGHT, i] if weighted else path.r_u[i]
        light.r_l[i] = light_sample_ratio(r_u, light_pdf, light.phase[i], light.survival[i], delta)
    mean_r = _mean(light.r_l, n)
    if mean_r > 0.0:
        share = ks.lights.pmf[chosen] if probing else 1.0
        for i in range(n):
            value = light.phase[i] * hit.reflectance[i] if on_surface else light.phase[i]
            contribution = share * next_event_contribution(path.beta[i], value, light.transmittance[i],
                                                           light.radiance[i], mean_r)
            path.radiance[i] += contribution
            if hold:
                path.probe[HELD, i] += contribution


@shared_inline
def _offer_fluorescence(ks, qx, qy, qz, sigma_bar, mean_r_u, depth, n, path, vertex, fl):
    """Offer each medium's fluorescent source at a tentative collision to the reservoirs `fl`: its weight
    Σ_i β_i σ_fl,i / (σ̄ · mean r_u) (the collision estimator of a source, as for thermal emission), times
    each reservoir's guide at the segment's dye optical depth, kept with probability guided weight ÷ the
    reservoir's total so far (one uniform for the three). Then the optical depth grows by the collision
    estimator of the dyes' absorption."""
    tau = fl.tau[0]
    for m in range(ks.media.density_scale.shape[0]):
        if ks.fluorescence.strength[m] <= 0.0:  # no dye: nothing to offer, and the tracking loop stays lean
            continue
        source = 0.0
        for i in range(n):
            source += path.beta[i] * vertex.medium_fl[m, i]
        if source <= 0.0:
            continue
        weight = collision_estimate(source, sigma_bar, mean_r_u)
        u = _next(path.stream)
        for k in range(RESERVOIRS):
            guided = weight if k == 0 else weight * (front_guide(tau) if k == 1 else back_guide(tau))
            fl.total[k] += guided
            if u * fl.total[k] < guided:
                fl.point[k, 0], fl.point[k, 1], fl.point[k, 2] = qx, qy, qz
                fl.medium[k, 0], fl.medium[k, 1] = m, depth + 1
                fl.tau_at[k] = tau
                for i in range(n):
                    fl.share[k, i] = path.beta[i] * vertex.medium_fl[m, i] / source
    if vertex.dye[0] > 0.0:
        fl.tau[0] = tau + vertex.dye[0] / sigma_bar


@shared_inline
def _free_flight(ks, ox, oy, oz, dx, dy, dz, t_max, depth, controls, scattered, collect, n, path, vertex, tracker, fl,
                 light):
    """Delta tracking to the next real event before t_max (a surface; EVENT_ESCAPE there), collecting emission
    (thermal, glow) and offering fluorescent sources at every tentative collision and weighting null collisions
    (spectral MIS ratios included). Returns (event, collision point, σ̄ there); `vertex` keeps the coefficients
    at a scattering collision. The area lights whose emitting faces the flight passes are added as it passes
    them (`_area_light_seen`, with the weights since the last tentative collision: the path's state at the
    face; `scattered`: whether o is a scattering vertex), drawing no random number.

    With `controls` (a grey path after a scattering vertex, `_is_grey`), light sampling's MIS ratio `r_l`
    takes no null-event probabilities: the controls are integrated instead, and an escaping path's
    survival is their transmittance, as a shadow ray's (`_transmittance`).

    Without `collect` (a sunward probe's segment, which looks only for its next real collision), nothing is
    collected or offered and no area light is looked for."""
    beta, r_u, r_l = path.beta, path.r_u, path.r_l
    sigma_a, sigma_s = vertex.sigma_a, vertex.sigma_s
    _tracker_start(ks, ox, oy, oz, dx, dy, dz, 0.0, t_max, tracker)
    if controls:
        for m in range(ks.media.density_scale.shape[0]):
            tracker.state_f[m, DEPTH] = 0.0
    fl.tau[0] = 0.0
    t, t_end, sigma_bar = 0.0, STALE, 0.0
    t_light, seen = _next_area_light(ks, ox, oy, oz, dx, dy, dz, 0.0, -1, t_max) if collect else (INF, -1)
    while True:
        t, t_end, sigma_bar = _tentative_collision(ks, path.stream, tracker, t, t_end, sigma_bar, controls, False)
        while t > t_light:
            _area_light_seen(ks, seen, ox, oy, oz, dx, dy, dz, t_light, scattered, n, path, light)
            t_light, seen = _next_area_light(ks, ox, oy, oz, dx, dy, dz, t_light, seen, t_max)
        if t == INF:
            return EVENT_ESCAPE, ox, oy, oz, 0.0
        qx, qy, qz = ox + t * dx, oy + t * dy, oz + t * dz
        _coefficients(ks, qx, qy, qz, path.lams, path.spec, n, vertex)
        if collect:
            mean_r_u = _mean(r_u, n)
            for i in range(n):
                if vertex.emission[i] > 0.0:
                    path.radiance[i] += collision_estimate(beta[i] * vertex.emission[i], sigma_bar, mean_r_u)
            _offer_fluorescence(ks, qx, qy, qz, sigma_bar, mean_r_u, depth, n, path, vertex, fl)
        choice = _next(path.stream) * sigma_bar
        if choice < sigma_a[0] + sigma_s[0]:
            # A real collision scatters, weighted by the albedo: absorption lowers the throughput
            # instead of ending the path (Russian roulette ends faint paths).
            probability0 = real_probability(sigma_a[0], sigma_s[0], sigma_bar)
            alive = False
            for i in range(n):
                beta[i], r_u[i] = real_collision(beta[i], r_u[i], sigma_a[i], sigma_s[i], sigma_bar, probability0)
                if beta[i] > 0.0:
                    alive = True
            return (EVENT_SCATTER if alive else EVENT_ABSORB), qx, qy, qz, sigma_bar
        probability0 = null_fraction(sigma_bar, sigma_a[0], sigma_s[0])
        alive = False
        for i in range(n):
            beta[i], r_u[i], r_l[i] = null_collision(beta[i], r_u[i], r_l[i], sigma_a[i], sigma_s[i], sigma_bar,
                                                     probability0, controls)
            if beta[i] > 0.0:
                alive = True
        if not alive:
            return EVENT_ABSORB, qx, qy, qz, sigma_bar


@shared_inline
def _escape(ks, dx, dy, dz, scattered, survival, n, path, light):
    """Radiance of the infinite lights seen along the escaping ray, each added by `_add_hit_light`; a camera
    ray sees through them with Film ▸ Transparent on (`_see_through`)."""
    if not scattered and ks.camera.transparent:
        _see_through(ks, n, path)
        return
    for chosen in range(ks.lights.kind.shape[0]):
        for i in range(n):
            light.radiance[i] = infinite_radiance(ks, chosen, on_grid(path.lams[i]), dx, dy, dz)
        light_pdf = ks.lights.pmf[chosen] * infinite_pdf(ks, chosen, dx, dy, dz) if scattered else 0.0
        _add_hit_light(scattered, survival, light_pdf, n, path, light)


@shared_inline
def _chosen_source(path, fl):
    """After a transport: the reservoir whose collision starts the next fluorescent sub-path and that
    collision's weight w / p (`fluorescent_reservoir.mixture_weight`), or (0, 0.0) when nothing was offered."""
    if fl.total[0] <= 0.0:
        return 0, 0.0
    k = chosen_reservoir(_next(path.stream))
    return k, mixture_weight(fl.tau_at[k], fl.total[0], fl.total[1], fl.total[2])


@shared_inline
def _start_fluorescent_branch(ks, path, fl, k):
    """A one-wavelength sub-path at reservoir k's collision: λ_in drawn ∝ the excitation of the medium
    that fluoresces (binned, then weighted to the interpolated spectrum), fresh weights, and empty
    reservoirs for its own fluorescent sources."""
    medium = fl.medium[k, 0]
    path.lams[0] = sample_binned(ks.fluorescence.excitation_cdf[medium], _next(path.stream))
    path.beta[0] = linear_over_binned(ks.fluorescence.excitation[medium], path.lams[0])
    path.r_u[0] = 1.0
    path.r_l[0] = 1.0
    path.radiance[0] = 0.0
    _fill_spectral_cache(ks, path.lams, 1, path.spec)
    for j in range(RESERVOIRS):
        fl.total[j] = 0.0


@shared_inline
def _phase_direction(ks, ax, ay, az, isotropic, path, vertex):
    """A direction drawn from the hero's phase function about the axis a (isotropic: uniformly): the cosine of
    its angle to a, and the direction (not normalised)."""
    u1, u2 = _next(path.stream), _next(path.stream)
    if isotropic:
        new_cos = 1.0 - 2.0 * u1
    else:
        medium = _pick_medium(ks, vertex.medium_s, 0, _next(path.stream))
        if ks.media.phase_kind[medium] == PHASE_RAYLEIGH:
            new_cos = rayleigh_sample_cos(u1)
        else:
            new_cos = hg_sample_cos(path.spec[medium, SPEC_ANISOTROPY, 0], u1)
    nx, ny, nz = sample_direction((ax, ay, az), new_cos, u2)
    return new_cos, nx, ny, nz


@shared_inline
def _sample_phase(ks, dx, dy, dz, isotropic, n, path, vertex, light):
    """Phase sampling of the next direction (the hero's phase; MIS pdfs at every wavelength, left in
    `light.phase`): the new direction, or a zero vector when the hero's pdf is zero (the path ends)."""
    phase_values = light.phase
    new_cos, nx, ny, nz = _phase_direction(ks, dx, dy, dz, isotropic, path, vertex)
    if isotropic:
        for i in range(n):
            phase_values[i] = INV_FOUR_PI
    else:
        _mixture_phase(ks, vertex.medium_s, path.spec, n, new_cos, phase_values)
    pdf0 = phase_values[0]
    if pdf0 <= 0.0:
        return 0.0, 0.0, 0.0
    for i in range(n):
        path.beta[i], path.r_u[i], path.r_l[i] = phase_sampled(path.beta[i], path.r_u[i], phase_values[i], pdf0)
    return normalize(nx, ny, nz)


@shared_inline
def _probe_from(ks, ox, oy, oz, ix, iy, iz, dx, dy, dz, n, path, vertex, light):
    """The sunward probe (`probe_grid`, docs/algorithm.md) at a medium vertex o where the path arrived along i and
    has drawn its next direction d (its phase values there in `light.phase`, its β and r_u before the draw in
    `START_*`). Where every wavelength scatters at o and the probe's chance a(o) is positive: the factor of
    r_u in the path's next sun estimate (`WEIGHT`, `estimator.probe_weight`), then, with probability a(o), a
    probe: a direction drawn from the phase function about the sun, and the path's β, r_u and r_l put aside
    (`SAVED_*`) for the probe's (`estimator.probe_sampled`). Returns (whether the next sun estimate is weighted,
    the probe's direction or a zero vector)."""
    medium_s = vertex.medium_s
    for i in range(n):
        total = 0.0
        for m in range(ks.media.density_scale.shape[0]):
            total += medium_s[m, i]
        if total <= 0.0:
            return False, 0.0, 0.0, 0.0
    chance = probe_chance(ks, ox, oy, oz)
    if chance <= 0.0:
        return False, 0.0, 0.0, 0.0
    sun = ks.lights.probe[0]
    wx, wy, wz = ks.lights.dir[sun, 0], ks.lights.dir[sun, 1], ks.lights.dir[sun, 2]
    sun_phase = path.probe[SUN_PHASE]
    _mixture_phase(ks, medium_s, path.spec, n, dx * wx + dy * wy + dz * wz, sun_phase)
    for i in range(n):
        path.probe[WEIGHT, i] = probe_weight(light.phase[i], chance, sun_phase[i])
    if _next(path.stream) >= chance:
        return True, 0.0, 0.0, 0.0
    sun_cos, px, py, pz = _phase_direction(ks, wx, wy, wz, False, path, vertex)
    px, py, pz = normalize(px, py, pz)
    _mixture_phase(ks, medium_s, path.spec, n, sun_cos, sun_phase)
    _mixture_phase(ks, medium_s, path.spec, n, ix * px + iy * py + iz * pz, light.phase)
    for i in range(n):
        path.probe[SAVED_BETA, i], path.probe[SAVED_R_U, i] = path.beta[i], path.r_u[i]
        path.probe[SAVED_R_L, i] = path.r_l[i]
        path.beta[i], path.r_u[i] = probe_sampled(path.probe[START_BETA, i], path.probe[START_R_U, i],
                                                  light.phase[i], chance, sun_phase[i])
        path.r_l[i] = path.r_u[i]
    return True, px, py, pz


@shared_inline
def _end_probe(n, path):
    """Back from a sunward probe: the path's β, r_u and r_l as they were."""
    for i in range(n):
        path.beta[i], path.r_u[i], path.r_l[i] = (path.probe[SAVED_BETA, i], path.probe[SAVED_R_U, i],
                                                  path.probe[SAVED_R_L, i])


@shared_inline
def _survives_roulette(ks, depth, n, path):
    """Russian roulette on the MIS-weighted throughput from `rr_depth` on; survivors are reweighted."""
    if depth < ks.termination.rr_depth:
        return True
    mean_r = _mean(path.r_u, n)
    largest = 0.0
    for i in range(n):
        largest = max(largest, path.beta[i] / mean_r)
    survive = roulette_survival(largest)
    if survive >= 1.0:
        return True
    if _next(path.stream) >= survive:
        return False
    for i in range(n):
        path.beta[i] /= survive
    return True


@shared_inline
def _transport(ks, ox, oy, oz, dx, dy, dz, depth, emitted, marking, n, path, vertex, light, tracker, fl, hit):
    """Transport from a camera ray, or (`emitted`) from an isotropic fluorescent emission at (ox, oy, oz)
    at vertex `depth`: collects the radiance per wavelength in `path.radiance` and offers fluorescent
    sources to `fl`. A vertex is a real collision in a medium or a surface the path reaches (`on_surface`).
    With `marking` (a camera path, for light passes or clamping), the path takes its marks (`light_split`).

    A sunward probe (`_probe_from`) is a detour through the same stages: from its vertex o the probe's segment is
    tracked to its next real collision, where its sun estimate is made, and the path goes on from o along its own
    direction (kept in `path.probe`'s `BACK` rows), its weights restored (`_end_probe`)."""
    grey = _is_grey(ks, n, path.spec)
    probes = ks.lights.probe[0] >= 0
    scattered = emitted
    at_vertex = emitted
    on_surface = False
    probing = False  # on a probe's segment; `arrived`: it found its collision
    arrived = False
    weighted = False  # the next sun estimate weighs the probe's strategy in (the path left a probing vertex)
    while True:
        if at_vertex:
            if marking and not probing:
                _mark_vertex(n, path, on_surface)
            if ks.lights.kind.shape[0] > 0 and (arrived or not probing):
                _next_event(ks, ox, oy, oz, dx, dy, dz, emitted, on_surface, grey, n, path, vertex, light, tracker,
                            hit, probing, weighted and not on_surface and not probing,
                            probing and marking)
            if probing:
                back = path.probe
                ox, oy, oz = back[BACK, 0], back[BACK, 1], back[BACK, 2]
                dx, dy, dz = back[BACK + 1, 0], back[BACK + 1, 1], back[BACK + 1, 2]
                _end_probe(n, path)
                probing, arrived = False, False
            else:
                weighted = False
                if marking and path.first[1] == AFTER_NEE:
                    _mark(n, path, AFTER_NEE)
                probe_here = probes and not on_surface and not emitted and depth < ks.termination.max_depth
                if probe_here:
                    for i in range(n):
                        path.probe[START_BETA, i], path.probe[START_R_U, i] = path.beta[i], path.r_u[i]
                ix, iy, iz = dx, dy, dz
                if on_surface:
                    dx, dy, dz = _sample_lambert(n, path, hit)
                else:
                    dx, dy, dz = _sample_phase(ks, dx, dy, dz, emitted, n, path, vertex, light)
                if dx == 0.0 and dy == 0.0 and dz == 0.0:
                    return
                scattered = True
                emitted = False
                if probe_here:
                    weighted, px, py, pz = _probe_from(ks, ox, oy, oz, ix, iy, iz, dx, dy, dz, n, path, vertex, light)
                    if px != 0.0 or py != 0.0 or pz != 0.0:
                        probing = True
                        back = path.probe
                        back[BACK, 0], back[BACK, 1], back[BACK, 2] = ox, oy, oz
                        back[BACK + 1, 0], back[BACK + 1, 1], back[BACK + 1, 2] = dx, dy, dz
                        dx, dy, dz = px, py, pz
            if not probing and not _survives_roulette(ks, depth, n, path):
                return
        t_hit, triangle = _closest_hit(ks, ox, oy, oz, dx, dy, dz, INF, False, not scattered, hit)
        controls = grey and scattered and not probing
        event, qx, qy, qz, sigma_bar = _free_flight(ks, ox, oy, oz, dx, dy, dz, t_hit, depth, controls, scattered,
                                                    not probing, n, path, vertex, tracker, fl, light)
        if probing:  # back to the vertex, through its sun estimate where the probe found a collision
            arrived = event == EVENT_SCATTER
            if arrived:
                ox, oy, oz = qx, qy, qz
            at_vertex = True
            continue
        if event == EVENT_ABSORB:
            return
        if event == EVENT_ESCAPE:
            survival = controls_transmittance(_control_depth(ks, tracker, path.spec, 0)) if controls else 1.0
            if triangle < 0:
                if marking and not scattered:
                    path.first[0] = BACKGROUND
                    _mark(n, path, FIRST)
                _escape(ks, dx, dy, dz, scattered, survival, n, path, light)
                return
            if not scattered and ks.surfaces.holdout[ks.surfaces.surface[triangle]]:
                _see_through(ks, n, path)  # a holdout seen by the camera: a hole, for camera rays only
                return
            _surface_emission(ks, triangle, t_hit, dx, dy, dz, scattered, survival, n, path, light)
            depth += 1
            if depth > ks.termination.max_depth:
                return
            ox, oy, oz, reflects = _arrive_at_surface(ks, triangle, ox + t_hit * dx, oy + t_hit * dy, oz + t_hit * dz,
                                                      dx, dy, dz, n, path, hit)
            if not reflects:
                return
            on_surface = True
            at_vertex = True
            continue
        depth += 1
        if depth > ks.termination.max_depth:
            return
        ox, oy, oz = qx, qy, qz
        on_surface = False
        at_vertex = True


@shared_inline
def _trace(ks, ox, oy, oz, dx, dy, dz, splitting, n, path, vertex, light, tracker, fl, hit):
    """Transport of one path from a camera ray, then of its fluorescent sub-paths one after another, all
    through the one `_transport` below (inlined once, not once per kind of path): collects the path's
    radiance per camera wavelength in `path.radiance`. With `splitting`, the camera path takes its marks
    (`light_split`; marks it never reached are its radiance) and the sub-paths add to them."""
    for j in range(RESERVOIRS):
        fl.total[j] = 0.0
    path.first[0], path.first[1] = NOTHING, FIRST
    for i in range(n):
        path.probe[HELD, i] = 0.0
    depth, emitted, count = 0, False, n
    while True:
        _transport(ks, ox, oy, oz, dx, dy, dz, depth, emitted, splitting and not emitted, count, path, vertex, light,
                   tracker, fl, hit)
        if splitting and not emitted:
            for index in range(path.first[1], MARKS):
                _mark(n, path, index)
        k, weight = _chosen_source(path, fl)
        for i in range(n):
            if emitted:  # a sub-path: its radiance at λ_in, then the weight of the next one
                contribution = fl.scale[i] * path.radiance[0]
                fl.radiance[i] += contribution
                if splitting:
                    _mark_fluorescence(path, i, depth, contribution)
                fl.scale[i] *= weight
            else:  # the camera path
                fl.radiance[i] = path.radiance[i]
                fl.scale[i] = weight * fl.share[k, i]
        if weight <= 0.0 or fl.medium[k, 1] > ks.termination.max_depth:
            break
        depth, emitted, count = fl.medium[k, 1], True, 1
        ox, oy, oz, dx, dy, dz = fl.point[k, 0], fl.point[k, 1], fl.point[k, 2], 0.0, 0.0, 1.0
        _start_fluorescent_branch(ks, path, fl, k)
    for i in range(n):
        path.radiance[i] = fl.radiance[i]


@cpu_jit
def _render_pixels(ks, x0, y0, tile_width, first, last, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                   sum_transparent, sum_light_passes, sum_spectrum):
    """Samples [sample_begin, sample_end) of the tile's pixels [first, last) (row-major), added to `sum_xyz`,
    `sum_sq`, `sum_transparent`, `sum_light_passes` and `sum_spectrum`. The path's buffers are made once for them
    all: each allocation updates Numba's global allocation counters atomically, which threads contend for."""
    media = max(ks.media.density_scale.shape[0], 1)
    path, vertex = _new_path(media), _new_coefficients(media)
    light, tracker, fl, hit = _new_light_sample(), _new_tracker(media), _new_fluorescent(), _new_hit()
    for index in range(first, last):
        row, column = index // tile_width, index % tile_width
        px, py = x0 + column, y0 + row
        sx, sy, sz, qx, qy, qz, st = _render_samples(ks, px, py, py * ks.camera.width + px, sample_begin, sample_end,
                                                     seed, band, path, vertex, light, tracker, fl, hit,
                                                     sum_light_passes[row, column], sum_spectrum, row, column)
        sum_xyz[row, column, 0] += sx
        sum_xyz[row, column, 1] += sy
        sum_xyz[row, column, 2] += sz
        sum_sq[row, column, 0] += qx
        sum_sq[row, column, 1] += qy
        sum_sq[row, column, 2] += qz
        sum_transparent[row, column] += st


@shared
def _render_samples(ks, px, py, pixel, sample_begin, sample_end, seed, band, path, vertex, light, tracker, fl, hit,
                    light_sums, sum_spectrum, row, column):
    """Samples [sample_begin, sample_end) of one pixel, (Σ X, Σ Y, Σ Z, Σ X², Σ Y², Σ Z², Σ transparency), in the
    path's buffers (`_render_pixels` makes them); the light categories' Σ XYZ added to `light_sums` (slots × 3,
    none without light passes) and each sample's spectrum to `sum_spectrum[row, column]` (unclamped). The scene and
    the buffers, which the caller keeps alive, are borrowed (`_borrowed`): the loop below then updates no reference
    counts."""
    ks, path, vertex, light, tracker, fl, hit = (_borrowed(ks), _borrowed(path), _borrowed(vertex), _borrowed(light),
                                                 _borrowed(tracker), _borrowed(fl), _borrowed(hit))
    light_sums = _borrowed(light_sums)
    n = ks.wavelengths.per_path
    # light passes or clamping: the camera paths take their marks (`light_split`); else no extra work
    term = ks.termination
    splitting = light_sums.shape[0] > 0 or term.clamp_direct > 0.0 or term.clamp_indirect > 0.0
    path.stream[2] = pixel_key(seed, band, pixel)
    sx, sy, sz, qx, qy, qz, st = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for sample in range(sample_begin, sample_end):
        path.stream[0] = path_key(path.stream[2], sample)
        path.stream[1] = 0
        path.stream[3] = sample
        _sample_wavelengths(ks, n, path)
        ox, oy, oz, dx, dy, dz = camera_ray(ks, px, py, _next(path.stream), _next(path.stream))
        _trace(ks, ox, oy, oz, dx, dy, dz, splitting, n, path, vertex, light, tracker, fl, hit)
        x, y, z = _path_xyz(ks, n, path)
        _path_spectrum(ks, n, path, sum_spectrum, row, column)
        if splitting:
            x, y, z = _split_light(ks, n, path, x, y, z, light_sums)
        sx, sy, sz = sx + x, sy + y, sz + z
        qx, qy, qz = qx + x * x, qy + y * y, qz + z * z
        st += path.transparent[0]
    return sx, sy, sz, qx, qy, qz, st


# A tile's pixels are shared among the threads in this many runs of neighbouring pixels, each with its own
# buffers (several runs per thread for up to 16 threads).
PIXEL_CHUNKS = 64


@cached
@cpu_jit(nogil=True)
def render_tile(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                sum_transparent, sum_light_passes, sum_spectrum):
    """Add samples [sample_begin, sample_end) of every pixel of a tile to the accumulators
    `sum_xyz` and `sum_sq` (shape (tile_height, tile_width, 3): Σ XYZ and Σ XYZ² per pixel),
    `sum_transparent` (shape (tile_height, tile_width): Σ transparency, `kernels/transparency.py`),
    `sum_light_passes` (shape (tile_height, tile_width, K, 3): Σ XYZ of each light category, `light_split`; K is
    `light_split.CATEGORIES`, or 0 for none) and `sum_spectrum` (shape (tile_height, tile_width, B): Σ of each bin's
    estimate, `kernels/spectrum_bins.py`; B = 0: none)."""
    _render_runs(ks.camera, ks.density, ks.majorant, ks.temperature, ks.glow, ks.media, ks.fluorescence, ks.lights,
                 ks.envmaps, ks.surfaces, ks.wavelengths, ks.termination, x0, y0, tile_width, tile_height, sample_begin,
                 sample_end, seed, band, sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum)


@cpu_jit(parallel=True, nogil=True)
def _render_runs(camera, density, majorant, temperature, glow, media, fluorescence, lights, envmaps, surfaces,
                 wavelengths, termination, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band,
                 sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum):
    """`render_tile`'s runs of pixels, in parallel. The kernel scene comes as its groups, and each run puts
    them together again: Numba's parallel loop hands a tuple to its threads member by member, which fails
    when a member is a tuple itself."""
    pixels = tile_width * tile_height
    chunks = min(pixels, PIXEL_CHUNKS)
    for chunk in prange(chunks):
        ks = KernelScene(camera, density, majorant, temperature, glow, media, fluorescence, lights, envmaps, surfaces,
                         wavelengths, termination)
        _render_pixels(ks, x0, y0, tile_width, chunk * pixels // chunks, (chunk + 1) * pixels // chunks, sample_begin,
                       sample_end, seed, band, sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum)


def set_threads(count: int) -> None:
    """Use `count` threads (at most the number Numba was started with)."""
    import numba

    numba.set_num_threads(max(1, min(count, numba.config.NUMBA_NUM_THREADS)))
