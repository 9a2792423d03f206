"""Writes rendered images: multilayer EXR (XYZ, RGB and variance), PNG previews, .npy arrays and text.

The multilayer EXR's channels are named as Blender names a render's passes (`LAYER.PASS.CHANNEL`):
`ViewLayer.Combined.R/G/B/A` (linear Rec.709), `ViewLayer.XYZ.X/Y/Z` and `ViewLayer.XYZ Variance.X/Y/Z`.
`PASSES` is the one list of them: the render engine registers these passes, so F12's EXR, Render to
Image's and the command lines' are named alike and Blender opens every one as the same render layer. The data
passes a scene asks for (`passes`: `ViewLayer.Depth.Z`, `ViewLayer.Mist.Z`, `ViewLayer.Normal.X/Y/Z`,
`ViewLayer.CryptoObject00.R/G/B/A`, …) follow them, with Cryptomatte's metadata in the header. The spectral EXR
(`spectral_exr`) is a file of its own, in the layout of Fichet et al. 2021.

All files of one command are written together (`write_all`): each to a temporary name beside its
destination, and only when every one was written are they renamed into place. A failed or cancelled
write never leaves a half-written file or clobbers an existing one, and never replaces some files but
not others. `check_destination` tells before a long render whether a file can be written at all, and
`check_distinct` that no two outputs name the same file (the second would replace the first).
"""

import errno
import os
import shutil
import tempfile
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np

from .checks import byte_size
from .errors import SpectralError
from .spectral_film import channel_wavelength


VIEW_LAYER = "ViewLayer"  # Blender's default view layer name: the layer of an EXR written outside Blender
COMBINED, XYZ, VARIANCE = "Combined", "XYZ", "XYZ Variance"
PASSES = {COMBINED: "RGBA", XYZ: "XYZ", VARIANCE: "XYZ"}  # each pass's channels, in order


def channel_names(pass_name: str, layer: str = VIEW_LAYER) -> list[str]:
    """The EXR channel names of one pass, e.g. `ViewLayer.XYZ.X`, `ViewLayer.XYZ.Y`, `ViewLayer.XYZ.Z`."""
    return [f"{layer}.{pass_name}.{letter}" for letter in PASSES[pass_name]]


class Output(NamedTuple):
    """A file to write: `write(temporary_name)` writes its contents to a file of that name."""

    path: Path
    write: Callable[[str], None]


def _open_image_io():
    try:
        import OpenImageIO
    except ImportError:
        raise SpectralError("writing EXR/PNG needs OpenImageIO (pip install OpenImageIO, or run inside Blender)") from None
    return OpenImageIO


def why(problem: OSError) -> str:
    """An OSError in words, a full disk said plainly."""
    if problem.errno == errno.ENOSPC:
        return "the disk is full (no space left on the device)"
    if problem.errno == errno.EDQUOT:
        return "the disk quota is exceeded (no space left for this user)"
    return problem.strerror or str(problem)


def _existing_ancestor(folder: Path) -> Path:
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    return folder


def check_destination(path, suffix: str | None = None) -> Path:
    """`path` if a file can be created there (its folder may not exist yet), else a SpectralError saying
    why; `suffix`, when given, is the file name ending the format needs. Leaves nothing behind."""
    path = Path(path)
    if suffix is not None and path.suffix.lower() != suffix:
        raise SpectralError(f"{path}: the file is written as {suffix[1:].upper()}, so its name must end in {suffix}")
    if path.is_dir():
        raise SpectralError(f"cannot write {path}: it is a folder")
    folder = _existing_ancestor(path.absolute().parent)
    if not folder.is_dir():
        raise SpectralError(f"cannot write {path}: {folder} is a file, not a folder")
    try:
        handle, probe = tempfile.mkstemp(prefix=f".{path.name}.", dir=folder)
        os.close(handle)
        os.unlink(probe)
    except OSError as problem:
        raise SpectralError(f"cannot write {path}: {why(problem)}") from None
    return path


