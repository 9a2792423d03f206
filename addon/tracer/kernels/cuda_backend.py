"""The CUDA backend: the Numba kernel's own path code (`numba_backend._render_samples` and everything it calls),
compiled by numba-cuda, one GPU thread per (pixel, sample) of a tile (`render_samples`).

`render_tile` takes `numba_backend.render_tile`'s arguments, so the render loop, its tiles and its cancellation
work unchanged: the kernel scene's arrays are copied to the device once per kernel scene (the last one is kept),
the tile's accumulators to it and back at every launch, and the threads add their sums to them with float64
atomics (`shared_math.accumulate`). A thread's path state holds `MAX_MEDIA` media (`backends.check_cuda_media`). numba-cuda
is imported on first use (`cuda_target`); the compiled kernel is cached per machine, beside the CPU kernel's
(`numba_cache`), keyed by the same kernel sources, numba-cuda's version and `cuda_target`'s source.
"""

import functools
import hashlib
import importlib.metadata
from pathlib import Path

import numpy as np

from . import cuda_target, numba_cache
from .layout import MAX_MEDIA
from .numba_backend import (_borrowed, _new_coefficients, _new_fluorescent, _new_hit, _new_light_sample, _new_path,
                            _new_tracker, _render_samples)
from ..shared_math import accumulate

THREADS = 64  # threads per block
KERNEL = "GPU kernel"  # what the notices call it ("Compiling the GPU kernel…")
cuda = None  # numba-cuda's `numba.cuda` (or its simulator), imported on first use by `kernel()`


def render_samples(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                   sum_transparent, sum_light_passes, sum_spectrum):
    """The CUDA kernel: thread t takes sample `sample_begin + t // pixels` of the tile's pixel `t % pixels`
    (samples outermost: neighbouring threads hold neighbouring pixels), traces it with `_render_samples` and adds
    its sums to the tile's (`render_tile`'s accumulators)."""
    thread = cuda.grid(1)
    pixels = tile_width * tile_height
    if thread >= pixels * (sample_end - sample_begin):
        return
    sample, index = sample_begin + thread // pixels, thread % pixels
    row, column = index // tile_width, index % tile_width
    px, py = x0 + column, y0 + row
    path, vertex = _new_path(MAX_MEDIA), _new_coefficients(MAX_MEDIA)
    light, tracker, fl, hit = _new_light_sample(), _new_tracker(MAX_MEDIA), _new_fluorescent(), _new_hit()
    sx, sy, sz, qx, qy, qz, st = _render_samples(ks, px, py, py * ks.camera.width + px, sample, sample + 1, seed,
                                                 band, path, vertex, light, tracker, fl, hit,
                                                 sum_light_passes[row, column], sum_spectrum, row, column)
    accumulate(sum_xyz, (row, column, 0), sx)
    accumulate(sum_xyz, (row, column, 1), sy)
    accumulate(sum_xyz, (row, column, 2), sz)
    accumulate(sum_sq, (row, column, 0), qx)
    accumulate(sum_sq, (row, column, 1), qy)
    accumulate(sum_sq, (row, column, 2), qz)
    accumulate(sum_transparent, (row, column), st)


def _cache_key() -> dict:
    """What the GPU kernel depends on besides the CPU kernel's key (`numba_cache.cache_key`)."""
    sources = b"".join(Path(path).read_bytes() for path in (cuda_target.__file__, __file__))
    return {"numba_cuda": importlib.metadata.version("numba-cuda"), "cuda_sources": hashlib.sha256(sources).hexdigest()}


def _cache(py_func):
    """numba-cuda's kernel cache, in our kernel folder for `_cache_key()` (none where it cannot be made)."""
    from numba.cuda.core.caching import NullCache, _InTreeCacheLocator
    from numba.cuda.dispatcher import CUDACache, CUDACacheImpl

    folder = numba_cache.usable_folder(_cache_key())
    if folder is None:
        return NullCache()

    class Locator(_InTreeCacheLocator):
        def __init__(self, py_func, py_file):
            super().__init__(py_func, py_file)
            self._cache_path = str(folder)

    class Impl(CUDACacheImpl):
        _locator_classes = [Locator]

    class Cache(CUDACache):
        _impl_class = Impl

    return Cache(py_func)


@functools.cache
def kernel():
    """`render_samples` as numba-cuda's kernel (the simulator's under NUMBA_ENABLE_CUDASIM=1), with its cache."""
    global cuda
    cuda = cuda_target.compiler()
    if cuda_target.simulating():
        return cuda.jit(render_samples)
    from numba.cuda.extending import overload

    overload(_borrowed, target="cuda")(lambda scene: lambda scene: scene)  # no reference counts to borrow
    dispatcher = cuda.jit(render_samples)
    dispatcher._cache = _cache(dispatcher.py_func)
    return dispatcher


_scene = (None, None)  # the last kernel scene and its copy on the device


def _copy(value, put):
    """`value` (a kernel scene: named tuples of arrays and numbers) with `put` applied to each of its arrays (made
    C-contiguous first)."""
    if isinstance(value, np.ndarray):
        return put(np.ascontiguousarray(value))
    if isinstance(value, tuple):
        members = [_copy(member, put) for member in value]
        return type(value)(*members) if hasattr(value, "_fields") else tuple(members)
    return value


def on_device(ks):
    """The kernel scene `ks` with its arrays on the device, copied once for each kernel scene."""
    global _scene
    kernel()
    if _scene[0] is not ks:
        _scene = (ks, _copy(ks, cuda.to_device))
    return _scene[1]


def device_arguments(arguments: tuple) -> tuple:
    """`render_tile`'s arguments as the kernel takes them: the scene and the accumulators on the device."""
    ks, *numbers, sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum = arguments
    return (on_device(ks), *numbers,
            *(cuda.to_device(array) for array in (sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum)))


def kernel_types(arguments: tuple) -> tuple:
    """The Numba types the kernel gets for `render_tile`'s `arguments`, found without a device (each array as a
    device copy types it: writable and C-contiguous): what `cuda_target.compile_ptx` compiles it for."""
    from numba import typeof

    return tuple(typeof(_copy(argument, np.copy)) for argument in arguments)


def render_tile(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                sum_transparent, sum_light_passes, sum_spectrum):
    """`numba_backend.render_tile` on the GPU: samples [sample_begin, sample_end) of every pixel of the tile added
    to the accumulators (NumPy arrays, copied to the device and back)."""
    host = (sum_xyz, sum_sq, sum_transparent, sum_light_passes, sum_spectrum)
    arguments = device_arguments((ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, *host))
    threads = int(tile_width) * int(tile_height) * int(sample_end - sample_begin)
    if threads > 0:
        kernel()[(threads + THREADS - 1) // THREADS, THREADS](*arguments)
    for array, device in zip(host, arguments[-5:]):
        device.copy_to_host(array)


def set_threads(count: int) -> None:
    """Nothing to set: the GPU runs as many threads as a tile has pixel-samples (the CPU's thread count is the
    numba backend's)."""
