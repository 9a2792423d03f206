"""Spectra: values tabulated on the shared wavelength grid, and every way to make one.

A `Spectrum` is immutable and holds `GRID.size` float64 values (see `wavelengths`). Sources: constant,
(λ, value) table, Gaussian, CIE standard illuminants, and the scene format's JSON description (`from_spec`).

Resampling onto GRID is linear interpolation; a tabulated source (table, illuminant dataset) is 0 outside
the wavelength range it covers.
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import colorimetry
from .errors import SpectralError
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

ILLUMINANT_NAMES = (
    "D65", "D50", "A", "E",
    *(f"FL{i}" for i in range(1, 13)),
    "LED-B1", "LED-B2", "LED-B3", "LED-B4", "LED-B5", "LED-BH1", "LED-RGB1", "LED-V1", "LED-V2",
)


@dataclass(frozen=True, eq=False)
class Spectrum:
    """A spectral function sampled on GRID (one value per nanometre, 250–830 nm)."""

    values: np.ndarray

    def __post_init__(self):
        values = np.asarray(self.values, dtype=np.float64)
        if values.shape != GRID.shape:
            raise SpectralError(f"a spectrum needs {GRID.size} values on the 1 nm grid, got shape {values.shape}")
        if not np.all(np.isfinite(values)):
            raise SpectralError("a spectrum contains NaN or infinite values")
        values = values.copy()
        values.flags.writeable = False
        object.__setattr__(self, "values", values)

    def __call__(self, lam):
        """Value(s) at wavelength(s) `lam` in nm, linear between grid points, 0 outside the grid."""
        return np.interp(lam, GRID, self.values, left=0.0, right=0.0)

    def __add__(self, other: "Spectrum") -> "Spectrum":
        return Spectrum(self.values + other.values)

    def __mul__(self, other) -> "Spectrum":
        if isinstance(other, Spectrum):
            return Spectrum(self.values * other.values)
        return Spectrum(self.values * float(other))

    __rmul__ = __mul__

    def integral(self) -> float:
        """∫ S(λ) dλ over the grid (trapezoid rule, nm units)."""
        return float(np.trapezoid(self.values, GRID))


def constant(value: float) -> Spectrum:
    return Spectrum(np.full(GRID.shape, float(value)))


def table(wavelengths, values, name: str = "table") -> Spectrum:
    """Piecewise-linear spectrum through (λ, value) pairs; 0 outside the tabulated range."""
    wavelengths = np.asarray(wavelengths, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if wavelengths.ndim != 1 or wavelengths.shape != values.shape:
        raise SpectralError(f"spectrum {name!r}: wavelengths and values must be two lists of equal length")
    if wavelengths.size == 0:
        raise SpectralError(f"spectrum {name!r} is empty")
    if not (np.all(np.isfinite(wavelengths)) and np.all(np.isfinite(values))):
        raise SpectralError(f"spectrum {name!r} contains NaN or infinite numbers")
    if np.any(np.diff(wavelengths) <= 0):
        raise SpectralError(f"spectrum {name!r}: wavelengths must increase strictly")
    if wavelengths[-1] < LAMBDA_MIN or wavelengths[0] > LAMBDA_MAX:
        raise SpectralError(f"spectrum {name!r} lies outside {LAMBDA_MIN:g}–{LAMBDA_MAX:g} nm (are the units nm?)")
    if wavelengths.size == 1:
        return constant(values[0])
    return Spectrum(np.interp(GRID, wavelengths, values, left=0.0, right=0.0))


def gaussian(peak: float, width: float, height: float = 1.0) -> Spectrum:
    """exp(-(λ-peak)²/(2·width²)) · height; `width` is the standard deviation in nm."""
    if width <= 0:
        raise SpectralError(f"Gaussian spectrum width must be positive, got {width}")
    return Spectrum(height * np.exp(-0.5 * ((GRID - peak) / width) ** 2))


@lru_cache(maxsize=None)
def _illuminant(name: str) -> Spectrum:
    dataset = colorimetry.colour_science().SDS_ILLUMINANTS[name]
    return table(dataset.wavelengths, dataset.values, name=f"illuminant {name}")


def illuminant(name: str) -> Spectrum:
    """CIE standard illuminant `name` (see ILLUMINANT_NAMES; case does not matter) from colour-science's
    datasets at the dataset's relative scale (D65, D50, A, E: 100 at 560 nm; FL, LED: as published); 0 outside
    the dataset's range (D65, D50, A: 300–780 nm; E: 360–830 nm; FL and LED: 380–780 nm)."""
    canonical = {known.upper(): known for known in ILLUMINANT_NAMES}.get(str(name).strip().upper())
    if canonical is None:
        raise SpectralError(f"unknown illuminant {name!r}; valid names: {', '.join(ILLUMINANT_NAMES)}")
    return _illuminant(canonical)


def from_spec(spec, name: str = "spectrum") -> Spectrum:
    """Build a spectrum from its scene-format description (a number or a dict with a "type")."""
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return constant(spec)
    if not isinstance(spec, dict) or "type" not in spec:
        raise SpectralError(f"{name}: a spectrum is a number or an object with a \"type\", got {spec!r}")
    kind = spec["type"]
    try:
        if kind == "constant":
            return constant(spec["value"])
        if kind == "table":
            return table(spec["wavelengths"], spec["values"], name)
        if kind == "gaussian":
            return gaussian(spec["peak"], spec["width"], spec.get("height", 1.0))
    except KeyError as missing:
        raise SpectralError(f"{name}: spectrum of type {kind!r} needs the field {missing}") from None
    raise SpectralError(f"{name}: unknown spectrum type {kind!r}")
