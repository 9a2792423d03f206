"""The Numba path kernel on the CUDA target (issue 32, item 3 groundwork): a generated copy of
`addon/tracer/kernels/numba_backend.py` (`kernel_copy`, the tracer untouched) in which every path function is a
device function, with one CUDA kernel, `render_samples`, running one thread per (pixel, sample) of a tile through
the kernel's own `_render_samples` and adding its sums to the tile's accumulators with atomics.

It prints the compile's seconds, what ptxas (nvJitLink, `cuda_target.assemble`) gives the kernel (registers,
stack frame, spills, constant bytes) and the size of one thread's path state; `--simulate` renders a tiny scene
with the copy in numba-cuda's simulator (a child process under NUMBA_ENABLE_CUDASIM=1) and compares it pixel by
pixel with the CPU kernel at the same seed (the same random streams trace the same paths). Figures and the plan
they support: docs/architecture.md, "GPU backend (in progress)". No GPU is needed.

    python -m bench.cuda_path_kernel [--max-media 4] [--simulate] [--no-compile] [--spp 2] [--seed 7]

What the copy changes (`REPLACEMENTS`, each refused when the kernel no longer contains it):
- `jit` is `shared_math`'s decorators: `shared_inline` for the `inline="always"` functions (Numba inlines them
  into their caller before typing, on either target), `shared` for the rest.
- `_borrowed` (an intrinsic writing the CPU's reference-counting fields) is the identity: CUDA arrays have none.
- The state's buffers (`np.empty`, `np.zeros` in `_new_*`) are `cuda.local.array`s of compile-time shapes, the
  media's dimension bounded by `MAX_MEDIA` (a scene with more is refused); zeroed where the kernel zeroes them.
- `render_tile` loses the kernel cache's decorator (it is never compiled here).
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.kernel_copy import kernel_copy

ROOT = Path(__file__).resolve().parents[1]
MAX_MEDIA = 4
THREADS = 64  # threads per block of `render_samples`

# What replaces `jit` in the copy (the name stays, so every decorator of the kernel keeps its text).
_JIT = '''from ..shared_math import shared as _shared, shared_inline as _shared_inline


def jit(function=None, **options):
    """(CUDA copy, bench/cuda_path_kernel.py) one definition for the CPU and CUDA targets:
    `shared_math.shared_inline` where the kernel asks for inline="always" (the state's constructors among them:
    their local arrays live in the calling kernel's frame), `shared` otherwise."""
    if function is None:
        return lambda function: jit(function, **options)
    return _shared_inline(function) if options.get("inline") == "always" else _shared(function)'''

REPLACEMENTS = (
    ('jit = functools.partial(njit, error_model="numpy")', _JIT),
    ("@intrinsic\ndef _borrowed(typingctx, scene):",
     '@jit(inline="always")\ndef _borrowed(scene):\n    return scene  # (CUDA copy) no reference counts to drop\n\n\n'
     "def _cpu_borrowed(typingctx, scene):"),
    ("np.empty(", "_local_empty("),
    ("np.zeros(", "_local_zeros("),
    ("(media, ", "(MAX_MEDIA, "),
    ("2 * BVH_MAX_DEPTH", "BVH_STACK"),
    ("@cached\n@jit(nogil=True)\ndef render_tile(", "def render_tile("),
)

# Appended to the copy: the local arrays and the kernel. `{max_media}` is the bound of the copy.
_EXTRA = '''

# ----------------------------------------------------------------------------- CUDA copy (bench/cuda_path_kernel.py)

from .cuda_target import compiler as _compiler

cuda = _compiler()
MAX_MEDIA = {max_media}
BVH_STACK = 2 * BVH_MAX_DEPTH


def _local_empty(shape, dtype=np.float64):
    """A thread's buffer: `cuda.local.array` on CUDA (below); NumPy's in the simulator, which runs Python."""
    return np.empty(shape, dtype)


def _local_zeros(shape, dtype=np.float64):
    return np.zeros(shape, dtype)


def _local_array(zeroed):
    """The CUDA code of `_local_empty` / `_local_zeros`: a local array of the literal shape, inlined into the
    caller before typing (its storage is the calling kernel's frame)."""
    from numba import types
    from numba.core.errors import TypingError

    def typer(shape, dtype=None):
        kinds = shape.types if isinstance(shape, types.BaseTuple) else (shape,)
        if not all(isinstance(kind, types.IntegerLiteral) for kind in kinds):
            raise TypingError(f"a local array needs a literal shape, not {{shape}}")
        dims = tuple(kind.literal_value for kind in kinds)
        element = dtype.dtype if isinstance(dtype, types.NumberClass) else types.float64
        # zeroed by loops over the array's own axes (a reshape calls into Numba's runtime, which PTX lacks)
        if len(dims) == 1:
            def impl(shape, dtype=None):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        array[a] = 0
                return array
        elif len(dims) == 2:
            def impl(shape, dtype=None):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        for b in range(dims[1]):
                            array[a, b] = 0
                return array
        else:
            def impl(shape, dtype=None):
                array = cuda.local.array(dims, element)
                if zeroed:
                    for a in range(dims[0]):
                        for b in range(dims[1]):
                            for c in range(dims[2]):
                                array[a, b, c] = 0
                return array
        return impl

    return typer


if not __import__("importlib").import_module("numba.cuda.core.config").ENABLE_CUDASIM:  # the simulator runs Python
    from numba.cuda.extending import overload as _overload

    _overload(_local_empty, target="cuda", inline="always", prefer_literal=True)(_local_array(False))
    _overload(_local_zeros, target="cuda", inline="always", prefer_literal=True)(_local_array(True))


def render_samples(ks, x0, y0, tile_width, tile_height, sample_begin, sample_end, seed, band, sum_xyz, sum_sq,
                   sum_transparent, sum_light_passes, sum_spectrum):
    """One thread per (pixel, sample) of the tile, samples outermost (neighbouring threads: neighbouring
    pixels): the kernel's `_render_samples` for that one sample, its sums added with atomics."""
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
    cuda.atomic.add(sum_xyz, (row, column, 0), sx)
    cuda.atomic.add(sum_xyz, (row, column, 1), sy)
    cuda.atomic.add(sum_xyz, (row, column, 2), sz)
    cuda.atomic.add(sum_sq, (row, column, 0), qx)
    cuda.atomic.add(sum_sq, (row, column, 1), qy)
    cuda.atomic.add(sum_sq, (row, column, 2), qz)
    cuda.atomic.add(sum_transparent, (row, column), st)
'''


def path_kernel(max_media=MAX_MEDIA, folder=None):
    """The copy's module (imported once per process and bound), its `render_samples` a plain function."""
    folder = Path(folder or Path(tempfile.gettempdir()) / "spectral_volume_cuda_copy")
    return kernel_copy(f"cuda_path_{max_media}", folder, REPLACEMENTS, _EXTRA.format(max_media=max_media))


def tiny_scene():
    """4 × 4 pixels of smoke under a sun and a sky, with a diffuse floor: media, NEE, MIS, surfaces."""
    from tests.support import scenes as s

    medium = s.medium(s.box_grid(), 3.0, albedo=0.8, g=0.3)
    floor = s.parallelogram([-1.5, -1.5, -1.2], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0], reflectance=0.5)
    return s.scene(s.ortho_camera(4, 4, scale=0.8), [medium], [s.sun([0.3, 0.2, 1.0], 3.0), s.environment(0.4)],
                   surfaces=[floor])


def launch_arguments(ks, spp, seed):
    """`render_samples`'s arguments for samples [0, spp) of the whole image: the CPU kernel's
    (`backends.tile_arguments`: the seed as uint64, zeroed accumulators, no light passes, no spectral bins)."""
    from addon.tracer.backends import tile_arguments

    return tile_arguments(ks, 0, (0, spp), (0, 0, ks.camera.width, ks.camera.height), seed)


def state_bytes(module, max_media):
    """Bytes of one thread's path state: each `_new_*` constructor of the copy, run in Python (NumPy arrays of the
    shapes its local arrays have)."""
    constructors = {"Path": module._new_path(max_media), "Coefficients": module._new_coefficients(max_media),
                    "LightSample": module._new_light_sample(), "Tracker": module._new_tracker(max_media),
                    "Fluorescent": module._new_fluorescent(), "Hit": module._new_hit()}
    return {name: sum(array.nbytes for array in state) for name, state in constructors.items()}


def print_state(max_media):
    sizes = state_bytes(path_kernel(max_media), max_media)
    print(f"path state per thread (MAX_MEDIA {max_media}): "
          + ", ".join(f"{name} {size} B" for name, size in sizes.items()) + f"; {sum(sizes.values())} B in all")


def compile_and_assemble(max_media):
    from numba import typeof

    from addon.tracer.kernels import cuda_target
    from addon.tracer.lowering import compile_scene

    start = time.perf_counter()
    cuda_target.compiler()
    print(f"import numba-cuda and patch it: {time.perf_counter() - start:.1f} s")
    module = path_kernel(max_media)
    ks = compile_scene(tiny_scene())
    start = time.perf_counter()
    argument_types = tuple(typeof(value) for value in launch_arguments(ks, 1, 0))
    ptx, _ = cuda_target.compile_ptx(module.render_samples, argument_types)
    seconds = time.perf_counter() - start
    allocates = "NRT_" in ptx or "malloc" in ptx
    saved = Path(tempfile.gettempdir()) / f"cuda_path_{max_media}.ptx"
    saved.write_text(ptx)
    print(f"PTX compiled in {seconds:.0f} s: {saved}", flush=True)
    start = time.perf_counter()
    resources = cuda_target.assemble(ptx)
    assembly = time.perf_counter() - start
    functions = set(re.findall(r"^(?:\.visible\s+)?\.(?:func|entry)\s+(?:\([^)]*\)\s*)?(\w+)", ptx, re.M))
    print(f"render_samples (MAX_MEDIA {max_media}): "
          f"compile {seconds:.1f} s, PTX {len(ptx) / 1024:.0f} KiB, {len(functions)} functions, "
          f"{'ALLOCATES' if allocates else 'no allocation'}; ptxas {assembly:.1f} s: {resources['registers']} "
          f"registers, {resources['stack']} B stack, {resources['spills']} B spilled, {resources['constant']} B "
          f"constant")
    return ptx, resources


def simulated(ks, spp, seed, max_media):
    """The copy's image in the simulator (call under NUMBA_ENABLE_CUDASIM=1): (Σ XYZ, Σ XYZ², Σ transparency)."""
    module = path_kernel(max_media)
    if ks.media.density_scale.shape[0] > max_media:
        raise SystemExit(f"the scene has {ks.media.density_scale.shape[0]} media; the copy holds {max_media}")
    arguments = launch_arguments(ks, spp, seed)
    threads = ks.camera.width * ks.camera.height * spp
    module.cuda.jit(module.render_samples)[(threads + THREADS - 1) // THREADS, THREADS](*arguments)
    return arguments[-5:-2]


def compare(spp, seed, max_media):
    """The simulator's image (a child process) against the CPU kernel's, same scene and seed."""
    from addon.tracer.lowering import compile_scene
    from addon.tracer.render import render_unit

    ks = compile_scene(tiny_scene())
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "simulated.npz"
        command = [sys.executable, "-m", "bench.cuda_path_kernel", "--child", str(out), "--spp", str(spp),
                   "--seed", str(seed), "--max-media", str(max_media)]
        start = time.perf_counter()
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True,
                              env=dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT)))
        if done.returncode:
            raise SystemExit(f"the simulator failed:\n{done.stderr[-4000:]}")
        print(f"simulator: {ks.camera.width}×{ks.camera.height} px, {spp} spp in {time.perf_counter() - start:.0f} s")
        got = np.load(out)
        sim = got["xyz"], got["sq"], got["transparent"]
    start = time.perf_counter()
    cpu = render_unit(ks, 0, (0, spp), (0, 0, ks.camera.width, ks.camera.height), seed)[:3]
    print(f"CPU kernel (compile or cache load included): {time.perf_counter() - start:.0f} s")
    for name, a, b in zip(("Σ XYZ", "Σ XYZ²", "Σ transparency"), sim, cpu):
        scale = max(np.abs(b).max(), 1e-300)
        worst = np.abs(a - b).max() / scale
        print(f"  {name}: largest |simulator − CPU| / largest |CPU| = {worst:.2e} (CPU mean {b.mean():.6g}, "
              f"simulator mean {a.mean():.6g})")
    worst = max(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300) for a, b in zip(sim[:2], cpu[:2]))
    print("agree to float rounding" if worst < 1e-9 else "DISAGREE beyond float rounding")
    return worst


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max-media", type=int, default=MAX_MEDIA)
    parser.add_argument("--simulate", action="store_true", help="compare the simulator with the CPU kernel")
    parser.add_argument("--no-compile", action="store_true", help="skip the PTX compile")
    parser.add_argument("--spp", type=int, default=2)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--child", help=argparse.SUPPRESS)  # the simulator's process: writes its sums here
    args = parser.parse_args(argv)
    if args.child:
        import warnings

        from addon.tracer.lowering import compile_scene

        warnings.filterwarnings("ignore", "overflow encountered", RuntimeWarning)  # the rng's uint64 hash wraps
        xyz, sq, transparent = simulated(compile_scene(tiny_scene()), args.spp, args.seed, args.max_media)
        np.savez(args.child, xyz=xyz, sq=sq, transparent=transparent)
        return
    if not args.no_compile:
        compile_and_assemble(args.max_media)
    print_state(args.max_media)
    if args.simulate:
        compare(args.spp, args.seed, args.max_media)


if __name__ == "__main__":
    main()
