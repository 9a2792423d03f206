"""Renders a scene: splits the work into units (a tile of one band's pass, about a quarter of a second of
work each), runs them on a backend and adds them to a `Film`, with progress by samples done and
cancellation between units.

`render_unit` is the pure unit of work (also what distributed workers run): its result depends only on
(scene, band, sample range, tile, seed), so any split of the work gives the same image. The passes
(sample ranges) depend only on the sample count, and every pixel receives them in order, so the film's
sums are formed exactly as by `distributed.render`, whatever the tiles. Renders running at once in one
process (the Rendered viewport's and F12's) take turns unit by unit.
"""

import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from . import adaptive, backends, sampling
from .backends import tile_arguments
from .light_passes import light_categories, light_images
from .passes import DATA_PASSES, PassImages, render_passes
from .errors import SpectralError
from .fireflies import Peaks, filtered, group_size
from .film import Film
from .kernels.layout import KernelScene
from .lowering import compile_scene
from .scene import Scene
from .wavelength_modes import default_band, with_band


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
                seed: int, backend: str = "numba", light_categories: int = 0,
                spectrum: bool = False, peaks: bool = False) -> tuple:
    """Σ XYZ, Σ XYZ² and Σ transparency over samples [begin, end) of each pixel in tile (x0, y0, width,
    height), then Σ XYZ of each of `light_categories` light categories (`light_passes.light_categories`; none
    when 0) and, with `spectrum`, the Σ of each spectral bin's estimate (height, width, bins; the scene's bins,
    `kernel_scene.wavelengths.spectrum_edges`; none without). With `peaks` (the samples are one group of the
    firefly filter's), a sixth: the same sums as the pixels' peaks (`fireflies.Peaks`)."""
    arguments = tile_arguments(kernel_scene, band, samples, tile, seed, light_categories, spectrum)
    backends.named(backend).kernels.render_tile(*arguments)
    sums = arguments[-5:]
    return (*sums, Peaks.of(sums[0], sums[1], sums[3], sums[4])) if peaks else sums


def passes(spp: int, first: int = 1, largest: int = 16) -> Iterator[tuple[int, int]]:
    """(first sample, samples) of each pass: sizes doubling from `first` up to `largest`, so the first
    image comes quickly."""
    begin, size = 0, first
    while begin < spp:
        count = min(size, spp - begin)
        yield begin, count
        begin += count
        size = min(size * 2, largest)


def pass_sizes(spp: int, first: int = 1, largest: int = 16) -> list[int]:
    """Samples per pass (see `passes`)."""
    return [count for _, count in passes(spp, first, largest)]


# Renders of one process (the Rendered viewport's and F12's) take turns unit by unit: Numba's workqueue
# threading layer aborts when two threads launch kernels at once.
KERNEL_LAUNCH = threading.Lock()
UNIT_SECONDS = 0.2  # aimed below the 0.25 s a unit may take, since tiles differ in cost
FIRST_UNIT = 1024  # pixel-samples of the first unit, before any throughput is known
GROWTH = 4  # a unit has at most this many times the pixel-samples of the largest one measured


