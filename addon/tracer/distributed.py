"""Distributed rendering on Dask: the same image as `render.render`, from one laptop to a render farm.

The render is split into independent tasks, one per (wavelength band, pass, image tile). A task runs
`render.render_unit` (a pure function of kernel scene, band, sample range, tile, seed and backend) on a
Dask worker and returns the tile's accumulators. The sample ranges are the single-process render's
passes (`render.pass_sizes`), and `PassMerger` adds each band's passes into the `Film` in pass order,
whatever order the tasks complete in, so the film's floating-point sums are formed exactly as in
`render.render`: the image is bit-for-bit identical for any number of workers, tile size or failure.

The kernel scenes (one per band, sharing their big arrays) travel once to each worker
(`Client.scatter(..., broadcast=True)`), not with every task, so no shared file system is needed.

Every task carries a fingerprint of what it must run (`fingerprint`: the tracer's sources, the numeric
packages' versions, the scene data, seed and backend); the worker returns the fingerprint of what it ran,
computed by its own code from its own copy of the scene, and the client adds a result only when the two
agree. A result that disagrees (a worker with other code, which may have joined mid-render) or comes
from code that does not say (an old tracer) is dropped and its task re-run only on the workers none of
whose results was refused, so workers may join and leave at any time and the image stays the
single-process one.
Dask is imported only here and only when a farm is opened: the rest of the tracer never needs it (the
extension bundles Dask's wheels for Blender, which ships none). See docs/distributed.md for starting
schedulers and workers.
"""

import asyncio
import dataclasses
import functools
import hashlib
import itertools
import logging
import os
import signal
import threading
import time
import uuid
from concurrent.futures import CancelledError
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import NamedTuple

import numpy as np

from . import checks
from . import render as single
from .errors import SpectralError
from .film import Film
from .render import RenderResult, render_stats
from .scene import Scene
from .validation import check_settings

DEFAULT_TIMEOUT = 10.0  # seconds to reach the scheduler and to wait for its first worker
DEFAULT_TILE_SIZE = 64
RETRIES = 2  # re-runs of a task that raised; tasks on workers that die are re-run by Dask anyway
REFUSALS = 8  # results of one task refused (from workers that disagree) before the render gives up
POLL_SECONDS = 0.02  # how often cancel() is asked while no task completes
WORKER_CHECK_SECONDS = 1.0
PACKAGES = ("numpy", "numba", "llvmlite")  # their versions must match between client and workers


# ------------------------------------------------------------------------------------- the task plan


@dataclass(frozen=True)
class Unit:
    """One task: samples [begin, end) (pass `pass_index`) of `band` over tile `tile_index`."""

    band: int
    pass_index: int
    tile_index: int
    samples: tuple[int, int]
    tile: tuple[int, int, int, int]  # x0, y0, width, height

    @property
    def pixel_samples(self) -> int:
        return self.tile[2] * self.tile[3] * (self.samples[1] - self.samples[0])


def image_tiles(width: int, height: int, tile_size: int) -> list[tuple[int, int, int, int]]:
    """Tiles (x0, y0, width, height) covering the image row by row; edge tiles are smaller."""
    if tile_size < 1:
        raise SpectralError(f"tile size must be at least 1 pixel, got {tile_size}")
    return [(x0, y0, min(tile_size, width - x0), min(tile_size, height - y0))
            for y0 in range(0, height, tile_size) for x0 in range(0, width, tile_size)]


def plan(width: int, height: int, bands: int, spp: int, tile_size: int) -> tuple[list[int], list, list[Unit]]:
    """(pass sizes, tiles, units): the single-process render's passes × bands × tiles, in pass order."""
    sizes = single.pass_sizes(spp)
    tiles = image_tiles(width, height, tile_size)
    units, begin = [], 0
    for pass_index, size in enumerate(sizes):
        for band in range(bands):
            for tile_index, tile in enumerate(tiles):
                units.append(Unit(band, pass_index, tile_index, (begin, begin + size), tile))
        begin += size
    return sizes, tiles, units


