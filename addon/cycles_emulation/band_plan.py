"""Chooses the Cycles emulation's wavelength bands for a scene, how many and where, from an estimate of the
colour error that band means cause, made before anything renders.

The estimate. A band render sees each spectrum only as its band mean, and the colour error comes from the
spectra's shape inside each band, made worse wherever the medium's optics bend them nonlinearly. Probes
stand for what the eye can see in a scene: every light (and the World, zenith and horizon) at luminance
1, on its own and seen through each medium's optics in simple ways whose answer is known both for a
spectrum and for band means:
- a thin medium (`optical_thickness` below THIN_BELOW), seen by single scattering: the albedo a(λ);
  where the anisotropy g(λ) varies, a(λ) · 4π p_HG(cosθ, g(λ)) at the scattering angles PHASE_ANGLES;
  where the extinction varies (ε(λ): the extinction over its largest value in the rendered range), its
  scattering a · ε and the light scattered on the way a · ε · exp(−τ ε) at relative optical depths
  τ ∈ TRANSMITTANCE_DEPTHS;
- a thick medium (optical thickness above THICK_ABOVE), seen by its multiple scattering: its diffuse
  reflectance R(a) = (1 − √(1−a)) / (1 + √(1−a)) (two-stream, a semi-infinite isotropic medium), which
  stretches differences near a = 1;
- every medium whose extinction varies: its transmittance exp(−τ ε);
- a hot medium's glow (Planck's law at its hottest temperature, times 1 − a).
For each probe: XYZ of the full spectrum against what the emulation renders (the same function of the
band means, `parameters.medium_bands`, summed with the band weights `bands.xyz_weights`), as CIEDE2000
against the light as white (a glow against D65 at its luminance, the display's white). The estimate is
the largest ΔE00 over the probes.
Multiple scattering through several media or paths is not modelled: the estimate is a guide to how
many bands a scene's spectra need, checked against renders in `bench/cycles_emulation.py`.

The choice. Edges lie at quantiles of a density over the rendered range: the eye's sensitivity
(x̄ + ȳ + z̄, with a floor so that no part of the range is left without a band) times one plus the
probes' relative variation per nanometre, so bands are narrow where the eye sees the spectra change.
For each count the better of these edges and equal bands is kept; the count is the smallest whose
estimate is below the target, as long as the Cycles renders it needs (`bands.pack`) stay within the
budget; otherwise the best estimate within the budget, with a warning.
"""

from dataclasses import dataclass

import numpy as np

from ..tracer import colorimetry, phase, spectra
from ..tracer.errors import SpectralError
from ..tracer.scene import Scene
from ..tracer.wavelength_modes import default_band
from ..tracer.wavelengths import GRID
from . import bands as bandlib
from . import parameters

TARGET_DELTA_E = 0.5
DEFAULT_MAX_RENDERS = 12
TRANSMITTANCE_DEPTHS = (1.0, 4.0)
PHASE_ANGLES = (5.0, 30.0, 90.0, 150.0)  # degrees
THIN_BELOW, THICK_ABOVE = 3.0, 1.0  # optical thickness: single scattering, multiple scattering (both between)
SENSITIVITY_FLOOR = 0.02  # of the eye's peak sensitivity: bands still cover the ends of the range


@dataclass(frozen=True)
class BandPlan:
    """The chosen bands, the estimated colour error with them (ΔE00, largest over the probes), the Cycles
    renders they need, and a warning when the budget could not reach the target (else None)."""

    bands: bandlib.Bands
    estimate: float
    renders: int
    target: float
    max_renders: int
    warning: str | None = None

    def summary(self) -> str:
        return (f"{self.bands.count} bands in {self.renders} Cycles render(s), estimated color error "
                f"ΔE00 {self.estimate:.2f} (target {self.target:g}, budget {self.max_renders} renders)")


@dataclass(frozen=True)
class _Probe:
    """One seen colour: full spectrum `light · medium_factor(a, ε)` with `factor` applied alike to band means."""

    light: np.ndarray  # (GRID.size,) at unit strength, or a glow's Planck spectrum
    medium: object  # tracer Medium or None (the light seen directly)
    factor: str  # "light" | "single" | "phase" | "thick" | "thin" | "transmitted" | "scattered" | "glow"
    depth: float = 0.0  # relative optical depth τ ("transmitted", "scattered")
    angle: float = 0.0  # scattering angle in degrees ("phase")
    level: int = 0  # row of the medium's albedo table


def _thick(albedo):
    s = np.sqrt(np.clip(1.0 - albedo, 0.0, 1.0))
    return (1.0 - s) / (1.0 + s)


