"""The `wavelength_sampling` modes: the hero-wavelength distribution each mode draws from for a lowered
scene (`wavelength_distribution`; the `light` mode follows `light_mode_sources`), the range the camera
samples (`default_band`), and a kernel scene drawing its hero wavelength from one band (`with_band`).
"""

import numpy as np

from . import sampling
from .errors import SpectralError
from .kernels.layout import LIGHT_SKY, KernelScene
from .kernels.media import blackbody_normalisation, glow_emission
from .planck import planck_radiance
from .spectra import Spectrum
from .wavelengths import GRID, LAMBDA_MIN

# Above this temperature a black body's shape over the grid is λ⁻⁴ (Rayleigh–Jeans) to 3e-4, so the
# `light` mode follows this one's (hotter ones may overflow in double precision).
BLACKBODY_SHAPE_MAX_KELVIN = 1e8
# The `light` mode's share of the `colour` density: it keeps the pdf positive wherever any light (emission,
# fluorescence, a sky's horizon, or a light outside the sources' spectra) can reach the camera.
LIGHT_MODE_DEFENSIVE_SHARE = 0.2


def light_mode_sources(kernel_scene: KernelScene) -> list[tuple[Spectrum, float]]:
    """The spectra the `light` mode follows, as (spectrum, weight): each light's spectrum weighted by its
    next-event selection probability (a sky's zenith and horizon spectra half each), then, with the lights
    together weighing 1, each emitting medium's black body at its hottest temperature (a glowing medium's glow
    there) and each fluorophore's emission spectrum weighing 1 each."""
    ks = kernel_scene
    sources = []
    for kind, spd, horizon, pmf in zip(ks.lights.kind, ks.lights.spd, ks.lights.spd_horizon, ks.lights.pmf):
        if kind == LIGHT_SKY:
            sources += [(Spectrum(spd), 0.5 * pmf), (Spectrum(horizon), 0.5 * pmf)]
        else:
            sources.append((Spectrum(spd), pmf))
    for m, offset in enumerate(ks.temperature.offset):
        hottest = 0.0
        if offset >= 0:
            size = int(np.prod(ks.temperature.shape[m]))
            scale, shift, _ = ks.temperature.map[m]
            hottest = scale * float(ks.temperature.data[offset:offset + size].max(initial=0.0)) + shift
        planck = planck_radiance(GRID, min(hottest, BLACKBODY_SHAPE_MAX_KELVIN))
        if ks.glow.glowing[m]:
            shape = glow_emission(1.0, ks.glow.spectrum[m], ks.glow.blackbody[m], planck,
                                  blackbody_normalisation(ks, hottest))
            if shape.any():
                sources.append((Spectrum(shape), 1.0))
        elif hottest > 0:
            sources.append((Spectrum(planck), 1.0))
    sources += [(Spectrum(pdf), 1.0) for pdf in ks.fluorescence.emission_pdf if pdf.any()]
    return sources


def wavelength_distribution(mode: str, kernel_scene: KernelScene, lo: float, hi: float):
    """The hero-wavelength distribution over [lo, hi] for a `wavelength_sampling` mode."""
    if mode in ("uniform", "uv"):
        return sampling.uniform(lo, hi)
    if mode == "colour":
        return sampling.colour_distribution(kernel_scene.wavelengths.xyz_weights, lo, hi)
    if mode == "visible":
        return sampling.visible_distribution(lo, hi)
    if mode == "d65_rejection":
        return sampling.d65(lo, hi)
    if mode == "light":
        return sampling.defensive_composite(light_mode_sources(kernel_scene),
                                            sampling.colour_distribution(kernel_scene.wavelengths.xyz_weights, lo, hi),
                                            LIGHT_MODE_DEFENSIVE_SHARE)
    raise SpectralError(f"unknown wavelength sampling {mode!r}")


def default_band(settings) -> tuple[float, float]:
    """The wavelength range the camera samples: the settings' range, from 250 nm in "uv" mode."""
    lo = LAMBDA_MIN if settings.wavelength_sampling == "uv" else settings.lambda_min
    return lo, settings.lambda_max


def with_band(kernel_scene: KernelScene, mode: str, lo: float, hi: float) -> KernelScene:
    """The same kernel data with the hero wavelength drawn from [lo, hi] by `mode`."""
    distribution = wavelength_distribution(mode, kernel_scene, lo, hi)
    wavelengths = kernel_scene.wavelengths._replace(cdf=np.asarray(distribution.cdf, dtype=np.float64),
                                                    pdf=np.asarray(distribution.bin_pdf, dtype=np.float64))
    return kernel_scene._replace(wavelengths=wavelengths)
