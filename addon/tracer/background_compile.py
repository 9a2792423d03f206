"""Compiling the Numba kernel ahead of the first render, in a separate process, so that the render only
loads it from the kernel cache (kernels/numba_cache.py).

Blender starts one (`start`) as soon as a scene renders with this engine: a file using it loads, or a
scene switches to it. By the time the user renders, the kernel is usually ready. A separate process,
not a thread of Blender's own, because Numba's compiler runs Python: in a thread it holds the GIL about a
third of the time, and Blender's interface, which runs Python for every panel it draws, would lag (measured:
5 ms on every Python call and stalls of up to 2 s, for minutes; bench/README.md).

The process runs `precompile.compile_kernel`. A render that starts while it compiles waits for it (`wait`,
called by the Numba backend's `prepare` in backends.py; cancellable, telling the user what the process said
it does: loading or compiling) instead of compiling the same kernel a second time; a failed or missing
process changes nothing, since the render then compiles the kernel itself. Where the extension ships a
portable kernel (kernels/numba_cache.py), the render does not wait: it loads that one at once, and the
process compiles the host's own (never loading the portable one) for the renders after. The process is left
to finish when Blender quits: it only fills the cache. It writes what it does to `background-compile.log`
in the kernel's cache folder.

The child imports the tracer under this process's package name ("addon.tracer", or
"bl_ext.<repo>.<extension>.addon.tracer" in Blender); its parent packages are made empty (their
`__init__` would import Blender). The kernel cache is shared by every name (kernels/numba_cache.py).
"""

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

# Run by the child: `python -c CHILD package tracer_folder function`, the function of precompile.py to call.
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
getattr(importlib.import_module(package + ".precompile"), function)()
"""

_lock = threading.Lock()
_process: subprocess.Popen | None = None
_started_at = 0.0  # time.time() when `start` started it: an older log is another process's


def start() -> bool:
    """Start compiling the kernel in a separate process, unless one was started already (by this process),
    this process has the kernel already, or the environment variable DISABLE_VARIABLE is set. Returns
    whether a process was started."""
    global _process, _started_at
    if os.environ.get(DISABLE_VARIABLE) or _kernel_loaded():
        return False
    with _lock:
        if _process is not None:
            return False
        _started_at = time.time()
        _process = subprocess.Popen(child_command("compile_kernel"), env=child_environment(), stdin=subprocess.DEVNULL,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0))  # no console on Windows
        return True


def _kernel_loaded() -> bool:
    """Whether this process has compiled or loaded the Numba kernel for this computer already (without
    importing it): not the portable one."""
    from .kernels import numba_cache

    kernel = sys.modules.get(f"{PACKAGE}.kernels.numba_backend")
    return kernel is not None and bool(kernel.render_tile.overloads) and not numba_cache.serves_portable(
        kernel.render_tile)


def child_command(function: str) -> list[str]:
    """The command that runs `function` of precompile.py in a child process, the tracer imported there under
    this process's package name."""
    return [sys.executable, "-c", CHILD, PACKAGE, str(TRACER), function]


def child_environment() -> dict:
    """This process's environment, with its module search path: in Blender it includes the folder of the
    extension's bundled wheels (Numba), which a plain Python does not search. The child compiles the
    host's kernel: it never loads the shipped portable one."""
    from .kernels import numba_cache

    return {**os.environ, "PYTHONPATH": os.pathsep.join(path for path in sys.path if path),
            numba_cache.NO_PREBUILT_VARIABLE: "1"}


def started() -> bool:
    """Whether `start` has started a compile in this process (running or finished)."""
    return _process is not None


def running() -> bool:
    """Whether a kernel compile started by `start` is still running."""
    return _process is not None and _process.poll() is None


def wait(cancel=None, notice=None) -> bool:
    """Wait for the compile `start` began, if one is running, asking `cancel()` (False when it says stop;
    the compile goes on) and telling `notice` what the process says it does (loading or compiling the
    kernel, kernels/numba_cache.py's notices, in its log). True when there is nothing (more) to wait for:
    no compile runs, or the shipped portable kernel renders meanwhile."""
    from .kernels import numba_cache

    if not running() or numba_cache.prebuilt_folder() is not None:
        return True
    try:
        log = numba_cache.kernel_folder() / LOG_NAME
    except OSError:  # the kernel sources cannot be read to name the folder: wait without notices
        log = None
    told = None
    while running():
        if cancel is not None and cancel():
            return False
        said = _last_notice(log, numba_cache.NOTICES) if notice is not None and log is not None else None
        if said is not None and said != told:
            notice(said)
            told = said
        time.sleep(POLL_SECONDS)
    return True


def _last_notice(log: Path, notices: tuple[str, ...]) -> str | None:
    """The last line of the running process's log that starts with one of `notices` (None before its
    first, or without a log)."""
    try:
        if log.stat().st_mtime < _started_at:
            return None
        lines = log.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    return next((line for line in reversed(lines) if line.startswith(notices)), None)