class PassMerger:
    """Adds unit results to a `Film` so that its sums are formed exactly as by `render.render`.

    The single-process render adds whole-image passes of each band in pass order. Pixels are
    independent, so adding a pass tile by tile gives the same per-pixel sums; what must be kept is
    the order of passes within a band. Results that arrive early are buffered until every tile of
    their pass has arrived and all earlier passes of their band have been added; the film's sample
    count of a band therefore always describes every pixel (previews are consistent)."""

    def __init__(self, film: Film, sizes: list[int], tiles: list[tuple[int, int, int, int]]):
        self.film, self.sizes, self.tiles = film, list(sizes), list(tiles)
        self.next_pass = [0] * film.bands
        self.waiting: dict[tuple[int, int], dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}

    def add(self, unit: Unit, sum_xyz: np.ndarray, sum_sq: np.ndarray, sum_transparent: np.ndarray) -> None:
        if unit.pass_index < self.next_pass[unit.band]:
            raise ValueError(f"pass {unit.pass_index} of band {unit.band} was already added")
        arrived = self.waiting.setdefault((unit.band, unit.pass_index), {})
        arrived[unit.tile_index] = (sum_xyz, sum_sq, sum_transparent)
        band = unit.band
        while self.next_pass[band] < len(self.sizes):
            parts = self.waiting.get((band, self.next_pass[band]))
            if parts is None or len(parts) < len(self.tiles):
                break
            del self.waiting[(band, self.next_pass[band])]
            for tile_index in sorted(parts):
                x0, y0, _, _ = self.tiles[tile_index]
                xyz, squares, transparent = parts[tile_index]
                self.film.add(band, y0, x0, xyz, squares, self.sizes[self.next_pass[band]], transparent)
            self.next_pass[band] += 1

    @property
    def complete(self) -> bool:
        return all(done == len(self.sizes) for done in self.next_pass)


# ------------------------------------------------------------------------------------ the worker side


