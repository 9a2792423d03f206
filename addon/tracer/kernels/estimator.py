"""The estimator's ledger and its named updates, per wavelength: what both backends do to a path's weights.

A path carries, at each of its wavelengths, its throughput β and two pdf ratios relative to the hero wavelength's
path pdf: r_u, of the unidirectional strategy (free flights and phase or BRDF sampling), and r_l, of light
sampling up to the last vertex (docs/algorithm.md, "Spectral MIS" and "Lights and next-event estimation"). Every
event updates them by one of the calls below, and every contribution divides by the mean of the strategies' ratios
(the balance heuristic over wavelengths and strategies). The functions take one wavelength's scalars (the Numba
kernel, in its loops over a path's wavelengths) or arrays of them (the NumPy backend, on (paths, wavelengths)
arrays with broadcasting): each backend keeps its loops, masks and state, and the arithmetic is written here once,
in the order the Numba kernel has always done it (its images stay bit for bit).

Shared by both backends (`shared_math`). Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

from ..shared_math import absolute, exp, floor, select, shared
from .layout import GREY_SPREAD, SHADOW_ROULETTE_STOP
from .media import null_fraction

ROULETTE_LEAST = 0.05  # a path's least chance of surviving Russian roulette


# ----------------------------------------------------------------------------- wavelengths and film

@shared
def companion_uniform(u, i, n):
    """The uniform number of a path's wavelength i of n, stratified from the hero's u: (u + i/n) mod 1."""
    ui = u + i / n
    return ui - floor(ui)


@shared
def camera_estimate(radiance, pdf, n):
    """A camera wavelength's share of the path's spectral estimate: its radiance over its pdf and the path's
    count of wavelengths, L / (p·n), which the XYZ weights then weigh."""
    return radiance / (pdf * n)


# ----------------------------------------------------------------------------- free flights

@shared
def collision_estimate(source, sigma_bar, mean_r_u):
    """A source at a tentative collision (β·ε of emission; Σ β·σ_fl of a fluorescent source) as the collision
    estimator counts it: source / (σ̄ · mean r_u), the spectral MIS weight of the tentative collision included."""
    return source / (sigma_bar * mean_r_u)


@shared
def real_probability(sigma_a, sigma_s, sigma_bar):
    """The chance σ_t / σ̄ that the hero's tentative collision is real (scattering or absorption)."""
    return (sigma_a + sigma_s) / sigma_bar


@shared
def real_collision(beta, r_u, sigma_a, sigma_s, sigma_bar, p0):
    """(β, r_u) after a real collision that the hero chose with probability p0: the collision scatters,
    weighted by the albedo (β takes σ_s / σ̄ / p0), and r_u takes this wavelength's σ_t / σ̄ / p0."""
    return beta * (sigma_s / sigma_bar / p0), r_u * ((sigma_a + sigma_s) / sigma_bar / p0)


@shared
def null_collision(beta, r_u, r_l, sigma_a, sigma_s, sigma_bar, p0, controls):
    """(β, r_u, r_l) after a null collision that the hero chose with probability p0: β and r_u take this
    wavelength's σ_n / σ̄ / p0; r_l, light sampling's ratio, takes 1/p0 (its null-event probability is the
    shadow ray's, 1), except on a path with `controls`, whose MIS uses the controls' transmittance instead."""
    ratio = null_fraction(sigma_bar, sigma_a, sigma_s)
    return beta * (ratio / p0), r_u * (ratio / p0), select(controls, r_l, r_l / p0)


# ----------------------------------------------------------------------------- shadow rays

@shared
def ratio_tracked(transmittance, survival, rate, excess, residual):
    """(transmittance, survival) of a shadow ray after a tentative collision drawn at `rate` where the medium
    exceeds the controls by σ_t `excess` (ratio tracking's factor σ_n / rate). The survival, the unidirectional
    strategy's chance of passing there, takes the same factor, except in residual ratio tracking, where it is
    the controls' transmittance (`residual_tracked`)."""
    ratio = null_fraction(rate, excess, 0.0)
    return transmittance * ratio, select(residual, survival, survival * ratio)


@shared
def controls_transmittance(control_depth):
    """The controls' transmittance exp(−τ_c) of residual ratio tracking: a shadow ray's survival (the chance MIS
    gives the unidirectional strategy of passing where it passed), and an escaping grey path's."""
    return exp(-control_depth)


@shared
def residual_tracked(transmittance, control_depth):
    """(transmittance, survival) at the end of a residual-ratio-tracked shadow ray: the ratio-tracked factors
    times the controls' transmittance, which is the survival."""
    survival = controls_transmittance(control_depth)
    return transmittance * survival, survival


