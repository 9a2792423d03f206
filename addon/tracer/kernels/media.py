"""A medium at a point: its density and temperature (grid look-ups), its albedo between density levels,
the coefficients of a collision there, its thermal emission and glow and its phase function; and the arithmetic of
tracking against a majorant σ̄ (free paths, null collisions).

Plain arithmetic shared by both backends (`shared_math`): one path's scalars in the Numba kernel, arrays of
paths in the NumPy backend (points as components x, y, z; wavelengths located by `lookups.on_grid`). They
branch on a medium's own parameters, never on a path's values. Part of the kernel cache's key
(`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..phase import hg_pdf, rayleigh_pdf
from ..shared_math import exp, shared
from .geometry import transform_point
from .layout import PHASE_RAYLEIGH
from .lookups import evenly_spaced_at, table_at, trilinear


@shared
def density(ks, m, x, y, z):
    """Medium m's raw density (before `density_scale`) at world point(s) (x, y, z)."""
    qx, qy, qz = transform_point(ks.density.world_to_padded[m], x, y, z)
    return trilinear(ks.density.data, ks.density.offset[m], ks.density.shape[m], qx - 1.0, qy - 1.0, qz - 1.0)


@shared
def temperature(ks, m, x, y, z):
    """Medium m's temperature (K) at world point(s) (x, y, z): its grid's value mapped by scale and offset."""
    qx, qy, qz = transform_point(ks.temperature.world_to_padded[m], x, y, z)
    raw = trilinear(ks.temperature.data, ks.temperature.offset[m], ks.temperature.shape[m], qx - 1.0, qy - 1.0,
                    qz - 1.0)
    return raw * ks.temperature.map[m, 0] + ks.temperature.map[m, 1]


@shared
def albedo(ks, m, raw_density, at):
    """Single-scattering albedo of medium m (two density levels or more; one level is its spectrum) at a
    raw density: its levels' spectra interpolated linearly in density, clamped beyond the first and last."""
    levels = ks.media.albedo_densities[m, :ks.media.albedo_count[m]]
    upper = np.minimum(np.maximum(np.searchsorted(levels, raw_density, side="left"), 1), levels.shape[0] - 1)
    low, high = levels[upper - 1], levels[upper]
    t = np.minimum(np.maximum((raw_density - low) / (high - low), 0.0), 1.0)
    table = ks.media.albedo_table[m]
    return (1.0 - t) * table_at(table, upper - 1, at) + t * table_at(table, upper, at)


@shared
def attenuation(rho, extinction, excitation):
    """σ_t = σ_s + σ_a at density ρ (scaled) whatever the albedo: ρ·(extinction + excitation), the dye's
    absorption included (as `collision_coefficients` splits it). Shadow rays need only this."""
    return rho * (extinction + excitation)


@shared
def collision_coefficients(rho, extinction, albedo_value, excitation, fluorescence_strength, emission_pdf):
    """At density ρ (scaled) with a medium's spectra at a wavelength: (σ_s, σ_a, plain absorption, σ_fl).
    σ_t = ρ·extinction scatters the albedo's share of it; the rest, the plain absorption, and the dye's
    ρ·excitation absorb; σ_fl = ρ·strength·emission pdf is the fluorescent source per unit radiance."""
    sigma_t = rho * extinction
    scattering = sigma_t * albedo_value
    plain_absorption = sigma_t - scattering
    return (scattering, plain_absorption + rho * excitation, plain_absorption,
            rho * fluorescence_strength * emission_pdf)


@shared
def thermal_emission(plain_absorption, intensity, planck):
    """Thermal emission σ_a · intensity · Planck(λ, T) of the plain absorption, given Planck(λ, T)."""
    return plain_absorption * intensity * planck


@shared
def blackbody_normalisation(ks, kelvin):
    """Cycles' scale of Planck's law at T (K): (σT⁴/π) / Y(Planck(·, T)), its logarithm interpolated linearly
    in log T on the lowered table (`glow.normalisation_table`), clamped beyond its ends."""
    log_kelvin = np.log(np.maximum(kelvin, 1e-3))
    return exp(evenly_spaced_at(ks.glow.log_normalisation, ks.glow.log_kelvin[0], ks.glow.log_kelvin[1],
                                   log_kelvin))


@shared
def glow_emission(rho, spectrum, blackbody, planck, normalisation):
    """A glow at density ρ (scaled): ρ · (spectrum + blackbody · tint · Lbb), where `blackbody` is
    blackbody · tint and Lbb = Planck(λ, T) · `normalisation` (`blackbody_normalisation`), given Planck(λ, T)."""
    return rho * (spectrum + blackbody * (planck * normalisation))


@shared
def phase_pdf(ks, m, g, cos_theta):
    """Medium m's phase function (= its pdf) at cos θ: Rayleigh, or Henyey–Greenstein with anisotropy g."""
    if ks.media.phase_kind[m] == PHASE_RAYLEIGH:
        return rayleigh_pdf(cos_theta)
    return hg_pdf(g, cos_theta)


@shared
def free_path(u, sigma_bar):
    """Distance to the next tentative collision against a majorant σ̄, for a uniform u: −ln(1 − u) / σ̄."""
    return -np.log(1.0 - u) / sigma_bar


@shared
def null_fraction(sigma_bar, sigma_a, sigma_s):
    """σ_n / σ̄ with σ_n = max(0, σ̄ − σ_a − σ_s): a null collision's share of a tentative one, and ratio
    tracking's factor on the transmittance (residual ratio tracking: σ̄ and σ_t − σ_c of the residual,
    with σ_s = 0)."""
    return np.maximum(0.0, sigma_bar - sigma_a - sigma_s) / sigma_bar
