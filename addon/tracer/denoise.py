"""Denoising of the film's display image with Intel Open Image Denoise (OIDN): Blender's own library, through
its C API (ctypes), on the CPU.

A display and output step: it takes the linear Rec.709 image (`Film.rgb()`, HDR) and returns a denoised
copy; the film's XYZ and variance passes are never changed. OIDN takes no variance, so the variance is
used beside it: the more precise the film's estimate (relative standard error of the luminance, averaged
over a small neighbourhood), the more of the rendered pixel is kept: all of it at no error, none from
`PRECISE_ERROR` on, so converged detail is not smoothed. The per-pixel variance means nothing
below `MIN_VARIANCE_SAMPLES` samples (a pixel whose few samples all missed the smoke reads as exact), so
`denoised_rgb` uses it only from there on. No albedo or normal feature passes: the kernel does not make
them. Negative RGB (colours outside Rec.709) is clipped to 0 for OIDN's HDR filter.

Blender ships OIDN for Cycles on every platform, so the extension bundles none: inside Blender the library
is already loaded and is found by its name; elsewhere (the CLI) it is loaded from the library folder of
the installed `bpy` module or Blender program.
"""

import ctypes
import importlib.util
import sys
import threading
from pathlib import Path

import numpy as np

from .errors import SpectralError

PRECISE_ERROR = 0.02  # relative standard error at and above which the denoised pixel is used alone
MIN_VARIANCE_SAMPLES = 16  # below this many samples per pixel the variance is not used
NEIGHBOURHOOD = 5  # side of the square over which each pixel's relative error is measured
QUALITIES = {"high": 6, "balanced": 5, "fast": 4}  # OIDN's (OIDNQuality): final renders, interactive, fastest

LIBRARY = {"win32": "OpenImageDenoise.dll", "darwin": "libOpenImageDenoise.2.dylib"}.get(
    sys.platform, "libOpenImageDenoise.so.2")
_DEVICE_CPU = 1  # OIDN_DEVICE_TYPE_CPU
_FORMAT_FLOAT3 = 3  # OIDN_FORMAT_FLOAT3
_SIGNATURES = {  # OIDN 2 C API: name -> (result, arguments)
    "oidnNewDevice": (ctypes.c_void_p, (ctypes.c_int,)),
    "oidnCommitDevice": (None, (ctypes.c_void_p,)),
    "oidnGetDeviceError": (ctypes.c_int, (ctypes.c_void_p, ctypes.POINTER(ctypes.c_char_p))),
    "oidnNewFilter": (ctypes.c_void_p, (ctypes.c_void_p, ctypes.c_char_p)),
    "oidnSetSharedFilterImage": (None, (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int,
                                        ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t,
                                        ctypes.c_size_t)),
    "oidnSetFilterBool": (None, (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_bool)),
    "oidnSetFilterInt": (None, (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int)),
    "oidnCommitFilter": (None, (ctypes.c_void_p,)),
    "oidnExecuteFilter": (None, (ctypes.c_void_p,)),
    "oidnReleaseFilter": (None, (ctypes.c_void_p,)),
}

_loaded = None  # (the OIDN library or None, why not) once `_load` has run
_lock = threading.Lock()  # one denoise at a time on the shared device
_device = None  # the committed CPU device, made on first use


def _library_paths():
    """Where Blender's OIDN may be: by name (already loaded in Blender's process, or on the loader's path),
    then the library folders of the `bpy` module (bpy/lib) or of a Blender program (beside its version
    folder, which holds scripts/modules/bpy)."""
    yield LIBRARY
    spec = importlib.util.find_spec("bpy")
    for location in (spec.submodule_search_locations or ()) if spec is not None else ():
        bpy = Path(location)
        folders = [bpy / "lib"] + ([bpy.parents[3] / "lib", bpy.parents[3] / "blender.shared"]
                                   if len(bpy.parents) > 3 else [])
        yield from (str(folder / LIBRARY) for folder in folders if (folder / LIBRARY).is_file())


def _load() -> tuple:
    """Blender's OIDN library and "", or None and the reason it cannot be used here (loaded on first use)."""
    global _loaded
    if _loaded is None:
        problem = None
        for path in _library_paths():
            try:
                library = ctypes.CDLL(path)
                for name, (result, arguments) in _SIGNATURES.items():
                    function = getattr(library, name)
                    function.restype, function.argtypes = result, arguments
            except (OSError, AttributeError) as error:  # AttributeError: a library without OIDN 2's API
                problem = problem or error
            else:
                _loaded = library, ""
                break
        else:
            _loaded = None, f"Open Image Denoise is not available on this platform ({problem})"
    return _loaded


def available() -> bool:
    """Whether this machine can denoise (Blender's OIDN library loads)."""
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
    library, reason = _load()
    if library is None:
        raise SpectralError(reason)
    denoised = _run_filter(library, np.ascontiguousarray(np.maximum(rgb, 0.0), dtype=np.float32), quality)
    if variance is None:
        return denoised
    keep = noisy_weight(rgb, variance)[..., None]
    return (keep * rgb + (1.0 - keep) * denoised).astype(np.float32)


def _run_filter(library, colour: np.ndarray, quality: str) -> np.ndarray:
    """OIDN's "RT" filter (HDR) on `colour`, a contiguous float32 (height, width, 3) image, on the CPU device."""
    global _device
    height, width, _ = colour.shape
    output = np.empty_like(colour)
    with _lock:
        if _device is None:
            _device = library.oidnNewDevice(_DEVICE_CPU)
            if _device:
                library.oidnCommitDevice(_device)
            _check_device(library, _device)
        flt = library.oidnNewFilter(_device, b"RT")
        try:
            for name, image in ((b"color", colour), (b"output", output)):
                library.oidnSetSharedFilterImage(flt, name, image.ctypes.data, _FORMAT_FLOAT3, width, height, 0, 0, 0)
            library.oidnSetFilterBool(flt, b"hdr", True)
            library.oidnSetFilterInt(flt, b"quality", QUALITIES[quality])
            library.oidnCommitFilter(flt)
            library.oidnExecuteFilter(flt)
            _check_device(library, _device)
        finally:
            if flt:
                library.oidnReleaseFilter(flt)
    return output


def _check_device(library, device) -> None:
    """Raise OIDN's last error on `device` (or that it could not be made) as a SpectralError."""
    if not device:
        raise SpectralError("Open Image Denoise failed: it could not make a CPU device")
    message = ctypes.c_char_p()
    if library.oidnGetDeviceError(device, ctypes.byref(message)) != 0:
        text = message.value.decode("utf-8", "replace") if message.value else "no reason given"
        raise SpectralError(f"Open Image Denoise failed: {text}")


def denoised_rgb(film, quality: str = "high") -> np.ndarray:
    """The film's linear Rec.709 image, denoised; its variance guides the denoiser from
    `MIN_VARIANCE_SAMPLES` samples per pixel on (see the module's docstring). A film without sample counts
    (the Cycles emulation's composite, whose variance comes from two renders) is denoised fully."""
    samples = getattr(film, "samples", None)
    variance = film.variance if samples is not None and samples.min() >= MIN_VARIANCE_SAMPLES else None
    return denoise(film.rgb(), variance, quality)
