"""Distributed rendering on Dask (loopback only): the image is bit-for-bit the single-process one.

The slow tests start a real `dask scheduler` and `dask worker` processes on 127.0.0.1 (the venv's Dask
command line, with PYTHONPATH set to this repository so the workers import `addon`) and stop them in
fixtures, even when a test fails. Scenes are tiny: the machine running CI may have two cores.
"""

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import cli, distributed, image_io
from addon.tracer import render as single
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from tests.support import scenes as s

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT = 120.0  # seconds for a scheduler or worker process to come up on a busy machine


def small_scene(spp=24, bands=2, seed=11):
    box = s.box_grid(cells=(6, 6, 6))
    return s.scene(s.perspective_camera(12, 10, fov_degrees=25.0),
                   [s.medium(box, extinction=s.smooth_ramp(3.0, 1.0), albedo=0.8, g=0.3)],
                   [s.environment(0.5), s.sun((1.0, 0.5, 2.0), strength=2.0)], spp=spp, bands=bands, seed=seed,
                   transparent=True)


def assert_same_film(expected: Film, actual: Film):
    assert np.array_equal(expected.samples, actual.samples)
    assert np.array_equal(expected.sum_xyz, actual.sum_xyz)
    assert np.array_equal(expected.sum_sq, actual.sum_sq)
    assert np.array_equal(expected.sum_transparent, actual.sum_transparent)
    assert np.array_equal(expected.xyz, actual.xyz)
    assert np.array_equal(expected.variance, actual.variance)


# -------------------------------------------------------------------------- plan and merge (no Dask)


def test_tiles_cover_the_image_once():
    coverage = np.zeros((10, 12), dtype=int)
    for x0, y0, width, height in distributed.image_tiles(12, 10, 5):
        coverage[y0:y0 + height, x0:x0 + width] += 1
    assert (coverage == 1).all()
    with pytest.raises(SpectralError, match="tile size"):
        distributed.image_tiles(12, 10, 0)


def test_plan_uses_the_single_process_passes():
    sizes, tiles, units = distributed.plan(12, 10, bands=3, spp=40, tile_size=5)
    assert sizes == single.pass_sizes(40)
    assert len(units) == len(sizes) * 3 * len(tiles)
    for band in range(3):
        for tile_index in range(len(tiles)):
            ranges = [u.samples for u in units if u.band == band and u.tile_index == tile_index]
            assert ranges == [(sum(sizes[:i]), sum(sizes[:i + 1])) for i in range(len(sizes))]


def test_merging_in_any_completion_order_is_bit_identical():
    """Synthetic pass results with a wide dynamic range, so that summation order shows in the bits."""
    width, height, bands, spp = 7, 5, 2, 40
    sizes, tiles, units = distributed.plan(width, height, bands, spp, tile_size=3)
    rng = np.random.default_rng(1)
    passes = rng.lognormal(0.0, 6.0, size=(len(sizes), bands, height, width, 3))
    expected = Film(width, height, bands)
    for index, size in enumerate(sizes):
        for band in range(bands):
            expected.add(band, 0, 0, passes[index, band], passes[index, band] ** 2, size, passes[index, band, ..., 0])

    def tile_of(unit):
        x0, y0, w, h = unit.tile
        values = passes[unit.pass_index, unit.band, y0:y0 + h, x0:x0 + w]
        return values, values**2, values[..., 0]

    for trial in range(5):
        order = rng.permutation(len(units))
        film = Film(width, height, bands)
        merger = distributed.PassMerger(film, sizes, tiles)
        for step, index in enumerate(order):
            merger.add(units[index], *tile_of(units[index]))
            # The sample count of a band always describes every pixel: only whole passes are added.
            for band in range(bands):
                merged = sum(sizes[:merger.next_pass[band]])
                assert film.samples[band] == merged
        assert merger.complete
        assert_same_film(expected, film)

    # The test has teeth: adding tiles as they come (passes out of order) changes the bits.
    naive = Film(width, height, bands)
    for index in rng.permutation(len(units)):
        unit = units[index]
        xyz, squares, transparent = tile_of(unit)
        naive.add(unit.band, unit.tile[1], unit.tile[0], xyz, squares, sizes[unit.pass_index], transparent)
    assert not np.array_equal(naive.sum_xyz, expected.sum_xyz)