class Tiler:
    """Cuts passes into tiles of about `seconds` of work each, sized from the cost measured so far.

    Tiles are runs of whole rows (or part of one row when a row is more work than a unit), in reading
    order. Rows differ (empty sky, dense cloud) but stay alike from pass to pass, so each row's cost per
    pixel-sample is remembered from the last tile that covered it; rows not measured yet count at the
    cost of all units so far, tracked pessimistically (it rises at once and falls by halves)."""

    def __init__(self, width: int, height: int, seconds: float = UNIT_SECONDS):
        self.width, self.height, self.seconds = width, height, seconds
        self.cost = None  # seconds per pixel-sample, all units so far
        self.row_cost = np.full(height, np.nan)  # seconds per pixel-sample of each row, last measured
        self.largest = FIRST_UNIT // GROWTH  # pixel-samples of the largest unit measured

    def measured(self, tile: tuple[int, int, int, int], samples: int, seconds: float) -> None:
        _, y0, width, height = tile
        pixel_samples = width * height * samples
        cost = seconds / pixel_samples
        self.cost = cost if self.cost is None or cost > self.cost else (self.cost + cost) / 2
        self.row_cost[y0:y0 + height] = cost
        self.largest = max(self.largest, pixel_samples)

    def _costs(self, y: int) -> np.ndarray:
        """Cost per pixel-sample of rows y, y + 1, … (0 while nothing is measured: growth limits then)."""
        costs = self.row_cost[y:]
        return np.where(np.isnan(costs), self.cost or 0.0, costs)

    def tiles(self, samples: int, active: np.ndarray | None = None) -> Iterator[tuple[int, int, int, int]]:
        """Tiles (x0, y0, width, height) covering the image once, for a pass of `samples` per pixel. With
        `active` (height, width, bool), each tile is cropped to the box of its active pixels and tiles
        without any are left out: every active pixel is covered once (and inactive ones inside a box too,
        which costs some samples but keeps the units few and large)."""
        for tile in self._full_tiles(samples):
            if active is None:
                yield tile
                continue
            x0, y0, width, height = tile
            rows, columns = np.nonzero(active[y0:y0 + height, x0:x0 + width])
            if rows.size:
                yield (x0 + int(columns.min()), y0 + int(rows.min()), int(columns.max() - columns.min()) + 1,
                       int(rows.max() - rows.min()) + 1)

    def _full_tiles(self, samples: int) -> Iterator[tuple[int, int, int, int]]:
        x, y = 0, 0
        while y < self.height:
            most = self.largest * GROWTH // samples  # pixels
            if x == 0:
                seconds = np.cumsum(self._costs(y)) * (self.width * samples)
                rows = min(int(np.searchsorted(seconds, self.seconds, side="right")), most // self.width)
                if rows > 0:
                    yield 0, y, self.width, rows
                    y += rows
                    continue
            cost = self._costs(y)[0] * samples
            columns = max(1, min(most, self.width - x, int(self.seconds / cost) if cost > 0 else most))
            yield x, y, columns, 1
            x += columns
            if x == self.width:
                x, y = 0, y + 1


@dataclass
class RenderResult:
    film: Film
    cancelled: bool = False
    seconds: float = 0.0
    stats: dict = field(default_factory=dict)
    # the data and light passes the scene asks for (`passes`, `light_passes`), once rendered
    passes: PassImages = field(default_factory=lambda: PassImages({}, {}))


def first_hit_passes(scene: Scene, kernel_scene: KernelScene, spp: int, seed: int, backend: str, cancel=None,
                     notice=None) -> PassImages | None:
    """The data passes the scene asks for (`passes.render_passes`: none when it asks for none), the backend's
    first-hit kernel made ready first (`Backend.prepare_first_hits`); None when `cancel()` said stop meanwhile.
    They need only the camera and the surfaces, so a farm or the Cycles emulation makes them here too."""
    if not any(name in DATA_PASSES for name in scene.settings.passes):
        return PassImages({}, {})
    if not backends.named(backend).prepare_first_hits(kernel_scene, cancel, notice):
        return None
    with KERNEL_LAUNCH:
        return render_passes(scene, kernel_scene, spp, seed, backend)


def render(scene: Scene, *, spp: int | None = None, seed: int | None = None, backend: str | None = None,
           threads: int | None = None, progress=None, cancel=None, notice=None,
           unit_seconds: float = UNIT_SECONDS) -> RenderResult:
    """Render `scene`. `progress(film, fraction)` is called after each unit of work, with the fraction of
    all samples done; `cancel()` is asked before each unit (and while the kernel compiles) and, when true,
    stops the render (the result says `cancelled`; the film holds the units done). `notice(text)` is told
    what the render waits for before it starts (the kernel compiling). Units take about `unit_seconds`."""
    settings = scene.settings
    spp = settings.spp if spp is None else int(spp)
    seed = settings.seed if seed is None else int(seed)
    backend = backend or settings.backend
    if spp < 1:
        raise SpectralError(f"samples per pixel must be at least 1, got {spp}")
    chosen = backends.named(backend)
    if threads:
        chosen.kernels.set_threads(int(threads))
    start = time.perf_counter()
    bands = band_scenes(scene)
    camera = scene.camera
    categories = light_categories(settings)
    group = group_size(spp) if settings.firefly_threshold > 0 else 0  # the firefly filter's samples per group
    film = Film(camera.width, camera.height, len(bands), categories, bands[0].wavelengths.spectrum_edges, group)
    total = camera.width * camera.height * spp * len(bands)
    done = 0
    cancelled = not chosen.prepare(bands[0], seed, cancel, notice)
    tiler = Tiler(camera.width, camera.height, unit_seconds)
    adaptive_state = Adaptive(settings, spp, film)
    for band, samples, tile in () if cancelled else _units(spp, len(bands), tiler, adaptive_state, group):
        if cancel is not None and cancel():
            cancelled = True
            break
        with KERNEL_LAUNCH:
            unit_start = time.perf_counter()
            sums = render_unit(bands[band], band, samples, tile, seed, backend, categories, film.bins > 0, group > 0)
            unit_seconds_taken = time.perf_counter() - unit_start
        size = samples[1] - samples[0]
        tiler.measured(tile, size, unit_seconds_taken)
        film.add(band, tile[1], tile[0], *sums[:2], size, *sums[2:])
        done += tile[2] * tile[3] * size
        if progress is not None:
            progress(film, (done + adaptive_state.skipped * len(bands)) / total)
    if group:
        film = filtered(film, settings.firefly_threshold)
    data_passes = None if cancelled else first_hit_passes(scene, bands[0], spp, seed, backend, cancel, notice)
    cancelled = data_passes is None
    data_passes = data_passes or PassImages({}, {})
    data_passes.images.update(light_images(film, settings))
    seconds = time.perf_counter() - start
    return RenderResult(film=film, cancelled=cancelled, seconds=seconds, stats=render_stats(film, seconds, backend),
                        passes=data_passes)


class Adaptive:
    """Adaptive sampling's state in one render (`adaptive`): which pixels the next pass samples, and the
    pixel-samples left out so far (so that progress still reaches 1)."""

    def __init__(self, settings, spp: int, film: Film):
        self.threshold, self.spp, self.film, self.skipped = settings.noise_threshold, spp, film, 0
        self.minimum = adaptive.minimum_samples(self.threshold, settings.min_samples, spp)

    def active(self, begin: int, size: int) -> np.ndarray | None:
        """The pixels the pass of samples [begin, begin + size) renders; None for all of them."""
        if self.threshold <= 0 or begin < self.minimum:
            return None
        active = adaptive.active_pixels(self.film, self.threshold)
        self.skipped += int(active.size - np.count_nonzero(active)) * size
        return active


def _units(spp: int, bands: int, tiler: Tiler, adaptive_state: Adaptive | None = None, group: int = 0):
    """(band, sample range, tile) of each unit: passes in order, each band's pass tile by tile (with adaptive
    sampling, only the pixels still active when the pass begins). With `group` (the firefly filter's samples per
    group, `fireflies.group_size`), the passes start at one group and run group by group, each over tiles as large
    as a unit of that many samples may be."""
    for begin, size in passes(spp, first=max(group, 1)):
        active = None if adaptive_state is None else adaptive_state.active(begin, size)
        if active is not None and not active.any():
            continue  # every pixel is done: the remaining passes are skipped
        for band in range(bands):
            for first, count in ((sample, group) for sample in range(begin, begin + size, group)) if group else \
                    ((begin, size),):
                for tile in tiler.tiles(count, active):
                    yield band, (first, first + count), tile


def render_stats(film: Film, seconds: float, backend: str) -> dict:
    """Timing, throughput and mean XYZ of a finished (or cancelled) render, for --stats and the UI."""
    pixel_samples = int(film.pixel_samples.sum())
    return {
        "seconds": seconds,
        "samples_per_pixel": int(film.samples.min()) if film.samples.size else 0,
        "pixel_samples_per_second": pixel_samples / seconds if seconds > 0 else 0.0,
        "mean_xyz": film.mean_xyz.tolist(),
        "backend": backend,
        "bands": film.bands,
    }
