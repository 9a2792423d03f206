"""Light policies: what a light's `strength` means in its unit (`strength_scale`) and the spectrum the kernels
take for it (`kernel_spectrum`), how often next-event estimation chooses each light (`selection_powers`,
which the lowering normalises to `KernelScene.lights.pmf`; an emissive surface's, `surface_power`) and each
texel of an envmap (`texel_weights`).
"""

import numpy as np

from . import colorimetry, envmaps
from .errors import SpectralError
from .scene import Light, Medium
from .spectra import Spectrum
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN


def strength_scale(light: Light, spectrum: Spectrum | None = None, cmf: str = "cie1931") -> float:
    """Factor turning a light's spectrum shape (default: `light.spectrum`; a sky's horizon too) into
    radiometric units with `strength` in the light's unit: luminous, luminance Y = strength with the
    colour matching functions `cmf`; radiant, ∫ spectrum dλ over the grid = strength (watts)."""
    spectrum = spectrum or light.spectrum
    if light.unit == "radiant":
        total = spectrum.integral()
    else:
        total = float(colorimetry.spectrum_to_xyz(spectrum.values, cmf)[1])
    if not total > 0:  # validation.validate refuses these with the light's path
        raise SpectralError(f"light {light.name or light.kind!r}: its spectrum has no {light.unit} part to scale")
    return light.strength / total


def kernel_spectrum(light: Light, spectrum: Spectrum | None = None, cmf: str = "cie1931") -> np.ndarray:
    """The radiometric spectrum on the grid that the kernels take for a light (`KernelLights.spd`): its shape
    (default: `light.spectrum`) scaled to its strength (`strength_scale`), and for an area light, whose
    strength is its power P, divided by π: a Lambertian emitter's intensity along its normal, P/π (its
    radiance P/(π · area) times its area), which its samples' falloff cos θ / d² turns into irradiance. An
    envmap's is its mean radiance over the sphere (`envmaps.mean_radiance`; its kernels read its map)."""
    if light.kind == "envmap":
        return envmaps.mean_radiance(light)
    spectrum = spectrum or light.spectrum
    values = spectrum.values * strength_scale(light, spectrum, cmf)
    return values / np.pi if light.kind == "area" else values


def peak_emission(light: Light, cmf: str) -> float:
    """The most the light emits per nm, in its kind's radiant unit (`scene.RADIANT_UNITS`): the peak of its
    kernel spectrum (of both of a sky's), or of an envmap's brightest texel (inf when that overflows)."""
    with np.errstate(over="ignore", invalid="ignore"):
        if light.kind == "envmap":
            basis = np.asarray(light.basis_values(), dtype=np.float64)
            texels = np.asarray(light.image, dtype=np.float64).reshape(-1, 3)
            return float(light.strength * (texels.max(axis=0) @ basis).max())
        spectra_ = [light.spectrum] + ([light.horizon_spectrum] if light.horizon_spectrum is not None else [])
        return float(max(kernel_spectrum(light, spectrum, cmf).max() for spectrum in spectra_))


def proxy_luminance(spd: np.ndarray, cmf: str) -> float:
    """The light-choice proxy of a radiometric spectrum: its luminance Y, or, where more, that of an
    equal-energy spectrum of the same radiant integral (so a light with no visible part, a UV lamp
    that makes fluorescence, is still chosen)."""
    equal_energy = np.trapezoid(spd, GRID) / (LAMBDA_MAX - LAMBDA_MIN)  # the constant-1 spectrum has Y = 1
    return max(float(colorimetry.spectrum_to_xyz(spd, cmf)[1]), float(equal_energy))


def _scene_centre_and_radius(media: tuple[Medium, ...]) -> tuple[np.ndarray, float]:
    corners = []
    for medium in media:
        n = np.array(medium.density.values.shape, dtype=np.float64)
        for corner in np.ndindex(2, 2, 2):
            index = np.where(corner, n, -1.0)
            corners.append((medium.density.index_to_world @ np.append(index, 1.0))[:3])
    if not corners:
        return np.zeros(3), 1.0
    corners = np.array(corners)
    centre = corners.mean(axis=0)
    return centre, float(np.linalg.norm(corners - centre, axis=1).max())


def selection_powers(lights: tuple[Light, ...], spds: np.ndarray, media: tuple[Medium, ...], cmf: str) -> np.ndarray:
    """The power each light is chosen in proportion to, from its kernel spectrum `spds[i]` (`kernel_spectrum`):
    the proxy luminance for a sun, π times it for an environment, sky or envmap (its mean radiance), and over
    the squared distance to the media's centre (at least their bounding radius) the light's power: 4π times it
    for a point or spot light, π times it for an area light (whichever side of it the media lie on: they may reach around it)."""
    centre, radius = _scene_centre_and_radius(media)
    power = np.zeros(len(lights))
    for index, (light, spd) in enumerate(zip(lights, spds)):
        luminance = proxy_luminance(spd, cmf)
        if light.kind == "sun":
            power[index] = luminance
        elif light.kind in ("environment", "sky", "envmap"):
            power[index] = np.pi * luminance
        else:
            with np.errstate(over="ignore"):  # a distance beyond float64 is inf: the light then weighs 0
                distance = max(np.linalg.norm(light.position - centre), radius, 1e-3)
            solid_angle = np.pi if light.kind == "area" else 4.0 * np.pi
            power[index] = solid_angle * luminance / distance**2
    return power


def surface_power(emission: np.ndarray, area: float, centre: np.ndarray, media: tuple[Medium, ...], cmf: str) -> float:
    """An emissive surface's selection power, as `selection_powers` gives an area light's: the proxy luminance
    of its power, 2π L A for radiance L leaving both sides of area A, over the squared distance from its
    centre to the media's centre (at least their bounding radius)."""
    media_centre, radius = _scene_centre_and_radius(media)
    distance = max(np.linalg.norm(centre - media_centre), radius, 1e-3)
    return 2.0 * np.pi * proxy_luminance(emission, cmf) * area / distance**2


def texel_weights(light: Light, cmf: str) -> np.ndarray:
    """(H, W): what an envmap's texels are drawn in proportion to: their power proxy, Σ_c rgb_c times the proxy
    luminance of the channel's basis (`proxy_luminance`; at strength 1, so a light of strength 0 has them too),
    times their solid angle. Positive wherever the texel's radiance is."""
    channels = np.array([proxy_luminance(spd, cmf) for spd in light.basis_values()])
    return (np.asarray(light.image, dtype=np.float64) @ channels) * envmaps.texel_solid_angles(light)