def test_scheduler_and_workers_are_exclusive():
    with pytest.raises(SpectralError, match="either"):
        distributed.render(small_scene(), scheduler="tcp://127.0.0.1:1", workers=2)


# ------------------------------------------------------------------------------ unreachable scheduler


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture
def silent_listener():
    """A TCP port that accepts connections but never says a word (a hung or wrong service)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()


@pytest.mark.parametrize("kind", ["refused", "silent"])
def test_unreachable_scheduler_is_a_clear_error_within_the_timeout(kind, request):
    address = (f"tcp://127.0.0.1:{_free_port()}" if kind == "refused"
               else request.getfixturevalue("silent_listener"))
    timeout = 2.0
    start = time.perf_counter()
    with pytest.raises(SpectralError) as error:
        distributed.render(small_scene(), scheduler=address, timeout=timeout)
    elapsed = time.perf_counter() - start
    assert address in str(error.value)
    assert elapsed < timeout + 3.0, f"took {elapsed:.1f} s"


def test_the_default_timeout_is_the_documented_one():
    assert distributed.DEFAULT_TIMEOUT == 10.0
    assert "10 s" in (ROOT / "docs" / "distributed.md").read_text(encoding="utf-8")


# ------------------------------------------------------------------------------ a real loopback cluster


# `python -m addon.tracer` with Ctrl-C raising KeyboardInterrupt, as in a terminal, whatever SIGINT
# disposition the test process passes on (an ignored SIGINT is inherited through exec).
AS_IN_A_TERMINAL = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
                    "runpy.run_module('addon.tracer', run_name='__main__', alter_sys=True)")


def _signal_masks(pid: int) -> str:
    """The process's ignored and caught signal masks (Linux), to say why a signal went unanswered."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError:
        return "no /proc status"
    return "; ".join(line for line in lines if line.startswith(("SigIgn", "SigCgt", "SigBlk")))


def _subprocess_env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env["NUMBA_NUM_THREADS"] = "1"  # two workers share a small machine
    return env


def _dask(*args) -> list[str]:
    return [sys.executable, "-m", "distributed.cli." + args[0], *args[1:]]


def _stop(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=15)


