"""The CUDA target's compile of the shared leaf functions (issue 32): for each module, how many of its shared
functions compile to PTX (for compute capability 9.0, no GPU needed) and in how many seconds, and the PTX's
size; then the batch kernels of tests/support/cuda_kernels.py as whole kernels, assembled by ptxas (nvJitLink)
for their registers, stack, spills and constant bytes. Figures in docs/architecture.md
("GPU backend").

    python -m bench.cuda_compile
"""

import time
from collections import defaultdict

from addon.tracer.kernels import cuda_target


def main():
    start = time.perf_counter()
    cuda_target.compiler()
    print(f"import numba-cuda and patch it: {time.perf_counter() - start:.1f} s")
    from tests.support import cuda_kernels, cuda_shared

    by_module = defaultdict(lambda: [0, 0, 0.0, 0])  # compiled, failed, seconds, PTX bytes
    for function, argument_types in cuda_shared.signatures().items():
        row = by_module[function.__module__.removeprefix("addon.tracer.")]
        start = time.perf_counter()
        try:
            ptx, _ = cuda_target.compile_ptx(function, argument_types, device=True)
        except Exception as error:  # noqa: BLE001 (reported, the rest still measured)
            row[1] += 1
            print(f"  {function.__qualname__}: {type(error).__name__}: {str(error).splitlines()[0]}")
        else:
            row[0] += 1
            row[3] += len(ptx)
        row[2] += time.perf_counter() - start
    print(f"{'module':<32} {'compiled':>8} {'failed':>6} {'seconds':>8} {'PTX KiB':>8}")
    for name, (compiled, failed, seconds, size) in by_module.items():
        print(f"{name:<32} {compiled:>8} {failed:>6} {seconds:>8.2f} {size / 1024:>8.0f}")
    totals = [sum(row[k] for row in by_module.values()) for k in range(4)]
    print(f"{'all':<32} {totals[0]:>8} {totals[1]:>6} {totals[2]:>8.2f} {totals[3] / 1024:>8.0f}")
    print("(a function taking the kernel scene declares each field of its 76 arrays as a parameter under a name "
          "mangled from the scene's whole type, 3 kB long: most of those KiB)")

    ks, batch = cuda_kernels.scene(), cuda_kernels.inputs()
    for kernel in cuda_kernels.KERNELS:
        start = time.perf_counter()
        ptx, _ = cuda_target.compile_ptx(kernel, cuda_kernels.argument_types(kernel, ks, batch))
        seconds = time.perf_counter() - start
        start = time.perf_counter()
        resources = cuda_target.assemble(ptx)
        assembly = time.perf_counter() - start
        print(f"{kernel.__name__:<14} compile {seconds:5.2f} s, PTX {len(ptx) / 1024:5.0f} KiB; "
              f"ptxas {assembly:5.2f} s: "
              f"{resources['registers']} registers, {resources['stack']} B stack, {resources['spills']} B spilled, "
              f"{resources['constant']} B constant")


if __name__ == "__main__":
    main()
