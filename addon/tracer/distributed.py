"""The worker's side of a farm: what a Dask worker runs (`render_task`, on the `SceneData` scattered to it) and
what it answers with (`TaskResult`), and the fingerprint that says which code and data a result comes from.

A task runs `render.render_unit` (a pure function of kernel scene, band, sample range, tile, seed and
backend) and returns the tile's accumulators: XYZ, its squares and the transparency, and where the render asks
for them the light passes' and the spectral bins' (`SceneData` says which, for every task alike). It carries the fingerprint of what it must run
(`fingerprint`: the tracer's sources, the numeric packages' versions, the scene data, seed and backend);
the worker computes the fingerprint of what it runs, with its own code from its own copy of the scene, and
returns it with the result, or alone when the two differ; the client (farm.py) keeps only results whose
fingerprint is the one it asked for.

Dask sends these names by reference, and workers and the scheduler import them by this module's path
(`addon.tracer.distributed.render_task`, `environment`, `SceneData`, `TaskResult`), so the path stays as it
is: a worker started from another checkout then still finds them, runs its own code and answers with its
own fingerprint (refused and re-run elsewhere) instead of failing to import a name it lacks.
"""

import functools
import hashlib
from importlib import metadata
from pathlib import Path
from typing import NamedTuple

import numpy as np

from . import backends, render

PACKAGES = ("numpy", "numba", "llvmlite")  # their versions must match between client and workers


class SceneData:
    """What is scattered to the workers: the kernel scene of each band, and what every task accumulates besides
    XYZ: how many light categories (`light_passes.light_categories`; 0 for none), whether the spectral bins, and
    whether each pixel's brightest group of samples (`fireflies.Peaks`, for the firefly filter).

    One picklable object rather than a list, so that pickling keeps the arrays the bands share
    (grids, majorants, light spectra) once instead of once per band. `digest()` hashes this copy (once per
    process: it is not pickled, so a worker hashes the copy it received)."""

    def __init__(self, band_scenes, light_categories: int = 0, spectrum: bool = False, peaks: bool = False):
        self.band_scenes = tuple(band_scenes)
        self.light_categories, self.spectrum, self.peaks = int(light_categories), bool(spectrum), bool(peaks)

    def __getstate__(self):
        return {"band_scenes": self.band_scenes, "light_categories": self.light_categories, "spectrum": self.spectrum,
                "peaks": self.peaks}

    def digest(self) -> str:
        if getattr(self, "_digest", None) is None:
            hasher = hashlib.blake2b(digest_size=32)
            _hash_value((self.band_scenes, self.light_categories, self.spectrum, self.peaks), hasher, {})
            self._digest = hasher.hexdigest()
        return self._digest


def _hash_value(value, hasher, arrays: dict) -> None:
    """Feed a kernel scene's nested tuples, arrays and numbers to `hasher` (each array's contents hashed once,
    in `arrays` by id: the bands share their big ones)."""
    if isinstance(value, tuple):
        hasher.update(f"({type(value).__name__}:{len(value)}".encode())
        for item in value:
            _hash_value(item, hasher, arrays)
    elif isinstance(value, np.ndarray):
        if id(value) not in arrays:
            contents = np.ascontiguousarray(value).reshape(-1).view(np.uint8)
            arrays[id(value)] = hashlib.blake2b(contents, digest_size=32).digest()
        hasher.update(f"{value.dtype.str}{value.shape}".encode() + arrays[id(value)])
    elif isinstance(value, np.generic):  # by its bytes: a NumPy scalar's repr depends on the print options
        hasher.update(f"{value.dtype.str}".encode() + value.tobytes())
    else:
        hasher.update(f"{type(value).__name__}={value!r}".encode())


def fingerprint(environment_: dict, scene_digest: str, seed: int, backend: str) -> str:
    """What a task's result depends on besides its band, samples and tile (which come back with it)."""
    text = repr((sorted(environment_.items()), scene_digest, int(seed), backend))
    return hashlib.sha256(text.encode()).hexdigest()


class TaskResult(NamedTuple):
    """A task's answer: the fingerprint of what the worker ran (`fingerprint`), the worker, and the tile's
    accumulators as `render.render_unit` returns them (None when the worker saw that its fingerprint is not the
    one asked for)."""

    fingerprint: str
    worker: str
    sums: tuple[np.ndarray, ...] | None


def render_task(scene_data: SceneData, band: int, samples: tuple[int, int], tile: tuple[int, int, int, int],
                seed: int, backend: str, threads: int | None = None, expected: str = "") -> TaskResult:
    """The Dask task: `render.render_unit` for one band, with `threads` kernel threads (by default
    the worker's cores shared among its Dask threads), unless this worker's fingerprint is not `expected`.
    Thread counts do not change the result."""
    ran = fingerprint(environment(), scene_data.digest(), seed, backend)
    if ran != expected:
        return TaskResult(ran, _worker_address(), None)
    backends.named(backend).kernels.set_threads(threads or _threads_per_task())
    return TaskResult(ran, _worker_address(), render.render_unit(scene_data.band_scenes[band], band, samples, tile,
                                                                 seed, backend, scene_data.light_categories,
                                                                 scene_data.spectrum, scene_data.peaks))


def _worker_address() -> str:
    from distributed import get_worker

    try:
        return get_worker().address
    except ValueError:  # not inside a worker
        return "this process"


def _threads_per_task() -> int:
    import numba
    from distributed import get_worker

    try:
        nthreads = get_worker().state.nthreads
    except ValueError:  # not inside a worker
        nthreads = 1
    return max(1, numba.config.NUMBA_NUM_THREADS // max(nthreads, 1))


@functools.cache
def sources_digest() -> str:
    """SHA-256 over every Python source of the tracer (this package), by relative path."""
    tracer = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for source in sorted(tracer.rglob("*.py")):
        digest.update(source.relative_to(tracer).as_posix().encode())
        digest.update(source.read_bytes())
    return digest.hexdigest()


def environment() -> dict:
    """What must match between the client and every worker for identical images: the tracer's
    sources (all of them: simple and strict) and the versions of the numeric packages."""
    versions = {}
    for package in PACKAGES:
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = None
    return {"tracer sources": sources_digest(), **versions}
