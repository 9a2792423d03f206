"""What the benchmark scripts measure with: our renders timed pass by pass, peak memory, image errors,
and a description of the machine the figures come from.

Timing of our tracer covers the kernel only (`render_unit` calls): the scene is lowered once with
`compile_scene` beforehand and the kernel is compiled (or loaded from Numba's cache) by a warm-up call,
so a figure never includes one-off costs; those are printed separately where they matter.
"""

import os
import platform
import re
import resource
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from addon.tracer import colorimetry
from addon.tracer.film import Film
from addon.tracer.kernels.layout import KernelScene
from addon.tracer.lowering import compile_scene
from addon.tracer.render import pass_sizes, render_unit
from addon.tracer.scene import Scene

GIB = 2**30
MIB = 2**20


# ----------------------------------------------------------------------------- machine

def machine() -> str:
    """One line naming the CPU, cores, memory and software the figures were measured with."""
    import numba

    model = "unknown CPU"
    try:
        found = re.search(r"model name\s*:\s*(.+)", Path("/proc/cpuinfo").read_text())
        model = found.group(1).strip() if found else model
    except OSError:
        pass
    try:
        import psutil

        memory = f"{psutil.virtual_memory().total / GIB:.0f} GiB RAM"
        load = " · load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())
    except (ImportError, OSError):
        memory, load = "? RAM", ""
    return (f"{model} · {os.cpu_count()} logical cores · {memory} · Numba {numba.__version__} with "
            f"{numba.get_num_threads()} threads · Python {platform.python_version()}{load}")


# ----------------------------------------------------------------------------- memory

def _status_kib(field: str) -> int | None:
    try:
        found = re.search(rf"{field}:\s+(\d+) kB", Path("/proc/self/status").read_text())
    except OSError:
        return None
    return int(found.group(1)) if found else None


def rss() -> int:
    """Resident set size of this process now, in bytes."""
    value = _status_kib("VmRSS")
    if value is not None:
        return value * 1024
    import psutil

    return psutil.Process().memory_info().rss


class PeakRSS:
    """Peak resident set size since the last `reset()`.

    On Linux the kernel's high-water mark (VmHWM) is reset by writing 5 to /proc/self/clear_refs, so
    each phase gets its own peak. Elsewhere the peak is getrusage's ru_maxrss, the peak of the whole
    process, which cannot be reset (`resettable` says which one this is)."""

    def __init__(self):
        self.resettable = self._clear()

    @staticmethod
    def _clear() -> bool:
        try:
            Path("/proc/self/clear_refs").write_text("5")
            return _status_kib("VmHWM") is not None
        except OSError:
            return False

    def reset(self) -> None:
        self.resettable = self._clear()

    def peak(self) -> int:
        """Bytes."""
        if self.resettable:
            return _status_kib("VmHWM") * 1024
        scale = 1 if sys.platform == "darwin" else 1024  # bytes on macOS, KiB on Linux
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale


# ----------------------------------------------------------------------------- our renders

@dataclass
class Image:
    """A rendered image: mean XYZ per pixel (H, W, 3), variance of that mean, samples, kernel seconds."""

    xyz: np.ndarray
    variance: np.ndarray | None
    spp: int
    seconds: float

    @property
    def y(self) -> np.ndarray:
        return self.xyz[..., 1]


def compile_timed(scene: Scene) -> tuple[KernelScene, float]:
    start = time.perf_counter()
    kernel_scene = compile_scene(scene)
    return kernel_scene, time.perf_counter() - start


def warm_up(kernel_scene: KernelScene) -> float:
    """Compile the kernel (or load it from Numba's cache), then render one untimed sample of the whole
    image (threads started, memory touched); seconds taken."""
    start = time.perf_counter()
    width, height = kernel_scene.camera.width, kernel_scene.camera.height
    render_unit(kernel_scene, 0, (0, 1), (0, 0, min(2, width), min(2, height)), 0)
    render_unit(kernel_scene, 0, (0, 1), (0, 0, width, height), 1)
    return time.perf_counter() - start


def render_ours(kernel_scene: KernelScene, spp: int, seed: int = 0, first_sample: int = 0) -> Image:
    """Samples [first_sample, first_sample + spp) of every pixel, in passes of up to 16 samples as
    `render.render` does; `seconds` is the kernel time only."""
    width, height = kernel_scene.camera.width, kernel_scene.camera.height
    film = Film(width, height)
    seconds = 0.0
    begin = first_sample
    for size in pass_sizes(spp, first=min(16, spp)):
        start = time.perf_counter()
        sum_xyz, sum_sq, sum_transparent = render_unit(kernel_scene, 0, (begin, begin + size), (0, 0, width, height),
                                                       seed)[:3]
        seconds += time.perf_counter() - start
        film.add(0, 0, 0, sum_xyz, sum_sq, size, sum_transparent)
        begin += size
    return Image(film.xyz, film.variance, spp, seconds)


