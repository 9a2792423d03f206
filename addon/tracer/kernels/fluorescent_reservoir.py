"""How a path picks the tentative collision where its fluorescent sub-path starts: three weighted
reservoirs, each guided differently, combined by one-sample MIS (a mixture of their choices).

Every tentative collision i offers its fluorescent source, weight w_i (the collision estimator of the
source, `_offer_fluorescence`), to three one-slot reservoirs; reservoir k keeps it with probability
w_i g_k(τ_i) / W_k, where W_k = Σ_j w_j g_k(τ_j) so far and τ_i is the dyes' optical depth (at a typical
excitation wavelength, `KernelScene.fluorescence.excitation_mean`) from the start of the path's segment to
the collision:

- g₀ = 1: in proportion to the source alone (uniform through a uniform dye);
- g₁ = exp(−τ): towards the segment's start (the face of a dense dye the ray entered, lit from there);
- g₂ = exp(+τ): towards its end (the far face, lit from behind); the constant exp(−τ_total) that would
  make it the optical depth to the end cancels out of the reservoir's choice, so it is not needed.

When the path ends, one reservoir is chosen with probability `SHARES[k]`; its collision i was drawn from
the mixture p(i) = w_i Σ_k SHARES[k] g_k(τ_i) / W_k, known exactly at that point, and the sub-path's
radiance is weighted by w_i / p(i) (`mixture_weight`). That is unbiased whatever the guides (each is
positive wherever a source is), and no worse than 1 / SHARES[0] times the unguided reservoir's weight.
In a dense dye the absorbed light, and so the fluorescence, lies within a few optical depths of the lit
faces: the unguided reservoir spends most sub-paths deep inside, where they find no light.

Plain arithmetic shared by both backends (`shared_math.shared`): scalars in the Numba kernel, arrays of
paths in the NumPy backend. Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

import numpy as np

from ..shared_math import exp, shared

# Probabilities of taking the unguided, the front-guided and the back-guided reservoir's collision.
SHARES = (0.5, 0.25, 0.25)
RESERVOIRS = len(SHARES)
# exp(+τ) is capped here (float64 holds exp(709)); beyond it the back guide is flat, still unbiased.
DEPTH_LIMIT = 500.0


@shared
def front_guide(tau):
    """g₁(τ) = exp(−τ)."""
    return exp(-tau)


@shared
def back_guide(tau):
    """g₂(τ) = exp(min(τ, DEPTH_LIMIT))."""
    return exp(np.minimum(tau, DEPTH_LIMIT))


@shared
def chosen_reservoir(u):
    """The reservoir (0, 1 or 2) whose collision the sub-path starts from, for a uniform u in [0, 1)."""
    return (u >= SHARES[0]) * 1 + (u >= SHARES[0] + SHARES[1]) * 1


@shared
def mixture_weight(tau, total0, total1, total2):
    """w_i / p(i) for the collision at dye depth τ chosen from reservoirs with totals W₀, W₁, W₂."""
    return 1.0 / (SHARES[0] / total0 + SHARES[1] * front_guide(tau) / total1 + SHARES[2] * back_guide(tau) / total2)