class LoopbackCluster:
    """A `dask scheduler` and `dask worker` processes (without nannies, so a pid is the worker)."""

    def __init__(self, folder: Path):
        self.folder, self.workers, self.scheduler, self.logs = folder, [], None, []
        self.env = _subprocess_env()

    def _log(self, name: str):
        self.logs.append(open(self.folder / name, "w"))
        return self.logs[-1]

    def start_scheduler(self) -> str:
        scheduler_file = self.folder / "scheduler.json"
        self.scheduler = subprocess.Popen(
            _dask("dask_scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                  "--scheduler-file", str(scheduler_file)),
            env=self.env, cwd=self.folder, stdout=subprocess.DEVNULL, stderr=self._log("scheduler.log"))
        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline:
            if self.scheduler.poll() is not None:
                raise RuntimeError(f"dask scheduler exited: {(self.folder / 'scheduler.log').read_text()}")
            try:
                self.address = json.loads(scheduler_file.read_text())["address"]
                return self.address
            except (FileNotFoundError, ValueError, KeyError):
                time.sleep(0.2)
        raise RuntimeError("dask scheduler did not start")

    def start_workers(self, count: int, importable: bool = True, preload: Path | None = None) -> None:
        """Start `count` workers and wait for them; `preload`: a script each runs first (`dask worker --preload`)."""
        env = self.env if importable else {key: value for key, value in self.env.items() if key != "PYTHONPATH"}
        extra = [] if preload is None else ["--preload", str(preload)]
        for index in range(count):
            log = self._log(f"worker{len(self.workers)}.log")
            self.workers.append(subprocess.Popen(
                _dask("dask_worker", self.address, "--host", "127.0.0.1", "--nthreads", "1", "--no-nanny",
                      "--no-dashboard", "--death-timeout", "60", "--name", f"test-worker-{len(self.workers)}",
                      *extra),
                env=env, cwd=self.folder, stdout=subprocess.DEVNULL, stderr=log))
        from distributed import Client

        with Client(self.address, timeout=START_TIMEOUT, set_as_default=False) as client:
            client.wait_for_workers(len([worker for worker in self.workers if worker.poll() is None]),
                                    timeout=START_TIMEOUT)

    def stop(self) -> None:
        for process in self.workers:
            _stop(process)
        if self.scheduler is not None:
            _stop(self.scheduler)
        for log in self.logs:
            log.close()


@pytest.fixture(scope="module")
def reference():
    """The single-process render every distributed one must equal (also fills the Numba cache that the
    worker processes then load instead of compiling)."""
    scene = small_scene()
    return scene, single.render(scene).film


@pytest.fixture(scope="module")
def loopback(tmp_path_factory):
    cluster = LoopbackCluster(tmp_path_factory.mktemp("dask"))
    try:
        cluster.start_scheduler()
        cluster.start_workers(2)
        yield cluster
    finally:
        cluster.stop()


@pytest.fixture
def fresh_loopback(tmp_path):
    cluster = LoopbackCluster(tmp_path)
    try:
        cluster.start_scheduler()
        yield cluster
    finally:
        cluster.stop()


@pytest.mark.slow
def test_scheduler_and_two_workers_give_the_single_process_image(reference, loopback):
    scene, expected = reference
    fractions = []
    result = distributed.render(scene, scheduler=loopback.address, tile_size=5,
                                progress=lambda film, fraction: fractions.append(fraction))
    assert not result.cancelled
    assert_same_film(expected, result.film)
    assert result.stats["workers"] == 2
    assert result.stats["tasks"] == len(single.pass_sizes(24)) * 2 * 6
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


@pytest.mark.slow
def test_cancel_stops_between_tasks_with_whole_passes(reference, loopback):
    scene, expected = reference
    result = distributed.render(scene, scheduler=loopback.address, tile_size=5, spp=200,
                                progress=lambda film, fraction: None, cancel=lambda: True)
    assert result.cancelled
    assert result.stats["tasks_done"] == 0
    calls = []

    def cancel_after_first_progress():
        return bool(calls)

    result = distributed.render(scene, scheduler=loopback.address, tile_size=5, spp=200,
                                progress=lambda film, fraction: calls.append(fraction), cancel=cancel_after_first_progress)
    assert result.cancelled
    assert result.stats["tasks_done"] < result.stats["tasks"]
    # Whatever was merged is whole passes of the single-process render.
    assert all(samples in np.cumsum([0] + single.pass_sizes(200)) for samples in result.film.samples)


@pytest.mark.slow
def test_a_worker_killed_mid_render_changes_nothing(reference, fresh_loopback):
    from distributed import Client

    scene = small_scene(spp=64)
    expected = single.render(scene).film
    fresh_loopback.start_workers(2)
    victim = fresh_loopback.workers[0]
    seen = {"killed_at": None, "lost": [], "after": []}
    with Client(fresh_loopback.address, timeout=START_TIMEOUT, set_as_default=False) as observer:
        [address] = [address for address, info in observer.scheduler_info()["workers"].items()
                     if info["name"] == "test-worker-0"]

        def progress(_film, fraction):
            if seen["killed_at"] is None and fraction >= 0.2:
                seen["lost"] = list(observer.processing(workers=[address]).get(address, ()))
                os.kill(victim.pid, signal.SIGKILL)
                seen["killed_at"] = fraction
            elif seen["killed_at"] is not None:
                seen["after"].append(fraction)

        result = distributed.render(scene, scheduler=fresh_loopback.address, tile_size=5, progress=progress)
    assert seen["killed_at"] is not None and seen["killed_at"] < 1.0 and seen["after"]
    assert seen["lost"], "the killed worker had no task in hand: the test proved nothing"
    assert victim.wait(timeout=10) == -signal.SIGKILL
    assert result.stats["workers"] == 1
    assert_same_film(expected, result.film)


OTHER_CODE = """
# A worker running other tracer code (issue 30): its sources' digest differs from the client's.
import addon.tracer.distributed as distributed

distributed.sources_digest = lambda: "the sources of another version"
"""
SLOW = """
# A worker with this code that takes 30 ms more per task, so that the render outlasts another worker's start.
import time

import addon.tracer.distributed as distributed

if not hasattr(distributed.single, "unslowed_render_unit"):  # Dask may import a preload twice
    distributed.single.unslowed_render_unit = distributed.single.render_unit
    distributed.single.render_unit = lambda *args: time.sleep(0.03) or distributed.single.unslowed_render_unit(*args)
"""


@pytest.mark.slow
def test_a_worker_with_other_code_joining_mid_render_changes_nothing(fresh_loopback, tmp_path):
    """On main such a worker was sent tasks unchecked and the image came back wrong, with exit 0."""
    scene = small_scene(spp=256, bands=1)
    expected = single.render(scene).film
    (tmp_path / "slow.py").write_text(SLOW)
    fresh_loopback.start_workers(1, preload=tmp_path / "slow.py")
    preload = tmp_path / "other_code.py"
    preload.write_text(OTHER_CODE)
    joined = []

    def progress(_film, fraction):
        if not joined:
            fresh_loopback.start_workers(1, preload=preload)
            joined.append(fraction)

    result = distributed.render(scene, scheduler=fresh_loopback.address, tile_size=3, progress=progress)
    assert joined and joined[0] < 0.5
    assert result.stats["workers"] == 2
    assert len(result.stats["workers_refused"]) == 1, "the other worker ran no task: the test proved nothing"
    assert_same_film(expected, result.film)


@pytest.mark.slow
def test_a_farm_whose_every_worker_disagrees_is_a_clear_error_not_a_hang(loopback, monkeypatch):
    """Here the client expects another fingerprint than every worker computes: each result is refused, and the
    render stops once a task has been refused REFUSALS times."""
    monkeypatch.setattr(distributed, "fingerprint", lambda *parts: "not what any worker runs")
    with pytest.raises(SpectralError, match=f"run other code .* refused {distributed.REFUSALS} times"):
        distributed.render(small_scene(spp=4, bands=1), scheduler=loopback.address, tile_size=6, timeout=20)


def test_a_result_is_refused_unless_its_fingerprint_is_the_tasks(reference, monkeypatch):
    """The worker's side: a task whose fingerprint is not this process's returns no pixels."""
    scene, _ = reference
    data = distributed.SceneData(single.band_scenes(scene))
    mine = distributed.fingerprint(distributed.environment(), data.digest(), 11, "numpy")
    ran = distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 11, "numpy", expected=mine)
    assert ran.fingerprint == mine and ran.sum_xyz.shape == (2, 2, 3)
    other = distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 12, "numpy", expected=mine)
    assert other.fingerprint != mine and other.sum_xyz is None
    monkeypatch.setattr(distributed, "sources_digest", lambda: "other sources")
    assert distributed.render_task(data, 0, (0, 1), (0, 0, 2, 2), 11, "numpy", expected=mine).sum_xyz is None
    import pickle

    copy = pickle.loads(pickle.dumps(data))
    assert getattr(copy, "_digest", None) is None and copy.digest() == data.digest()


