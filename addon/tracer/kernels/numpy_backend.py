"""NumPy backend: the spectral null-scattering volume path tracer as a vectorised wavefront.

It runs the algorithm of `numba_backend` (see its docstring) with no compiled dependency, and is the
second engine that validates the Numba kernel. Paths are not traced one at a time: the paths of a tile
(in chunks of at most `CHUNK_PATHS`) are arrays of path states (`_Batch`, one row per path) that step
together and are compacted as they end. One `_bounce` takes every live path through free flight, escape,
the scattering or fluorescent vertex, next-event estimation, phase sampling, the sunward probes (`_probe`) and
Russian roulette. The physics at each point and the estimator's per-wavelength updates are the arithmetic the
Numba kernel compiles (look-ups, coefficients, phase functions, lights, free paths; `estimator`: weights, MIS
ratios, contributions, roulettes: docs/algorithm.md), called here on arrays of paths; this module holds the
wavefront's loops, masks and state, and one tracking loop, `_track`, for free flights and shadow rays (as the Numba
kernel has one).

Surfaces: every ray is tested against every triangle (`_closest_hits`, brute force over chunks of triangles,
the independent check of the Numba kernel's hierarchy); a path's free flight ends at the nearest one, where it
collects the surface's emission and reflects (`_arrive_at_surfaces`, then `_scatter` with the Lambertian BRDF
for the rows `on_surface`), and shadow rays that meet one carry nothing.

Free flight and shadow rays traverse each medium's majorant grid block by block, a DDA vectorised over
rays (`_tracker_*`, the same state machine as the Numba kernel's, on the shared per-axis arithmetic of
`dda`): each loop iteration moves every ray by one segment or one tentative collision, and rays that are
done leave the batch. Shadow rays towards delta lights and of grey paths use residual ratio tracking
(`_transmittance`).

Every path draws from the same stream of random numbers (`rng`: low-discrepancy, then hashed), in the same order
and with the same arithmetic as the Numba kernel, so the two backends trace the same paths: images agree
pixel by pixel up to floating-point differences (transcendental functions may differ in the last bit,
which can send a path down another branch). Masked lanes may compute values that are then discarded
(1/σ̄ where σ̄ = 0, say), so floating-point warnings are silenced while tracing.
"""

from types import SimpleNamespace

import numpy as np

from ..binned import linear_over_binned, pdf_binned, sample_binned
from ..phase import INV_FOUR_PI, hg_sample_cos, rayleigh_sample_cos, sample_direction
from ..planck import planck_radiance
from . import media
from .fluorescent_reservoir import RESERVOIRS, back_guide, chosen_reservoir, front_guide, mixture_weight
from .dda import axis_entry, axis_span
from .estimator import (
    attenuates_alike, camera_estimate, collision_estimate, companion_uniform, controls_transmittance,
    hit_light_contribution, hit_light_ratio, lambert_sampled, light_sample_ratio, next_event_contribution,
    null_collision, phase_sampled, probe_sampled, probe_weight, ratio_tracked, real_collision, real_probability,
    residual_tracked, roulette_survival, shadow_bound, shadow_roulette)
from .geometry import camera_depths, camera_ray, normalize, transform_point, transform_vector
from .layout import LIGHT_AREA, PHASE_RAYLEIGH, SHADOW_ROULETTE_BELOW, SURFACE_OFFSET
from .light_sampling import (
    area_direction_pdf, area_light_hit, area_radiance, choose_light, incident_radiance, infinite_pdf,
    infinite_radiance, is_delta, sample_light)
from .light_split import (
    AFTER_NEE, BACKGROUND, CATEGORIES, EMISSION, ENVIRONMENT, FIRST, MARKS, MEDIUM, SECOND, SURFACE, clamp_factor,
    clamped_mark, direct_slot)
from .lookups import on_grid, probe_chance, table_at
from .rng import LOW_DISCREPANCY_DIMENSIONS, low_discrepancy, path_key, pixel_key, uniform
from .spectrum_bins import spectrum_bin, spectrum_weight
from .surfaces import (emitter_pdf, facing_normal, lambert_pdf, lambert_sample_cos, offset_point, rgb_reflectance,
                       texel_colour, triangle_distance)
from .transparency import transparency_weight

CHUNK_PATHS = 65536  # paths traced together: bounds the memory of a large tile
CHUNK_PAIRS = 1 << 20  # ray–triangle pairs tested together (`_closest_hits`: ~20 arrays of this size)
INF = np.inf
EVENT_ESCAPE, EVENT_SCATTER, EVENT_ABSORB = 0, 1, 2


class _Batch:
    """A struct of arrays with one row per path (or ray); `take` keeps some rows, in a new batch. A member
    that is not an array (`stream`: state shared by every batch of the same paths) is kept as it is."""

    def __init__(self, **arrays):
        vars(self).update(arrays)

    def take(self, rows):
        return _Batch(**{name: array[rows] if isinstance(array, np.ndarray) else array
                         for name, array in vars(self).items()})

    def __len__(self):
        return len(next(iter(vars(self).values())))


def _draw(paths, rows=slice(None)):
    """The next uniform number of each selected path's stream (`paths.stream`, indexed by path id: key,
    counter, and pixel key and sample for the low-discrepancy dimensions; `rng`). A path's fluorescent
    sub-paths go on drawing from its stream."""
    ids, stream = paths.id[rows], paths.stream
    counter = stream.counter[ids]
    u = uniform(stream.key[ids], counter)
    low = np.flatnonzero(counter < LOW_DISCREPANCY_DIMENSIONS)
    if low.size:
        u[low] = low_discrepancy(stream.pixel_key[ids[low]], stream.sample[ids[low]], counter[low])
    stream.counter[ids] += np.uint64(1)
    return u


# ----------------------------------------------------------------------------- small helpers

def _columns(v):
    """The components (x, y, z) of rows of 3-vectors, as the shared functions take points and directions
    (of `v[:, :, None]`: columns (rows, 1), to meet spectra (rows, wavelengths))."""
    return v[:, 0], v[:, 1], v[:, 2]


def _rows(components, count):
    """Rows of 3-vectors from components (a component that is one scalar for every row is repeated)."""
    return np.stack([np.broadcast_to(c, (count,)) for c in components], axis=1)


def _direction(d, cos_theta, u):
    """Rows of unit vectors at angle acos(cos_theta) from the rows of `d`, azimuth 2πu."""
    return _rows(sample_direction(_columns(d), cos_theta, u), d.shape[0])


def _mean(values):
    """Mean over the wavelengths (columns), summed in order as in the Numba kernel."""
    total = np.zeros(values.shape[0])
    for i in range(values.shape[1]):
        total = total + values[:, i]
    return total / values.shape[1]


# ----------------------------------------------------------------------------- volume look-ups

def _coefficients(ks, points, lams):
    """Medium coefficients at points (rows) for each path wavelength (columns), summed over media;
    per-medium scattering and fluorescence coefficients (which medium scatters); emission (thermal, glow)."""
    count, n = lams.shape
    shape = (count, ks.media.density_scale.shape[0], n)
    out = _Batch(sigma_a=np.zeros((count, n)), sigma_s=np.zeros((count, n)),
                 emission=np.zeros((count, n)), medium_s=np.zeros(shape),
                 medium_fl=np.zeros(shape), dye=np.zeros(count))
    for m in range(shape[1]):
        rho = media.density(ks, m, *_columns(points)) * ks.media.density_scale[m]
        rows = np.flatnonzero(rho > 0.0)
        if rows.size == 0:
            continue
        if ks.fluorescence.strength[m] > 0.0:
            out.dye[rows] += rho[rows] * ks.fluorescence.excitation_mean[m]
        lam, r = lams[rows], rho[rows, None]
        at = on_grid(lam)
        albedo_value = (table_at(ks.media.albedo_table[m], 0, at) if ks.media.albedo_count[m] == 1
                        else media.albedo(ks, m, r / ks.media.density_scale[m], at))
        scattering, absorption, plain_absorption, fluorescence = media.collision_coefficients(
            r, table_at(ks.media.extinction, m, at), albedo_value, table_at(ks.fluorescence.excitation, m, at),
            ks.fluorescence.strength[m], table_at(ks.fluorescence.emission_pdf, m, at))
        out.medium_s[rows, m] = scattering
        out.medium_fl[rows, m] = fluorescence
        out.sigma_s[rows] += scattering
        out.sigma_a[rows] += absorption
        kelvin, planck = 0.0, 0.0
        if ks.temperature.offset[m] >= 0:
            kelvin = media.temperature(ks, m, *_columns(points[rows]))[:, None]
            planck = planck_radiance(lam, kelvin)
            out.emission[rows] += media.thermal_emission(plain_absorption, ks.temperature.map[m, 2], planck)
        if ks.glow.glowing[m]:
            out.emission[rows] += media.glow_emission(r, table_at(ks.glow.spectrum, m, at),
                                                      table_at(ks.glow.blackbody, m, at), planck,
                                                      media.blackbody_normalisation(ks, kelvin))
    return out


