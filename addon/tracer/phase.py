"""Phase functions: Henyey–Greenstein, Rayleigh and isotropic, each with its pdf and its sampler.

Conventions: directions are unit 3-vectors; cos_theta is the cosine between the incoming propagation
direction and the outgoing propagation direction, so g > 0 scatters forward. Pdfs are per steradian.

The kernel-facing functions are plain arithmetic on NumPy ufuncs, without branches on values: the NumPy
backend calls them on arrays of paths, and they compile unchanged inside Numba kernels (`shared_math.shared`)
for one path's scalars. A direction is anything indexable by component, `w[0], w[1], w[2]`:
a (3,) array or a 3-tuple for one path, a (3, m) array for m paths; directions are returned as 3-tuples
(of scalars, or of (m,) arrays).
"""

import numpy as np

from .shared_math import absolute, cbrt, copysign, shared, sqrt

INV_FOUR_PI = 1.0 / (4.0 * np.pi)
# |g| beyond this is refused (`validation.validate`). The lobe of HG is about 1 − |g| radians wide and peaks at
# (1 + |g|) / (4π (1 − |g|)²): at 1 − 1e-6 that is 1.6e11 per steradian, and cosθ near 1 still resolves
# the lobe in float64 (steps of 1.5e-8 rad). Closer to 1 the lobe falls between representable cosines
# and single samples carry absurd weights (at 1 − 1e-10, NaN pixels before the pdf was made stable).
HG_G_LIMIT = 1.0 - 1e-6


@shared
def hg_pdf(g, cos_theta):
    """Henyey–Greenstein phase function (1 − g²) / (4π (1 + g² − 2g cosθ)^{3/2}), per steradian.

    With a = |g| and s = sign(g) the denominator is written (1 − a)² + 2a (1 − s cosθ), a sum of two
    non-negative terms: the textbook form cancels to zero or below near the forward peak as |g| → 1."""
    a = absolute(g)
    one_minus_a = 1.0 - a
    denom = one_minus_a * one_minus_a + 2.0 * a * (1.0 - copysign(1.0, g) * cos_theta)
    return INV_FOUR_PI * one_minus_a * (1.0 + a) / (denom * sqrt(denom))


@shared
def hg_sample_cos(g, u):
    """cosθ distributed as Henyey–Greenstein with anisotropy g, by exact inversion of its CDF (u in [0, 1)).

    The textbook inverse (1 + g² − ((1 − g²) / (1 − g + 2gu))²) / (2g) divides a difference that
    vanishes with g by g, which loses all precision as g → 0 (and is 0/0 at g = 0). With ξ = 2u − 1 the
    same function reads  cosθ = ξ + g (1 − ξ²)(3 + 2gξ − g²) / (2 (1 + gξ)²):  algebraically identical,
    no division by g, equal to the isotropic ξ at g = 0, and exactly ±1 at u = 0, 1. 1 − ξ² is computed as
    4u(1 − u) to avoid cancellation near the poles; the result is clamped to [−1, 1] against rounding."""
    xi = 2.0 * u - 1.0
    d = 1.0 + g * xi
    cos_theta = xi + g * (4.0 * u * (1.0 - u)) * (3.0 + 2.0 * g * xi - g * g) / (2.0 * d * d)
    return np.minimum(np.maximum(cos_theta, -1.0), 1.0)


@shared
def rayleigh_pdf(cos_theta):
    """Rayleigh phase function 3 (1 + cos²θ) / (16π), per steradian."""
    return 3.0 / (16.0 * np.pi) * (1.0 + cos_theta * cos_theta)


@shared
def rayleigh_sample_cos(u):
    """cosθ distributed as Rayleigh scattering, by exact inversion of its CDF (u in [0, 1)).

    The CDF of μ = cosθ is (μ³ + 3μ + 4) / 8; setting it to u gives the depressed cubic μ³ + 3μ − 4ξ = 0
    (ξ = 2u − 1), whose one real root (Cardano) is μ = A − 1/A with A = ∛(2ξ + √(1 + 4ξ²)). The root is
    odd in ξ, so it is evaluated at |ξ| (A ≥ 1, no cancellation inside the cube root) and given ξ's sign."""
    xi = 2.0 * u - 1.0
    a = cbrt(2.0 * absolute(xi) + sqrt(1.0 + 4.0 * xi * xi))
    return np.minimum(copysign(a - 1.0 / a, xi), 1.0)


@shared
def isotropic_pdf(cos_theta):
    """Isotropic phase function 1 / (4π) per steradian (shaped like `cos_theta`)."""
    return cos_theta * 0.0 + INV_FOUR_PI


@shared
def orthonormal_basis(n):
    """Two unit vectors (t, b) with (t, b, n) a right-handed orthonormal frame, for unit `n`.

    Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)): branch-free, using
    copysign for the hemisphere of n's z, and continuous everywhere except across z = 0."""
    x, y, z = n[0], n[1], n[2]
    sign = copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return (1.0 + sign * x * x * a, sign * b, -sign * x), (b, sign + y * y * a, -y)


@shared
def sample_direction(wi, cos_theta, u2):
    """The outgoing direction at angle cos_theta to `wi` (both propagation directions), azimuth 2πu2."""
    t, b = orthonormal_basis(wi)
    sin_theta = sqrt(np.maximum((1.0 - cos_theta) * (1.0 + cos_theta), 0.0))
    phi = 2.0 * np.pi * u2
    st, sb = sin_theta * np.cos(phi), sin_theta * np.sin(phi)
    return (
        st * t[0] + sb * b[0] + cos_theta * wi[0],
        st * t[1] + sb * b[1] + cos_theta * wi[1],
        st * t[2] + sb * b[2] + cos_theta * wi[2],
    )