class SceneData:
    """What is scattered to the workers: the kernel scene of each band.

    One picklable object rather than a list, so that pickling keeps the arrays the bands share
    (grids, majorants, light spectra) once instead of once per band. `digest()` hashes this copy (once per
    process: it is not pickled, so a worker hashes the copy it received)."""

    def __init__(self, band_scenes):
        self.band_scenes = tuple(band_scenes)

    def __getstate__(self):
        return {"band_scenes": self.band_scenes}

    def digest(self) -> str:
        if getattr(self, "_digest", None) is None:
            hasher = hashlib.blake2b(digest_size=32)
            _hash_value(self.band_scenes, hasher, {})
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
    accumulators (None when the worker saw that its fingerprint is not the one asked for)."""

    fingerprint: str
    worker: str
    sum_xyz: np.ndarray | None
    sum_sq: np.ndarray | None
    sum_transparent: np.ndarray | None


def render_task(scene_data: SceneData, band: int, samples: tuple[int, int], tile: tuple[int, int, int, int],
                seed: int, backend: str, threads: int | None = None, expected: str = "") -> TaskResult:
    """The Dask task: `render.render_unit` for one band, with `threads` kernel threads (by default
    the worker's cores shared among its Dask threads), unless this worker's fingerprint is not `expected`.
    Thread counts do not change the result."""
    ran = fingerprint(environment(), scene_data.digest(), seed, backend)
    if ran != expected:
        return TaskResult(ran, _worker_address(), None, None, None)
    if backend == "numba":
        from .kernels import numba_backend

        numba_backend.set_threads(threads or _threads_per_task())
    return TaskResult(ran, _worker_address(), *single.render_unit(scene_data.band_scenes[band], band, samples, tile,
                                                                  seed, backend))


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


# ------------------------------------------------------------------------------------ the client side


def _import_dask():
    try:
        import distributed
    except ImportError as problem:
        raise SpectralError(f"distributed rendering needs the 'dask' and 'distributed' packages "
                            f"(pinned in requirements.lock): {problem}") from None
    if not hasattr(distributed, "LocalCluster"):
        raise SpectralError(f"the module {getattr(distributed, '__file__', distributed)!r} hides Dask's 'distributed' "
                            f"package: rename it, or run from another folder")
    return distributed


def _probe(address: str, timeout: float) -> None:
    """Connect once to `address` and hang up: a clear error within `timeout` instead of a hang."""
    from distributed.comm import connect

    async def attempt():
        comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout + 1.0)
        await comm.close()

    try:
        asyncio.run(attempt())
    except (OSError, asyncio.TimeoutError) as problem:
        raise SpectralError(f"cannot reach the Dask scheduler at {address} within {timeout:g} s "
                            f"(is `dask scheduler` running there and the port open?): {problem}") from None
    except ValueError as problem:
        raise SpectralError(f"{address!r} is not a Dask scheduler address (expected tcp://HOST:PORT): "
                            f"{problem}") from None
    except Exception as problem:  # something answered, but not a Dask scheduler
        raise SpectralError(f"the service at {address} does not speak the Dask protocol "
                            f"({type(problem).__name__}: {problem}); is it a Dask scheduler?") from None


def _ctrl_c_is_keyboard_interrupt() -> bool:
    """Whether this is the main thread of a process where Ctrl-C raises KeyboardInterrupt (a command line),
    the only case where the helpers below change and restore the SIGINT handler (not inside Blender)."""
    return (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler)


@contextmanager
def _children_ignore_ctrl_c():
    """Processes started inside ignore SIGINT (inherited through exec): Ctrl-C in a terminal reaches every
    process of its group, and local workers dying of it at once flood stderr with hundreds of tracebacks.
    This process still gets it and closes the farm, which stops them."""
    if not _ctrl_c_is_keyboard_interrupt():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def _ctrl_c_sets(flag: list):
    """Inside, Ctrl-C (SIGINT) appends to `flag` instead of raising KeyboardInterrupt at an arbitrary point
    (inside a Dask call it leaves the client broken and its closing floods stderr with tracebacks)."""
    if not _ctrl_c_is_keyboard_interrupt():
        yield
        return
    previous = signal.signal(signal.SIGINT, lambda _signum, _frame: flag.append(True))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _local_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class RenderFarm:
    """A connection to Dask workers: a remote scheduler (`scheduler="tcp://HOST:PORT"`) or a local
    cluster of `workers` processes with one thread each (the default: one per core).

    Open it once and render many scenes (an animation's frames are just scenes), then close it; or use
    the module-level `render`, which opens and closes a farm around one render."""

    def __init__(self, scheduler: str | None = None, workers: int | None = None, *,
                 timeout: float = DEFAULT_TIMEOUT):
        if scheduler is not None and workers is not None:
            raise SpectralError("give either a scheduler address or a number of local workers, not both")
        distributed = _import_dask()
        self.timeout = checks.positive(checks.number(timeout, "the Dask time-out"), "the Dask time-out (seconds)")
        self.cluster = None
        self.client = None
        self.local_workers = None
        try:
            if scheduler is None:
                count = _local_cores() if workers is None else int(workers)
                if count < 1:
                    raise SpectralError(f"the number of local workers must be at least 1, got {count}")
                self.local_workers = count
                try:
                    # Without a dashboard nobody reads the workers' statistical profiler, which
                    # samples their threads every 10 ms: switch it off (the workers inherit this).
                    import dask

                    with dask.config.set({"distributed.worker.profile.enabled": False}), _children_ignore_ctrl_c():
                        self.cluster = distributed.LocalCluster(
                            n_workers=count, threads_per_worker=1, processes=True, host="127.0.0.1",
                            dashboard_address=None, silence_logs=logging.CRITICAL)
                except Exception as problem:
                    raise SpectralError(
                        f"cannot start {count} local Dask worker processes ({problem}); a script that starts "
                        f"them must keep its code under `if __name__ == '__main__':`, since each worker is a "
                        f"new process that imports the script") from None
                self.address = self.cluster.scheduler_address
            else:
                self.address = str(scheduler)
                _probe(self.address, self.timeout)
            try:
                self.client = distributed.Client(self.cluster or self.address, timeout=self.timeout,
                                                 set_as_default=False)
            except Exception as problem:
                raise SpectralError(f"cannot connect to the Dask scheduler at {self.address}: {problem}") from None
            self.wait_for_workers()
        except BaseException:
            self.close()
            raise

    # -- lifetime

    def close(self) -> None:
        """Disconnect (and stop the local cluster, if this farm started one).

        Dask's log records are muted meanwhile: after a cancelled render, a local scheduler reports every
        task it can no longer tell the departed client about, with a "Closed comm" traceback each."""
        client, cluster, self.client, self.cluster = self.client, self.cluster, None, None
        muted = logging.root.manager.disable
        logging.disable(logging.CRITICAL)
        try:
            for part in (client, cluster):
                if part is not None:
                    try:
                        part.close()
                    except Exception:
                        pass
        finally:
            logging.disable(muted)

    def __enter__(self):
        return self

    def __exit__(self, *_):
        self.close()

    # -- workers

    def workers(self) -> dict[str, int]:
        """Connected workers and their thread counts."""
        return dict(self.client.nthreads())

    def wait_for_workers(self) -> None:
        try:
            self.client.wait_for_workers(1, timeout=self.timeout)
        except Exception:
            raise SpectralError(f"the Dask scheduler at {self.address} has no workers (waited {self.timeout:g} s): "
                                f"start some with `dask worker {self.address}` (docs/distributed.md)") from None

    def check_environment(self) -> None:
        """The scheduler (which unpickles the tasks) and every worker must import this tracer and run the
        same sources and numeric packages as this process."""
        expected = environment()
        found = {}
        for role, run in (("scheduler", self.client.run_on_scheduler), ("workers", self.client.run)):
            try:
                answer = run(environment)
            except Exception as problem:  # an ImportError over there arrives as a plain Exception naming it
                if isinstance(problem, ImportError) or "No module named" in str(problem):
                    raise SpectralError(
                        f"the Dask {role} of {self.address} cannot import the tracer ({problem}): start the "
                        f"scheduler and the workers from this repository's pinned environment with PYTHONPATH "
                        f"set to the folder holding 'addon' (docs/distributed.md)") from None
                raise SpectralError(f"cannot check the Dask {role} of {self.address}: {problem}") from None
            found.update({f"scheduler {self.address}": answer} if role == "scheduler"
                         else {f"worker {worker}": env for worker, env in answer.items()})
        for who, env in sorted(found.items()):
            different = [f"{name} {env.get(name)!r} (here {value!r})" for name, value in expected.items()
                         if env.get(name) != value]
            if different:
                raise SpectralError(f"Dask {who} differs from this machine, so its pixels could differ: "
                                    + "; ".join(different) + " (docs/distributed.md)")

    # -- rendering

    def render(self, scene: Scene, *, spp: int | None = None, seed: int | None = None, backend: str | None = None,
               threads: int | None = None, tile_size: int = DEFAULT_TILE_SIZE, progress=None,
               cancel=None) -> RenderResult:
        """Render `scene` on the farm: the same `RenderResult` (and the same film, bit for bit) as
        `render.render(scene, spp=spp, seed=seed, backend=backend)`.

        `progress(film, fraction)` is called as tasks complete (the film holds every pass merged so
        far); `cancel()` is asked between task completions and, when true, cancels the remaining tasks
        (the result says `cancelled`). `threads` is the kernel threads per task (default: for a local
        farm, the cores shared among its workers; otherwise each worker's cores over its Dask threads)."""
        from distributed import as_completed

        if scene.settings.passes:
            raise SpectralError(f"a farm does not render data passes yet ({', '.join(scene.settings.passes)}): "
                                "render them on this computer, or turn them off")
        start = time.perf_counter()
        settings = scene.settings
        spp = settings.spp if spp is None else spp
        seed = settings.seed if seed is None else seed
        backend = backend or settings.backend
        # The overrides obey the scene's rules (a seed above 2⁶⁴ − 1 would fail on the workers, after the setup).
        check_settings(dataclasses.replace(settings, spp=spp, seed=seed, backend=backend))
        if threads is None and self.local_workers is not None:
            threads = max(1, _local_cores() // self.local_workers)
        threads = int(threads) if threads else None

        bands = single.band_scenes(scene)
        camera = scene.camera
        film = Film(camera.width, camera.height, len(bands))
        sizes, tiles, units = plan(camera.width, camera.height, len(bands), spp, int(tile_size))
        merger = PassMerger(film, sizes, tiles)

        self.wait_for_workers()
        self.check_environment()
        refused = {}  # worker → the fingerprint of what it ran (None: its code did not say)
        client = self.client
        scene_data = SceneData(bands)
        expected = fingerprint(environment(), scene_data.digest(), seed, backend)
        [scene_future] = client.scatter([scene_data], broadcast=True, hash=False)
        setup_seconds = time.perf_counter() - start

        token = uuid.uuid4().hex[:12]
        futures, submissions = {}, itertools.count()

        def submit(unit: Unit, attempt: int = 0, workers=None):
            """Submit `unit`'s task (a re-run after a refused result only to `workers`)."""
            future = client.submit(render_task, scene_future, unit.band, unit.samples, unit.tile, seed, backend,
                                   threads, expected, key=f"spectral-unit-{token}-{unit.band}-{unit.pass_index}-"
                                                      f"{unit.tile_index}-{next(submissions)}",
                                   priority=-unit.pass_index, retries=RETRIES, workers=workers,
                                   allow_other_workers=False)
            futures[future] = (unit, attempt, workers)
            return future

        for unit in units:
            submit(unit)
        completed = as_completed(list(futures), loop=client.loop)
        done, cancelled = 0, False
        work, work_done = sum(unit.pixel_samples for unit in units), 0
        last_check, alone_since = time.perf_counter(), None
        interrupted = []  # Ctrl-C cancels like `cancel` (Dask stays consistent), then is raised
        with _ctrl_c_sets(interrupted):
            try:
                while done < len(units):
                    if interrupted or (cancel is not None and cancel()):
                        cancelled = True
                        break
                    batch = completed.next_batch(block=False)
                    if not batch:
                        now = time.perf_counter()
                        if now - last_check >= WORKER_CHECK_SECONDS:
                            last_check = now
                            alone_since = self._check_alive(alone_since, now)
                            connected = set(self.workers())
                            for future, (unit, attempt, workers) in list(futures.items()):
                                if workers is not None and not set(workers) & connected:
                                    futures.pop(future).cancel()  # its workers left: to those now connected
                                    completed.add(submit(unit, attempt, self._not_refused(refused)))
                        time.sleep(POLL_SECONDS)
                        continue
                    alone_since = None
                    batch = [future for future in batch if future in futures]  # not those cancelled above
                    for future in batch:
                        if future.status == "error":
                            raise _task_error(future, futures[future][0], self.address)
                        if future.status == "cancelled":  # not by us: the scheduler dropped it
                            raise self._dropped_error()
                    try:
                        results = client.gather(batch)
                    except CancelledError:  # dropped by the scheduler between next_batch and gather
                        raise self._dropped_error() from None
                    except Exception as problem:
                        raise SpectralError(f"collecting render results from {self.address} failed: "
                                            f"{type(problem).__name__}: {problem}") from problem
                    for future, result in zip(batch, results):
                        unit, attempt, _ = futures.pop(future)
                        worker = self._who_ran(future, result)
                        future.release()
                        if not (isinstance(result, TaskResult) and result.fingerprint == expected):
                            refused[worker] = result.fingerprint if isinstance(result, TaskResult) else None
                            if attempt + 1 >= REFUSALS:
                                raise self._refused_error(refused)
                            completed.add(submit(unit, attempt + 1, self._not_refused(refused)))
                            continue
                        merger.add(unit, result.sum_xyz, result.sum_sq, result.sum_transparent)
                        work_done += unit.pixel_samples
                        done += 1
                    if progress is not None:
                        progress(film, work_done / work)
            finally:
                completed.clear()
                if futures:
                    client.cancel(list(futures))
                futures.clear()
                scene_future.release()
        if interrupted:
            raise KeyboardInterrupt
        if not cancelled and not merger.complete:
            raise SpectralError("internal error: every task completed but the film is missing passes")

        seconds = time.perf_counter() - start
        stats = {
            **render_stats(film, seconds, backend),
            "scheduler": self.address,
            "workers": len(self.workers()),
            "tasks": len(units),
            "tasks_done": done,
            "tile_size": int(tile_size),
            "setup_seconds": setup_seconds,
            "workers_refused": sorted(refused),
        }
        return RenderResult(film=film, cancelled=cancelled, seconds=seconds, stats=stats)

    def _who_ran(self, future, result) -> str:
        """The worker that computed `future`'s result (by its own word, or where the scheduler holds it)."""
        if isinstance(result, TaskResult):
            return result.worker
        try:
            return next(iter(self.client.who_has([future]).get(future.key, ())), "an unknown worker")
        except Exception:  # the worker has left with it
            return "an unknown worker"

    def _not_refused(self, refused: dict) -> list[str] | None:
        """The connected workers none of whose results was refused (None when there are none: any worker)."""
        return sorted(set(self.workers()) - set(refused)) or None

    def _refused_error(self, refused: dict) -> SpectralError:
        return SpectralError(f"Dask worker(s) {', '.join(sorted(refused))} of {self.address} run other code or hold "
                             f"other scene data than this machine, so their pixels could differ, and a task was "
                             f"refused {REFUSALS} times: no worker that agrees takes it; the render is incomplete "
                             f"(docs/distributed.md)")

    def _check_alive(self, alone_since, now):
        """Raise when the scheduler has had no workers for `timeout` seconds during a render."""
        try:
            count = len(self.client.nthreads())
        except Exception as problem:
            raise SpectralError(f"lost the Dask scheduler at {self.address}: {problem}") from None
        if count:
            return None
        alone_since = now if alone_since is None else alone_since
        if now - alone_since > self.timeout:
            raise SpectralError(f"every Dask worker of {self.address} has left and none came back within "
                                f"{self.timeout:g} s; the render is incomplete")
        return alone_since


    def _dropped_error(self) -> SpectralError:
        """Why the scheduler cancelled a render task: nearly always because every worker holding the
        scattered scene left, which loses it for good."""
        try:
            workers = len(self.client.nthreads())
        except Exception:  # the scheduler is gone too
            workers = 0
        if not workers:
            return SpectralError(f"every Dask worker of {self.address} has left, and the scene data they held "
                                 f"left with them; the render is incomplete")
        return SpectralError(f"the Dask scheduler at {self.address} dropped render tasks (the workers holding the "
                             f"scene data left, or another client cancelled them); the render is incomplete")


def _task_error(future, unit: Unit, address: str) -> SpectralError:
    from distributed.scheduler import KilledWorker

    problem = future.exception()
    where = f"band {unit.band}, samples {unit.samples[0]}–{unit.samples[1]}, tile {unit.tile}"
    if isinstance(problem, SpectralError):
        return problem
    if isinstance(problem, KilledWorker):
        return SpectralError(f"the render task for {where} was running on {problem.allowed_failures + 1} Dask "
                             f"workers of {address} that died (out of memory?); giving up")
    if isinstance(problem, ImportError):
        return SpectralError(f"a Dask worker of {address} cannot import the tracer ({problem}): start it with "
                             f"PYTHONPATH set to the folder holding 'addon' (docs/distributed.md)")
    error = SpectralError(f"the render task for {where} failed on a Dask worker of {address}: "
                          f"{type(problem).__name__}: {problem}")
    error.__cause__ = problem
    return error


def render(scene: Scene, *, scheduler: str | None = None, workers: int | None = None, spp: int | None = None,
           seed: int | None = None, backend: str | None = None, threads: int | None = None,
           tile_size: int = DEFAULT_TILE_SIZE, progress=None, cancel=None,
           timeout: float = DEFAULT_TIMEOUT) -> RenderResult:
    """Render `scene` on Dask and return the same `RenderResult` as `render.render` (identical film).

    `scheduler="tcp://HOST:PORT"` uses a running Dask scheduler and its workers; otherwise a local
    cluster of `workers` processes (default: one per core, one thread each) is started and stopped.
    An unreachable scheduler, or one without workers, raises SpectralError within `timeout` seconds."""
    with RenderFarm(scheduler, workers, timeout=timeout) as farm:
        return farm.render(scene, spp=spp, seed=seed, backend=backend, threads=threads, tile_size=tile_size,
                           progress=progress, cancel=cancel)