# ----------------------------------------------------------------------------- majorant tracking

def _tracker_start(ks, origins, directions, t_max):
    """One DDA per ray and medium over the medium's majorant blocks, in padded index space.

    phase (rays, media): 0 before entry, 1 inside, 2 done; t_entry, t_exit: the ray's span in the
    medium's block grid; cell, step, t_next, t_delta (rays, media, 3): the usual DDA state;
    lo, ld: the ray's origin and direction in the medium's padded index space."""
    count, media = origins.shape[0], ks.media.density_scale.shape[0]
    tracker = _Batch(phase=np.zeros((count, media), dtype=np.int8),
                     t_entry=np.zeros((count, media)), t_exit=np.zeros((count, media)),
                     cell=np.zeros((count, media, 3), dtype=np.int64), step=np.zeros((count, media, 3), dtype=np.int64),
                     t_next=np.zeros((count, media, 3)), t_delta=np.zeros((count, media, 3)),
                     lo=np.zeros((count, media, 3)), ld=np.zeros((count, media, 3)))
    for m in range(media):
        lo = _rows(transform_point(ks.density.world_to_padded[m], *_columns(origins)), count)
        ld = _rows(transform_vector(ks.density.world_to_padded[m], *_columns(directions)), count)
        t0, t1 = np.zeros(count), np.broadcast_to(t_max, (count,)).astype(np.float64)
        for axis in range(3):
            t0, t1 = axis_span(lo[:, axis], ld[:, axis], ks.majorant.shape[m, axis] * ks.majorant.block[m], t0, t1)
        tracker.phase[:, m] = np.where(t0 >= t1, 2, 0)
        tracker.t_entry[:, m], tracker.t_exit[:, m] = t0, t1
        tracker.lo[:, m], tracker.ld[:, m] = lo, ld
    return tracker


def _tracker_enter(ks, tracker, rays, media):
    """Put the DDAs of the (ray, medium) pairs `rays[k]`, `media[k]` into their first block."""
    cell, step, t_next, t_delta = axis_entry(tracker.lo[rays, media], tracker.ld[rays, media],
                                             tracker.t_entry[rays, media][:, None],
                                             ks.majorant.block[media][:, None], ks.majorant.shape[media])
    tracker.cell[rays, media], tracker.step[rays, media] = cell, step
    tracker.t_next[rays, media], tracker.t_delta[rays, media] = t_next, t_delta
    tracker.phase[rays, media] = 1


def _tracker_boundary(tracker):
    """(rays, media): the ray parameter where each medium's current majorant changes next."""
    inside = np.minimum(tracker.t_exit, tracker.t_next.min(axis=2))
    return np.where(tracker.phase == 0, tracker.t_entry, np.where(tracker.phase == 1, inside, INF))


def _blocks(ks, tracker):
    """(rays, media): where each medium's current block is in `majorant.data` (and `majorant.minorant`)."""
    shape = ks.majorant.shape
    cell = np.minimum(np.maximum(tracker.cell, 0), shape - 1)
    return ks.majorant.offset + (cell[..., 0] * shape[:, 1] + cell[..., 1]) * shape[:, 2] + cell[..., 2]


def _tracker_segment(ks, tracker, controls=None):
    """(end of each ray's current segment, the combined majorant σ̄ on it, control, the controls' share of
    σ̄): for the rays in mask `controls`, control is (rays, media) each medium's control σ_c, its block's
    minorant (scaled density; 0 outside its blocks and for other rays), and the share Σ σ_c·coeff (σ̄ less it
    is the residual majorant of residual ratio tracking); 0 for the other rays."""
    t_end = _tracker_boundary(tracker).min(axis=1, initial=INF)
    blocks = _blocks(ks, tracker)
    inside = tracker.phase == 1
    scaled = ks.majorant.data[blocks].astype(np.float64) * ks.majorant.coeff
    minorant = np.zeros(scaled.shape)
    if controls is not None:
        minorant = np.where(inside & controls[:, None], ks.majorant.minorant[blocks].astype(np.float64), 0.0)
    scaled_minorant = minorant * ks.majorant.coeff
    sigma_bar, control_rate = np.zeros(len(tracker)), np.zeros(len(tracker))
    for m in range(ks.majorant.shape.shape[0]):
        sigma_bar = sigma_bar + np.where(inside[:, m], scaled[:, m], 0.0)
        control_rate = control_rate + scaled_minorant[:, m]
    return t_end, sigma_bar, minorant * ks.media.density_scale, control_rate


def _tracker_advance(ks, tracker, moving, t_end):
    """For the rays in mask `moving`, move every medium whose boundary is at `t_end` into its next block
    (or out)."""
    due = moving[:, None] & (_tracker_boundary(tracker) <= t_end[:, None])
    entering = due & (tracker.phase == 0)
    inside = due & (tracker.phase == 1)
    leaving = inside & (tracker.t_exit <= t_end[:, None])
    stepping = inside & ~leaving
    if entering.any():
        _tracker_enter(ks, tracker, *np.nonzero(entering))
    tracker.phase[leaving] = 2
    if stepping.any():
        rays, media = np.nonzero(stepping)
        axis = np.argmin(tracker.t_next[rays, media], axis=1)
        tracker.cell[rays, media, axis] += tracker.step[rays, media, axis]
        tracker.t_next[rays, media, axis] += tracker.t_delta[rays, media, axis]
        cell = tracker.cell[rays, media, axis]
        gone = (cell < 0) | (cell >= ks.majorant.shape[media, axis])
        tracker.phase[rays[gone], media[gone]] = 2


def _track(ks, paths, rows, origins, directions, t_max, collide, controls=None, travel=None, residual=False):
    """Tentative collisions along rays against the majorant (delta and ratio tracking share this).

    Ray k belongs to path `rows[k]` and draws its free-flight distances from that path's stream.
    `collide(rays, points, rate)` handles the rays (indices) that have a tentative collision (drawn at that
    rate) and returns which of them stop there; a ray also stops when it leaves every medium.

    The controls of residual ratio tracking: `travel(rays, dt, control)` hears of each step before `collide`:
    the rays that move by dt (0 for those that leave) and, for those in mask `controls`, their control
    (`_tracker_segment`). With `residual`, these rays draw against σ̄ less their controls' share (the
    residual majorant); otherwise every ray draws against σ̄."""
    flight = _tracker_start(ks, origins, directions, t_max)
    flight.ray = np.arange(origins.shape[0])
    flight.t = np.zeros(origins.shape[0])
    if controls is not None:
        flight.controls = controls
    while len(flight):
        t_end, sigma_bar, control, control_rate = _tracker_segment(ks, flight,
                                                                   None if controls is None else flight.controls)
        rate = sigma_bar - control_rate if residual else sigma_bar
        escaped = t_end == INF
        drawing = ~escaped & (rate > 0.0)
        step = np.zeros(len(flight))
        step[drawing] = media.free_path(_draw(paths, rows[flight.ray[drawing]]), rate[drawing])
        crossing = ~escaped & (~drawing | (flight.t + step >= t_end))
        colliding = drawing & ~crossing
        t = np.where(crossing, t_end, np.where(colliding, flight.t + step, flight.t))
        if travel is not None:
            travel(flight.ray, t - flight.t, control)
        flight.t = t
        _tracker_advance(ks, flight, crossing, t_end)
        stop = escaped
        hits = np.flatnonzero(colliding)
        if hits.size:
            rays = flight.ray[hits]
            points = origins[rays] + flight.t[hits, None] * directions[rays]
            stop[hits] = collide(rays, points, rate[hits])
        if stop.any():
            flight = flight.take(~stop)


# ----------------------------------------------------------------------------- phase functions

