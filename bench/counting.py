"""An instrumented copy of the Numba kernel that counts density look-ups, for `bench/throughput.py`.

The tracer's kernel has no counters (counting there would slow every render), so this module builds a
copy of `addon/tracer/kernels/numba_backend.py` with counters wrapped around three of the functions it
calls, and runs the same paths (same scene, seed and sample indices) through it:

- `density` (`kernels/media.py`): one call is one density look-up (a trilinear interpolation, 8 voxel
  reads); the kernel calls it once per medium at every tentative collision, on camera paths and on
  shadow rays;
- `_transmittance`: one call is one shadow ray (next-event estimation);
- `_tracker_advance`: one call is one step of the majorant-grid DDA.

The copy is made by `kernel_copy` (written to the cache folder, cached by Numba like the real kernel).
Timed figures never come from this copy: `throughput.py` multiplies the counts per pixel-sample
measured here by the pixel-samples per second of the real kernel.
"""

from collections import namedtuple
from pathlib import Path

import numba
import numpy as np

from addon.tracer.kernels.layout import KernelScene

from bench.kernel_copy import CopyRenderer, kernel_copy

COUNTERS = ("density_lookups", "shadow_rays", "dda_steps")
_STRIDE = 8  # int64 slots per thread: one 64-byte cache line, so threads never share a line

_WRAPPERS = '''

# ---- bench/counting.py: per-thread counters around three functions (resolved when first compiled)
from numba import get_thread_id as _bench_thread_id

from bench.counting import CountingScene

_density_uncounted = density
_transmittance_uncounted = _transmittance
_tracker_advance_uncounted = _tracker_advance


@njit
def density(ks, m, px, py, pz):
    ks.bench_counters[_bench_thread_id() * 8 + 0] += 1
    return _density_uncounted(ks, m, px, py, pz)


@njit
def _transmittance(ks, ox, oy, oz, dx, dy, dz, t_max, residual, n, path, light, tracker):
    ks.bench_counters[_bench_thread_id() * 8 + 1] += 1
    _transmittance_uncounted(ks, ox, oy, oz, dx, dy, dz, t_max, residual, n, path, light, tracker)


@njit
def _tracker_advance(ks, tracker, t_end):
    ks.bench_counters[_bench_thread_id() * 8 + 2] += 1
    _tracker_advance_uncounted(ks, tracker, t_end)
'''

# The counters and the kernel scene's groups (`ks.camera`, `ks.majorant`, ...): the copy reads the groups by
# name, as the kernel does, and `_borrowed` borrows the counters with the groups' arrays.
CountingScene = namedtuple("CountingScene", ("bench_counters",) + KernelScene._fields)
# The lines the wrappers mirror (the call of the shared `density`, the definitions of the others): a changed
# signature refuses the copy instead of failing to compile.
_CHECKED = ("rho = density(ks, m, px, py, pz) * ks.media.density_scale[m]",
            "def _transmittance(ks, ox, oy, oz, dx, dy, dz, t_max, residual, n, path, light, tracker):",
            "def _tracker_advance(ks, tracker, t_end):")
# The parallel loop takes the kernel scene's groups one by one (`numba_backend._render_runs`): the counters go
# through it as one more, first.
_THROUGH_THE_LOOP = (("    _render_runs(ks.camera,", "    _render_runs(ks.bench_counters, ks.camera,"),
                     ("def _render_runs(camera,", "def _render_runs(bench_counters, camera,"),
                     ("ks = KernelScene(camera,", "ks = CountingScene(bench_counters, camera,"))


def counting_backend(folder: Path):
    """The instrumented kernel module (see the module docstring)."""
    # Replacing each line by itself checks that the three functions are still there.
    return kernel_copy("counting", folder, [(name, name) for name in _CHECKED] + list(_THROUGH_THE_LOOP), _WRAPPERS)


def count(kernel_scene: KernelScene, spp: int, seed: int, folder: Path, first_sample: int = 0) -> dict:
    """Totals of COUNTERS over samples [first_sample, first_sample + spp) of every pixel."""
    counters = np.zeros(numba.config.NUMBA_NUM_THREADS * _STRIDE, dtype=np.int64)
    renderer = CopyRenderer(counting_backend(folder), CountingScene(counters, *kernel_scene), seed)
    renderer.next_sample = first_sample
    renderer.render(spp)
    per_thread = counters.reshape(-1, _STRIDE)
    return {name: int(per_thread[:, slot].sum()) for slot, name in enumerate(COUNTERS)}
