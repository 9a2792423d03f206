"""Run the numerically sensitive tests as if on other CPUs, so that a test that holds only on the CPU it
was written on fails here, not on a stranger's machine.

Three libraries pick code by the CPU they run on, and each rounds the last bits its own way (where OpenBLAS
cannot run another family's kernels on the host, which crash on some virtual AMD hosts, its own are used,
and the run says so):
- Numba compiles the kernels for the host CPU (`NUMBA_CPU_NAME` overrides it);
- NumPy dispatches `exp`, `log`, `cbrt`, … to AVX2 / AVX-512 implementations (`NPY_DISABLE_CPU_FEATURES`
  switches its dispatched targets off);
- OpenBLAS picks kernels by CPU family (`OPENBLAS_CORETYPE` overrides it).
A path tracer amplifies such differences: one path that takes another branch changes a pixel. Every
variant below runs `TEST_PATHS` (less `LEFT_OUT`) with all three overridden; a variant whose instructions the
host lacks is left out, and says so.

    python tools/cpu_variants.py [--only NAME ...] [pytest arguments ...]
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# The tests whose results come from rendering or from fits to rendered data.
TEST_PATHS = ("tests/tracer", "tests/demos", "tests/cycles_emulation")
# Less the CUDA target's (about 85 s a run): they check the GPU build (PTX) and the simulator, and what in them
# depends on the host's code paths (a kernel against another at one seed, to 1e-12) is the lock-step test's
# (tests/tracer/kernels/test_backends.py), which every variant runs.
LEFT_OUT = ("tests/tracer/kernels/test_cuda_backend.py", "tests/tracer/kernels/test_cuda_shared.py")
# NumPy's dispatchable x86-64 targets above its baseline (unknown names are ignored by NumPy).
NUMPY_X86_TARGETS = ("X86_V3", "X86_V4", "AVX512_ICL", "AVX512_SPR")

VARIANTS = {
    # Any x86-64 CPU: no FMA, no AVX in the kernels, NumPy's and OpenBLAS's baseline code.
    "generic": ({"NUMBA_CPU_NAME": "generic", "OPENBLAS_CORETYPE": "Prescott",
                 "NPY_DISABLE_CPU_FEATURES": " ".join(NUMPY_X86_TARGETS)}, ()),
    # An AVX2 + FMA CPU without AVX-512 (runs only where the host has AVX2 and FMA).
    "haswell": ({"NUMBA_CPU_NAME": "haswell", "OPENBLAS_CORETYPE": "Haswell",
                 "NPY_DISABLE_CPU_FEATURES": " ".join(NUMPY_X86_TARGETS[1:])}, ("avx2", "fma")),
}


def host_flags() -> set[str]:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


# A matrix product that OpenBLAS 0.3.34's Haswell (and Zen) kernels end in a segmentation fault on some
# virtual AMD EPYC hosts (any m ≥ 100 rows by 471, times 471 × 3): a fault of that library on that host,
# not of the code under test.
OPENBLAS_PROBE = "import numpy as np; np.dot(np.ones((256, 471)), np.ones((471, 3)))"


def openblas_works(coretype: str) -> bool:
    """Whether OpenBLAS, told to use `coretype`'s kernels, multiplies matrices on this host without crashing."""
    probe = subprocess.run([sys.executable, "-c", OPENBLAS_PROBE], env={**os.environ, "OPENBLAS_CORETYPE": coretype},
                           capture_output=True, timeout=120)
    return probe.returncode == 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=sorted(VARIANTS), help="run only these variants")
    args, pytest_args = parser.parse_known_args(argv)
    if os.uname().machine not in ("x86_64", "AMD64"):
        print(f"cpu_variants: the variants emulate x86-64 CPUs; nothing to do on {os.uname().machine}")
        return 0
    flags, failed = host_flags(), []
    for name in args.only or VARIANTS:
        environment, needs = VARIANTS[name]
        missing = [flag for flag in needs if flag not in flags]
        if missing:
            print(f"cpu_variants: {name}: left out, this CPU lacks {', '.join(missing)}")
            continue
        coretype = environment.get("OPENBLAS_CORETYPE")
        if coretype is not None and not openblas_works(coretype):
            environment = {key: value for key, value in environment.items() if key != "OPENBLAS_CORETYPE"}
            print(f"cpu_variants: {name}: OpenBLAS's {coretype} kernels crash on this host (a 256×471 by 471×3 "
                  "product): its own kernels are used instead")
        print(f"cpu_variants: {name}: {' '.join(f'{k}={v!r}' for k, v in environment.items())}", flush=True)
        start = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", *TEST_PATHS,
                               *(f"--ignore={path}" for path in LEFT_OUT), *pytest_args], cwd=REPO,
                              env={**os.environ, **environment})
        print(f"cpu_variants: {name}: {'passed' if done.returncode == 0 else 'FAILED'} in "
              f"{time.monotonic() - start:.0f} s", flush=True)
        if done.returncode != 0:
            failed.append(name)
    if failed:
        print(f"cpu_variants: failed under {', '.join(failed)}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
