"""Compiling the kernel in a separate process (addon/tracer/background_compile.py, the child running
addon/tracer/precompile.py): the child imports the tracer under the parent's package name and fills the cache
folder every import name reads; a render waits for it, passing on what it says it does, and that wait can be
cancelled; where the shipped portable kernel serves, a render does not wait."""

import subprocess
import sys
import time

import pytest

from addon.tracer import background_compile
from addon.tracer.kernels import numba_cache

EXTENSION_PACKAGE = "bl_ext.user_default.spectral_volume.addon.tracer"  # as Blender imports the extension


def in_child(function: str, package: str, cwd=None) -> str:
    """What `function` of precompile.py prints, run in the background compile's child, which imports the tracer
    as `package`."""
    command = background_compile.child_command(function)
    command[command.index(background_compile.PACKAGE)] = package
    return subprocess.run(command, env=background_compile.child_environment(), capture_output=True, text=True,
                          check=True, cwd=cwd).stdout


def test_the_child_imports_the_tracer_under_the_parents_package_name(tmp_path):
    package, folder = in_child("describe", background_compile.PACKAGE, tmp_path).split()  # not from the repository
    assert package == background_compile.PACKAGE == numba_cache.PACKAGE
    assert folder == str(numba_cache.kernel_folder())
    extension_package, extension_folder = in_child("describe", EXTENSION_PACKAGE, tmp_path).split()
    assert extension_package == EXTENSION_PACKAGE and extension_folder == folder  # one cache for both names


def test_a_background_compile_fills_this_process_cache_once(monkeypatch):
    monkeypatch.setattr(background_compile, "_process", None)
    monkeypatch.setattr(background_compile, "_kernel_loaded", lambda: False)  # as if no render ran before
    monkeypatch.delenv(background_compile.DISABLE_VARIABLE, raising=False)
    assert background_compile.start()
    assert not background_compile.start()  # one per process
    assert background_compile.wait()
    assert background_compile._process.returncode == 0
    folder = numba_cache.kernel_folder()
    log = (folder / background_compile.LOG_NAME).read_text()
    assert log.startswith(f"{numba_cache.PACKAGE} {folder}") and "\nkernel " in log
    assert list(folder.glob("*.nbi"))  # Numba's cache index, where this process looks for the kernel


def test_the_extension_loads_the_kernel_the_checkout_compiled():
    """The kernel in the cache (compiled under `addon.tracer` by the test above, or earlier) is loaded,
    not compiled, by the tracer imported under the installed extension's name."""
    in_child("compile_kernel", background_compile.PACKAGE)
    in_child("compile_kernel", EXTENSION_PACKAGE)
    log = (numba_cache.kernel_folder() / background_compile.LOG_NAME).read_text()
    assert log.startswith(EXTENSION_PACKAGE) and "\nkernel loaded from the cache in " in log, log


def test_no_background_compile_when_switched_off(monkeypatch):
    monkeypatch.setattr(background_compile, "_process", None)
    monkeypatch.setenv(background_compile.DISABLE_VARIABLE, "1")
    assert not background_compile.start() and not background_compile.started()


def test_no_background_compile_once_this_process_has_the_kernel(monkeypatch):
    from addon.tracer import builders as b
    from addon.tracer.render import render

    monkeypatch.setattr(background_compile, "_process", None)
    monkeypatch.delenv(background_compile.DISABLE_VARIABLE, raising=False)
    render(b.scene(b.perspective((0, -4, 0), (0, 0, 0), 2, 2, 40), [], [b.environment()], spp=1))
    assert not background_compile.start() and not background_compile.started()


def test_waiting_for_the_compile_says_what_it_does_and_can_be_cancelled(monkeypatch, tmp_path):
    monkeypatch.setenv(numba_cache.CACHE_DIR_VARIABLE, str(tmp_path))
    log = numba_cache.kernel_folder() / background_compile.LOG_NAME
    log.parent.mkdir(parents=True)
    log.write_text("Compiling the kernel (about 300 s on this machine)…\n")  # an earlier process's
    monkeypatch.setattr(background_compile, "_started_at", time.time() + 1.0)
    slow = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    monkeypatch.setattr(background_compile, "_process", slow)
    said = "Compiling the kernel (about 12 s on this machine)…"

    def cancel():
        if time.time() > background_compile._started_at + 0.2 and said not in log.read_text():
            log.write_text(f"{numba_cache.PACKAGE} {log.parent}\n{numba_cache.LOADING_MESSAGE}\n{said}\n")
        return len(notices) == 1

    try:
        notices, begun = [], time.perf_counter()
        assert not background_compile.wait(cancel=cancel, notice=notices.append)
        assert time.perf_counter() - begun < 10
        assert notices == [said]  # its last notice, once; not the older log's
        assert background_compile.running()  # a cancelled wait leaves the compile running
    finally:
        slow.kill()
        slow.wait()
    assert background_compile.wait(cancel=lambda: pytest.fail("nothing to wait for, nothing to ask"))


def test_a_render_does_not_wait_for_the_compile_where_the_portable_kernel_serves(monkeypatch, tmp_path):
    slow = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    monkeypatch.setattr(background_compile, "_process", slow)
    try:
        monkeypatch.setattr(numba_cache, "prebuilt_folder", lambda: tmp_path)
        assert background_compile.wait(cancel=lambda: False) and background_compile.running()
        monkeypatch.setattr(numba_cache, "prebuilt_folder", lambda: None)
        assert not background_compile.wait(cancel=lambda: True)  # without one it waits (here: cancelled)
    finally:
        slow.kill()
        slow.wait()


def test_the_background_compile_builds_the_hosts_kernel_not_the_portable_one():
    assert background_compile.child_environment()[numba_cache.NO_PREBUILT_VARIABLE]
