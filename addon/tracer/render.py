"""Renders a scene: splits the work into (band, sample range, tile) units, runs them on a backend,
and accumulates them on a `Film`, with progress callbacks and cancellation between passes.

`render_unit` is the pure unit of work (also what distributed workers run): its result depends only on
(scene, band, sample range, tile, seed), so any split of the work gives the same image.
"""

import time
from dataclasses import dataclass, field

import numpy as np

from . import sampling
from .compile import KernelScene, compile_scene, default_band, with_band
from .errors import SpectralError
from .film import Film
from .scene import Scene

BACKENDS = ("numba", "numpy")


def backend_module(name: str):
    if name == "numba":
        from .kernels import numba_backend

        return numba_backend
    if name == "numpy":
        from .kernels import numpy_backend

        return numpy_backend
    raise SpectralError(f"unknown backend {name!r}: choose one of {', '.join(BACKENDS)}")


def band_scenes(scene: Scene, kernel_scene: KernelScene | None = None) -> list[KernelScene]:
    """Kernel data for each wavelength band of the scene's settings."""
    settings = scene.settings
    kernel_scene = kernel_scene if kernel_scene is not None else compile_scene(scene)
    if settings.bands == 1:
        return [kernel_scene]
    lo, hi = default_band(settings)
    return [with_band(kernel_scene, settings.wavelength_sampling, band_lo, band_hi)
            for band_lo, band_hi in sampling.band_ranges(lo, hi, settings.bands)]


def render_unit(kernel_scene: KernelScene, band: int, samples: tuple[int, int], tile: tuple[int, int, int, int],
                seed: int, backend: str = "numba") -> tuple[np.ndarray, np.ndarray]:
    """Σ XYZ and Σ XYZ² over samples [begin, end) of each pixel in tile (x0, y0, width, height)."""
    x0, y0, width, height = tile
    sum_xyz = np.zeros((height, width, 3))
    sum_sq = np.zeros((height, width, 3))
    backend_module(backend).render_tile(kernel_scene, x0, y0, width, height, samples[0], samples[1],
                                        seed, band, sum_xyz, sum_sq)
    return sum_xyz, sum_sq


def pass_sizes(spp: int, first: int = 1, largest: int = 16) -> list[int]:
    """Samples per pass: doubling from `first` up to `largest`, so the first image comes quickly."""
    sizes, size = [], first
    while sum(sizes) < spp:
        sizes.append(min(size, spp - sum(sizes)))
        size = min(size * 2, largest)
    return sizes


@dataclass
class RenderResult:
    film: Film
    cancelled: bool = False
    seconds: float = 0.0
    stats: dict = field(default_factory=dict)


def render(scene: Scene, *, spp: int | None = None, seed: int | None = None, backend: str | None = None,
           threads: int | None = None, progress=None, cancel=None) -> RenderResult:
    """Render `scene`. `progress(film, done_fraction)` is called after each pass; `cancel()` is asked
    between passes and, when true, stops the render (the result says `cancelled`)."""
    settings = scene.settings
    spp = settings.spp if spp is None else int(spp)
    seed = settings.seed if seed is None else int(seed)
    backend = backend or settings.backend
    if spp < 1:
        raise SpectralError(f"samples per pixel must be at least 1, got {spp}")
    module = backend_module(backend)
    if threads:
        module.set_threads(int(threads))
    start = time.perf_counter()
    bands = band_scenes(scene)
    camera = scene.camera
    film = Film(camera.width, camera.height, len(bands))
    tile = (0, 0, camera.width, camera.height)
    sizes = pass_sizes(spp)
    total_units = len(sizes) * len(bands)
    done_units = 0
    begin = 0
    cancelled = False
    for size in sizes:
        for band, kernel_scene in enumerate(bands):
            if cancel is not None and cancel():
                cancelled = True
                break
            sum_xyz, sum_sq = render_unit(kernel_scene, band, (begin, begin + size), tile, seed, backend)
            film.add(band, 0, 0, sum_xyz, sum_sq)
            film.count(band, size)
            done_units += 1
            if progress is not None:
                progress(film, done_units / total_units)
        if cancelled:
            break
        begin += size
    seconds = time.perf_counter() - start
    return RenderResult(film=film, cancelled=cancelled, seconds=seconds, stats=render_stats(film, seconds, backend))


def render_stats(film: Film, seconds: float, backend: str) -> dict:
    """Timing, throughput and mean XYZ of a finished (or cancelled) render, for --stats and the UI."""
    pixel_samples = int(film.samples.sum()) * film.width * film.height
    return {
        "seconds": seconds,
        "samples_per_pixel": int(film.samples.min()) if film.samples.size else 0,
        "pixel_samples_per_second": pixel_samples / seconds if seconds > 0 else 0.0,
        "mean_xyz": film.xyz.reshape(-1, 3).mean(axis=0).tolist(),
        "backend": backend,
        "bands": film.bands,
    }
