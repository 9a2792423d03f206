"""A true metameric pair of cubes: the same colour under D65, clearly different under illuminant A.

A dense cube's colour is not its albedo spectrum: multiple scattering makes its apparent reflectance
a nonlinear function of the albedo. But that function is the same at every wavelength (extinction and
phase function do not depend on λ, and the transport at one wavelength never sees another), so:

1. Calibrate. For an albedo `a` constant over λ, a front-face pixel's spectral radiance is
   S(λ)·G(a), S the light's spectrum, G a number that only the geometry fixes. G is measured by
   rendering the two-cube scene with constant albedos (through a camera cropped to the left cube's
   front face: same eye, same rays, only the pixels that are averaged) and interpolated in
   s = √(1 − a), in which G is smooth (G is steep near a = 1, like 1 − √(1 − a) for a half-space).
   The apparent reflectance is ρ(a) = G(a) / G(1): the face relative to a white (albedo 1) cube.
2. Design, with colour-science's observer, illuminants, CIELAB and CIEDE2000, in apparent
   reflectance: ρ₁ is a smooth spectrum (Jakob & Hanika 2019 recovery of an RGB colour); ρ₂ has the
   same XYZ under D65 (three equality constraints) and maximises ΔE00 against ρ₁ under A, with a
   smoothness penalty, within [0, DESIGN_CEILING], by SLSQP on knots every 20 nm. This step is
   deterministic arithmetic: it does not depend on the calibration (whose noise would otherwise move
   the bound and with it the optimum), only the check that the cube can show the ceiling does.
3. Invert per wavelength: albedo_i(λ) = ρ⁻¹(ρ_i(λ)).

The render then shows what the design promised only as far as the calibration holds: `metrics`
measures ΔE00 on the rendered faces.

Reproducibility: the calibration is a seeded Monte Carlo render, so on one machine it gives the same
G every time, but another CPU (other last bits in OpenBLAS, NumPy's SIMD or the C library) traces some
paths differently and gets another G within its noise. The albedos therefore reproduce across
machines only within the calibration's own standard error, which `Calibration.albedo_errors`
propagates to each wavelength's albedo.
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.optimize import minimize

from addon.tracer import colorimetry, spectra
from addon.tracer.render import render
from addon.tracer.wavelengths import GRID

from . import metrics, scenes

CALIBRATION_ALBEDOS = (0.0, 0.5, 0.75, 0.88, 0.94, 0.97, 1.0)
MAX_ALBEDO = 0.97  # designs stay at or below this albedo (near 1, paths get long and ρ very steep)
DESIGN_CEILING = 0.75  # highest apparent reflectance designed: ρ(MAX_ALBEDO) is 0.76 in the two-cube scene
CALIBRATION_SPP = 128
BOUND_SNAP = 1e-6  # designed knots this close to a bound are put on it
KNOTS = np.arange(380.0, 721.0, 20.0)
BASE_RGB = (0.22, 0.3, 0.18)  # ρ₁: a muted olive green under D65
SMOOTHNESS = 2.0
DESIGN_STARTS = 6


@dataclass(frozen=True)
class Calibration:
    """G(a), the mean front-face Y per unit radiometric light, at the calibration albedos, with the
    standard error of each (zero where it is exact)."""

    albedos: np.ndarray
    response: np.ndarray
    errors: np.ndarray | None = None

    def g(self, albedo):
        s = np.sqrt(1.0 - np.asarray(albedo, dtype=np.float64))
        order = np.argsort(self.s)
        return PchipInterpolator(self.s[order], self.response[order])(s)

    @property
    def s(self) -> np.ndarray:
        return np.sqrt(1.0 - self.albedos)

    def reflectance(self, albedo):
        """Apparent reflectance ρ(a) = G(a) / G(1)."""
        return self.g(albedo) / self.g(1.0)

    def albedo_for(self, reflectance) -> np.ndarray:
        """ρ⁻¹: the albedo whose apparent reflectance is `reflectance` (ρ increases with a)."""
        table = np.linspace(0.0, 1.0, 2001)
        return np.interp(reflectance, self.reflectance(table), table)

    def albedo_errors(self, reflectance) -> np.ndarray:
        """Standard error of `albedo_for(reflectance)` that the calibration's noise causes: the albedo's
        change when each response moves by its standard error, added in quadrature (first-order
        propagation; counting the responses' errors as independent overstates it, since they share
        random numbers and partly cancel in G(a) / G(1))."""
        errors = np.zeros_like(self.response) if self.errors is None else self.errors
        albedo = self.albedo_for(reflectance)
        squares = np.zeros_like(albedo)
        for k, error in enumerate(errors):
            if error > 0.0:
                moved = replace(self, response=self.response + error * (np.arange(self.response.size) == k))
                squares += (moved.albedo_for(reflectance) - albedo) ** 2
        return np.sqrt(squares)


# ----------------------------------------------------------------------------- 1. calibration


def face_camera(camera, centre, size: int):
    """The part of `camera`'s view that the front face of the cube at `centre` fills (inside the
    region `metrics.face_mask` averages): the same eye and rays, a narrower window, `size` pixels wide."""
    half = scenes.CUBE_EDGE * (0.5 - 0.2)
    c = np.asarray(centre, dtype=np.float64)
    corners = np.array([[c[0] + dx, c[1] - scenes.CUBE_EDGE / 2, c[2] + dz, 1.0]
                        for dx in (-half, half) for dz in (-half, half)])
    local = corners @ np.linalg.inv(camera.to_world).T
    image = local[:, :2] / -local[:, 2:3]  # positions on the z = −1 image plane
    (x0, y0), (x1, y1) = image.min(axis=0), image.max(axis=0)
    span = x1 - x0
    height = max(4, int(round(size * (y1 - y0) / span)))
    return replace(camera, width=size, height=height, fov=2.0 * np.arctan(span / 2.0), sensor_fit="HORIZONTAL",
                   shift_x=0.5 * (x0 + x1) / span, shift_y=0.5 * (y0 + y1) / span)


def face_response(scene, albedo: float, spp: int = 48, size: int = 24) -> tuple[float, float]:
    """G(albedo) and its standard error: the mean Y of the left cube's front face in the two-cube
    `scene` when every medium has the constant albedo `albedo` and every light a flat spectrum
    (strengths kept), seen through `face_camera`."""
    flat = spectra.constant(1.0)
    media = tuple(replace(medium, albedo_table=np.full_like(medium.albedo_table, albedo)) for medium in scene.media)
    lights = tuple(replace(light, spectrum=flat) for light in scene.lights)
    camera = face_camera(scene.camera, scenes.CUBE_CENTRES[0], size)
    probe = replace(scene, camera=camera, media=media, lights=lights, settings=replace(scene.settings, spp=spp))
    film = render(probe).film
    face = metrics.face_mask(camera, scenes.CUBE_CENTRES[0], scenes.CUBE_EDGE)
    error = np.sqrt(film.variance[face][:, 1].sum()) / face.sum()
    return float(metrics.region_xyz(film.xyz, face)[1]), float(error)


def calibrate(spp: int = CALIBRATION_SPP, size: int = 24) -> Calibration:
    """G at each albedo in CALIBRATION_ALBEDOS, in the code-built two-cube scene (a sun of radiometric
    irradiance 1 and its fill)."""
    scene = scenes.two_cubes(1.0, 1.0, spectra.constant(1.0), 8, 8, spp)
    responses, errors = zip(*(face_response(scene, albedo, spp, size) for albedo in CALIBRATION_ALBEDOS))
    return Calibration(np.array(CALIBRATION_ALBEDOS), np.array(responses), np.array(errors))


# ----------------------------------------------------------------------------- 2. design


def _xyz(reflectance: np.ndarray, light: np.ndarray) -> np.ndarray:
    return colorimetry.spectrum_to_xyz(reflectance * light)


def _lab(reflectance: np.ndarray, light: np.ndarray) -> np.ndarray:
    colour = colorimetry.colour_science()
    white = _xyz(np.ones_like(GRID), light)
    return colour.XYZ_to_Lab(_xyz(reflectance, light) / white[1], colour.XYZ_to_xy(white))


def delta_e(reflectance_1, reflectance_2, light: np.ndarray) -> float:
    """CIEDE2000 between two reflectances under `light` (white: the perfect reflector)."""
    colour = colorimetry.colour_science()
    return float(colour.delta_E(_lab(reflectance_1, light), _lab(reflectance_2, light), method="CIE 2000"))


def _on_grid(knot_values) -> np.ndarray:
    return np.interp(GRID, KNOTS, knot_values)


def design_pair(highest: float, base_rgb=BASE_RGB) -> tuple[np.ndarray, np.ndarray]:
    """Two apparent reflectances (on GRID) in [0, `highest`] with equal XYZ under D65 and the
    largest ΔE00 under A this search finds."""
    d65, a = spectra.illuminant("D65").values, spectra.illuminant("A").values
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = np.interp(KNOTS, GRID, spectra.from_rgb(base_rgb).values)
    first_knots = np.clip(base, 0.02, highest)
    first = _on_grid(first_knots)
    target = _xyz(first, d65)

    def objective(knots):
        return -delta_e(first, _on_grid(knots), a) + SMOOTHNESS * np.sum(np.diff(knots, 2) ** 2)

    same_under_d65 = {"type": "eq", "fun": lambda knots: 100.0 * (_xyz(_on_grid(knots), d65) - target)}
    best = None
    for seed in range(DESIGN_STARTS):
        start = np.clip(first_knots + 0.1 * np.random.default_rng(seed).standard_normal(KNOTS.size), 0.0, highest)
        result = minimize(objective, start, method="SLSQP", bounds=[(0.0, highest)] * KNOTS.size,
                          constraints=[same_under_d65], options={"maxiter": 300})
        feasible = np.abs(same_under_d65["fun"](result.x)).max() < 1e-3
        if feasible and (best is None or result.fun < best.fun):
            best = result
    # Knots SLSQP left on a bound sit there to within ~1e-8, by amounts that differ between CPUs; on the
    # bound exactly, the .blend's curve (whose handles flatten at extrema and ties) is the same everywhere.
    knots = np.where(best.x < BOUND_SNAP, 0.0, np.where(best.x > highest - BOUND_SNAP, highest, best.x))
    return first, _on_grid(knots)


# ----------------------------------------------------------------------------- 3. the pair


@dataclass(frozen=True)
class MetamerPair:
    calibration: Calibration
    reflectances: tuple[np.ndarray, np.ndarray]
    albedos: tuple[spectra.Spectrum, spectra.Spectrum]

    def predicted_delta_e(self, light: str) -> float:
        return delta_e(*self.reflectances, scenes.LIGHTS[light].values)

    @property
    def albedo_errors(self) -> tuple[np.ndarray, np.ndarray]:
        """Each albedo's standard error per wavelength from the calibration's noise: how far the same
        design can land on another CPU (see the module's docstring)."""
        return tuple(self.calibration.albedo_errors(r) for r in self.reflectances)


def metamer_pair(calibration: Calibration) -> MetamerPair:
    reachable = float(calibration.reflectance(MAX_ALBEDO))
    if reachable < DESIGN_CEILING:
        raise ValueError(f"the cube's apparent reflectance reaches only {reachable:.3f} at albedo {MAX_ALBEDO}, "
                         f"below the design ceiling {DESIGN_CEILING}")
    reflectances = design_pair(DESIGN_CEILING)
    albedos = tuple(spectra.Spectrum(np.clip(calibration.albedo_for(r), 0.0, 1.0)) for r in reflectances)
    return MetamerPair(calibration, reflectances, albedos)


def metamerism_designed(pair: MetamerPair, light: str):
    """Builder of the designed pair's cubes under `light` ("D65" or "A")."""
    def build(width: int, height: int, spp: int):
        return scenes.two_cubes(*pair.albedos, scenes.LIGHTS[light], width, height, spp)

    return build
