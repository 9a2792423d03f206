"""Writes rendered images: multilayer EXR (XYZ, RGB and variance), PNG previews and .npy arrays.

Every file is written to a temporary name in the target folder and renamed into place, so a failed
or cancelled write never leaves a half-written file or clobbers an existing one.
"""

import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import SpectralError


def _open_image_io():
    try:
        import OpenImageIO
    except ImportError:
        raise SpectralError("writing EXR/PNG needs OpenImageIO (pip install OpenImageIO, or run inside Blender)") from None
    return OpenImageIO


def _atomic_write(path: Path, write) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(handle)
    try:
        write(temporary)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)
    return path


def _write_oiio(filename: str, pixels: np.ndarray, channel_names: list[str], pixel_type: str) -> None:
    oiio = _open_image_io()
    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, pixel_type)
    spec.channelnames = tuple(channel_names)
    if filename.endswith(".exr"):
        spec.attribute("compression", "zip")
    output = oiio.ImageOutput.create(filename)
    if output is None or not output.open(filename, spec):
        raise SpectralError(f"cannot write image {filename}: {oiio.geterror()}")
    ok = output.write_image(np.ascontiguousarray(pixels))
    output.close()
    if not ok:
        raise SpectralError(f"cannot write image {filename}: {oiio.geterror()}")


def write_exr(path, xyz: np.ndarray, rgb: np.ndarray, variance: np.ndarray | None = None) -> Path:
    """Multilayer EXR: R, G, B (linear Rec.709), A, spectral.X/Y/Z and, if given, variance.X/Y/Z."""
    alpha = np.ones(xyz.shape[:2] + (1,))
    layers = [rgb, alpha, xyz]
    names = ["R", "G", "B", "A", "spectral.X", "spectral.Y", "spectral.Z"]
    if variance is not None:
        layers.append(variance)
        names += ["variance.X", "variance.Y", "variance.Z"]
    pixels = np.concatenate(layers, axis=2).astype(np.float32)
    return _atomic_write(path, lambda name: _write_oiio(name, pixels, names, "float"))


def srgb_display(rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """The "Standard" view: exposure in stops, clip to [0, 1], sRGB transfer function; 8-bit values."""
    linear = np.clip(rgb * 2.0**exposure, 0.0, 1.0)
    encoded = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def write_png(path, rgb: np.ndarray, exposure: float = 0.0) -> Path:
    """PNG preview of linear Rec.709 through the Standard (sRGB) view transform."""
    pixels = srgb_display(rgb, exposure)
    return _atomic_write(path, lambda name: _write_oiio(name, pixels, ["R", "G", "B"], "uint8"))


def write_npy(path, xyz: np.ndarray) -> Path:
    """XYZ as a float32 array of shape (height, width, 3)."""
    return _atomic_write(path, lambda name: np.save(name, xyz.astype(np.float32)))


def read_exr(path) -> dict[str, np.ndarray]:
    """Channels of an EXR file by name, from every part (Blender writes one part per render pass)."""
    oiio = _open_image_io()
    image = oiio.ImageInput.open(str(path))
    if image is None:
        raise SpectralError(f"cannot read image {path}: {oiio.geterror()}")
    channels, part = {}, 0
    while image.seek_subimage(part, 0):
        spec = image.spec()
        pixels = image.read_image(part, 0, 0, spec.nchannels, "float")
        channels.update({name: pixels[:, :, i] for i, name in enumerate(spec.channelnames)})
        part += 1
    image.close()
    return channels
