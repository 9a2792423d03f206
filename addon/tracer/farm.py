"""Rendering on a Dask farm, from the client's side: the same image as `render.render`, from one laptop to a
render farm.

`RenderFarm` connects to a scheduler (or starts local worker processes), checks that every worker runs this
tracer, and renders scenes on it: the plan's units (farm_plan.py: band × pass × tile) become Dask tasks
(distributed.py: `render_task`), the kernel scenes travel once to each worker (`Client.scatter(...,
broadcast=True)`, so no shared file system is needed), and `PassMerger` adds the results to the film in pass
order, so the image is bit-for-bit the single-process one for any number of workers, tile size or failure.
A result whose fingerprint is not the task's (a worker with other code or data, which may have joined
mid-render) is dropped and its task re-run only on the workers none of whose results was refused, so
workers may join and leave at any time.

Dask is imported only when a farm is opened, here and by the tasks on the workers (distributed.py): the rest
of the tracer never needs it (the extension bundles Dask's wheels for Blender, which ships none). See docs/distributed.md for starting
schedulers and workers.
"""

import asyncio
import dataclasses
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

from . import checks
from . import distributed as worker
from .errors import SpectralError
from .fireflies import filtered, group_size
from .farm_plan import PassMerger, Unit, plan
from .film import Film
from .light_passes import light_categories, light_images
from .render import RenderResult, band_scenes, first_hit_passes, render_stats
from .scene import Scene
from .validation import check_settings