def _apply(probe: _Probe, albedo, extinction, extinction_peak: float, anisotropy):
    """The probe's medium factor at these albedos, extinctions and anisotropies (spectra or band means)."""
    relative = np.asarray(extinction, dtype=np.float64) / extinction_peak
    if probe.factor == "light":
        return np.ones_like(relative)
    if probe.factor == "single":
        return albedo
    if probe.factor == "phase":
        return albedo * 4.0 * np.pi * phase.hg_pdf(anisotropy, np.cos(np.radians(probe.angle)))
    if probe.factor == "thick":
        return _thick(albedo)
    if probe.factor == "thin":
        return albedo * relative
    if probe.factor == "transmitted":
        return np.exp(-probe.depth * relative)
    if probe.factor == "scattered":
        return albedo * relative * np.exp(-probe.depth * relative)
    return 1.0 - albedo  # "glow": emission σ_a · Planck, relative to σ_t


def _varies(values, inside) -> bool:
    return bool(np.ptp(np.asarray(values)[inside]) > 0)


def optical_thickness(medium, inside: np.ndarray) -> float:
    """How thick the medium is for light: the smallest, over the grid's three axes, of the median optical
    depth of its non-empty columns (at the extinction's mean over the rendered range)."""
    values, voxel = medium.density.values, np.linalg.norm(medium.density.index_to_world[:3, :3], axis=0)
    extinction = float(np.mean(medium.extinction.values[inside])) * medium.density_scale
    depths = []
    for axis in range(3):
        columns = values.sum(axis=axis, dtype=np.float64) * voxel[axis]
        filled = columns[columns > 0]
        depths.append(float(np.median(filled)) if filled.size else 0.0)
    return min(depths) * extinction


def _probes(scene: Scene, inside: np.ndarray) -> list[_Probe]:
    shapes = []
    for light in scene.lights:
        shapes.append(parameters.unit_strength(light))
        if light.horizon_spectrum is not None:
            shapes.append(parameters.unit_strength(light, light.horizon_spectrum))
    probes = [_Probe(shape, None, "light") for shape in shapes]
    for medium in scene.media:
        thickness = optical_thickness(medium, inside)
        thin, thick = thickness < THIN_BELOW, thickness > THICK_ABOVE
        chromatic = _varies(medium.extinction.values, inside)
        for shape in shapes:
            for level in range(medium.albedo_table.shape[0]):
                if thin:
                    probes.append(_Probe(shape, medium, "single", level=level))
                    if medium.phase == "hg" and _varies(medium.anisotropy.values, inside):
                        probes += [_Probe(shape, medium, "phase", angle=angle, level=level) for angle in PHASE_ANGLES]
                if thick:
                    probes.append(_Probe(shape, medium, "thick", level=level))
            if chromatic:
                probes += [_Probe(shape, medium, "transmitted", depth) for depth in TRANSMITTANCE_DEPTHS]
            if chromatic and thin:
                probes.append(_Probe(shape, medium, "thin"))
                probes += [_Probe(shape, medium, "scattered", depth) for depth in TRANSMITTANCE_DEPTHS]
        if medium.emission is not None:
            hottest = parameters.hottest_temperature(medium.emission)
            glow = spectra.planck(GRID, hottest) if hottest > 0 else np.zeros(GRID.size)
            probes.append(_Probe(glow, medium, "glow"))
    return probes


class _Estimator:
    """ΔE00 of every probe for given bands (the probes' full-spectrum colours computed once)."""

    def __init__(self, scene: Scene):
        settings = scene.settings
        self.scene, self.cmf = scene, settings.cmf
        self.lo, self.hi = default_band(settings)
        self.inside = (GRID >= self.lo) & (GRID <= self.hi)
        self.probes = _probes(scene, self.inside)
        if not self.probes:
            raise SpectralError("the Cycles emulation needs a light or a glowing medium to plan its bands")
        full = np.array([self._full_spectrum(probe) for probe in self.probes])
        self.full_spectra = full * self.inside
        self.full_xyz = colorimetry.spectrum_to_xyz(self.full_spectra, self.cmf)
        # White: the probe's light, or for a glow the display's D65 at the glow's luminance; XYZ scaled so
        # that the white has Y = 1.
        d65 = colorimetry.spectrum_to_xyz(spectra.illuminant("D65").values * self.inside, self.cmf)
        whites = np.array([colorimetry.spectrum_to_xyz(probe.light * self.inside, self.cmf)
                           if probe.factor != "glow" else d65 / d65[1] * xyz[1]
                           for probe, xyz in zip(self.probes, self.full_xyz)])
        self.whites = whites / np.maximum(whites[:, 1:2], 1e-300)
        self.scale = 1.0 / np.maximum(whites[:, 1], 1e-300)

    def _full_spectrum(self, probe: _Probe) -> np.ndarray:
        medium = probe.medium
        if medium is None:
            return probe.light
        return probe.light * _apply(probe, medium.albedo_table[probe.level], medium.extinction.values,
                                    self._extinction_peak(medium), medium.anisotropy.values)

    def _extinction_peak(self, medium) -> float:
        return max(float(medium.extinction.values[self.inside].max()), 1e-300)

    def delta_e(self, bands: bandlib.Bands) -> np.ndarray:
        """ΔE00 of each probe with these bands."""
        return self.evaluate(bands)[0]

    def evaluate(self, bands: bandlib.Bands) -> tuple[np.ndarray, int]:
        """ΔE00 of each probe with these bands, and the Cycles renders they need (`bands.pack`)."""
        media = {id(medium): parameters.medium_bands(medium, bands, self.cmf) for medium in self.scene.media}
        renders = len(bandlib.pack([tuple(m.phase_key(k) for m in media.values()) for k in range(bands.count)]))
        weights = bandlib.xyz_weights(bands, self.cmf, parameters.reference_spectrum(self.scene.lights,
                                                                                      tuple(media.values())))
        emulated = []
        for probe in self.probes:
            light = bandlib.band_means(probe.light, bands, self.cmf)
            if probe.medium is None:
                emulated.append(light)
                continue
            m = media[id(probe.medium)]
            emulated.append(light * _apply(probe, m.albedo[probe.level], m.extinction,
                                           self._extinction_peak(probe.medium), m.anisotropy))
        band_xyz = np.array(emulated) @ weights
        return (_delta_e00(self.full_xyz * self.scale[:, None], band_xyz * self.scale[:, None], self.whites),
                renders)

    def variation(self) -> np.ndarray:
        """Per-nanometre relative variation of the probes' spectra (mean over probes, each over its peak)."""
        spectra_ = self.full_spectra / np.maximum(self.full_spectra.max(axis=1, keepdims=True), 1e-300)
        change = np.abs(np.gradient(spectra_, axis=1))
        return change.mean(axis=0)


