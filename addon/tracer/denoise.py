"""Denoising of the film's display image with Intel Open Image Denoise (OIDN, through the `pyoidn` package).

A display and output step: it takes the linear Rec.709 image (`Film.rgb()`, HDR) and returns a denoised
copy; the film's XYZ and variance passes are never changed. OIDN takes no variance, so the variance is
used beside it: the more precise the film's estimate (relative standard error of the luminance, averaged
over a small neighbourhood), the more of the rendered pixel is kept: all of it at no error, none from
`PRECISE_ERROR` on, so converged detail is not smoothed. The per-pixel variance means nothing
below `MIN_VARIANCE_SAMPLES` samples (a pixel whose few samples all missed the smoke reads as exact), so
`denoised_rgb` uses it only from there on. No albedo or normal feature passes: the kernel does not make
them. Negative RGB (colours outside Rec.709) is clipped to 0 for OIDN's HDR filter.
"""

import numpy as np

from .errors import SpectralError

PRECISE_ERROR = 0.02  # relative standard error at and above which the denoised pixel is used alone
MIN_VARIANCE_SAMPLES = 16  # below this many samples per pixel the variance is not used
NEIGHBOURHOOD = 5  # side of the square over which each pixel's relative error is measured
QUALITIES = ("high", "balanced", "fast")  # OIDN's: final renders, interactive, fastest


_loaded = None  # (the `pyoidn` module or None, why not) once `_load` has run: importing it takes 0.1–0.2 s


def _load() -> tuple:
    """The `pyoidn` module and "", or None and the reason it cannot be used here (imported on first use)."""
    global _loaded
    if _loaded is None:
        try:
            import pyoidn
        except (ImportError, OSError) as problem:  # OSError: the bundled library cannot load on this machine
            _loaded = None, f"Open Image Denoise is not available on this platform ({problem})"
        else:
            _loaded = pyoidn, ""
    return _loaded


def available() -> bool:
    """Whether this machine can denoise (the `pyoidn` package and its OIDN library load)."""
    return _load()[0] is not None


def unavailable_reason() -> str:
    """Why this machine cannot denoise ("" when it can)."""
    return _load()[1]


def _check_image(name: str, image, shape=None) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or 0 in image.shape:
        raise SpectralError(f"the {name} image to denoise must be height × width × 3, not {image.shape}")
    if shape is not None and image.shape != shape:
        raise SpectralError(f"the {name} image is {image.shape}, but the image to denoise is {shape}")
    if not np.issubdtype(image.dtype, np.number) or not np.isfinite(image).all():
        raise SpectralError(f"the {name} image to denoise has non-finite values (NaN or infinity)")
    return image


def _box_mean(image: np.ndarray, size: int) -> np.ndarray:
    """Mean over a size × size square around each pixel (edges repeated), by shifted sums (no running
    sums: their rounding next to huge values would turn a zero neighbourhood's mean negative)."""
    pad = size // 2
    padded = np.pad(image, pad, mode="edge")
    height, width = image.shape
    rows = sum(padded[dy:dy + height] for dy in range(size))
    return sum(rows[:, dx:dx + width] for dx in range(size)) / (size * size)


def noisy_weight(rgb: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """How much of each pixel stays noisy (1: precise enough to keep, 0: use the denoised pixel): from the
    relative standard error of the luminance, averaged over `NEIGHBOURHOOD`, against `PRECISE_ERROR`."""
    luminance = _box_mean(np.maximum(rgb, 0.0) @ np.array([0.2126, 0.7152, 0.0722]), NEIGHBOURHOOD)
    floor = 1e-3 * max(float(luminance.mean()), 1e-12)  # black pixels of zero variance count as precise
    error = np.sqrt(_box_mean(variance[..., 1], NEIGHBOURHOOD)) / np.maximum(luminance, floor)
    return np.clip(1.0 - error / PRECISE_ERROR, 0.0, 1.0)


def denoise(rgb, variance=None, quality: str = "high") -> np.ndarray:
    """Denoised copy (float32) of a linear Rec.709 HDR image (height, width, 3). `variance`: the per-pixel
    variance of the film's XYZ estimate (height, width, 3, as `Film.variance`), or None to denoise every
    pixel fully; `quality`: one of `QUALITIES`. Raises SpectralError for bad input or without OIDN."""
    rgb = _check_image("colour", rgb)
    if quality not in QUALITIES:
        raise SpectralError(f"denoise quality {quality!r} is not one of {', '.join(QUALITIES)}")
    if variance is not None:
        variance = _check_image("variance", variance, rgb.shape)
    pyoidn, reason = _load()
    if pyoidn is None:
        raise SpectralError(reason)
    colour = np.ascontiguousarray(np.maximum(rgb, 0.0), dtype=np.float32)
    try:
        denoised = pyoidn.denoise(colour, hdr=True, quality=quality)
    except (RuntimeError, ValueError, TypeError) as problem:
        raise SpectralError(f"Open Image Denoise failed: {problem}") from problem
    if variance is None:
        return denoised
    keep = noisy_weight(rgb, variance)[..., None]
    return (keep * rgb + (1.0 - keep) * denoised).astype(np.float32)


def denoised_rgb(film, quality: str = "high") -> np.ndarray:
    """The film's linear Rec.709 image, denoised; its variance guides the denoiser from
    `MIN_VARIANCE_SAMPLES` samples per pixel on (see the module's docstring). A film without sample counts
    (the Cycles emulation's composite, whose variance comes from two renders) is denoised fully."""
    samples = getattr(film, "samples", None)
    variance = film.variance if samples is not None and samples.min() >= MIN_VARIANCE_SAMPLES else None
    return denoise(film.rgb(), variance, quality)
