"""Rendering on a Dask farm (addon/tracer/farm.py; loopback only): the image is bit-for-bit the single-process one.

The slow tests start a real `dask scheduler` and `dask worker` processes on 127.0.0.1 (the venv's Dask
command line, with PYTHONPATH set to this repository so the workers import `addon`) and stop them in
fixtures, even when a test fails. Scenes are tiny: the machine running CI may have two cores.
"""

import dataclasses
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

from addon.tracer import cli, distributed, farm, image_io
from addon.tracer import render as single
from addon.tracer.errors import SpectralError
from tests.support import scenes as s
from tests.support.farm import assert_same_film, small_scene


def with_floor(scene):
    """`scene` with a diffuse floor under its box, and the Depth, Normal and CryptoObject passes asked for."""
    floor = s.parallelogram((-3.0, -3.0, -0.6), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, name="floor")
    settings = dataclasses.replace(scene.settings, passes=("Depth", "Normal", "CryptoObject"))
    return dataclasses.replace(scene, surfaces=(*scene.surfaces, floor), settings=settings)

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT = 120.0  # seconds for a scheduler or worker process to come up on a busy machine


def test_scheduler_and_workers_are_exclusive():
    with pytest.raises(SpectralError, match="either"):
        farm.render(small_scene(), scheduler="tcp://127.0.0.1:1", workers=2)


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
        farm.render(small_scene(), scheduler=address, timeout=timeout)
    elapsed = time.perf_counter() - start
    assert address in str(error.value)
    assert elapsed < timeout + 3.0, f"took {elapsed:.1f} s"


def test_the_default_timeout_is_the_documented_one():
    assert farm.DEFAULT_TIMEOUT == 10.0
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
    result = farm.render(scene, scheduler=loopback.address, tile_size=5,
                                progress=lambda film, fraction: fractions.append(fraction))
    assert not result.cancelled
    assert_same_film(expected, result.film)
    assert result.stats["workers"] == 2
    assert result.stats["tasks"] == len(single.pass_sizes(24)) * 2 * 6
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


@pytest.mark.slow
def test_a_farm_makes_the_data_passes_as_one_process_does(loopback):
    """The data passes come from the camera rays' first hits, made beside the farm's merge: the same images
    and manifests as a single-process render's (here a floor under the box: depths, normals, mattes)."""
    scene = with_floor(small_scene(spp=4, bands=1))
    expected = single.render(scene).passes
    result = farm.render(scene, scheduler=loopback.address, tile_size=5)
    assert set(result.passes.images) == set(expected.images) >= {"Depth", "Normal", "CryptoObject00"}
    assert np.any(expected.images["Depth"] < 1e9)  # the floor is seen
    for name, image in expected.images.items():
        np.testing.assert_array_equal(result.passes.images[name], image)
    assert result.passes.mattes == expected.mattes


@pytest.mark.slow
def test_a_farm_makes_the_light_passes_and_the_spectrum_as_one_process_does(loopback):
    """The light passes' and the spectral bins' sums travel with each task's XYZ and are merged in pass order: the
    same film, bit for bit, and the same pass images."""
    scene = small_scene(spp=6, bands=2)
    scene = dataclasses.replace(scene, settings=dataclasses.replace(
        scene.settings, passes=("Emission", "Environment", "Volume Direct", "Volume Indirect"), spectrum=True))
    expected = single.render(scene)
    assert expected.film.light_categories and expected.film.bins and expected.film.sum_spectrum.any()
    result = farm.render(scene, scheduler=loopback.address, tile_size=5)
    assert_same_film(expected.film, result.film)
    assert set(result.passes.images) == set(expected.passes.images) >= {"Environment", "Volume Direct"}
    for name, image in expected.passes.images.items():
        np.testing.assert_array_equal(result.passes.images[name], image)


@pytest.mark.slow
def test_a_farm_filters_fireflies_as_one_process_does(loopback):
    """With the firefly filter each task keeps its pixels' brightest samples, and the passes are of one sample (as
    a single-process render's then are): the same filtered film, bit for bit, peaks and light passes included."""
    scene = small_scene(spp=5, bands=2)
    scene = dataclasses.replace(scene, settings=dataclasses.replace(
        scene.settings, passes=("Volume Direct", "Volume Indirect"), spectrum=True, firefly_threshold=0.5))
    expected = single.render(scene)
    assert expected.film.peaks
    result = farm.render(scene, scheduler=loopback.address, tile_size=5)
    assert result.stats["tasks"] == 5 * 2 * 6  # five passes of one sample, two bands, six tiles
    assert_same_film(expected.film, result.film)
    for name, image in expected.passes.images.items():
        np.testing.assert_array_equal(result.passes.images[name], image)


