"""Compiling the Numba kernel ahead of the first render, in a separate process, so that the render only
loads it from the kernel cache (kernels/numba_cache.py).

Blender starts one (`start`) as soon as a scene renders with this engine: a file using it loads, or a
scene switches to it. By the time the user renders, the kernel is usually ready. A separate process,
not a thread of Blender's own, because Numba's compiler runs Python: in a thread it holds the GIL about a
third of the time, and Blender's interface, which runs Python for every panel it draws, would lag (measured:
5 ms on every Python call and stalls of up to 2 s, for minutes; bench/README.md).

A render that starts while the process compiles waits for it (`wait`, cancellable, telling the user why)
instead of compiling the same kernel a second time; a failed or missing process changes nothing, since the
render then compiles the kernel itself. The process is left to finish when Blender quits: it only fills the
cache. It writes what it did to `background-compile.log` in the kernel's cache folder.

The child imports the tracer under this process's package name ("addon.tracer", or
"bl_ext.<repo>.<extension>.addon.tracer" in Blender), because a kernel cached under one name cannot be
read under another. Its parent packages are made empty (their `__init__` would import Blender).
"""

import contextlib
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

DISABLE_VARIABLE = "SPECTRAL_VOLUME_NO_BACKGROUND_COMPILE"  # set (to anything) to never start one
LOG_NAME = "background-compile.log"
POLL_SECONDS = 0.05
PACKAGE = __name__.rpartition(".")[0]  # the tracer's package, as kernels/numba_cache.py names it
TRACER = Path(__file__).resolve().parent

# Run by the child: `python -c CHILD package tracer_folder function`, the function of this module to call.
CHILD = """
import importlib, sys, types
package, folder, function = sys.argv[1], sys.argv[2], sys.argv[3]
parts = package.split(".")
path = __import__("pathlib").Path(folder)
for depth in range(len(parts) - 1):
    name = ".".join(parts[:depth + 1])
    module = types.ModuleType(name)
    module.__path__ = [str(path.parents[len(parts) - depth - 2])]
    sys.modules[name] = module
getattr(importlib.import_module(package + ".background_compile"), function)()
"""

_lock = threading.Lock()
_process: subprocess.Popen | None = None


def start() -> bool:
    """Start compiling the kernel in a separate process, unless one was started already (by this process),
    this process has the kernel already, or the environment variable DISABLE_VARIABLE is set. Returns
    whether a process was started."""
    global _process
    if os.environ.get(DISABLE_VARIABLE) or _kernel_loaded():
        return False
    with _lock:
        if _process is not None:
            return False
        _process = subprocess.Popen(child_command("compile_kernel"), env=child_environment(), stdin=subprocess.DEVNULL,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0))  # no console on Windows
        return True


def _kernel_loaded() -> bool:
    """Whether this process has compiled or loaded the Numba kernel already (without importing it)."""
    kernel = sys.modules.get(f"{PACKAGE}.kernels.numba_backend")
    return kernel is not None and bool(kernel.render_tile.overloads)


def child_command(function: str) -> list[str]:
    """The command that runs `function` of this module in a child process, the tracer imported there under
    this process's package name."""
    return [sys.executable, "-c", CHILD, PACKAGE, str(TRACER), function]


def child_environment() -> dict:
    """This process's environment, with its module search path: in Blender it includes the folder of the
    extension's bundled wheels (Numba), which a plain Python does not search."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join(path for path in sys.path if path)}


def started() -> bool:
    """Whether `start` has started a compile in this process (running or finished)."""
    return _process is not None


def running() -> bool:
    """Whether a kernel compile started by `start` is still running."""
    return _process is not None and _process.poll() is None


def wait(cancel=None, notice=None) -> bool:
    """Wait for the compile `start` began, if one is running, asking `cancel()` (False when it says stop;
    the compile goes on) and, if it takes longer than a cache load, telling `notice` the compiling message.
    True when there is nothing (more) to wait for."""
    from .kernels import numba_cache

    begun, told = time.perf_counter(), False
    while running():
        if cancel is not None and cancel():
            return False
        if notice is not None and not told and time.perf_counter() - begun > numba_cache.NOTICE_AFTER_SECONDS:
            notice(numba_cache.compiling_message())
            told = True
        time.sleep(POLL_SECONDS)
    return True


def describe() -> None:
    """Print the package the tracer was imported as and its kernel cache folder."""
    from .kernels import numba_cache

    print(f"{numba_cache.PACKAGE} {numba_cache.kernel_folder()}", flush=True)


def compile_kernel() -> None:
    """What the child runs: compile the kernel (or find it in the cache) for the argument types every scene
    gives it, writing what it does to LOG_NAME in the kernel's cache folder."""
    from .builders import environment, perspective, scene
    from .kernels import numba_backend, numba_cache
    from .lowering import compile_scene
    from .render import kernel_ready

    folder = numba_cache.kernel_folder()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / LOG_NAME, "w", encoding="utf-8") as log, contextlib.redirect_stdout(log), \
            contextlib.redirect_stderr(log):
        describe()
        empty = scene(perspective((0.0, -1.0, 0.0), (0.0, 0.0, 0.0), 1, 1, 40.0), (), (environment(),), spp=1)
        begun = time.perf_counter()
        kernel_ready(numba_backend, compile_scene(empty), 0, None, None)
        print(f"kernel ready in {time.perf_counter() - begun:.1f} s", flush=True)
