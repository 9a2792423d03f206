"""Run code in a child process whose NumPy computes elementary functions with the C library, as
Numba's kernels do.

NumPy dispatches `cbrt`, `exp`, `log`, `power`, … to its own SIMD implementations when the CPU has
AVX2 or AVX-512 (`np.show_runtime()` lists them under "found"). Those round differently from the C
library's functions in the last bit (on an AVX-512 machine, `np.cbrt` differs from `math.cbrt` for about
half of all inputs), while Numba's kernels call the C library. Two backends that trace the same paths
with the same random numbers then agree bit for bit only where NumPy uses the C library too: with its
dispatched SIMD targets switched off (`NPY_DISABLE_CPU_FEATURES`, read when NumPy is imported, hence a
child process). The baseline targets cannot be switched off and hold no such functions on x86-64.
"""

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def environment() -> dict:
    """This process's environment with every NumPy SIMD target that this build can dispatch to switched
    off (names the CPU lacks are ignored by NumPy)."""
    from numpy._core._multiarray_umath import __cpu_dispatch__

    return {**os.environ, "PYTHONPATH": str(REPO), "NPY_DISABLE_CPU_FEATURES": " ".join(__cpu_dispatch__)}


def run(code: str, *args: str, timeout: float = 600) -> str:
    """Run Python `code` (with `args` as sys.argv[1:]) in the repository, NumPy using the C library's
    elementary functions; its standard output, or AssertionError with its standard error if it fails."""
    done = subprocess.run([sys.executable, "-c", code, *args], cwd=REPO, env=environment(), capture_output=True, text=True,
                          timeout=timeout)
    assert done.returncode == 0, done.stderr
    return done.stdout