def _mixture_phase(ks, medium_s, lams, cos_theta):
    """Phase pdf (= value) at each path wavelength: the σ_s-weighted mixture of the media's phases."""
    total = np.zeros(lams.shape)
    weighted = np.zeros(lams.shape)
    at = on_grid(lams)
    for m in range(medium_s.shape[1]):
        weight = medium_s[:, m]
        scatters = weight > 0.0
        pdf = media.phase_pdf(ks, m, table_at(ks.media.anisotropy, m, at), cos_theta[:, None])
        total = total + np.where(scatters, weight, 0.0)
        weighted = weighted + np.where(scatters, weight * pdf, 0.0)
    return np.where(total > 0.0, weighted / total, 0.0)


def _pick_medium(weights, u):
    """Medium index drawn ∝ weights (paths, media) with uniform numbers u."""
    total = np.zeros(weights.shape[0])
    for m in range(weights.shape[1]):
        total = total + weights[:, m]
    target = u * total
    chosen = np.full(weights.shape[0], weights.shape[1] - 1)
    open_ = np.ones(weights.shape[0], dtype=bool)
    for m in range(weights.shape[1]):
        target = target - weights[:, m]
        hit = open_ & (target < 0.0)
        chosen[hit] = m
        open_ &= ~hit
    return chosen


# ----------------------------------------------------------------------------- lights

def _sample_lights(ks, lights, points, u1, u2, lams):
    """`light_sampling.sample_light` from `points` towards each path's own light (`lights`, one index per
    path): directions w, solid-angle pdf, distance, delta flag and the radiance arriving per wavelength."""
    count = points.shape[0]
    out = _Batch(w=np.zeros((count, 3)), pdf=np.zeros(count), distance=np.zeros(count),
                 delta=np.zeros(count, dtype=bool), radiance=np.zeros(lams.shape))
    for light in range(ks.lights.kind.shape[0]):
        rows = np.flatnonzero(lights == light)
        if rows.size:
            wx, wy, wz, out.pdf[rows], out.distance[rows], falloff = sample_light(
                ks, light, *_columns(points[rows]), u1[rows], u2[rows])
            out.w[rows] = _rows((wx, wy, wz), rows.size)
            out.delta[rows] = is_delta(ks, light)
            out.radiance[rows] = incident_radiance(ks, light, on_grid(lams[rows]), *_columns(out.w[rows, :, None]),
                                                   np.broadcast_to(falloff, (rows.size,))[:, None])
    return out


def _next_area_lights(ks, origins, directions, after, after_light, t_max):
    """Each ray's next area light face after (after, after_light) (its t, then its index) and before t_max:
    (t, light), INF and -1 where none is (the Numba kernel's `_next_area_light`)."""
    best_t, best = np.full(origins.shape[0], INF), np.full(origins.shape[0], -1, dtype=np.int64)
    for light in np.flatnonzero(ks.lights.kind == LIGHT_AREA):
        t = area_light_hit(ks, light, *_columns(origins), *_columns(directions), t_max)
        closer = ((t > after) | ((t == after) & (light > after_light))) & (t < best_t)
        best_t[closer], best[closer] = t[closer], light
    return best_t, best


def _area_lights_seen(ks, paths, rows, lights, distance, radiance):
    """Radiance of the area lights (`lights`) whose emitting faces paths `rows` reach at `distance` along their
    rays from their vertices, with their weights there: plain for camera rays (where the light is visible to
    the camera), MIS-weighted against light sampling after a scattering vertex (the Numba kernel's
    `_area_light_seen`)."""
    for light in np.unique(lights):
        mine = (lights == light) & (paths.scattered[rows] | ks.lights.camera_visible[light])
        seen = rows[mine]
        emitted = area_radiance(ks, light, on_grid(paths.lams[seen]))
        cos_light = -(paths.d[seen] @ ks.lights.dir[light])
        light_pdf = (ks.lights.pmf[light] * area_direction_pdf(ks, light, *_columns(paths.o[seen]), distance[mine],
                                                               cos_light))[:, None]
        scattered = paths.scattered[seen, None]
        mean_r = _mean(hit_light_ratio(paths.r_u[seen], paths.r_l[seen], 1.0, light_pdf, scattered))[:, None]
        radiance[paths.id[seen]] += np.where(mean_r > 0.0, hit_light_contribution(paths.beta[seen], emitted, 1.0,
                                                                                  scattered, mean_r), 0.0)


# ----------------------------------------------------------------------------- surfaces

