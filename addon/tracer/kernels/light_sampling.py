"""The choice of a light for next-event estimation, by its selection pmf (`KernelScene.light_pmf`).

Plain arithmetic shared by both backends (`shared_math`): one path's scalar in the Numba kernel, arrays of
paths in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..shared_math import shared


@shared
def choose_light(pmf, u):
    """The light drawn from the selection pmf with a uniform u (walking the pmf: the first light whose
    cumulative probability exceeds u, the last one for u beyond all)."""
    chosen = np.int64(u * 0.0)
    for light in range(pmf.shape[0] - 1):
        further = (chosen == light) & (u >= pmf[light])
        u = u - pmf[light] * further
        chosen = chosen + further
    return chosen
