"""Compiling the kernel in a separate process (addon/tracer/background_compile.py): the child imports the
tracer under the parent's package name, so it fills the very cache folder the parent reads; a render waits
for it, and that wait can be cancelled."""

import subprocess
import sys
import time

import pytest

from addon.tracer import background_compile
from addon.tracer.kernels import numba_cache

EXTENSION_PACKAGE = "bl_ext.user_default.spectral_volume.addon.tracer"  # as Blender imports the extension


def described(package: str, cwd) -> list[str]:
    command = background_compile.child_command("describe")
    command[command.index(background_compile.PACKAGE)] = package
    return subprocess.run(command, env=background_compile.child_environment(), capture_output=True, text=True,
                          check=True, cwd=cwd).stdout.split()


def test_the_child_imports_the_tracer_under_the_parents_package_name(tmp_path):
    package, folder = described(background_compile.PACKAGE, tmp_path)  # not run from the repository
    assert package == background_compile.PACKAGE == numba_cache.PACKAGE
    assert folder == str(numba_cache.kernel_folder())
    extension_package, extension_folder = described(EXTENSION_PACKAGE, tmp_path)
    assert extension_package == EXTENSION_PACKAGE and extension_folder != folder  # its own cache key


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
    assert log.startswith(f"{numba_cache.PACKAGE} {folder}") and "kernel ready" in log
    assert list(folder.glob("*.nbi"))  # Numba's cache index, where this process looks for the kernel


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


def test_waiting_for_the_compile_tells_why_and_can_be_cancelled(monkeypatch):
    slow = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    monkeypatch.setattr(background_compile, "_process", slow)
    try:
        notices, begun = [], time.perf_counter()
        assert not background_compile.wait(cancel=lambda: time.perf_counter() - begun > 1.5,
                                           notice=notices.append)
        assert time.perf_counter() - begun < 10
        assert notices == [numba_cache.compiling_message()]  # once, after a cache load's time
        assert background_compile.running()  # a cancelled wait leaves the compile running
    finally:
        slow.kill()
        slow.wait()
    assert background_compile.wait(cancel=lambda: pytest.fail("nothing to wait for, nothing to ask"))
