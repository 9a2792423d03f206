"""The CUDA backend's kernel (`addon/tracer/kernels/cuda_backend.py`, `render_samples`: the Numba kernel's own path
code, one thread per pixel-sample) compiled without a GPU (issue 32).

It prints the seconds of numba-cuda's front end (bytecode to typed IR, everything inlined into `_render_samples`,
then LLVM IR) and of NVVM at each optimisation level asked for (LLVM IR to PTX), what ptxas (nvJitLink,
`cuda_target.assemble`) gives each PTX (registers, stack frame, spills, constant bytes), and the bytes of one
thread's path state. Figures and what they mean: docs/architecture.md, "GPU backend". The simulator's check of
the kernel against the CPU's is a test (tests/tracer/kernels/test_cuda_backend.py).

    python -m bench.cuda_path_kernel [--opt 3 0] [--inline-all]

`--inline-all` measures the other way to compile the kernel: every `shared_inline` function inlined into its
caller before typing, as on the CPU, instead of compiled as a device function, typed once and called
(`shared_math`). It sets their `targetoptions` for this process only, which would also change a CPU kernel
compiled in it.
"""

import argparse
import re
import tempfile
import time
from pathlib import Path

from addon.tracer.backends import tile_arguments
from addon.tracer.builders import environment, perspective, scene
from addon.tracer.kernels import cuda_backend, cuda_target, numba_backend
from addon.tracer.kernels.layout import MAX_MEDIA
from addon.tracer.lowering import compile_scene


def state_bytes() -> dict:
    """Bytes of one thread's path state: each `_new_*` constructor run in Python (NumPy arrays of the shapes its
    local arrays have on CUDA)."""
    nb = numba_backend
    constructors = {"Path": nb._new_path(MAX_MEDIA), "Coefficients": nb._new_coefficients(MAX_MEDIA),
                    "LightSample": nb._new_light_sample(), "Tracker": nb._new_tracker(MAX_MEDIA),
                    "Fluorescent": nb._new_fluorescent(), "Hit": nb._new_hit()}
    return {name: sum(array.nbytes for array in state) for name, state in constructors.items()}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--opt", type=int, nargs="+", default=[3, 0], help="NVVM optimisation levels (3, 0)")
    parser.add_argument("--inline-all", action="store_true",
                        help="inline every shared_inline function before typing (see above)")
    args = parser.parse_args(argv)
    if args.inline_all:
        called = [function for function in vars(numba_backend).values()
                  if callable(getattr(function, "targetoptions", {}).get("inline"))]
        for function in called:
            function.targetoptions = {"inline": "always"}
        print(f"{len(called)} shared_inline functions inlined before typing", flush=True)
    from numba.cuda.compiler import _compile_pyfunc_with_fixup
    from numba.cuda.cudadrv import nvrtc, nvvm

    start = time.perf_counter()
    cuda_backend.kernel()
    print(f"import numba-cuda and patch it: {time.perf_counter() - start:.1f} s", flush=True)
    sizes = state_bytes()
    print(f"path state per thread (MAX_MEDIA {MAX_MEDIA}): "
          + ", ".join(f"{name} {size} B" for name, size in sizes.items()) + f"; {sum(sizes.values())} B in all")
    empty = scene(perspective((0.0, -1.0, 0.0), (0.0, 0.0, 0.0), 1, 1, 40.0), (), (environment(),), spp=1)
    kinds = cuda_backend.kernel_types(tile_arguments(compile_scene(empty), 0, (0, 1), (0, 0, 1, 1), 0))
    cc = cuda_target.COMPUTE_CAPABILITY
    start = time.perf_counter()
    library, _ = _compile_pyfunc_with_fixup(cuda_backend.render_samples, kinds, device=False, cc=cc, abi="numba")
    irs = library.llvm_strs
    print(f"front end (typing, lowering to LLVM IR): {time.perf_counter() - start:.0f} s, "
          f"{sum(map(len, irs)) / 1024:.0f} KiB of LLVM IR", flush=True)
    for level in args.opt:
        start = time.perf_counter()
        ptx = nvvm.compile_ir(list(irs), opt=level, arch=nvrtc.get_arch_option(*cc)).decode().strip("\x00").strip()
        seconds = time.perf_counter() - start
        saved = Path(tempfile.gettempdir()) / f"cuda_render_samples_opt{level}.ptx"
        saved.write_text(ptx)
        start = time.perf_counter()
        resources = cuda_target.assemble(ptx)
        assembly = time.perf_counter() - start
        functions = set(re.findall(r"^(?:\.visible\s+)?\.(?:func|entry)\s+(?:\([^)]*\)\s*)?(\w+)", ptx, re.M))
        allocates = "NRT_" in ptx or "malloc" in ptx
        print(f"NVVM -opt={level}: {seconds:.0f} s, PTX {len(ptx) / 1024:.0f} KiB ({saved}), {len(functions)} "
              f"functions, {'ALLOCATES' if allocates else 'no allocation'}; ptxas {assembly:.1f} s: "
              f"{resources['registers']} registers, {resources['stack']} B stack, {resources['spills']} B spilled, "
              f"{resources['constant']} B constant", flush=True)


if __name__ == "__main__":
    main()