@pytest.mark.slow
def test_losing_the_last_worker_mid_render_is_the_documented_error_within_the_timeout(fresh_loopback):
    fresh_loopback.start_workers(1)
    [victim] = fresh_loopback.workers
    killed = {}

    def progress(_film, fraction):
        if not killed:
            os.kill(victim.pid, signal.SIGKILL)
            killed["at"] = time.perf_counter()

    timeout = 2.0
    with pytest.raises(SpectralError, match="every Dask worker of .* has left"):
        distributed.render(small_scene(spp=200), scheduler=fresh_loopback.address, tile_size=5, timeout=timeout,
                           progress=progress)
    assert killed and time.perf_counter() - killed["at"] < timeout + 3.0


@pytest.mark.slow
def test_a_scheduler_without_workers_is_a_clear_error(fresh_loopback):
    start = time.perf_counter()
    with pytest.raises(SpectralError, match="has no workers") as error:
        distributed.render(small_scene(), scheduler=fresh_loopback.address, timeout=2.0)
    assert fresh_loopback.address in str(error.value)
    assert time.perf_counter() - start < 2.0 + 5.0


@pytest.mark.slow
def test_a_worker_that_cannot_import_the_tracer_is_a_clear_error(fresh_loopback):
    fresh_loopback.start_workers(1, importable=False)
    with pytest.raises(SpectralError, match="cannot import the tracer.*PYTHONPATH"):
        distributed.render(small_scene(), scheduler=fresh_loopback.address)


