"""Checks of single values, each raising a SpectralError that starts with `where` (a scene-file path such
as `media[0].albedo`, or a command-line option) and shows the offending value.

Shared by the scene file reader (types) and `validation.validate` (ranges), so that a rule and its message
are written once.
"""

import numpy as np

from .errors import SpectralError
from .wavelengths import GRID


def shown(value, limit: int = 80) -> str:
    """`repr(value)`, shortened to about `limit` characters (a huge or deeply nested value stays readable)."""
    try:
        text = repr(value)
    except (RecursionError, ValueError):  # nesting beyond the interpreter's limit; ints over 4300 digits
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 1] + "…"


_BYTE_UNITS = {"PiB": 2**50, "TiB": 2**40, "GiB": 2**30, "MiB": 2**20, "KiB": 2**10}


def byte_size(count: int, unit: str | None = None) -> str:
    """A number of bytes for people: "3.55 PiB", "281 KiB"; in `unit` ("GiB", ...) when given."""
    if unit is None:
        unit = next((name for name, scale in _BYTE_UNITS.items() if count >= scale), None)
        if unit is None:
            return f"{count} bytes"
    if count >= 2**1000 or count / _BYTE_UNITS[unit] >= 1e15:  # integers from JSON have no size limit
        return f"more than 1e15 {unit}"
    value = count / _BYTE_UNITS[unit]
    return f"{value:.3g} {unit}" if value < 1000 else f"{value:.0f} {unit}"


def number(value, where: str) -> float:
    """A finite real number (JSON booleans are not numbers)."""
    try:
        real = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        result = float(value) if real else np.nan
    except OverflowError:  # an integer beyond float64's range
        result = np.nan
    if not np.isfinite(result):
        raise SpectralError(f"{where}: expected a finite number, found {shown(value)}")
    return result


def whole(value, where: str) -> int:
    """An integer (JSON booleans are not integers)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SpectralError(f"{where}: expected a whole number, found {shown(value)}")
    return int(value)


def within(value: float, where: str, low: float = -np.inf, high: float = np.inf, closed: bool = True) -> float:
    """`value` if it lies in [low, high] (or (low, high) when not `closed`)."""
    inside = low <= value <= high if closed else low < value < high
    if not inside:
        brackets = "[]" if closed else "()"
        raise SpectralError(f"{where}: must be within {brackets[0]}{low:g}, {high:g}{brackets[1]}, found {value:g}")
    return value


def positive(value: float, where: str) -> float:
    if not value > 0:
        raise SpectralError(f"{where}: must be positive, found {value:g}")
    return value


def whole_within(value, where: str, minimum: int, maximum: int | None = None) -> int:
    """An integer of at least `minimum` (and at most `maximum`, when given)."""
    value = whole(value, where)
    if value < minimum:
        raise SpectralError(f"{where}: must be at least {minimum}, found {value}")
    if maximum is not None and value > maximum:
        raise SpectralError(f"{where}: must be at most {maximum}, found {shown(value, 40)}")
    return value


def one_of(value, where: str, allowed: tuple):
    if isinstance(value, (dict, list)) or value not in allowed:
        raise SpectralError(f"{where}: unknown value {shown(value)} (allowed: {', '.join(map(str, allowed))})")
    return value


def spectrum_within(values: np.ndarray, where: str, rule: str, low: float, high: float, closed: bool = True) -> None:
    """Error naming the worst value of a spectrum on GRID outside [low, high] (or the open interval) and
    its wavelength; `rule` says the rule in words."""
    outside = (values < low) | (values > high) if closed else (values <= low) | (values >= high)
    if outside.any():
        excess = np.where(outside, np.maximum(low - values, values - high), -np.inf)
        worst = int(np.argmax(excess))
        raise SpectralError(f"{where}: {rule}, found {values[worst]:.10g} at {GRID[worst]:g} nm")


def vector(value, where: str) -> np.ndarray:
    """A list (or array) of 3 finite numbers as a float64 array."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3:
        raise SpectralError(f"{where}: expected a list of 3 numbers, found {shown(value)}")
    return np.array([number(c, f"{where}[{i}]") for i, c in enumerate(value)])