class OurRenderer:
    """Our tracer on one lowered scene, handing out fresh samples (same seed, next sample indices)."""

    def __init__(self, kernel_scene: KernelScene, seed: int):
        self.kernel_scene, self.seed, self.next_sample = kernel_scene, seed, 0

    def render(self, spp: int) -> Image:
        image = render_ours(self.kernel_scene, spp, self.seed, self.next_sample)
        self.next_sample += spp
        return image


def combine(images: list[Image]) -> Image:
    """Images of fresh samples of the same scene as one image (variance kept only if all have it)."""
    spp = sum(image.spp for image in images)
    xyz = sum(image.xyz * image.spp for image in images) / spp
    variance = None
    if all(image.variance is not None for image in images):
        # variance of the mean of the pooled samples, from each part's variance of its own mean
        variance = sum(image.variance * image.spp**2 for image in images) / spp**2
    return Image(xyz, variance, spp, sum(image.seconds for image in images))


def equal_time(renderers: dict, seconds: float, passes: int = 4, calibration_spp: int = 1) -> dict:
    """Render with each of `renderers` (name -> object with `render(spp) -> Image`) for about `seconds`
    of its own time, in `passes` interleaved rounds (A, B, …, A, B, …) so that a change of machine load
    during the run hits all alike. Each round's sample count is sized from the time per sample measured
    so far (first from a `calibration_spp` render, which is discarded), aiming at the budget."""
    per_spp = {name: max(renderer.render(calibration_spp).seconds / calibration_spp, 1e-9)
               for name, renderer in renderers.items()}
    parts = {name: [] for name in renderers}
    for index in range(passes):
        for name, renderer in renderers.items():
            spent = sum(image.seconds for image in parts[name])
            done = sum(image.spp for image in parts[name])
            if done:
                per_spp[name] = spent / done
            remaining = max(seconds - spent, 0.0)
            size = max(1, round(remaining / per_spp[name] / (passes - index)))
            parts[name].append(renderer.render(size))
    return {name: combine(images) for name, images in parts.items()}


def at_time(mse: float, seconds: float, budget: float) -> float:
    """An unbiased renderer's MSE after `budget` seconds, from its MSE after `seconds` (MSE ∝ 1/time)."""
    return mse * seconds / budget


# ----------------------------------------------------------------------------- errors

def rmse(values: np.ndarray, reference: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(values) - np.asarray(reference)) ** 2)))


def reference_noise(reference: Image, channel: int | None = 1) -> float:
    """Mean variance of the reference's pixel estimates (channel 1: Y; None: all of X, Y, Z): the part
    of a measured MSE that is the reference's own noise, subtracted by `corrected_mse`."""
    variance = reference.variance if channel is None else reference.variance[..., channel]
    return float(np.mean(variance))


def corrected_mse(image_values: np.ndarray, reference_values: np.ndarray, reference_variance: float) -> float:
    """MSE against the reference minus the reference's own noise (floored at a tenth of the MSE)."""
    mse = rmse(image_values, reference_values) ** 2
    return max(mse - reference_variance, 0.1 * mse)


def warn_reference(reference: Image, images) -> None:
    """Say so when the reference has fewer than 16× the samples of an image it judges: its noise is
    subtracted from the MSE, but that estimate is only good when the reference is much the cleaner."""
    most = max(image.spp for image in images)
    if reference.spp < 16 * most:
        print(f"  note: the reference has {reference.spp} spp, only {reference.spp / most:.0f}× the {most} spp of an "
              f"image it judges; raise --reference-spp for firmer figures")


def white_for(reference: Image) -> np.ndarray:
    """The white for CIELAB: D65's chromaticity at the 99th percentile of the reference's luminance."""
    y_white = float(np.percentile(reference.y, 99))
    x, y = 0.31271, 0.32902  # D65
    return np.array([x / y, 1.0, (1 - x - y) / y]) * y_white


def mean_delta_e(image_xyz: np.ndarray, reference_xyz: np.ndarray, white: np.ndarray) -> float:
    """Mean CIEDE2000 difference over pixels (CIELAB relative to `white`)."""
    return float(np.mean(colorimetry.delta_e_2000(image_xyz.reshape(-1, 3), reference_xyz.reshape(-1, 3), white)))


def efficiency(mse: float, seconds: float) -> float:
    """1 / (MSE · time): independent of the sample count for an unbiased renderer."""
    return 1.0 / (mse * seconds) if mse > 0 and seconds > 0 else float("inf")


def fmt_bytes(count: float) -> str:
    return f"{count / GIB:.2f} GiB" if count >= GIB else f"{count / MIB:.0f} MiB"