def _same_file(first: Path, second: Path) -> bool:
    """Whether two paths name one file: equal once `..` and symbolic links are resolved, or (both existing)
    one file by two names (hard links, a case-insensitive file system)."""
    if first.resolve() == second.resolve():
        return True
    try:
        return os.path.samefile(first, second)
    except OSError:  # one does not exist (yet): only equal resolved paths name the same file
        return False


def check_distinct(named_paths) -> None:
    """A SpectralError naming both when two of the (name, path) pairs (None paths skipped) name the same file:
    the second write would replace the first."""
    seen = []
    for name, path in named_paths:
        if path is None:
            continue
        for other_name, other_path in seen:
            if _same_file(Path(other_path), Path(path)):
                both = f"{other_path}" if str(other_path) == str(path) else f"{other_path} and {path}"
                raise SpectralError(f"{other_name} and {name} name the same file ({both}): each output needs a "
                                    "file of its own, or one would replace the other")
        seen.append((name, path))


def _make_folders(folder: Path) -> list[Path]:
    """Create `folder` and its missing parents; returns those created, deepest first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    for created in reversed(missing):
        created.mkdir()
    return missing


def write_all(outputs: list[Output]) -> list[Path]:
    """Write every output or none (see the module docstring); folders are created as needed and removed
    again when the writing fails. Returns the paths written."""
    check_distinct((f"the output {output.path}", output.path) for output in outputs)
    for output in outputs:
        check_destination(output.path)
    staged, created, done = [], [], False
    try:
        for output in outputs:
            path = Path(output.path)
            try:
                created += _make_folders(path.parent)
                handle, temporary = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
                os.close(handle)
                staged.append(temporary)
                output.write(temporary)
            except OSError as problem:
                raise SpectralError(f"cannot write {path}: {why(problem)}") from None
            except SpectralError as problem:
                raise SpectralError(f"cannot write {path}: {problem}") from None
        mode = _new_file_mode()
        for temporary, output in zip(staged, outputs):
            try:
                os.chmod(temporary, mode)  # mkstemp makes files private (0600): give the mode a new file gets
                os.replace(temporary, output.path)
            except OSError as problem:  # rare after a successful write in the same folder
                raise SpectralError(f"cannot write {output.path}: {why(problem)}") from None
        done = True
    finally:
        for temporary in staged:
            if os.path.exists(temporary):
                os.unlink(temporary)
        if not done:
            for folder in created:
                if folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()
    return [Path(output.path) for output in outputs]


def _new_file_mode() -> int:
    """The mode a file created here gets (0666 less the process's umask), as Blender's own writes get."""
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask


def _write_oiio(filename: str, pixels: np.ndarray, channel_names: list[str], pixel_type: str,
                straight_alpha: bool = False, attributes: dict | None = None) -> None:
    """Write `pixels` as they are; `straight_alpha`: their colour is already divided by alpha (OpenImageIO would
    otherwise divide it again for a format whose alpha is straight, as PNG's); `attributes`: header fields."""
    oiio = _open_image_io()
    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, pixel_type)
    spec.channelnames = tuple(channel_names)
    if straight_alpha:
        spec.attribute("oiio:UnassociatedAlpha", 1)
    for key, value in (attributes or {}).items():
        spec.attribute(key, value)
    if filename.endswith(".exr"):
        spec.attribute("compression", "zip")
    output = oiio.ImageOutput.create(filename)
    if output is None:
        raise SpectralError(f"OpenImageIO cannot write it: {oiio.geterror() or 'it gave no reason'}")
    ok = output.open(filename, spec) and output.write_image(np.ascontiguousarray(pixels))
    reason = output.geterror() or oiio.geterror()  # the file's own error first: the global one is often empty
    ok = output.close() and ok
    if not ok:
        full = _disk_space_short(filename, pixels.nbytes)
        raise SpectralError(f"OpenImageIO cannot write it: {'; '.join(filter(None, (full, reason))) or 'it gave no reason'}")


def _disk_space_short(filename: str, size: int) -> str:
    """"the disk is full ..." when the disk holding `filename` has less free space than `size` bytes (the
    uncompressed image: OpenImageIO does not say why a write failed), else ""."""
    try:
        free = shutil.disk_usage(Path(filename).absolute().parent).free
    except OSError:
        return ""
    if free >= size:
        return ""
    return f"the disk is full ({byte_size(free)} free, the image takes up to {byte_size(size)})"


def exr(path, xyz: np.ndarray, rgb: np.ndarray, variance: np.ndarray | None = None, alpha: np.ndarray | None = None,
        layer: str = VIEW_LAYER, data=None) -> Output:
    """Multilayer EXR of the render layer `layer`: the Combined pass (RGB linear Rec.709, `alpha`, default 1),
    XYZ and, if given, XYZ Variance and the data passes `data` (a `passes.PassImages`; see the module
    docstring)."""
    alpha = np.ones(xyz.shape[:2]) if alpha is None else alpha
    layers = [rgb, alpha[..., None], xyz]
    names = channel_names(COMBINED, layer) + channel_names(XYZ, layer)
    if variance is not None:
        layers.append(variance)
        names += channel_names(VARIANCE, layer)
    extra, extra_names, attributes = data_layers(data, layer)
    pixels = finite(np.concatenate(layers + extra, axis=2), path)
    names += extra_names
    return Output(check_destination(path, ".exr"), lambda name: _write_oiio(name, pixels, names, "float", attributes=attributes))


def data_layers(data, layer: str = VIEW_LAYER) -> tuple[list[np.ndarray], list[str], dict]:
    """The data passes of `data` (a `passes.PassImages`, or None) as EXR layers: their pixels, channel names
    (`LAYER.PASS.CHANNEL`) and header attributes (Cryptomatte's, its layer names given for `layer`)."""
    if data is None:
        return [], [], {}
    from .passes import CHANNELS

    arrays, names = [], []
    for pass_name, pixels in data.images.items():
        arrays.append(pixels)
        names += [f"{layer}.{pass_name}.{letter}" for letter in CHANNELS.get(pass_name, "RGBA")]
    return arrays, names, data.metadata(layer)


def finite(pixels: np.ndarray, path) -> np.ndarray:
    """`pixels` as float32, or a SpectralError when any is not finite there (NaN, or beyond float32's 3.4e38,
    as the squares of very bright samples are): no file ever holds one."""
    with np.errstate(over="ignore"):
        pixels = np.asarray(pixels).astype(np.float32)
    bad = ~np.isfinite(pixels)
    if bad.any():
        row, column = (int(i) for i in np.argwhere(bad)[0][:2])
        raise SpectralError(f"cannot write {path}: {int(bad.sum())} of its values are NaN or beyond float32's range "
                            f"(3.4e38), the first at row {row}, column {column}; lower the brightest lights or "
                            "emission")
    return pixels


SPECTRAL_LAYOUT_VERSION = "1.0"  # the version of Fichet et al. 2021's layout the spectral EXR follows


def spectral_channel_names(edges) -> list[str]:
    """The spectral EXR's channel of each bin (`edges`: B + 1 values in nm): `S0.<centre>nm`, the first Stokes
    component (unpolarised emission) at the bin's centre (`spectral_film.channel_wavelength`: `S0.385nm`,
    `S0.382,5nm`)."""
    edges = np.asarray(edges, dtype=np.float64)
    return [f"S0.{channel_wavelength(centre)}nm" for centre in (edges[:-1] + edges[1:]) / 2]


def spectral_exr(path, spectrum: np.ndarray, edges, units: str, rgb: np.ndarray | None = None,
                 alpha: np.ndarray | None = None) -> Output:
    """The spectral image `spectrum` (height, width, bins: the mean spectral radiance over each bin of `edges`,
    `Film.spectrum`) as an EXR in the layout of Fichet et al. 2021: a channel per bin (`spectral_channel_names`),
    the header's `spectralLayoutVersion` and `emissiveUnits` (`units`: `spectral_film.radiance_units`), and, when
    given, linear Rec.709 `rgb` as R, G, B (and `alpha` as A) for viewers that show no spectra."""
    layers, names = [], []
    if rgb is not None:
        layers.append(rgb)
        names += ["R", "G", "B"]
        if alpha is not None:
            layers.append(alpha[..., None])
            names.append("A")
    names += spectral_channel_names(edges)
    if spectrum.shape[2] != len(edges) - 1:
        raise SpectralError(f"the spectral image has {spectrum.shape[2]} bins, but {len(edges)} edges make "
                            f"{len(edges) - 1}")
    pixels = finite(np.concatenate(layers + [spectrum], axis=2), path)
    attributes = {"spectralLayoutVersion": SPECTRAL_LAYOUT_VERSION, "emissiveUnits": units}
    return Output(check_destination(path, ".exr"),
                  lambda name: _write_oiio(name, pixels, names, "float", attributes=attributes))


def write_spectral_exr(path, spectrum: np.ndarray, edges, units: str, rgb: np.ndarray | None = None,
                       alpha: np.ndarray | None = None) -> Path:
    """Write `spectral_exr(...)` on its own."""
    return write_all([spectral_exr(path, spectrum, edges, units, rgb, alpha)])[0]


def write_exr(path, xyz: np.ndarray, rgb: np.ndarray, variance: np.ndarray | None = None,
              alpha: np.ndarray | None = None, layer: str = VIEW_LAYER, data=None) -> Path:
    """Write `exr(...)` on its own."""
    return write_all([exr(path, xyz, rgb, variance, alpha, layer, data)])[0]


def srgb_display(rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """The "Standard" view: exposure in stops, clip to [0, 1], sRGB transfer function; 8-bit values."""
    linear = np.clip(rgb * 2.0**exposure, 0.0, 1.0)
    encoded = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def png(path, rgb: np.ndarray, exposure: float = 0.0, alpha: np.ndarray | None = None) -> Output:
    """PNG preview of linear Rec.709 through the Standard (sRGB) view transform; with `alpha` (height, width),
    an RGBA PNG: the colour, premultiplied in a render, is divided by alpha first (PNG's alpha is straight, as
    Blender saves it), and alpha is clipped to [0, 1]."""
    rgb = finite(rgb, path)
    if alpha is None:
        return Output(check_destination(path, ".png"),
                      lambda name: _write_oiio(name, srgb_display(rgb, exposure), ["R", "G", "B"], "uint8"))
    alpha = np.clip(finite(alpha, path), 0.0, 1.0)[..., None]
    straight = np.divide(rgb, alpha, out=np.zeros_like(rgb), where=alpha > 0.0)
    pixels = np.concatenate([srgb_display(straight, exposure), np.round(alpha * 255).astype(np.uint8)], axis=2)
    return Output(check_destination(path, ".png"),
                  lambda name: _write_oiio(name, pixels, ["R", "G", "B", "A"], "uint8", straight_alpha=True))


def write_png(path, rgb: np.ndarray, exposure: float = 0.0, alpha: np.ndarray | None = None) -> Path:
    """Write `png(...)` on its own."""
    return write_all([png(path, rgb, exposure, alpha)])[0]


def npy(path, xyz: np.ndarray) -> Output:
    """XYZ as a float32 array of shape (height, width, 3)."""
    pixels = finite(xyz, path)
    return Output(check_destination(path, ".npy"), lambda name: np.save(name, pixels))


def write_npy(path, xyz: np.ndarray) -> Path:
    """Write `npy(...)` on its own."""
    return write_all([npy(path, xyz)])[0]


def text(path, content: str) -> Output:
    """A UTF-8 text file."""
    return Output(check_destination(path), lambda name: Path(name).write_text(content, encoding="utf-8"))


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
