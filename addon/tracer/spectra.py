"""Spectra: values tabulated on the shared wavelength grid, and every way to make one.

A `Spectrum` is immutable and holds `GRID.size` float64 values (see `wavelengths`). Sources: constant,
(λ, value) table, CSV file, Gaussian, Planck blackbody, CIE standard illuminants, and a smooth reflectance
for an RGB colour; operations: λ window, scale and sum. `from_spec` builds any of these from the scene
format's JSON description and `to_spec` writes one back.

Resampling onto GRID is linear interpolation; a tabulated source (table, CSV file, illuminant dataset)
is 0 outside the wavelength range it covers.
"""

import csv
import warnings
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from . import colorimetry, jakob2019
from .constants import WIEN
from .planck import planck_radiance
from .checks import shown
from .errors import SpectralError
from .files import SPECTRUM_LIMIT, regular_file
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

ILLUMINANT_NAMES = (
    "D65", "D50", "A", "E",
    *(f"FL{i}" for i in range(1, 13)),
    "LED-B1", "LED-B2", "LED-B3", "LED-B4", "LED-B5", "LED-BH1", "LED-RGB1", "LED-V1", "LED-V2",
)
# Named narrow bands (lamp and laser lines), Gaussian peaks: (label, peak nm, standard deviation nm).
BANDS = {
    "UV254": ("UV-C 254 nm", 254.0, 4.0),
    "UV365": ("UV-A 365 nm", 365.0, 6.0),
    "V405": ("Violet 405 nm", 405.0, 6.0),
    "B450": ("Blue 450 nm", 450.0, 8.0),
    "G532": ("Green 532 nm", 532.0, 2.0),
}
# The description types of `from_spec` and the fields each takes besides "type"; any other field is an error.
SPEC_FIELDS = {
    "constant": ("value",),
    "table": ("wavelengths", "values"),
    "gaussian": ("peak", "width", "height"),
    "blackbody": ("temperature",),
    "illuminant": ("name",),
    "csv": ("path", "units"),
    "window": ("of", "min", "max"),
    "scale": ("of", "factor"),
    "sum": ("of",),
}
SPEC_TYPES = tuple(SPEC_FIELDS)
MAX_SPEC_DEPTH = 32  # descriptions nest ("scale" of a "sum" of ...) at most this deep
RGB_METHODS = {"jakob2019": "Jakob 2019", "otsu2018": "Otsu 2018"}
# Wavelength units a CSV file may be in, as nanometres per unit.
CSV_UNITS = {"nm": 1.0, "um": 1e3, "µm": 1e3, "μm": 1e3, "A": 0.1, "Å": 0.1}

_NM = 1e-9  # metres


class NonFiniteSpectrum(SpectralError):
    """A spectrum's values would not all be finite (`from_spec` names the description that made them)."""


@dataclass(frozen=True, eq=False)
class Spectrum:
    """A spectral function sampled on GRID (one value per nanometre, 250–830 nm)."""

    values: np.ndarray

    def __post_init__(self):
        values = np.asarray(self.values, dtype=np.float64)
        if values.shape != GRID.shape:
            raise SpectralError(f"a spectrum needs {GRID.size} values on the 1 nm grid, got shape {values.shape}")
        if not np.all(np.isfinite(values)):
            raise NonFiniteSpectrum("a spectrum contains NaN or infinite values")
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