def _closest_hits(ks, origins, directions, t_max, camera=False):
    """(t, triangle) of the nearest triangle along each ray with 0 < t < t_max (t_max and -1 where none is), by
    testing every triangle (in chunks of about CHUNK_PAIRS ray–triangle pairs); rays that are `camera` rays (a
    mask, or one value for all) pass the surfaces camera rays do not see."""
    count, triangles = origins.shape[0], ks.surfaces.corner.shape[0]
    best_t, best = np.broadcast_to(t_max, (count,)).astype(np.float64), np.full(count, -1, dtype=np.int64)
    if not triangles or not count:
        return best_t, best
    step = max(1, CHUNK_PAIRS // count)
    o, d = _columns(origins[:, :, None]), _columns(directions[:, :, None])
    passing = np.broadcast_to(np.asarray(camera), (count,))[:, None]
    for first in range(0, triangles, step):
        k = np.arange(first, min(first + step, triangles))
        t = triangle_distance(ks, k[None, :], *o, *d)
        t = np.where(passing & ~ks.surfaces.camera[ks.surfaces.surface[k]][None, :], np.inf, t)
        nearest = np.argmin(t, axis=1)
        t = t[np.arange(count), nearest]
        closer = t < best_t
        best_t[closer], best[closer] = t[closer], k[nearest[closer]]
    return best_t, best


def first_hits(camera, surfaces, x0, y0, width, height, sample_begin, sample_end, seed, values, triangles):
    """The oracle of `first_hit.first_hits` (the data passes' first hits), testing every triangle: the same rays
    (band 0's film points), the same `values` and `triangles`."""
    ks = SimpleNamespace(camera=camera, surfaces=surfaces)
    samples = sample_end - sample_begin
    rows, columns, index = np.meshgrid(np.arange(height), np.arange(width), np.arange(samples), indexing="ij")
    px, py = (x0 + columns).ravel(), (y0 + rows).ravel()
    with np.errstate(over="ignore"):  # the random numbers' hashes wrap around, as they should
        keys = pixel_key(seed, 0, (py * camera.width + px).astype(np.uint64))
        sample = (sample_begin + index.ravel()).astype(np.uint64)
        u1, u2 = low_discrepancy(keys, sample, np.uint64(1)), low_discrepancy(keys, sample, np.uint64(2))
    ray = np.broadcast_arrays(*camera_ray(ks, px, py, u1, u2), np.zeros(px.size))[:6]
    t, k = _closest_hits(ks, np.stack(ray[:3], axis=1), np.stack(ray[3:], axis=1), np.inf, camera=True)
    hit = k >= 0
    depth, distance = camera_depths(camera.to_world, camera.kind, t, *ray[3:])
    normal = np.stack(facing_normal(ks, np.maximum(k, 0), *ray[3:]), axis=1) * hit[:, None]
    out = np.column_stack((np.where(hit, depth, np.inf), np.where(hit, distance, np.inf), normal))
    values[...] = out.reshape(values.shape)
    triangles[...] = k.reshape(triangles.shape)


def _shadow_blocked(ks, origins, directions, distance):
    """Which shadow rays meet a surface before `distance` (stopping SURFACE_OFFSET short of the end, which may lie
    on an emissive surface), as the Numba kernel's `_shadow_blocked`."""
    ends = origins + np.where(np.isfinite(distance), distance, 0.0)[:, None] * directions
    shortened = distance - SURFACE_OFFSET * (1.0 + np.abs(ends).max(axis=1))
    return _closest_hits(ks, origins, directions, np.where(np.isfinite(distance), shortened, INF))[1] >= 0


def _surface_emission(ks, paths, triangle, distance, survival, radiance):
    """Radiance of the emissive surfaces that paths hit (triangle, at `distance` along their rays): plain for
    camera rays, MIS-weighted against light sampling after a scattering vertex, with each path's `survival`
    along its ray (as `_escape`)."""
    light = ks.surfaces.light[ks.surfaces.surface[triangle]]
    rows = np.flatnonzero(light >= 0)
    if not rows.size:
        return
    paths, triangle, light = paths.take(rows), triangle[rows], light[rows]
    emitted = table_at(ks.lights.spd, light[:, None], on_grid(paths.lams))
    normal = ks.surfaces.normal[triangle]
    cos_light = np.abs(np.sum(normal * paths.d, axis=1))
    light_pdf = (ks.lights.pmf[light] * emitter_pdf(ks.surfaces.area[ks.surfaces.surface[triangle]], distance[rows],
                                                    cos_light))[:, None]
    survival, scattered = survival[rows, None], paths.scattered[:, None]
    mean_r = _mean(hit_light_ratio(paths.r_u, paths.r_l, survival, light_pdf, scattered))[:, None]
    radiance[paths.id] += np.where(mean_r > 0.0, hit_light_contribution(paths.beta, emitted, survival, scattered,
                                                                        mean_r), 0.0)


def _arrive_at_surfaces(ks, paths, triangle, distance):
    """Paths reaching triangles at `distance` along their rays: the surfaces' normals on the paths' side and
    their reflectance at the paths' wavelengths, the paths moved to the points leaving the surfaces there
    (as the Numba kernel's `_arrive_at_surface`); returns which paths the surfaces reflect any light of."""
    points = paths.o + distance[:, None] * paths.d
    normal = _rows(facing_normal(ks, triangle, *_columns(paths.d)), len(paths))
    paths.normal = normal
    surface = ks.surfaces.surface[triangle]
    paths.reflectance = table_at(ks.surfaces.reflectance, surface[:, None], on_grid(paths.lams))
    textured = np.flatnonzero(ks.surfaces.texture_offset[surface] >= 0)
    if textured.size:
        rgb = texel_colour(ks, surface[textured], triangle[textured], *_columns(points[textured]))
        paths.reflectance[textured] = rgb_reflectance(ks.surfaces.rgb_spectra, *(c[:, None] for c in rgb),
                                                      on_grid(paths.lams[textured]))
    paths.o = _rows(offset_point(*_columns(points), *_columns(normal)), len(paths))
    paths.on_surface = np.ones(len(paths), dtype=bool)
    return np.any((paths.reflectance > 0.0) & (paths.beta > 0.0), axis=1)


# ----------------------------------------------------------------------------- transport

def _surface_state(count, n):
    """A new batch's surface fields: not on a surface (`on_surface`), its normal and reflectance
    (`_arrive_at_surfaces`); and its sunward probe's: whether the next sun estimate weighs the probe's strategy
    in, and by what factor of r_u (`_probe`)."""
    return dict(on_surface=np.zeros(count, dtype=bool), normal=np.zeros((count, 3)), reflectance=np.zeros((count, n)),
                weighted=np.zeros(count, dtype=bool), weight=np.ones((count, n)))


def _camera_paths(ks, px, py, pixel_keys, samples):
    """New paths through pixels (px, py) (box filter), samples `samples` of the pixels keyed `pixel_keys`:
    wavelengths (hero and stratified companions) and camera rays. Returns the path batch and the camera
    wavelengths with their pdfs."""
    count, n = samples.shape[0], ks.wavelengths.per_path
    stream = _Batch(key=path_key(pixel_keys, samples), counter=np.zeros(count, dtype=np.uint64), pixel_key=pixel_keys,
                    sample=samples)
    paths = _Batch(id=np.arange(count), stream=stream,
                   lams=np.empty((count, n)), beta=np.ones((count, n)), r_u=np.ones((count, n)),
                   r_l=np.ones((count, n)), o=np.zeros((count, 3)), d=np.zeros((count, 3)),
                   depth=np.zeros(count, dtype=np.int64), scattered=np.zeros(count, dtype=bool),
                   **_surface_state(count, n))
    u = _draw(paths)
    lam_cam, pdf_cam = np.empty((count, n)), np.empty((count, n))
    for i in range(n):
        lam_cam[:, i] = sample_binned(ks.wavelengths.cdf, companion_uniform(u, i, n))
        pdf_cam[:, i] = pdf_binned(ks.wavelengths.pdf, lam_cam[:, i])
    paths.lams[:] = lam_cam
    paths.grey = _is_grey(ks, paths.lams)
    ray = camera_ray(ks, px, py, _draw(paths), _draw(paths))
    paths.o, paths.d = _rows(ray[:3], count), _rows(ray[3:], count)
    return paths, lam_cam, pdf_cam


def _offer_fluorescence(ks, paths, rows, points, sigma_bar, mean_r_u, c, fl):
    """Offer each medium's fluorescent source at the tentative collisions of paths `rows` to their
    reservoirs `fl` (indexed by path id; `fluorescent_reservoir`), as the Numba kernel's
    `_offer_fluorescence`; then the dye optical depth of each path's segment grows."""
    ids = paths.id[rows]
    beta = paths.beta[rows]
    tau = fl.tau[ids]
    guides = None  # each reservoir's guide at each row's τ, once some medium offers (never without a dye)
    for m in range(ks.media.density_scale.shape[0]):
        if ks.fluorescence.strength[m] <= 0.0:  # no dye: nothing to offer
            continue
        source = np.zeros(rows.size)
        for i in range(beta.shape[1]):  # summed in order, as in the Numba kernel
            source = source + beta[:, i] * c.medium_fl[:, m, i]
        offering = np.flatnonzero(source > 0.0)
        if not offering.size:
            continue
        weight = collision_estimate(source[offering], sigma_bar[offering], mean_r_u[offering])
        if guides is None:
            guides = (None, front_guide(tau), back_guide(tau))
        u = _draw(paths, rows[offering])
        for k in range(RESERVOIRS):
            guided = weight if k == 0 else weight * guides[k][offering]
            fl.total[ids[offering], k] += guided
            kept = offering[u * fl.total[ids[offering], k] < guided]
            fl.point[ids[kept], k] = points[kept]
            fl.medium[ids[kept], k] = m
            fl.depth[ids[kept], k] = paths.depth[rows[kept]] + 1
            fl.tau_at[ids[kept], k] = tau[kept]
            fl.share[ids[kept], k, :beta.shape[1]] = beta[kept] * c.medium_fl[kept, m] / source[kept, None]
    fl.tau[ids] = tau + c.dye / sigma_bar


def _free_flight(ks, paths, radiance, fl, t_max, collect=True):
    """Delta tracking of every path to its next real event before t_max (a surface, or INF), collecting emission
    (thermal, glow) and offering fluorescent sources at each tentative collision and weighting null collisions
    (spectral MIS ratios included). Grey paths after a scattering vertex (`_is_grey`) integrate their controls
    instead of putting null-event probabilities into `r_l`, as the Numba kernel's `_free_flight`.

    Returns each path's event (EVENT_ESCAPE for one that reaches t_max), the vertex data of scattering events
    (position q and the per-medium σ_s at q) and each path's survival along its ray as a shadow ray would give it
    (`_transmittance`; 1 where `r_l` has the null-event probabilities), for `_escape` and `_surface_emission`.

    Without `collect` (sunward probes, `_probe`), nothing is collected or offered and no area light is looked for,
    and no path integrates its controls."""
    count, n = paths.lams.shape
    vertex = _Batch(event=np.full(count, EVENT_ESCAPE, dtype=np.int8), q=np.zeros((count, 3)),
                    medium_s=np.zeros((count, ks.media.density_scale.shape[0], n)), survival=np.ones(count))
    controls = paths.grey & paths.scattered & collect
    depth = np.zeros((count, ks.media.density_scale.shape[0]))  # the controls' integral along each ray so far
    t_light, seen = (_next_area_lights(ks, paths.o, paths.d, 0.0, -1, t_max) if collect
                     else (np.full(count, INF), np.full(count, -1)))

    def pass_lights(rows, t):
        """Add the area lights that paths `rows` pass before t (as the Numba kernel's `_free_flight`)."""
        k = np.flatnonzero(t > t_light[rows])
        while k.size:
            passing = rows[k]
            _area_lights_seen(ks, paths, passing, seen[passing], t_light[passing], radiance)
            t_light[passing], seen[passing] = _next_area_lights(ks, paths.o[passing], paths.d[passing],
                                                                t_light[passing], seen[passing],
                                                                np.broadcast_to(t_max, (count,))[passing])
            k = k[t[k] > t_light[passing]]

    def travel(rays, dt, control):
        depth[rays] += control * dt[:, None]

    def collide(rows, points, sigma_bar):
        c = _coefficients(ks, points, paths.lams[rows])
        beta, r_u, r_l = paths.beta[rows], paths.r_u[rows], paths.r_l[rows]
        bar = sigma_bar[:, None]
        if collect:
            pass_lights(rows, np.sum((points - paths.o[rows]) * paths.d[rows], axis=1))
            mean_r_u = _mean(r_u)
            radiance[paths.id[rows]] += np.where(c.emission > 0.0,
                                                 collision_estimate(beta * c.emission, bar, mean_r_u[:, None]), 0.0)
            _offer_fluorescence(ks, paths, rows, points, sigma_bar, mean_r_u, c, fl)
        choice = _draw(paths, rows) * sigma_bar
        # A real collision scatters, weighted by the albedo (as in the Numba kernel).
        collided = choice < c.sigma_a[:, 0] + c.sigma_s[:, 0]
        p0 = np.where(collided, real_probability(c.sigma_a[:, 0], c.sigma_s[:, 0], sigma_bar),
                      media.null_fraction(sigma_bar, c.sigma_a[:, 0], c.sigma_s[:, 0]))[:, None]
        real = real_collision(beta, r_u, c.sigma_a, c.sigma_s, bar, p0)
        null = null_collision(beta, r_u, r_l, c.sigma_a, c.sigma_s, bar, p0, controls[rows, None])
        beta, r_u, r_l = (np.where(collided[:, None], real[0], null[0]), np.where(collided[:, None], real[1], null[1]),
                          np.where(collided[:, None], r_l, null[2]))
        paths.beta[rows], paths.r_u[rows], paths.r_l[rows] = beta, r_u, r_l
        alive = np.any(beta > 0.0, axis=1)
        scattered = collided & alive
        stop = collided | ~alive
        vertex.event[rows[stop]] = np.where(scattered, EVENT_SCATTER, EVENT_ABSORB)[stop]
        keep = rows[scattered]
        vertex.q[keep], vertex.medium_s[keep] = points[scattered], c.medium_s[scattered]
        return stop

    if collect:
        fl.tau[paths.id] = 0.0
    _track(ks, paths, np.arange(count), paths.o, paths.d, t_max, collide, controls=controls,
           travel=travel if controls.any() else None)
    if not collect:
        return vertex
    escaped = np.flatnonzero(vertex.event == EVENT_ESCAPE)
    pass_lights(escaped, np.full(escaped.size, INF))
    escaped = np.flatnonzero(controls & (vertex.event == EVENT_ESCAPE))
    spectra = _attenuation_spectra(ks, paths.lams[escaped, :1])
    vertex.survival[escaped] = controls_transmittance(_control_depth(depth[escaped], *spectra)[:, 0])
    return vertex


def _escape(ks, paths, radiance, survival):
    """Radiance of the infinite lights seen by escaping paths: plain for camera rays, MIS-weighted
    against light sampling after a scattering vertex, with each path's `survival` along its ray
    (`_free_flight`)."""
    at = on_grid(paths.lams)
    directions = _columns(paths.d[:, :, None])
    survival, scattered = survival[:, None], paths.scattered[:, None]
    for light in range(ks.lights.kind.shape[0]):
        light_radiance = infinite_radiance(ks, light, at, *directions)
        light_pdf = ks.lights.pmf[light] * infinite_pdf(ks, light, *directions)
        mean_r = _mean(hit_light_ratio(paths.r_u, paths.r_l, survival, light_pdf, scattered))[:, None]
        radiance[paths.id] += np.where(mean_r > 0.0, hit_light_contribution(paths.beta, light_radiance, survival,
                                                                            scattered, mean_r), 0.0)


def _holes(ks, paths, sky, surface, triangle):
    """Which escaping paths (`sky`) or paths reaching a surface (`surface`, at `triangle`) see through: camera
    rays (not scattered) reaching the background with Film ▸ Transparent on, or a holdout surface."""
    camera = ~paths.scattered
    holdout = (ks.surfaces.holdout[ks.surfaces.surface[np.maximum(triangle, 0)]] if ks.surfaces.surface.size
               else False)
    return camera & ((sky & ks.camera.transparent) | (surface & holdout))


def _see_through(ks, paths, transparent):
    """Camera paths that see through (`_holes`): their throughput into their transparency, as `transparency`
    weighs it (the Numba kernel's `_see_through`); nothing with Film ▸ Transparent off (a holdout is black)."""
    if not ks.camera.transparent:
        return
    mean_r = _mean(paths.r_u)
    n = paths.lams.shape[1]
    total = np.zeros(len(paths))
    for i in range(n):
        weight = transparency_weight(ks, paths.lams[:, i], pdf_binned(ks.wavelengths.pdf, paths.lams[:, i]), n)
        total = total + np.where(mean_r > 0.0, paths.beta[:, i] / mean_r * weight, 0.0)
    transparent[paths.id] += total


def _attenuation_spectra(ks, lams):
    """(extinction, excitation), each (rays, media, wavelengths): every medium's spectra at the rays'
    wavelengths `lams` (rays, wavelengths)."""
    at = on_grid(lams)
    extinction, excitation = np.zeros((2, lams.shape[0], ks.media.density_scale.shape[0], lams.shape[1]))
    for m in range(ks.media.density_scale.shape[0]):
        extinction[:, m] = table_at(ks.media.extinction, m, at)
        excitation[:, m] = table_at(ks.fluorescence.excitation, m, at)
    return extinction, excitation


def _control_depth(depth, extinction, excitation):
    """(rays, wavelengths): the controls' optical depth, from each medium's integral `depth` (rays, media) of
    its control and its spectra (`_attenuation_spectra`)."""
    total = np.zeros((depth.shape[0], extinction.shape[2]))
    for m in range(depth.shape[1]):
        total = total + media.attenuation(depth[:, m, None], extinction[:, m], excitation[:, m])
    return total


def _is_grey(ks, lams):
    """The Numba kernel's `_is_grey` for paths of wavelengths `lams`: a light is not a delta light and every
    medium attenuates each path's wavelengths alike (to GREY_SPREAD); never with an area light."""
    if all(is_delta(ks, light) for light in range(ks.lights.kind.shape[0])) or np.any(ks.lights.kind == LIGHT_AREA):
        return np.zeros(lams.shape[0], dtype=bool)
    value = media.attenuation(1.0, *_attenuation_spectra(ks, lams))
    first = value[:, :, :1]
    return np.all(attenuates_alike(value, first), axis=(1, 2))


def _transmittance(ks, paths, rows, origins, directions, t_max, lams, residual):
    """Ratio tracking along shadow rays (ray k from path rows[k]): the transmittance per wavelength and
    the unidirectional strategy's survival for MIS (the Numba kernel's `_transmittance`): the product of
    the null-event probabilities σ_n/σ̄ at its tentative collisions. The rays in mask `residual` (towards
    delta lights, and of grey paths) use residual ratio tracking: their blocks' minorants are integrated
    exactly (`depth`), only the rest is ratio-tracked, and their survival is the controls' transmittance.
    Faint rays (every transmittance, bounded with the least control depth, below SHADOW_ROULETTE_BELOW)
    play Russian roulette at each tentative collision."""
    count, n = lams.shape
    transmittance = np.ones(lams.shape)
    survival = np.ones(lams.shape)
    extinction, excitation = _attenuation_spectra(ks, lams)
    depth = np.zeros((count, ks.media.density_scale.shape[0]))  # the controls' integral along each ray so far
    control_now = np.zeros(depth.shape)

    def control_depth(rays):
        return _control_depth(depth[rays], extinction[rays], excitation[rays])

    def faint_survives(rays):
        """Russian roulette on the faint rays among `rays`; which of them stop."""
        largest = np.max(transmittance[rays], axis=1, initial=0.0)
        bounded = np.flatnonzero(residual[rays] & (largest >= SHADOW_ROULETTE_BELOW))
        least = np.min(control_depth(rays[bounded]), axis=1, initial=INF)
        largest[bounded] = shadow_bound(largest[bounded], least)
        faint = np.flatnonzero((largest > 0.0) & (largest < SHADOW_ROULETTE_BELOW))
        transmittance[rays[faint]] = shadow_roulette(transmittance[rays[faint]],
                                                     _draw(paths, rows[rays[faint]])[:, None])
        stop = largest == 0.0
        stop[faint] = ~np.any(transmittance[rays[faint]] > 0.0, axis=1)
        return stop

    def travel(rays, dt, control):
        depth[rays] += control * dt[:, None]
        control_now[rays] = control

    def collide(rays, points, rate):
        excess = np.zeros((rays.size, n))
        for m in range(depth.shape[1]):
            rho = media.density(ks, m, *_columns(points)) * ks.media.density_scale[m] - control_now[rays, m]
            excess = excess + media.attenuation(rho[:, None], extinction[rays, m], excitation[rays, m])
        transmittance[rays], survival[rays] = ratio_tracked(transmittance[rays], survival[rays], rate[:, None], excess,
                                                            residual[rays, None])
        return faint_survives(rays)

    _track(ks, paths, rows, origins, directions, t_max, collide, controls=residual, travel=travel, residual=True)
    transmittance[residual], survival[residual] = residual_tracked(transmittance[residual],
                                                                   control_depth(np.flatnonzero(residual)))
    return transmittance, survival


def _next_event(ks, paths, vertex, isotropic, radiance, probing=False, held=None):
    """Next-event estimation from every vertex: one light chosen by its pmf, ratio-tracked
    transmittance (residual ratio tracking towards delta lights and on grey paths), MIS against phase
    sampling (balance heuristic over wavelengths and strategies). The paths `weighted` weigh the sunward
    probe's strategy into their sun's estimate (`weight`). Sunward probes at their collisions (`probing`, as
    the Numba kernel's `_next_event`): the probe's sun, chosen with certainty (its estimate times the chance
    the path's own choice gives it), their light also added to `held` (by path id) where it is given."""
    if probing:
        u1, u2 = _draw(paths), _draw(paths)
        lights = np.full(len(paths), ks.lights.probe[0])
    else:
        choice, u1, u2 = _draw(paths), _draw(paths), _draw(paths)
        lights = choose_light(ks.lights.pmf, choice)
    sample = _sample_lights(ks, lights, paths.o, u1, u2, paths.lams)
    cos_theta = (paths.d[:, 0] * sample.w[:, 0] + paths.d[:, 1] * sample.w[:, 1]
                 + paths.d[:, 2] * sample.w[:, 2])
    cos_surface = (paths.normal[:, 0] * sample.w[:, 0] + paths.normal[:, 1] * sample.w[:, 1]
                   + paths.normal[:, 2] * sample.w[:, 2])
    phase_values = np.where(isotropic[:, None], INV_FOUR_PI,
                            _mixture_phase(ks, vertex.medium_s, paths.lams, cos_theta))
    phase_values = np.where(paths.on_surface[:, None], lambert_pdf(cos_surface)[:, None], phase_values)
    lit = np.any((sample.radiance > 0.0) & (phase_values > 0.0) & (paths.beta > 0.0), axis=1)
    candidates = np.flatnonzero(lit)
    lit[candidates] = ~_shadow_blocked(ks, paths.o[candidates], sample.w[candidates], sample.distance[candidates])
    rows = np.flatnonzero(lit)
    if rows.size == 0:
        return
    transmittance, survival = _transmittance(ks, paths, rows, paths.o[rows], sample.w[rows], sample.distance[rows],
                                             paths.lams[rows], sample.delta[rows] | paths.grey[rows])
    weighted = (paths.weighted[rows] & ~paths.on_surface[rows] & (lights[rows] == ks.lights.probe[0]))[:, None]
    r_u = np.where(weighted, paths.r_u[rows] * paths.weight[rows], paths.r_u[rows])
    phase_values = phase_values[rows]
    light_pdf = (ks.lights.pmf[lights[rows]] * sample.pdf[rows])[:, None]
    mean_r = _mean(light_sample_ratio(r_u, light_pdf, phase_values, survival, sample.delta[rows, None]))
    counted = mean_r > 0.0
    values = np.where(paths.on_surface[rows, None], phase_values * paths.reflectance[rows], phase_values)
    contribution = next_event_contribution(paths.beta[rows], values, transmittance, sample.radiance[rows],
                                           mean_r[:, None])
    if probing:
        contribution = ks.lights.pmf[lights[rows]][:, None] * contribution
    radiance[paths.id[rows[counted]]] += contribution[counted]
    if held is not None:
        held[paths.id[rows[counted]]] += contribution[counted]


def _sample_phase(ks, paths, vertex, isotropic):
    """Phase sampling of the next direction (the hero's phase; MIS pdfs at every wavelength), or on a surface
    cosine-weighted sampling (the same pdf at every wavelength: the throughput takes the reflectance).
    Returns which paths continue (those whose hero pdf is positive)."""
    u1, u2 = _draw(paths), _draw(paths)
    new_cos = 1.0 - 2.0 * u1
    surface = paths.on_surface
    anisotropic = np.flatnonzero(~isotropic & ~surface)
    new_cos[anisotropic] = _hero_phase_cos(ks, paths, anisotropic, vertex.medium_s[anisotropic], u1[anisotropic])
    new_cos[surface] = lambert_sample_cos(u1[surface])
    direction = _direction(np.where(surface[:, None], paths.normal, paths.d), new_cos, u2)
    phase_values = np.where(isotropic[:, None], INV_FOUR_PI,
                            _mixture_phase(ks, vertex.medium_s, paths.lams, new_cos))
    phase_values = np.where(surface[:, None], lambert_pdf(new_cos)[:, None], phase_values)
    pdf0 = phase_values[:, :1]
    sampled = np.where(surface[None, :, None], lambert_sampled(paths.beta, paths.r_u, paths.reflectance, pdf0),
                       phase_sampled(paths.beta, paths.r_u, phase_values, pdf0))
    paths.beta, paths.r_u, paths.r_l = sampled
    paths.d = _rows(normalize(*_columns(direction)), len(paths))
    paths.scattered[:] = True
    return pdf0[:, 0] > 0.0, phase_values


def _hero_phase_cos(ks, paths, rows, medium_s, u1):
    """cos θ drawn from the hero's phase function for paths `rows` (their per-medium σ_s `medium_s`): a medium
    drawn ∝ its σ_s at the hero wavelength, then its phase function (as the Numba kernel's `_phase_direction`)."""
    new_cos = np.zeros(rows.size)
    medium = _pick_medium(medium_s[:, :, 0], _draw(paths, rows))
    for m in range(ks.media.density_scale.shape[0]):
        mine = medium == m
        if ks.media.phase_kind[m] == PHASE_RAYLEIGH:
            new_cos[mine] = rayleigh_sample_cos(u1[mine])
        else:
            new_cos[mine] = hg_sample_cos(table_at(ks.media.anisotropy, m, on_grid(paths.lams[rows[mine], 0])),
                                          u1[mine])
    return new_cos


def _roulette(ks, paths):
    """Russian roulette on the MIS-weighted throughput once paths reach `rr_depth`; returns survivors."""
    survival = roulette_survival(np.max(paths.beta / _mean(paths.r_u)[:, None], axis=1, initial=0.0))
    playing = np.flatnonzero((paths.depth >= ks.termination.rr_depth) & (survival < 1.0))
    survive = survival[playing]
    lost = _draw(paths, playing) >= survive
    paths.beta[playing] /= survive[:, None]
    keep = np.ones(len(paths), dtype=bool)
    keep[playing[lost]] = False
    return keep


def _scatter(ks, paths, vertex, isotropic, radiance, marks=None):
    """Next-event estimation and phase sampling at every path's vertex (isotropic where `isotropic`), the
    sunward probes (`_probe`), then Russian roulette; returns the paths still alive. With `marks` (camera paths,
    `_Marks`), the paths at their first vertex take their mark after next-event estimation."""
    if ks.lights.kind.shape[0] > 0:
        _next_event(ks, paths, vertex, isotropic, radiance)
    paths.weighted[:] = False
    if marks is not None:
        marks.take(paths.id[marks.taken[paths.id] == AFTER_NEE], AFTER_NEE, radiance)
    probing = (ks.lights.probe[0] >= 0) & ~isotropic & ~paths.on_surface & (paths.depth < ks.termination.max_depth)
    start = paths.beta.copy(), paths.r_u.copy(), paths.d.copy()
    keep, phase_values = _sample_phase(ks, paths, vertex, isotropic)
    rows = np.flatnonzero(probing & keep)
    if rows.size:
        _probe(ks, paths, rows, vertex, start, phase_values, radiance, marks)
    paths = paths.take(keep)
    return paths.take(_roulette(ks, paths))


def _probe(ks, paths, rows, vertex, start, phase_values, radiance, marks):
    """The sunward probes (`probe_grid`, the Numba kernel's `_probe_from`) at the medium vertices of paths `rows`,
    which have drawn their directions (their phase values there: `phase_values`; `start`: their β, r_u and
    direction before the draw): where every wavelength scatters and the chance a(o) is positive, the factor of r_u
    in the path's next sun estimate (`weight`); then, with probability a(o), a probe drawn about the sun, tracked
    to its next real collision (nothing collected) and its sun estimate made there (also held for the marks)."""
    medium_s = vertex.medium_s[rows]
    chance = probe_chance(ks, *_columns(paths.o[rows]))
    eligible = np.all(np.sum(medium_s, axis=1) > 0.0, axis=1) & (chance > 0.0)
    rows, medium_s, chance = rows[eligible], medium_s[eligible], chance[eligible]
    if not rows.size:
        return
    w = ks.lights.dir[ks.lights.probe[0]]
    d = paths.d[rows]
    sun_phase = _mixture_phase(ks, medium_s, paths.lams[rows], d[:, 0] * w[0] + d[:, 1] * w[1] + d[:, 2] * w[2])
    paths.weight[rows] = probe_weight(phase_values[rows], chance[:, None], sun_phase)
    paths.weighted[rows] = True
    sent = _draw(paths, rows) < chance
    rows, medium_s, chance = rows[sent], medium_s[sent], chance[sent]
    if not rows.size:
        return
    u1, u2 = _draw(paths, rows), _draw(paths, rows)
    sun_cos = _hero_phase_cos(ks, paths, rows, medium_s, u1)
    p = _rows(normalize(*_columns(_direction(np.tile(w, (rows.size, 1)), sun_cos, u2))), rows.size)
    sun_phase = _mixture_phase(ks, medium_s, paths.lams[rows], sun_cos)
    beta, r_u, incoming = (value[rows] for value in start)
    phase = _mixture_phase(ks, medium_s, paths.lams[rows],
                           incoming[:, 0] * p[:, 0] + incoming[:, 1] * p[:, 1] + incoming[:, 2] * p[:, 2])
    probes = paths.take(rows)
    probes.beta, probes.r_u = probe_sampled(beta, r_u, phase, chance[:, None], sun_phase)
    probes.r_l, probes.d, probes.weighted = probes.r_u.copy(), p, np.zeros(rows.size, dtype=bool)
    t_hit, _ = _closest_hits(ks, probes.o, probes.d, INF)
    found = _free_flight(ks, probes, radiance, None, t_hit, collect=False)
    arrived = found.event == EVENT_SCATTER
    if not arrived.any():
        return
    probes, found = probes.take(arrived), found.take(arrived)
    probes.o = found.q
    _next_event(ks, probes, found, np.zeros(len(probes), dtype=bool), radiance, probing=True,
                held=None if marks is None else marks.held)


class _Marks:
    """The camera paths' marks of their radiance (`light_split`), by path id: the marks (paths, MARKS, n), how
    many each has taken, and what each met first (the Numba kernel's `Path.marks` and `Path.first`)."""

    def __init__(self, count, n):
        self.values = np.zeros((count, MARKS, n))
        self.held = np.zeros((count, n))  # what sunward probes brought before the second mark, which it leaves out
        self.taken = np.zeros(count, dtype=np.int64)
        self.first = np.zeros(count, dtype=np.int64)

    def take(self, ids, index, radiance):
        """Paths `ids` take their mark `index`: their radiance now (the second: but for what probes from the first
        vertex brought, light scattered at a second vertex, indirect; the Numba kernel's `_mark`)."""
        self.values[ids, index] = radiance[ids] - self.held[ids] if index == SECOND else radiance[ids]
        self.taken[ids] = index + 1

    def at_vertex(self, paths, radiance):
        """The paths reach a vertex: their first (what it is, and the mark), or their second (the mark)."""
        taken = self.taken[paths.id]
        first = paths.id[taken == FIRST]
        self.first[first] = np.where(paths.on_surface[taken == FIRST], SURFACE, MEDIUM)
        self.take(first, FIRST, radiance)
        self.take(paths.id[taken == SECOND], SECOND, radiance)

    def finish(self, radiance):
        """Marks a path never reached are its radiance."""
        for index in range(MARKS):
            ids = np.flatnonzero(self.taken <= index)
            self.values[ids, index] = radiance[ids] - self.held[ids] if index == SECOND else radiance[ids]
        self.taken[:] = MARKS

    def add_fluorescence(self, ids, depth, contribution):
        """Sub-paths from collisions at vertex `depth` (of paths `ids`) add `contribution` (rows, n): as a medium's
        emission there, to the marks taken after it."""
        self.values[ids[depth == 1]] += contribution[depth == 1][:, None, :]
        self.values[ids[depth == 2], SECOND] += contribution[depth == 2]


def _bounce(ks, paths, radiance, fl, transparent, marks=None):
    """Every live path to its next scattering vertex (in a medium or on a surface) and past it; returns the
    paths still alive. Camera paths that see through add to `transparent` (`_holes`); with `marks`, they take
    their marks (`_Marks`)."""
    t_hit, triangle = _closest_hits(ks, paths.o, paths.d, INF, camera=~paths.scattered)
    vertex = _free_flight(ks, paths, radiance, fl, t_hit)
    escaped = vertex.event == EVENT_ESCAPE
    sky, surface = escaped & (triangle < 0), escaped & (triangle >= 0)
    holes = _holes(ks, paths, sky, surface, triangle)
    if holes.any():
        _see_through(ks, paths.take(holes), transparent)
        sky, surface = sky & ~holes, surface & ~holes
    if sky.any():
        if marks is not None:
            background = paths.id[sky & ~paths.scattered]
            marks.first[background] = BACKGROUND
            marks.take(background, FIRST, radiance)
        _escape(ks, paths.take(sky), radiance, vertex.survival[sky])
    if surface.any():
        _surface_emission(ks, paths.take(surface), triangle[surface], t_hit[surface], vertex.survival[surface],
                          radiance)
    deep_enough = paths.depth + 1 <= ks.termination.max_depth
    real = (vertex.event == EVENT_SCATTER) & deep_enough
    surface &= deep_enough
    arriving = np.flatnonzero(surface)
    if arriving.size:
        at_surface = paths.take(arriving)
        reflects = _arrive_at_surfaces(ks, at_surface, triangle[arriving], t_hit[arriving])
        for name in ("o", "normal", "reflectance", "on_surface"):
            getattr(paths, name)[arriving] = getattr(at_surface, name)
        surface[arriving[~reflects]] = False
    paths.o[real] = vertex.q[real]
    paths.on_surface[real] = False
    moving = real | surface
    paths, vertex = paths.take(moving), vertex.take(moving)
    if not len(paths):
        return paths
    paths.depth += 1
    if marks is not None:
        marks.at_vertex(paths, radiance)
    return _scatter(ks, paths, vertex, np.zeros(len(paths), dtype=bool), radiance, marks)


def _choose_sources(stream, fl, ids, reservoir, weight):
    """After a round of transport of paths `ids`: the reservoir whose collision starts each one's next
    fluorescent sub-path (into `reservoir`) and that collision's weight w / p (into `weight`; 0 where
    nothing was offered), as the Numba kernel's `_chosen_source`."""
    weight[ids] = 0.0
    offered = ids[fl.total[ids, 0] > 0.0]
    if offered.size:
        chosen = chosen_reservoir(_draw(_Batch(id=offered, stream=stream)))
        reservoir[offered] = chosen
        totals = fl.total[offered]
        weight[offered] = mixture_weight(fl.tau_at[offered, chosen], totals[:, 0], totals[:, 1], totals[:, 2])


def _fluorescent_paths(ks, stream, ids, reservoir, fl):
    """One-wavelength sub-paths from the chosen reservoirs' collisions of paths `ids` (as the Numba
    kernel's `_start_fluorescent_branch`): λ_in drawn ∝ the excitation of the medium that fluoresces,
    fresh weights, empty reservoirs; each emits isotropically (`_scatter`)."""
    count = ids.size
    chosen = reservoir[ids]
    paths = _Batch(id=ids, stream=stream, lams=np.zeros((count, 1)), beta=np.ones((count, 1)),
                   r_u=np.ones((count, 1)), r_l=np.ones((count, 1)), o=fl.point[ids, chosen],
                   d=np.tile([0.0, 0.0, 1.0], (count, 1)), depth=fl.depth[ids, chosen],
                   scattered=np.ones(count, dtype=bool), **_surface_state(count, 1))
    u = _draw(paths)
    for m in range(ks.media.density_scale.shape[0]):
        dyed = fl.medium[ids, chosen] == m
        paths.lams[dyed, 0] = sample_binned(ks.fluorescence.excitation_cdf[m], u[dyed])
        paths.beta[dyed, 0] = linear_over_binned(ks.fluorescence.excitation[m], paths.lams[dyed, 0])
    paths.grey = _is_grey(ks, paths.lams)
    fl.total[ids] = 0.0
    return paths


def _trace(ks, px, py, pixel_keys, samples, light_passes=False):
    """XYZ estimates (paths, 3) and transparencies (paths,) of one camera path per sample, through pixels
    (px, py) keyed `pixel_keys`: the camera paths, then rounds of fluorescent sub-paths (the Numba kernel's
    `_trace`); with `light_passes` each path's light categories' XYZ (paths, CATEGORIES, 3), else None; and the
    spectral estimates (`_path_spectrum`, unclamped). The XYZ are clamped where the scene clamps (`_split_light`)."""
    paths, lam_cam, pdf_cam = _camera_paths(ks, px, py, pixel_keys, samples)
    count, n = lam_cam.shape
    stream = paths.stream
    fl = _Batch(total=np.zeros((count, RESERVOIRS)), point=np.zeros((count, RESERVOIRS, 3)),
                share=np.zeros((count, RESERVOIRS, n)), medium=np.zeros((count, RESERVOIRS), dtype=np.int64),
                depth=np.zeros((count, RESERVOIRS), dtype=np.int64), tau_at=np.zeros((count, RESERVOIRS)),
                tau=np.zeros(count))
    radiance, transparent = np.zeros((count, n)), np.zeros(count)
    term = ks.termination
    marks = _Marks(count, n) if light_passes or term.clamp_direct > 0.0 or term.clamp_indirect > 0.0 else None
    while len(paths):
        paths = _bounce(ks, paths, radiance, fl, transparent, marks)
    if marks is not None:
        marks.finish(radiance)
    everyone = np.arange(count)
    reservoir, weight = np.zeros(count, dtype=np.int64), np.zeros(count)
    _choose_sources(stream, fl, everyone, reservoir, weight)
    scale = weight[:, None] * fl.share[everyone, reservoir]
    ids = np.flatnonzero((weight > 0.0) & (fl.depth[everyone, reservoir] <= ks.termination.max_depth))
    while ids.size:
        depth = fl.depth[ids, reservoir[ids]]
        paths = _fluorescent_paths(ks, stream, ids, reservoir, fl)
        emitted = np.zeros((count, 1))
        paths = _scatter(ks, paths, _Batch(medium_s=np.zeros((ids.size, ks.media.density_scale.shape[0], 1))),
                         np.ones(ids.size, dtype=bool), emitted)
        while len(paths):
            paths = _bounce(ks, paths, emitted, fl, transparent)
        radiance[ids] += scale[ids] * emitted[ids]
        if marks is not None:
            marks.add_fluorescence(ids, depth, scale[ids] * emitted[ids])
        _choose_sources(stream, fl, ids, reservoir, weight)
        scale[ids] *= weight[ids, None]
        ids = ids[(weight[ids] > 0.0) & (fl.depth[ids, reservoir[ids]] <= ks.termination.max_depth)]
    xyz, spectrum = _xyz(ks, lam_cam, pdf_cam, radiance), _path_spectrum(ks, lam_cam, pdf_cam, radiance)
    if marks is None:
        return xyz, transparent, None, spectrum
    xyz, light = _split_light(ks, marks, lam_cam, pdf_cam, xyz, light_passes)
    return xyz, transparent, light, spectrum


def _xyz(ks, lam_cam, pdf_cam, radiance):
    """XYZ (paths, 3) of each path's radiance (paths, n): each camera wavelength's over its pdf, through the XYZ
    weights."""
    count, n = lam_cam.shape
    xyz = np.zeros((count, 3))
    for i in range(n):
        counted = (radiance[:, i] != 0.0) & (pdf_cam[:, i] > 0.0)
        scale_i = camera_estimate(radiance[:, i], pdf_cam[:, i], n)
        at = on_grid(lam_cam[:, i])
        for c in range(3):
            xyz[:, c] += np.where(counted, scale_i * table_at(ks.wavelengths.xyz_weights, c, at), 0.0)
    return xyz


def _path_spectrum(ks, lam_cam, pdf_cam, radiance):
    """Each camera wavelength's bin (paths, n; -1 outside the bins) and its addition there (`spectrum_bins`), or
    None without bins."""
    edges = ks.wavelengths.spectrum_edges
    if edges.shape[0] == 0:
        return None
    bins = spectrum_bin(edges, lam_cam).astype(np.int64)
    return bins, spectrum_weight(edges, radiance, pdf_cam, lam_cam.shape[1])


def _split_light(ks, marks, lam_cam, pdf_cam, xyz, light_passes):
    """The paths' XYZ clamped (Light Paths ▸ Clamping, `light_split`), and with `light_passes` split by their marks
    into the light categories (paths, CATEGORIES, 3) (else None), as the Numba kernel's `_split_light`."""
    first, after_nee, second = (_xyz(ks, lam_cam, pdf_cam, marks.values[:, index]) for index in (FIRST, AFTER_NEE,
                                                                                               SECOND))
    term = ks.termination
    direct = clamp_factor(*after_nee.T, term.xyz_to_rgb, term.clamp_direct)[:, None]
    indirect = clamp_factor(*(xyz - after_nee).T, term.xyz_to_rgb, term.clamp_indirect)[:, None]
    clamped = ((direct < 1.0) | (indirect < 1.0))[:, 0]  # the other paths stay exactly as unclamped
    xyz = np.where(clamped[:, None], clamped_mark(xyz, after_nee, direct, indirect), xyz)
    second = np.where(clamped[:, None], clamped_mark(second, after_nee, direct, indirect), second)
    first = np.where(clamped[:, None], direct * first, first)
    if not light_passes:
        return xyz, None
    light = np.zeros((xyz.shape[0], CATEGORIES, 3))
    rows = np.arange(xyz.shape[0])
    light[:, EMISSION] = first
    background = marks.first == BACKGROUND
    light[background, ENVIRONMENT] = xyz[background] - first[background]
    slot = direct_slot(marks.first)
    vertex = ~background
    light[rows[vertex], slot[vertex]] = second[vertex] - first[vertex]
    light[rows[vertex], slot[vertex] + 1] = xyz[vertex] - second[vertex]
    return xyz, light


def render_tile(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                sum_transparent, sum_light_passes, sum_spectrum):
    """Add samples [sample_begin, sample_end) of every pixel of a tile to the accumulators
    `sum_xyz` and `sum_sq` (shape (tile_height, tile_width, 3): Σ XYZ and Σ XYZ² per pixel),
    `sum_transparent` (shape (tile_height, tile_width): Σ transparency, `kernels/transparency.py`),
    `sum_light_passes` (shape (tile_height, tile_width, K, 3): Σ XYZ of each light category, `light_split`; K is
    `light_split.CATEGORIES`, or 0 for none) and `sum_spectrum` (shape (tile_height, tile_width, B): Σ of each bin's
    estimate, `kernels/spectrum_bins.py`; B = 0: none)."""
    light_passes = sum_light_passes.shape[2] > 0
    samples = sample_end - sample_begin
    total = tile_width * tile_height * samples
    for start in range(0, total, CHUNK_PATHS):
        index = np.arange(start, min(start + CHUNK_PATHS, total))
        pixel, sample = np.divmod(index, samples)
        row, column = np.divmod(pixel, tile_width)
        px, py = x0 + column, y0 + row
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            pixel_keys = pixel_key(seed, band, py * ks.camera.width + px)
            xyz, transparent, light, spectrum = _trace(ks, px, py, pixel_keys,
                                                       (sample_begin + sample).astype(np.uint64), light_passes)
        np.add.at(sum_xyz, (row, column), xyz)
        if light is not None:
            np.add.at(sum_light_passes, (row, column), light)
        np.add.at(sum_sq, (row, column), xyz * xyz)
        np.add.at(sum_transparent, (row, column), transparent)
        if sum_spectrum.shape[2] and spectrum is not None:
            bins, values = spectrum
            inside = bins >= 0  # in the order the Numba kernel adds them: by path, then by camera wavelength
            np.add.at(sum_spectrum, (np.broadcast_to(row[:, None], bins.shape)[inside],
                                     np.broadcast_to(column[:, None], bins.shape)[inside], bins[inside]), values[inside])


def set_threads(count: int) -> None:
    """Does nothing: this backend runs in the calling thread (NumPy's element-wise operations are
    single-threaded); run tiles in several processes, e.g. Dask workers, to use more cores."""
