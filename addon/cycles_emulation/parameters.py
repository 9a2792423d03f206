"""Per-band numbers of a tracer Scene for the Cycles emulation: media coefficients, light and world colours,
upsampled RGB colours, and the plan of Cycles renders.

Everything comes from the exported tracer Scene (`addon.export`), so the emulation and the tracer render
the same material definition. In band k a medium has extinction ext_k, albedo_k(ρ) (band mean of the
scattering coefficient over that of the extinction, per density level, so σ_s is preserved), anisotropy
g_k, the fluorophore's excitation (absorption only: Cycles cannot re-emit at another wavelength) and
its blackbody emission as a table over temperature. A
light's colour in band k is the band mean of its spectrum scaled to strength 1 in its unit (`lights.strength_scale`),
its Cycles strength stays Blender's, so XYZ = Σ_k render_k · w_k (`bands.xyz_weights`, shaped within each
band by the lights' spectra) matches the tracer.
"""

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..tracer import colorimetry, spectra
from ..tracer.errors import SpectralError
from ..tracer.lights import strength_scale
from ..tracer.scene import Light, Medium, Scene
from ..tracer.wavelength_modes import default_band
from ..tracer.wavelengths import GRID
from . import bands as bandlib

FLUORESCENCE_WARNING = ("material of {name!r} fluoresces: Cycles cannot re-emit light at another wavelength, "
                        "so the emulation renders its excitation as absorption only (no fluorescent glow)")
THERMAL_SAMPLES = 24  # temperatures of the blackbody table, evenly over the grid's range


@dataclass(frozen=True, eq=False)
class ThermalBands:
    """Blackbody emission σ_a · intensity · Planck(λ, T) in the bands: `radiance[i, k]` is the band mean of
    Planck's law (W·m⁻²·sr⁻¹·nm⁻¹) at `temperatures[i]`, linear in between (0 at and below 0 K); T is the
    grid value × `scale` + `offset`."""

    temperatures: np.ndarray  # (N,) kelvin, increasing
    radiance: np.ndarray  # (N, K)
    intensity: float
    scale: float
    offset: float


@dataclass(frozen=True, eq=False)
class MediumBands:
    name: str
    density_scale: float
    extinction: np.ndarray  # (K,)
    excitation: np.ndarray  # (K,) absorption of the fluorophore (0 without one)
    albedo_densities: np.ndarray  # (L,) raw density levels, increasing
    albedo: np.ndarray  # (L, K)
    anisotropy: np.ndarray  # (K,)
    phase: str  # "hg" | "rayleigh"
    thermal: ThermalBands | None = None

    def phase_key(self, k: int) -> tuple:
        """What must be equal for two bands to share a Cycles render."""
        return (self.phase,) if self.phase == "rayleigh" else (self.phase, round(float(self.anisotropy[k]), 4))


@dataclass(frozen=True, eq=False)
class Plan:
    bands: bandlib.Bands
    weights: np.ndarray  # (K, 3) XYZ per unit of band value
    media: tuple[MediumBands, ...]
    light_colours: dict  # light name → (K,) colour per band (Cycles strength: Blender's own)
    world: Light | None  # the spectral World, if on
    world_colours: tuple  # ((K,) zenith or uniform colour, (K,) horizon colour or None)
    renders: tuple[tuple[int, ...], ...]  # band indices per Cycles render (R, G, B)
    cmf: str
    warnings: tuple[str, ...]


def medium_bands(medium: Medium, bands: bandlib.Bands, cmf: str = "cie1931") -> MediumBands:
    extinction = bandlib.band_means(medium.extinction.values, bands, cmf)
    scattering = bandlib.band_means(medium.albedo_table * medium.extinction.values, bands, cmf)
    safe = np.where(extinction > 0, extinction, 1.0)
    albedo = np.where(extinction > 0, scattering / safe, bandlib.band_means(medium.albedo_table, bands, cmf))
    excitation = np.zeros(bands.count)
    if medium.fluorescence is not None:
        excitation = bandlib.band_means(medium.fluorescence.excitation.values, bands, cmf)
    return MediumBands(name=medium.name, density_scale=medium.density_scale, extinction=extinction,
                       excitation=excitation, albedo_densities=np.asarray(medium.albedo_densities, dtype=np.float64),
                       albedo=np.clip(albedo, 0.0, 1.0),
                       anisotropy=bandlib.band_means(medium.anisotropy.values, bands, cmf), phase=medium.phase,
                       thermal=None if medium.emission is None else thermal_bands(medium.emission, bands, cmf))


def hottest_temperature(emission) -> float:
    """The highest temperature (kelvin) a blackbody emission's grid holds (0 for an empty grid)."""
    kelvin = emission.temperature.values * emission.temperature_scale + emission.temperature_offset
    return float(np.max(kelvin, initial=0.0))


def thermal_bands(emission, bands: bandlib.Bands, cmf: str = "cie1931") -> ThermalBands:
    """The blackbody table over the temperatures the grid holds (the tracer evaluates Planck's law exactly;
    this is linear between THERMAL_SAMPLES temperatures)."""
    temperatures = np.linspace(0.0, max(hottest_temperature(emission), 1.0), THERMAL_SAMPLES)
    planck = spectra.planck(GRID[None, :], np.maximum(temperatures, 1e-3)[:, None])
    planck[0] = 0.0
    return ThermalBands(temperatures=temperatures, radiance=bandlib.band_means(planck, bands, cmf),
                        intensity=emission.intensity, scale=emission.temperature_scale,
                        offset=emission.temperature_offset)