def _delta_e00(xyz_a, xyz_b, whites) -> np.ndarray:
    colour = colorimetry.colour_science()
    xy = colour.XYZ_to_xy(whites)
    lab_a, lab_b = colour.XYZ_to_Lab(xyz_a, xy), colour.XYZ_to_Lab(xyz_b, xy)
    return np.asarray(colour.delta_E(lab_a, lab_b, method="CIE 2000"), dtype=np.float64)


def _placed(density: np.ndarray, lo: float, hi: float, count: int) -> bandlib.Bands | None:
    """`count` bands of whole nanometres over [lo, hi] holding equal parts of `density` (None if the
    range has fewer nanometres than bands)."""
    if hi - lo < count:
        return None
    inside = (GRID >= lo) & (GRID <= hi)
    nodes, weights = GRID[inside], density[inside]
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (weights[1:] + weights[:-1]))])
    cuts = np.interp(np.arange(1, count) / count * cumulative[-1], cumulative, nodes)
    edges = [float(lo)]
    for k, cut in enumerate(np.round(cuts)):
        # whole nanometres, at least 1 nm per band, leaving room for the bands still to come
        edges.append(float(min(max(cut, edges[-1] + 1.0), hi - (count - 1 - k))))
    edges.append(float(hi))
    return bandlib.Bands(tuple(edges))


def estimate(scene: Scene, bands: bandlib.Bands) -> float:
    """The largest ΔE00 over the scene's probes with these bands."""
    return float(_Estimator(scene).delta_e(bands).max())


def plan_bands(scene: Scene, target: float = TARGET_DELTA_E, max_renders: int = DEFAULT_MAX_RENDERS) -> BandPlan:
    """The fewest bands whose estimated colour error is below `target` within `max_renders` Cycles renders."""
    if max_renders < 1:
        raise SpectralError(f"the Cycles emulation needs a budget of at least 1 render, got {max_renders}")
    parameters.require_emulable(scene)
    estimator = _Estimator(scene)
    lo, hi = estimator.lo, estimator.hi
    sensitivity = colorimetry.cmf(estimator.cmf).sum(axis=0)
    sensitivity = np.maximum(sensitivity / sensitivity.max(), SENSITIVITY_FLOOR)
    variation = estimator.variation()
    density = sensitivity * (1.0 + variation / max(float(variation[estimator.inside].mean()), 1e-300))
    best = None
    for count in range(1, int(hi - lo) + 1):
        candidates = [bandlib.split(lo, hi, count), _placed(density, lo, hi, count)]
        scored = []
        for bands in (candidate for candidate in candidates if candidate is not None):
            errors, renders = estimator.evaluate(bands)
            if renders <= max_renders:
                scored.append((float(errors.max()), renders, bands))
        if not scored:
            if count >= bandlib.CHANNELS * max_renders:
                break
            continue
        error, renders, bands = min(scored, key=lambda item: item[0])
        if best is None or error < best.estimate:
            best = BandPlan(bands, error, renders, target, max_renders)
        if error < target:
            return best
    if best is None:
        raise SpectralError(f"no band plan fits in {max_renders} Cycles render(s)")
    warning = (f"the Cycles emulation's bands reach an estimated color error of ΔE00 {best.estimate:.2f}, above "
               f"the target {target:g}, within the budget of {max_renders} renders: raise Max Renders for "
               f"more bands")
    return BandPlan(best.bands, best.estimate, best.renders, target, max_renders, warning)