def matrix3(value, where: str) -> np.ndarray:
    """A 3 × 3 matrix (a list of 3 rows of 3 finite numbers) as a float64 array."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3:
        raise SpectralError(f"{where}: expected a 3 × 3 matrix (a list of 3 rows), found {shown(value)}")
    return np.array([vector(row, f"{where}[{index}]") for index, row in enumerate(value)])


def direction(value, where: str) -> np.ndarray:
    """A 3-vector of non-zero length (not normalised; any finite length, 1e-300 or 1e200, is fine)."""
    result = vector(value, where)
    if not np.abs(result).max() > 0:
        raise SpectralError(f"{where}: a direction cannot have zero length")
    return result


def unit(vectors: np.ndarray, axis: int = -1) -> np.ndarray:
    """Finite non-zero vectors (along `axis`) scaled to length 1 without overflow or underflow: each is first
    divided by its largest component, so that the length of one of length 1e200 is not inf (nor 1e-200's 0)."""
    vectors = np.asarray(vectors, dtype=np.float64)
    scaled = vectors / np.abs(vectors).max(axis=axis, keepdims=True)
    return scaled / np.linalg.norm(scaled, axis=axis, keepdims=True)


def unit_vector(value, where: str) -> np.ndarray:
    """A direction (see `direction`) normalised to length 1."""
    return unit(direction(value, where))


def affine_matrix(value, what: str) -> np.ndarray:
    """`value` as a 4×4 float64 affine matrix (row-major, acting on column vectors), or a SpectralError."""
    try:
        matrix = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError, RecursionError):
        raise SpectralError(f"{what}: a matrix is 4 lists of 4 numbers, got {shown(value)}") from None
    if matrix.shape != (4, 4):
        raise SpectralError(f"{what}: a matrix is 4 lists of 4 numbers, got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise SpectralError(f"{what}: the matrix contains NaN or infinite numbers")
    if not np.allclose(matrix[3], [0.0, 0.0, 0.0, 1.0], rtol=0.0, atol=1e-9):
        raise SpectralError(
            f"{what}: the bottom row must be [0, 0, 0, 1], found {matrix[3].tolist()} "
            "(matrices are row-major and act on column vectors: is it transposed?)"
        )
    matrix[3] = [0.0, 0.0, 0.0, 1.0]
    # Scale-free test: |det| against the product of the column lengths (1 for a rotation of any scale).
    linear = matrix[:3, :3]
    if abs(np.linalg.det(linear)) <= 1e-9 * np.prod(np.linalg.norm(linear, axis=0)):
        raise SpectralError(f"{what}: the matrix is singular (a zero scale, or two axes in one direction?)")
    return matrix


def grid_values(values: np.ndarray, where: str, nonnegative: bool) -> None:
    """A grid's values: a 3-D array, not empty, finite, and non-negative where `nonnegative`."""
    if values.ndim != 3:
        raise SpectralError(f"{where} must be a 3-D array indexed [x, y, z], found shape {values.shape}")
    if values.size == 0:
        raise SpectralError(f"{where} is empty (shape {values.shape})")
    bad = ~np.isfinite(values)
    if bad.any():
        raise SpectralError(f"{where} has {int(bad.sum())} NaN or infinite values, first at index {_first_index(bad)}")
    negative = values < 0
    if nonnegative and negative.any():
        raise SpectralError(
            f"{where} has {int(negative.sum())} negative values (min {values.min():g}), "
            f"first at index {_first_index(negative)}"
        )


def _first_index(mask: np.ndarray) -> tuple:
    return tuple(int(i) for i in np.argwhere(mask)[0])