DEFAULT_TIMEOUT = 10.0  # seconds to reach the scheduler and to wait for its first worker
DEFAULT_TILE_SIZE = 64
RETRIES = 2  # re-runs of a task that raised; tasks on workers that die are re-run by Dask anyway
REFUSALS = 8  # results of one task refused (from workers that disagree) before the render gives up
POLL_SECONDS = 0.02  # how often cancel() is asked while no task completes
WORKER_CHECK_SECONDS = 1.0


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
        expected = worker.environment()
        found = {}
        for role, run in (("scheduler", self.client.run_on_scheduler), ("workers", self.client.run)):
            try:
                answer = run(worker.environment)
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
        start = time.perf_counter()
        job = _Job.of(scene, spp, seed, backend, tile_size)
        threads = self._threads_per_task(threads)
        self.wait_for_workers()
        self.check_environment()
        scene_data = worker.SceneData(job.bands, job.film.light_categories, job.film.bins > 0, bool(job.film.peaks))
        expected = worker.fingerprint(worker.environment(), scene_data.digest(), job.seed, job.backend)
        [scene_future] = self.client.scatter([scene_data], broadcast=True, hash=False)
        setup_seconds = time.perf_counter() - start

        tasks = _Tasks(self, job, scene_future, threads, expected)
        interrupted = []  # Ctrl-C cancels like `cancel` (Dask stays consistent), then is raised
        with _ctrl_c_sets(interrupted):
            try:
                cancelled = self._merge_results(tasks, progress,
                                                lambda: bool(interrupted) or (cancel is not None and cancel()))
            finally:
                tasks.close()
                scene_future.release()
        if interrupted:
            raise KeyboardInterrupt
        if not cancelled and not job.merger.complete:
            raise SpectralError("internal error: every task completed but the film is missing passes")
        # The data passes need no farm: the first hits of the camera rays, on this computer (`first_hit_passes`).
        passes = None if cancelled else first_hit_passes(scene, job.bands[0], job.spp, job.seed, job.backend, cancel)
        if job.film.peaks:
            job.merger.film = filtered(job.film, scene.settings.firefly_threshold)
        result = self._result(job, tasks, time.perf_counter() - start, setup_seconds, passes is None)
        if passes is None:
            return result
        passes.images.update(light_images(job.film, scene.settings))
        return dataclasses.replace(result, passes=passes)

    def _threads_per_task(self, threads: int | None) -> int | None:
        """Kernel threads per task: `threads`, or on a local farm its cores shared among its workers (None:
        each worker shares its own cores among its Dask threads)."""
        if threads is None and self.local_workers is not None:
            threads = max(1, _local_cores() // self.local_workers)
        return int(threads) if threads else None

    def _merge_results(self, tasks: "_Tasks", progress, stop) -> bool:
        """Merge the tasks' results as they complete, telling `progress`; while none completes, check every
        WORKER_CHECK_SECONDS that the farm still has workers and send the tasks bound to workers that left
        elsewhere. True when `stop()` said stop before every task was merged."""
        last_check, alone_since = time.perf_counter(), None
        while not tasks.finished:
            if stop():
                return True
            if not tasks.collect():
                now = time.perf_counter()
                if now - last_check >= WORKER_CHECK_SECONDS:
                    last_check = now
                    alone_since = self._check_alive(alone_since, now)
                    tasks.reroute_orphans()
                time.sleep(POLL_SECONDS)
                continue
            alone_since = None
            if progress is not None:
                progress(tasks.job.film, tasks.work_done / tasks.work)
        return False

    def _result(self, job: "_Job", tasks: "_Tasks", seconds: float, setup_seconds: float,
                cancelled: bool) -> RenderResult:
        stats = {
            **render_stats(job.film, seconds, job.backend),
            "scheduler": self.address,
            "workers": len(self.workers()),
            "tasks": len(job.units),
            "tasks_done": tasks.done,
            "tile_size": job.tile_size,
            "setup_seconds": setup_seconds,
            "workers_refused": sorted(tasks.refused),
        }
        return RenderResult(film=job.film, cancelled=cancelled, seconds=seconds, stats=stats)

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


@dataclass
class _Job:
    """One render on the farm, settled before anything is sent: the settings with their overrides (obeying the
    scene's own rules), the kernel scene of each band, and the plan, whose merger holds the film."""

    spp: int
    seed: int
    backend: str
    tile_size: int
    bands: list
    units: list[Unit]
    merger: PassMerger

    @classmethod
    def of(cls, scene: Scene, spp: int | None, seed: int | None, backend: str | None, tile_size: int) -> "_Job":
        settings = scene.settings
        spp = settings.spp if spp is None else spp
        seed = settings.seed if seed is None else seed
        backend = backend or settings.backend
        # The overrides obey the scene's rules (a seed above 2⁶⁴ − 1 would fail on the workers, after the setup).
        check_settings(dataclasses.replace(settings, spp=spp, seed=seed, backend=backend))
        bands = band_scenes(scene)
        camera = scene.camera
        group = group_size(spp) if settings.firefly_threshold > 0 else 0
        sizes, tiles, units = plan(camera.width, camera.height, len(bands), spp, int(tile_size), group)
        film = Film(camera.width, camera.height, len(bands), light_categories(settings),
                    bands[0].wavelengths.spectrum_edges, group)
        merger = PassMerger(film, sizes, tiles)
        return cls(spp, seed, backend, int(tile_size), bands, units, merger)

    @property
    def film(self) -> Film:
        return self.merger.film


class _Tasks:
    """The Dask tasks of one render: each submitted with the fingerprint it must run and a priority by pass (the
    first, noisy image comes early); a result whose fingerprint differs is refused and its task re-run only on
    the workers none of whose results was refused; the results kept are merged in pass order."""

    def __init__(self, farm: RenderFarm, job: _Job, scene_future, threads: int | None, expected: str):
        from distributed import as_completed

        self.farm, self.job, self.scene_future, self.threads, self.expected = farm, job, scene_future, threads, expected
        self.token = uuid.uuid4().hex[:12]
        self.submissions = itertools.count()
        self.futures = {}  # future → (unit, attempt, the workers it may run on: None for any)
        self.refused = {}  # worker → the fingerprint of what it ran (None: its code did not say)
        self.done, self.work, self.work_done = 0, sum(unit.pixel_samples for unit in job.units), 0
        for unit in job.units:
            self._submit(unit)
        self.completed = as_completed(list(self.futures), loop=farm.client.loop)

    @property
    def finished(self) -> bool:
        return self.done == len(self.job.units)

    def _submit(self, unit: Unit, attempt: int = 0, workers=None):
        """Submit `unit`'s task (a re-run after a refused result only to `workers`)."""
        job = self.job
        future = self.farm.client.submit(
            worker.render_task, self.scene_future, unit.band, unit.samples, unit.tile, job.seed, job.backend,
            self.threads, self.expected,
            key=f"spectral-unit-{self.token}-{unit.band}-{unit.pass_index}-{unit.tile_index}-{next(self.submissions)}",
            priority=-unit.pass_index, retries=RETRIES, workers=workers, allow_other_workers=False)
        self.futures[future] = (unit, attempt, workers)
        return future

    def _resubmit(self, unit: Unit, attempt: int) -> None:
        self.completed.add(self._submit(unit, attempt, self._not_refused()))

    def reroute_orphans(self) -> None:
        """Re-submit the tasks whose workers have all left to the agreeing workers now connected."""
        connected = set(self.farm.workers())
        for future, (unit, attempt, workers) in list(self.futures.items()):
            if workers is not None and not set(workers) & connected:
                self.futures.pop(future).cancel()
                self._resubmit(unit, attempt)

    def collect(self) -> bool:
        """Merge the results that have come in (refusing those of other code or data); False when none has."""
        batch = self.completed.next_batch(block=False)
        if not batch:
            return False
        batch = [future for future in batch if future in self.futures]  # not those `reroute_orphans` cancelled
        for future, result in zip(batch, self._gather(batch)):
            unit, attempt, _ = self.futures.pop(future)
            ran_on = self._who_ran(future, result)
            future.release()
            if not (isinstance(result, worker.TaskResult) and result.fingerprint == self.expected):
                self.refused[ran_on] = result.fingerprint if isinstance(result, worker.TaskResult) else None
                if attempt + 1 >= REFUSALS:
                    raise self._refused_error()
                self._resubmit(unit, attempt + 1)
                continue
            self.job.merger.add(unit, *result.sums)
            self.work_done += unit.pixel_samples
            self.done += 1
        return True

    def _gather(self, batch: list) -> list:
        """The results of `batch`; a task that failed or that the scheduler dropped is an error."""
        farm = self.farm
        for future in batch:
            if future.status == "error":
                raise _task_error(future, self.futures[future][0], farm.address)
            if future.status == "cancelled":  # not by us: the scheduler dropped it
                raise farm._dropped_error()
        try:
            return farm.client.gather(batch)
        except CancelledError:  # dropped by the scheduler between next_batch and gather
            raise farm._dropped_error() from None
        except Exception as problem:
            raise SpectralError(f"collecting render results from {farm.address} failed: "
                                f"{type(problem).__name__}: {problem}") from problem

    def close(self) -> None:
        """Cancel the tasks still pending (after a cancel or an error)."""
        self.completed.clear()
        if self.futures:
            self.farm.client.cancel(list(self.futures))
        self.futures.clear()

    def _who_ran(self, future, result) -> str:
        """The worker that computed `future`'s result (by its own word, or where the scheduler holds it)."""
        if isinstance(result, worker.TaskResult):
            return result.worker
        try:
            return next(iter(self.farm.client.who_has([future]).get(future.key, ())), "an unknown worker")
        except Exception:  # the worker has left with it
            return "an unknown worker"

    def _not_refused(self) -> list[str] | None:
        """The connected workers none of whose results was refused (None when there are none: any worker)."""
        return sorted(set(self.farm.workers()) - set(self.refused)) or None

    def _refused_error(self) -> SpectralError:
        return SpectralError(f"Dask worker(s) {', '.join(sorted(self.refused))} of {self.farm.address} run other "
                             f"code or hold other scene data than this machine, so their pixels could differ, and a "
                             f"task was refused {REFUSALS} times: no worker that agrees takes it; the render is "
                             f"incomplete (docs/distributed.md)")


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
