"""The kernel backends, one row each: its name (a scene's `render.backend`), its kernels (the module with
`render_tile` and `set_threads`), and what makes them ready to run in this process before a render starts:
`prepare(kernel_scene, seed, cancel, notice)` for the path tracer, `prepare_first_hits(kernel_scene, cancel,
notice)` for the data passes' first-hit kernel, each False when `cancel()` said stop first. A new backend adds
one row. `tile_arguments` gives every backend's `render_tile` the same arguments.

The Numba row's `prepare` is the one place where a render (and `precompile`, in the background compile's
process) makes the kernel ready: a compile that `background_compile` runs in another process is waited for
(its notices passed on), then the kernel is loaded from the cache or compiled for the
argument types every unit passes (`kernels/numba_cache.py` does it in a helper thread, asking `cancel()` and
telling `notice` "Loading the kernel…" or "Compiling the kernel (about N s here)…"). Compiling without
running leaves nothing running in the background after a cancel (Numba's workqueue threading layer aborts
when two threads launch kernels at once). The NumPy backend has nothing to prepare.

The CUDA row (`kernels/cuda_backend.py`) refuses a scene with more media than its threads hold, then one where
no GPU is usable (`cuda_target.require_device`: a SpectralError naming the missing package, driver or GPU),
then copies the kernel scene to the device and loads or compiles the GPU kernel for it as the Numba row does
("Loading the GPU kernel…", "Compiling the GPU kernel…"). Its data passes' first hits run on the CPU, with the
Numba row's first-hit kernel.
"""

from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from . import background_compile
from .errors import SpectralError
from .kernels.layout import MAX_MEDIA, KernelScene
from .passes import first_hit_ready


@dataclass(frozen=True)
class Backend:
    """One row of the table: a backend's name, its kernels and its `prepare` hooks."""

    name: str
    load: Callable[[], ModuleType]  # imports its kernel module
    prepare: Callable[..., bool]  # (kernel_scene, seed, cancel, notice) → False when cancelled
    prepare_first_hits: Callable[..., bool]  # (kernel_scene, cancel, notice) → False when cancelled

    @property
    def kernels(self) -> ModuleType:
        """Its kernel module (`render_tile`, `set_threads`), imported on first use."""
        return self.load()


def tile_arguments(kernel_scene: KernelScene, band: int, samples: tuple[int, int], tile: tuple[int, int, int, int],
                   seed: int, light_categories: int = 0, spectrum: bool = False) -> tuple:
    """The arguments of a backend's `render_tile`, with zeroed accumulators (the last five: Σ XYZ, Σ XYZ²,
    Σ transparency, the light categories' with `light_categories` slots per pixel, none for no light passes, and
    the spectrum's, with no bins unless `spectrum`). Integers go as int64 (the seed as uint64, its whole range)
    whatever their values, so that no value changes the compiled kernel's argument types (a seed of 2⁶³ would be
    typed uint64, and compile a second kernel)."""
    x0, y0, width, height = (np.int64(value) for value in tile)
    bins = max(kernel_scene.wavelengths.spectrum_edges.size - 1, 0) if spectrum else 0
    h, w = int(height), int(width)
    return (kernel_scene, x0, y0, width, height, np.int64(samples[0]), np.int64(samples[1]), np.uint64(seed),
            np.int64(band), np.zeros((h, w, 3)), np.zeros((h, w, 3)), np.zeros((h, w)),
            np.zeros((h, w, int(light_categories), 3)), np.zeros((h, w, bins)))


def _numba_kernels() -> ModuleType:
    from .kernels import numba_backend

    return numba_backend


def _numpy_kernels() -> ModuleType:
    from .kernels import numpy_backend

    return numpy_backend


def _prepare_numba(kernel_scene: KernelScene, seed: int, cancel=None, notice=None) -> bool:
    """Wait for a compile running in the background, then load or compile the Numba kernel for the argument
    types of the scene's units, cancellably (module docstring)."""
    import numba

    from .kernels import numba_cache

    if not background_compile.wait(cancel, notice):
        return False
    kernel = _numba_kernels().render_tile
    signature = tuple(numba.typeof(argument) for argument in tile_arguments(kernel_scene, 0, (0, 1), (0, 0, 1, 1),
                                                                               seed))
    return numba_cache.ready(kernel, lambda: kernel.compile(signature), cancel, notice)


def check_cuda_media(count: int, where: str = "the scene") -> None:
    """A SpectralError when a scene has more media than a CUDA thread's path state holds (`layout.MAX_MEDIA`)."""
    if count > MAX_MEDIA:
        raise SpectralError(f"{where}: {count} media, and the cuda backend renders at most {MAX_MEDIA} (the numba "
                            f"backend renders any number)")


def _cuda_kernels() -> ModuleType:
    from .kernels import cuda_backend

    return cuda_backend


def _prepare_cuda(kernel_scene: KernelScene, seed: int, cancel=None, notice=None) -> bool:
    """Check the scene's media and the device, then load or compile the GPU kernel for the argument types of the
    scene's units, cancellably (module docstring)."""
    import numba

    from .kernels import cuda_target, numba_cache

    cuda_backend = _cuda_kernels()
    check_cuda_media(kernel_scene.media.density_scale.shape[0])
    cuda_target.require_device()
    kernel = cuda_backend.kernel()
    arguments = cuda_backend.device_arguments(tile_arguments(kernel_scene, 0, (0, 1), (0, 0, 1, 1), seed))
    signature = tuple(numba.typeof(argument) for argument in arguments)
    return numba_cache.ready(kernel, lambda: kernel.compile(signature), cancel, notice, cuda_backend.KERNEL)


def _ready(*_arguments) -> bool:
    """Nothing to prepare: the NumPy backend runs as it is."""
    return True


ROWS = (
    Backend("numba", _numba_kernels, _prepare_numba, first_hit_ready),  # the default: compiled, cached per machine
    Backend("numpy", _numpy_kernels, _ready, _ready),  # the oracle: no compiler
    Backend("cuda", _cuda_kernels, _prepare_cuda, first_hit_ready),  # numba-cuda: a GPU, compiled, cached per machine
)
NAMES = tuple(backend.name for backend in ROWS)  # the choices of a scene's `render.backend`


def named(name: str) -> Backend:
    """The row of the backend called `name` (a SpectralError naming the choices for any other)."""
    for backend in ROWS:
        if backend.name == name:
            return backend
    raise SpectralError(f"unknown backend {name!r}: choose one of {', '.join(NAMES)}")