def unit_strength(light: Light, spectrum=None, cmf: str = "cie1931") -> np.ndarray:
    """A light's spectrum (or its `spectrum`, e.g. a sky's horizon) on GRID, scaled to strength 1 in the
    light's unit (luminance Y with `cmf`, or watts)."""
    spectrum = spectrum or light.spectrum
    return spectrum.values * strength_scale(dataclasses.replace(light, strength=1.0), spectrum, cmf)


def light_bands(light: Light, bands: bandlib.Bands, cmf: str = "cie1931", spectrum=None) -> np.ndarray:
    """(K,) colour of a light (or of its `spectrum`, e.g. a sky's horizon) for a Cycles strength of
    Blender's own: the spectrum scaled to strength 1 in its unit."""
    return bandlib.band_means(unit_strength(light, spectrum, cmf), bands, cmf)


def reflectance_bands(rgb, bands: bandlib.Bands, cmf: str = "cie1931", method: str = "jakob2019") -> np.ndarray:
    """(K,) band means of the smooth reflectance whose colour under D65 is `rgb` (clipped to [0, 1])."""
    rgb = np.clip(np.asarray(rgb, dtype=np.float64)[:3], 0.0, 1.0)
    return bandlib.band_means(spectra.from_rgb(rgb, method).values, bands, cmf)


def emitter_bands(rgb, bands: bandlib.Bands, cmf: str = "cie1931", method: str = "jakob2019") -> np.ndarray:
    """(K,) colour of an RGB emitter: white (1, 1, 1) is D65 at luminance 1, any colour that reflectance
    under D65, brighter colours scaled (so an RGB light of strength s keeps its luminance)."""
    rgb = np.maximum(np.asarray(rgb, dtype=np.float64)[:3], 0.0)
    peak = float(rgb.max())
    if peak <= 0:
        return np.zeros(bands.count)
    d65 = spectra.illuminant("D65").values
    spectrum = spectra.from_rgb(rgb / peak, method).values * d65 / colorimetry.spectrum_to_xyz(d65)[1]
    return peak * bandlib.band_means(spectrum, bands, cmf)


def reference_spectrum(lights, media=()) -> np.ndarray | None:
    """The scene's illumination shape: the lights' spectra at luminance 1, weighted by their strengths, plus
    the glow of each hot medium (Planck's law at its hottest temperature, at luminance 1); None when there
    is neither (flat). Band weights shaped by it (`bands.xyz_weights`) render these colours exactly."""
    total = np.zeros(GRID.size)
    for medium in media:
        if medium.thermal is not None:
            hottest = medium.thermal.temperatures[-1]
            glow = spectra.planck(GRID, hottest) if hottest > 0 else np.zeros(GRID.size)
            luminance = colorimetry.spectrum_to_xyz(glow)[1]
            total += glow / luminance if luminance > 0 else 0.0
    for light in lights:
        total += light.strength * unit_strength(light)
        if light.horizon_spectrum is not None:
            total += light.strength * unit_strength(light, light.horizon_spectrum)
    return total if total.any() else None


def require_emulable(scene: Scene) -> None:
    """Refuse what the emulation cannot render at all: an HDRI or Sky Texture World (an envmap: its per-texel
    spectra have no band colours here)."""
    for light in scene.lights:
        if light.kind == "envmap":
            raise SpectralError(f"the Cycles emulation does not render an HDRI or Sky Texture World ({light.name or 'envmap'!r}); "
                                "render it with the tracer (Render ▸ Renderer: Tracer)")


def plan(scene: Scene, bands: bandlib.Bands | int) -> Plan:
    """The emulation of `scene` with `bands` (chosen ones, `band_plan.plan_bands`, or a count of equal bands
    over the tracer's rendered wavelength range)."""
    require_emulable(scene)
    settings = scene.settings
    if isinstance(bands, int):
        if bands < 1:
            raise SpectralError(f"the Cycles emulation needs at least 1 band, got {bands}")
        bands = bandlib.split(*default_band(settings), bands)
    media = tuple(medium_bands(medium, bands, settings.cmf) for medium in scene.media)
    warnings = [FLUORESCENCE_WARNING.format(name=m.name) for m in scene.media if m.fluorescence is not None]
    warnings += [f"{m.name!r}: its glow (Blender's volume emission) is not emulated" for m in scene.media
                 if m.glow is not None]
    world = next((light for light in scene.lights if light.kind in ("environment", "sky")), None)
    world_colours = (None, None)
    if world is not None:
        horizon = world.horizon_spectrum
        world_colours = (light_bands(world, bands, settings.cmf),
                         None if horizon is None else light_bands(world, bands, settings.cmf, horizon))
    colours = {light.name: light_bands(light, bands, settings.cmf) for light in scene.lights if light is not world}
    keys = [tuple(medium.phase_key(k) for medium in media) for k in range(bands.count)]
    weights = bandlib.xyz_weights(bands, settings.cmf, reference_spectrum(scene.lights, media))
    return Plan(bands=bands, weights=weights, media=media, light_colours=colours,
                world=world, world_colours=world_colours, renders=bandlib.pack(keys), cmf=settings.cmf,
                warnings=tuple(warnings))