@shared
def shadow_bound(largest, least_depth):
    """A bound of a shadow ray's transmittance for its roulette: its largest ratio-tracked factor, times the
    controls' transmittance at their least optical depth where that is positive."""
    return select(least_depth > 0.0, largest * controls_transmittance(least_depth), largest)


@shared
def shadow_roulette(transmittance, u):
    """A faint shadow ray's transmittance after Russian roulette with uniform u: 0 when it stops (probability
    SHADOW_ROULETTE_STOP), else divided by the chance of going on."""
    return select(u < SHADOW_ROULETTE_STOP, 0.0, transmittance / (1.0 - SHADOW_ROULETTE_STOP))


@shared
def attenuates_alike(value, first):
    """Whether a medium attenuates a wavelength (`value`, its σ_t per unit density) as it does the hero
    (`first`), to GREY_SPREAD: a path whose wavelengths all do is grey (residual ratio tracking in MIS)."""
    return absolute(value - first) <= GREY_SPREAD * first


# ----------------------------------------------------------------------------- lights

@shared
def light_sample_ratio(r_u, light_pdf, phase, survival, delta):
    """The strategies' ratios summed for a direction drawn by light sampling: light sampling's r_u·p_light
    (its choice of the light included), plus the unidirectional strategy's r_u·p_phase·survival, which finds
    no delta light."""
    return r_u * light_pdf + select(delta, 0.0, r_u * phase * survival)


@shared
def next_event_contribution(beta, value, transmittance, radiance, mean_r):
    """Radiance that next-event estimation adds: β · (phase or BRDF value) · transmittance · radiance over the
    mean of the strategies' ratios."""
    return beta * value * transmittance * radiance / mean_r


@shared
def hit_light_ratio(r_u, r_l, survival, light_pdf, scattered):
    """The strategies' ratios summed for a light that the path's ray finds: after a scattering vertex the
    unidirectional r_u · survival (its survival along the ray as a shadow ray's) plus light sampling's
    r_l · p_light; from the camera r_u alone (no light sampling could have found it)."""
    return select(scattered, r_u * survival + r_l * light_pdf, r_u)


@shared
def hit_light_contribution(beta, radiance, survival, scattered, mean_r):
    """Radiance of a light that the path's ray finds: β · radiance over the mean of the ratios
    (`hit_light_ratio`), times the survival after a scattering vertex."""
    return beta * radiance * select(scattered, survival, 1.0) / mean_r


# ----------------------------------------------------------------------------- vertices

@shared
def phase_sampled(beta, r_u, phase, pdf0):
    """(β, r_u, r_l) after a direction drawn with the hero's pdf pdf0 where this wavelength's phase function
    is `phase`: β and r_u take phase / pdf0; r_l starts again from r_u / pdf0 (light sampling's pdf joins it
    at the next vertex)."""
    return beta * (phase / pdf0), r_u * (phase / pdf0), r_u / pdf0


# ----------------------------------------------------------------------------- the sunward probe

@shared
def probe_sampled(beta, r_u, phase, chance, sun_phase):
    """(β, r_u) of a sunward probe from a vertex where the path had (β, r_u), along a direction where this
    wavelength's phase function is `phase` and the probe's pdf (the phase function about the sun) `sun_phase`:
    β takes the phase; r_u the pdf of both strategies that draw the direction, the path's phase sampling and
    the probe drawn with probability `chance` (the balance heuristic; no division by the chance, which the sum
    holds)."""
    return beta * phase, r_u * (phase + chance * sun_phase)


@shared
def probe_weight(phase, chance, sun_phase):
    """The factor of r_u in the path's next sun estimate, after phase sampling drew a direction where this
    wavelength's phase is `phase` and the probe's pdf `sun_phase`: both strategies' pdf over the path's own
    (1 where the path's phase is 0: no probe is sent from such a vertex)."""
    return select(phase > 0.0, (phase + chance * sun_phase) / phase, 1.0)


@shared
def lambert_sampled(beta, r_u, reflectance, pdf0):
    """(β, r_u, r_l) after a cosine-weighted direction of pdf pdf0 leaving a Lambertian surface: the pdf is
    every wavelength's, so β takes the reflectance and r_u stays; r_l starts again from r_u / pdf0."""
    return beta * reflectance, r_u, r_u / pdf0


@shared
def roulette_survival(largest):
    """The chance that a path whose largest MIS-weighted throughput β / mean r_u is `largest` survives Russian
    roulette: 1 from 1 up, else `largest` but at least ROULETTE_LEAST. A survivor's β is divided by it."""
    return select(largest >= 1.0, 1.0, select(largest > ROULETTE_LEAST, largest, ROULETTE_LEAST))