@pytest.mark.slow
def test_cancel_stops_between_tasks_with_whole_passes(reference, loopback):
    scene, expected = reference
    result = farm.render(scene, scheduler=loopback.address, tile_size=5, spp=200,
                                progress=lambda film, fraction: None, cancel=lambda: True)
    assert result.cancelled
    assert result.stats["tasks_done"] == 0
    calls = []

    def cancel_after_first_progress():
        return bool(calls)

    result = farm.render(scene, scheduler=loopback.address, tile_size=5, spp=200,
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

        result = farm.render(scene, scheduler=fresh_loopback.address, tile_size=5, progress=progress)
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

import addon.tracer.render as render

if not hasattr(render, "unslowed_render_unit"):  # Dask may import a preload twice
    render.unslowed_render_unit = render.render_unit
    render.render_unit = lambda *args: time.sleep(0.03) or render.unslowed_render_unit(*args)
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

    result = farm.render(scene, scheduler=fresh_loopback.address, tile_size=3, progress=progress)
    assert joined and joined[0] < 0.5
    assert result.stats["workers"] == 2
    assert len(result.stats["workers_refused"]) == 1, "the other worker ran no task: the test proved nothing"
    assert_same_film(expected, result.film)


@pytest.mark.slow
def test_a_farm_whose_every_worker_disagrees_is_a_clear_error_not_a_hang(loopback, monkeypatch):
    """Here the client expects another fingerprint than every worker computes: each result is refused, and the
    render stops once a task has been refused REFUSALS times."""
    monkeypatch.setattr(distributed, "fingerprint", lambda *parts: "not what any worker runs")
    with pytest.raises(SpectralError, match=f"run other code .* refused {farm.REFUSALS} times"):
        farm.render(small_scene(spp=4, bands=1), scheduler=loopback.address, tile_size=6, timeout=20)


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
        farm.render(small_scene(spp=200), scheduler=fresh_loopback.address, tile_size=5, timeout=timeout,
                           progress=progress)
    assert killed and time.perf_counter() - killed["at"] < timeout + 3.0


@pytest.mark.slow
def test_a_scheduler_without_workers_is_a_clear_error(fresh_loopback):
    start = time.perf_counter()
    with pytest.raises(SpectralError, match="has no workers") as error:
        farm.render(small_scene(), scheduler=fresh_loopback.address, timeout=2.0)
    assert fresh_loopback.address in str(error.value)
    assert time.perf_counter() - start < 2.0 + 5.0


@pytest.mark.slow
def test_a_worker_that_cannot_import_the_tracer_is_a_clear_error(fresh_loopback):
    fresh_loopback.start_workers(1, importable=False)
    with pytest.raises(SpectralError, match="cannot import the tracer.*PYTHONPATH"):
        farm.render(small_scene(), scheduler=fresh_loopback.address)


@pytest.mark.slow
def test_cli_with_two_local_workers_writes_the_single_process_exr(write_scene, tmp_path):
    from tests.tracer.conftest import tiny_scene_dict

    data = tiny_scene_dict()
    data["render"] = {"spp": 24, "bands": 2, "seed": 5}
    scene_path = write_scene(data)
    alone, on_farm = tmp_path / "alone.exr", tmp_path / "farm.exr"
    assert cli.main(["render", str(scene_path), "--out", str(alone), "--quiet"]) == cli.EXIT_OK
    run = subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene_path), "--out", str(on_farm),
                          "--workers", "2", "--tile-size", "3"],
                         cwd=ROOT, env=_subprocess_env(), capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "100.0%" in run.stderr  # the progress bar ran to the end
    expected, actual = image_io.read_exr(alone), image_io.read_exr(on_farm)
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
        farm.render(small_scene(), scheduler="tcp://127.0.0.1:9", **options)


def test_bad_overrides_are_refused_like_the_scenes_own_settings():
    no_cluster = farm.RenderFarm.__new__(farm.RenderFarm)  # refused before any Dask call
    with pytest.raises(SpectralError, match="render.seed: must be at most 18446744073709551615"):
        no_cluster.render(small_scene(), seed=2**64)
    with pytest.raises(SpectralError, match="render.spp: must be at least 1, found 0"):
        no_cluster.render(small_scene(), spp=0)


def test_cli_rejects_distributed_options_without_a_farm(write_scene, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["render", str(write_scene()), "--out", str(tmp_path / "x.exr"), "--tile-size", "8"])
    assert exit_.value.code == cli.EXIT_USAGE
    with pytest.raises(SystemExit):
        cli.main(["render", str(write_scene()), "--out", str(tmp_path / "x.exr"), "--workers", "2",
                  "--scheduler", "tcp://127.0.0.1:1"])