@pytest.mark.slow
def test_cli_with_two_local_workers_writes_the_single_process_exr(write_scene, tmp_path):
    from tests.tracer.conftest import tiny_scene_dict

    data = tiny_scene_dict()
    data["render"] = {"spp": 24, "bands": 2, "seed": 5}
    scene_path = write_scene(data)
    alone, farm = tmp_path / "alone.exr", tmp_path / "farm.exr"
    assert cli.main(["render", str(scene_path), "--out", str(alone), "--quiet"]) == cli.EXIT_OK
    run = subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene_path), "--out", str(farm),
                          "--workers", "2", "--tile-size", "3"],
                         cwd=ROOT, env=_subprocess_env(), capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "100.0%" in run.stderr  # the progress bar ran to the end
    expected, actual = image_io.read_exr(alone), image_io.read_exr(farm)
    assert sorted(expected) == sorted(actual)
    for channel in expected:
        assert np.array_equal(expected[channel], actual[channel]), channel


@pytest.mark.slow
def test_ctrl_c_during_a_local_farm_render_stops_quietly(write_scene, tmp_path):
    """Ctrl-C reaches every process of the terminal's group: the render stops within seconds with exit 130
    and one line, not the hundreds of "Closed comm" tracebacks of the scheduler and the dying workers."""
    from tests.tracer.conftest import tiny_scene_dict

    data = tiny_scene_dict()
    data["camera"].update(width=64, height=48)
    out = tmp_path / "farm.exr"
    process = subprocess.Popen([sys.executable, "-c", AS_IN_A_TERMINAL, "render", str(write_scene(data)), "--out",
                                str(out), "--workers", "2", "--spp", "2000", "--tile-size", "16"],
                               cwd=ROOT, env=_subprocess_env(), stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        shown = ""
        # The first progress above 0 %: the farm is up and tasks are running (the bar shows 0 % at once).
        while not re.search(r"\] +(0\.[1-9]|[1-9][0-9.]*)%", shown) and process.poll() is None:
            shown += process.stderr.read(1)
        time.sleep(1.0)
        dispositions = _signal_masks(process.pid)
        os.killpg(process.pid, signal.SIGINT)
        signalled = time.perf_counter()
        stderr = process.communicate(timeout=60)[1]
    finally:
        _stop(process)
    assert process.returncode == cli.EXIT_INTERRUPTED, f"{dispositions}\n{stderr[-3000:]}"
    assert time.perf_counter() - signalled < 10.0
    assert "interrupted: nothing written" in stderr
    assert "Traceback" not in stderr and "Closed comm" not in stderr, stderr[-2000:]
    assert not out.exists()


@pytest.mark.parametrize(("options", "words"), [
    ({"timeout": float("nan")}, "the Dask time-out: expected a finite number, found nan"),
    ({"timeout": -5}, r"the Dask time-out \(seconds\): must be positive, found -5"),
])
def test_bad_time_outs_are_named_before_connecting(options, words):
    """NaN was reported as a service that "does not speak the Dask protocol", −5 without a reason."""
    with pytest.raises(SpectralError, match=words):
        distributed.render(small_scene(), scheduler="tcp://127.0.0.1:9", **options)


def test_bad_overrides_are_refused_like_the_scenes_own_settings():
    farm = distributed.RenderFarm.__new__(distributed.RenderFarm)  # no cluster: refused before any Dask call
    with pytest.raises(SpectralError, match="render.seed: must be at most 18446744073709551615"):
        farm.render(small_scene(), seed=2**64)
    with pytest.raises(SpectralError, match="render.spp: must be at least 1, found 0"):
        farm.render(small_scene(), spp=0)


def test_cli_rejects_distributed_options_without_a_farm(write_scene, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["render", str(write_scene()), "--out", str(tmp_path / "x.exr"), "--tile-size", "8"])
    assert exit_.value.code == cli.EXIT_USAGE
    with pytest.raises(SystemExit):
        cli.main(["render", str(write_scene()), "--out", str(tmp_path / "x.exr"), "--workers", "2",
                  "--scheduler", "tcp://127.0.0.1:1"])