def _float_array(numbers, what: str, name: str) -> np.ndarray:
    try:
        return np.asarray(numbers, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise SpectralError(f"{name}: the spectrum's {what} must be a list of numbers") from None


def table(wavelengths, values, name: str = "table") -> Spectrum:
    """Piecewise-linear spectrum through (λ, value) pairs, at least two; 0 outside the tabulated range."""
    wavelengths = _float_array(wavelengths, "wavelengths", name)
    values = _float_array(values, "values", name)
    if wavelengths.ndim != 1 or wavelengths.shape != values.shape:
        raise SpectralError(f"{name}: the spectrum's wavelengths and values must be two lists of equal length")
    if wavelengths.size < 2:
        raise SpectralError(f"{name}: a table needs at least 2 rows (wavelength, value), found {wavelengths.size}: "
                            "it is 0 outside the range its rows span; for one value at every wavelength give a "
                            "constant")
    if not (np.all(np.isfinite(wavelengths)) and np.all(np.isfinite(values))):
        raise SpectralError(f"{name}: the spectrum contains NaN or infinite numbers")
    if np.any(np.diff(wavelengths) <= 0):
        raise SpectralError(f"{name}: the spectrum's wavelengths must increase strictly")
    if wavelengths[-1] < LAMBDA_MIN or wavelengths[0] > LAMBDA_MAX:
        raise SpectralError(f"{name}: the spectrum lies outside {LAMBDA_MIN:g}–{LAMBDA_MAX:g} nm (are the units nm?)")
    return Spectrum(np.interp(GRID, wavelengths, values, left=0.0, right=0.0))


def gaussian(peak: float, width: float, height: float = 1.0) -> Spectrum:
    """exp(-(λ-peak)²/(2·width²)) · height; `width` is the standard deviation in nm."""
    if width <= 0:
        raise SpectralError(f"Gaussian spectrum width must be positive, got {width}")
    return Spectrum(height * np.exp(-0.5 * ((GRID - peak) / width) ** 2))


def _nm_per_unit(units: str) -> float:
    if units not in CSV_UNITS:
        raise SpectralError(f"unknown wavelength unit {units!r}; use one of {', '.join(CSV_UNITS)}")
    return CSV_UNITS[units]


def _csv_fields(line: str) -> list[str]:
    return [field.strip() for field in next(csv.reader([line]))]


def _parse_csv_row(fields: list[str], where: str) -> tuple[float, float]:
    if len(fields) != 2:
        raise SpectralError(f"{where}: expected 2 comma-separated columns (wavelength, value), got {len(fields)}")
    numbers = []
    for field in fields:
        try:
            number = float(field)
        except ValueError:
            raise SpectralError(f"{where}: {field!r} is not a number") from None
        if not np.isfinite(number):
            raise SpectralError(f"{where}: {field!r} is not a finite number")
        numbers.append(number)
    return numbers[0], numbers[1]


def _is_numeric(field: str) -> bool:
    try:
        float(field)
    except ValueError:
        return False
    return True


def _read_csv_rows(path: Path) -> list[tuple[int, float, float]]:
    """(line number, λ, value) of each data row; blank lines and `#` comments are skipped, and the first
    row may be a header (any non-numeric field)."""
    try:
        text = regular_file(path, "spectrum file", SPECTRUM_LIMIT).read_text(encoding="utf-8-sig")
    except OSError as error:
        raise SpectralError(f"cannot read spectrum file {str(path)!r}: {error.strerror}") from None
    except UnicodeDecodeError:
        raise SpectralError(f"spectrum file {str(path)!r} is not UTF-8 text") from None
    rows = []
    first = True
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = _csv_fields(line)
        header = first and not all(map(_is_numeric, fields))
        if not header:
            rows.append((number, *_parse_csv_row(fields, f"{path}, line {number}")))
        first = False
    return rows


def from_csv(path, units: str = "nm") -> Spectrum:
    """Spectrum from a CSV file of (wavelength, value) rows with strictly increasing wavelengths.

    `units` is the wavelength unit (see CSV_UNITS); wavelengths are converted to nm, values are used as
    they are. An optional header row, blank lines and `#` comment lines are allowed."""
    scale = _nm_per_unit(units)
    path = Path(path)
    rows = _read_csv_rows(path)
    if not rows:
        raise SpectralError(f"spectrum file {str(path)!r} has no data rows (expected: wavelength, value)")
    for (previous_line, previous, _), (line, lam, _) in zip(rows, rows[1:]):
        if lam <= previous:
            raise SpectralError(f"{path}, line {line}: wavelength {lam:g} {units} does not increase "
                                f"(line {previous_line} has {previous:g} {units})")
    _, wavelengths, values = zip(*rows)
    return table(np.array(wavelengths) * scale, values, name=str(path))


def _kelvin(temperature) -> np.ndarray:
    temperature = np.asarray(temperature, dtype=np.float64)
    bad = ~(np.isfinite(temperature) & (temperature > 0))
    if np.any(bad):
        raise SpectralError(f"blackbody temperature must be a positive number of kelvin, got {temperature[bad][0]:g}")
    return temperature


def planck(lam, temperature):
    """Planck's law: black-body spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ at wavelength(s) `lam` (nm) and
    temperature(s) in kelvin; the two broadcast against each other. Underflows to 0, never overflows."""
    return planck_radiance(np.asarray(lam, dtype=np.float64), _kelvin(temperature))


def blackbody(temperature: float) -> Spectrum:
    """Shape of a black body's spectral radiance at `temperature` kelvin, scaled so that its maximum over
    all wavelengths (at Wien's λ = b/T, possibly off the grid) is 1."""
    peak_nm = WIEN / _kelvin(temperature) / _NM
    return Spectrum(planck(GRID, temperature) / planck(peak_nm, temperature))


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


def window(spectrum: Spectrum, lo: float, hi: float) -> Spectrum:
    """`spectrum` between `lo` and `hi` nm (inclusive), 0 elsewhere."""
    if not lo <= hi:
        raise SpectralError(f"spectral window needs min ≤ max, got {lo:g}–{hi:g} nm")
    return Spectrum(np.where((GRID >= lo) & (GRID <= hi), spectrum.values, 0.0))


def _rgb_triple(rgb) -> tuple[float, float, float]:
    values = np.asarray(_finite_triple(rgb), dtype=np.float64)
    if np.any((values < 0) | (values > 1)):
        raise SpectralError(f"a reflectance RGB colour needs components in [0, 1], got {values.tolist()}")
    return tuple(values.tolist())


def from_rgb(rgb, method: str = "jakob2019") -> Spectrum:
    """A smooth reflectance spectrum in [0, 1] whose colour under D65 is `rgb` (linear Rec.709, in [0, 1]).

    `method` (see RGB_METHODS): "jakob2019" (Jakob & Hanika 2019 sigmoid polynomial, `jakob2019`) or
    "otsu2018" (colour-science's `colour.recovery`). The fit spans 360–830 nm (Otsu: 380–730 nm); beyond it the
    value at its end is held."""
    if method not in RGB_METHODS:
        raise SpectralError(f"unknown RGB-to-spectrum method {method!r}; choose one of {', '.join(RGB_METHODS)}")
    return _from_rgb(_rgb_triple(rgb), method)


@lru_cache(maxsize=1024)
def _from_rgb(rgb: tuple[float, float, float], method: str) -> Spectrum:
    observer = colorimetry.cie1931_observer()
    d65 = illuminant("D65")(observer.wavelengths)
    xyz = colorimetry.rgb_to_xyz(rgb, "rec709")
    if method == "jakob2019":
        coefficients, _ = jakob2019.fit(xyz, observer.values.T, d65)
        lo, hi = observer.wavelengths[0], observer.wavelengths[-1]
        values = jakob2019.reflectance(coefficients, np.clip((GRID - lo) / (hi - lo), 0.0, 1.0))
        return Spectrum(np.clip(values, 0.0, 1.0))
    colour = colorimetry.colour_science()
    with warnings.catch_warnings():
        # Otsu 2018 resamples to its dataset's 380–730 nm, 10 nm shape and warns about it on every call.
        warnings.simplefilter("ignore", colour.utilities.ColourRuntimeWarning)
        recovered = colour.XYZ_to_sd(xyz, method=RGB_METHODS[method], cmfs=observer,
                                     illuminant=colour.SpectralDistribution(d65, observer.wavelengths))
    return Spectrum(np.clip(np.interp(GRID, recovered.wavelengths, recovered.values), 0.0, 1.0))


def scaled_from_rgb(rgb, method: str = "jakob2019") -> Spectrum:
    """A smooth spectrum for any non-negative RGB (linear Rec.709), not only a reflectance: 0 for black,
    `from_rgb` of it when its components are at most 1, else the reflectance of `rgb` divided by its largest component,
    times that component. Cycles' colours and coefficients may exceed 1 (Volume Coefficients, emission)."""
    values = np.maximum(np.asarray(_finite_triple(rgb), dtype=np.float64), 0.0)
    peak = float(values.max())
    if peak == 0.0:
        return constant(0.0)  # black is no light and no scattering, exactly
    if peak <= 1.0:
        return from_rgb(values, method)
    return from_rgb(np.minimum(values / peak, 1.0), method) * peak


def emission_from_rgb(rgb, method: str = "jakob2019") -> Spectrum:
    """The spectral radiance of an RGB emission colour (linear Rec.709, components ≥ 0, any size), as
    Cycles' emitters mean it: the colour's reflectance under D65, with D65 scaled to luminance Y = 1,
    so that white (1, 1, 1) has Y = 1 and the colour's XYZ is that of `rgb`."""
    return scaled_from_rgb(rgb, method) * _d65_of_luminance_one()


def blackbody_of_luminance_one(temperature: float) -> Spectrum:
    """Planck's spectrum at `temperature` kelvin scaled to luminance Y = 1 (CIE 1931): the colour of
    Blender's Blackbody node, which is normalised to luminance 1 too."""
    shape = blackbody(temperature)
    return shape * (1.0 / float(colorimetry.spectrum_to_xyz(shape.values)[1]))


@lru_cache(maxsize=1)
def _d65_of_luminance_one() -> Spectrum:
    d65 = illuminant("D65")
    return d65 * (1.0 / float(colorimetry.spectrum_to_xyz(d65.values)[1]))


def _finite_triple(rgb) -> tuple[float, float, float]:
    try:
        values = np.asarray(rgb, dtype=np.float64)
    except (TypeError, ValueError):
        values = None
    if values is None or values.shape != (3,) or not np.all(np.isfinite(values)):
        raise SpectralError(f"an RGB colour is three finite numbers, got {rgb!r}")
    return tuple(values.tolist())


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _field(spec: dict, key: str, name: str, default=None):
    if key not in spec:
        if default is not None:
            return default
        raise SpectralError(f"{name}: spectrum of type {spec['type']!r} needs the field {key!r}")
    return spec[key]


def _finite(value, what: str) -> float:
    """A JSON number as a float; integers beyond float64's range are an error, not an OverflowError."""
    try:
        return float(value)
    except OverflowError:
        digits = int(abs(value).bit_length() * 0.30103) + 1  # str() refuses integers over 4300 digits
        raise SpectralError(f"{what} (about {digits} digits) is too large") from None


def _number(spec: dict, key: str, name: str, default=None) -> float:
    value = _field(spec, key, name, default)
    if not _is_number(value):
        raise SpectralError(f"{name}: field {key!r} of a spectrum of type {spec['type']!r} must be a number, "
                            f"got {value!r}")
    return _finite(value, f"{name}: field {key!r} of a spectrum of type {spec['type']!r}:")


def _text(spec: dict, key: str, name: str, default=None) -> str:
    value = _field(spec, key, name, default)
    if not isinstance(value, str):
        raise SpectralError(f"{name}: field {key!r} of a spectrum of type {spec['type']!r} must be text, "
                            f"got {value!r}")
    return value


def _csv_path(spec: dict, name: str, base_dir) -> Path:
    path = Path(_text(spec, "path", name))
    return path if base_dir is None or path.is_absolute() else Path(base_dir) / path


def _sum(spec: dict, name: str, base_dir, depth: int) -> Spectrum:
    parts = _field(spec, "of", name)
    if not isinstance(parts, list) or not parts:
        raise SpectralError(f"{name}: field 'of' of a 'sum' spectrum must be a non-empty list of spectra")
    spectra = [_from_spec(part, f"{name}.of[{i}]", base_dir, depth + 1) for i, part in enumerate(parts)]
    return Spectrum(np.sum([spectrum.values for spectrum in spectra], axis=0))


def _build(spec: dict, name: str, base_dir, depth: int) -> Spectrum:
    kind = spec["type"]
    if kind not in SPEC_FIELDS:
        raise SpectralError(f"{name}: unknown spectrum type {kind!r}; known types: {', '.join(SPEC_TYPES)}")
    allowed = ("type", *SPEC_FIELDS[kind])
    for key in spec:
        if key not in allowed:
            raise SpectralError(f"{name}: unknown field {key!r} in a spectrum of type {kind!r} "
                                f"(allowed: {', '.join(allowed)})")

    def inner():
        return _from_spec(_field(spec, "of", name), f"{name}.of", base_dir, depth + 1)

    match kind:
        case "constant":
            return constant(_number(spec, "value", name))
        case "table":
            return table(_field(spec, "wavelengths", name), _field(spec, "values", name), name)
        case "gaussian":
            return gaussian(_number(spec, "peak", name), _number(spec, "width", name),
                            _number(spec, "height", name, default=1.0))
        case "blackbody":
            return blackbody(_number(spec, "temperature", name))
        case "illuminant":
            return illuminant(_text(spec, "name", name))
        case "csv":
            return from_csv(_csv_path(spec, name, base_dir), _text(spec, "units", name, default="nm"))
        case "window":
            return window(inner(), _number(spec, "min", name), _number(spec, "max", name))
        case "scale":
            return inner() * _number(spec, "factor", name)
        case "sum":
            return _sum(spec, name, base_dir, depth)


def from_spec(spec, name: str = "spectrum", *, base_dir=None) -> Spectrum:
    """Build a spectrum from its scene-format description: a number (a constant) or a dict whose "type" is
    one of SPEC_TYPES, with the fields SPEC_FIELDS lists for it (others are errors), nested at most
    MAX_SPEC_DEPTH deep. A relative csv "path" is taken relative to `base_dir` (the scene file's folder)."""
    return _from_spec(spec, name, base_dir, 0)


def _from_spec(spec, name: str, base_dir, depth: int) -> Spectrum:
    if depth >= MAX_SPEC_DEPTH:
        raise SpectralError(f"{name}: spectra are nested more than {MAX_SPEC_DEPTH} deep")
    if _is_number(spec):
        return constant(_finite(spec, f"{name}: the number"))
    if not isinstance(spec, dict) or "type" not in spec:
        raise SpectralError(f"{name}: a spectrum is a number or an object with a \"type\", got {shown(spec)}")
    with np.errstate(all="ignore"):  # an overflow is reported below, naming the description
        try:
            return _build(spec, name, base_dir, depth)
        except NonFiniteSpectrum:
            raise SpectralError(f"{name}: the spectrum {shown(spec)} has values beyond float64's range (1.8e308) "
                                "or undefined (NaN) at some wavelengths: its numbers are too extreme") from None


def to_spec(spectrum: Spectrum) -> dict:
    """Scene-format description of `spectrum`: its grid values as a "table" (from_spec restores it exactly)."""
    return {"type": "table", "wavelengths": GRID.tolist(), "values": spectrum.values.tolist()}
