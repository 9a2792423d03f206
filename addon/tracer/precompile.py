"""Compiling the Numba kernel ahead of any render, in a process of its own: what the background compile's child
runs (`background_compile.start` starts it with `compile_kernel`; `describe` says how it imported the tracer),
and what `make extension` runs to compile the portable kernel (tools/build_extension.py).

The kernel is made ready exactly as a render makes it (`backends`, the Numba row's `prepare`), for the
argument types every scene gives it, and what it does is written to `background_compile.LOG_NAME` in the
kernel's cache folder, where a render waiting for it reads its notices.
"""

import contextlib
import time

from .background_compile import LOG_NAME
from .backends import named
from .builders import environment, perspective, scene
from .kernels import numba_backend, numba_cache
from .lowering import compile_scene


def describe() -> None:
    """Print the package the tracer was imported as and its kernel cache folder."""
    print(f"{numba_cache.PACKAGE} {numba_cache.kernel_folder()}", flush=True)


def compile_kernel() -> None:
    """Compile the kernel (or find it in the cache) for the argument types every scene gives it, writing what
    it does to LOG_NAME in the kernel's cache folder."""
    folder = numba_cache.kernel_folder()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / LOG_NAME, "w", encoding="utf-8") as log, contextlib.redirect_stdout(log), \
            contextlib.redirect_stderr(log):
        describe()
        empty = scene(perspective((0.0, -1.0, 0.0), (0.0, 0.0, 0.0), 1, 1, 40.0), (), (environment(),), spp=1)
        begun = time.perf_counter()
        named("numba").prepare(compile_scene(empty), 0, None, lambda text: print(text, flush=True))
        how = "loaded from the cache" if sum(numba_backend.render_tile.stats.cache_hits.values()) else "compiled"
        print(f"kernel {how} in {time.perf_counter() - begun:.1f} s", flush=True)
