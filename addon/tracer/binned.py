"""The arithmetic of a binned wavelength pdf that the kernels compile: drawing from it and its density.

A binned pdf (`sampling.BinnedDistribution` builds them) is constant over each 1 nm bin [GRID[i], GRID[i+1])
of the shared grid (580 bins from 250 nm), stored as `cdf` (581 values, 0 … 1) and `bin_pdf` (580 values,
density per nm):

    sample_binned(cdf, u) -> lam                 u in [0, 1)
    pdf_binned(bin_pdf, lam) -> pdf              0 outside the grid
    stratified_binned(cdf, bin_pdf, u, n) -> (lams, pdfs)

They are plain functions of arrays (the NumPy backend calls them on arrays of paths) and compile unchanged
inside Numba kernels (`shared_math.shared`), where they are called with one path's scalars; except
`stratified_binned`, which allocates its result and serves the NumPy side only
(`sampling.stratified_wavelengths`). This module is part of the kernel cache's key
(`numba_cache.KERNEL_SOURCES`); the distributions themselves are not.
"""

import numpy as np

from .shared_math import floor, shared
from .wavelengths import LAMBDA_MIN

# u is clamped into [0, 1) (a generator's u = 1 would land past the last non-empty bin), and the
# position inside a bin stays below 1 by more than the float spacing at 830 nm (~1e-13), so a sample
# never rounds up onto the next bin's left edge (which may have pdf 0).
_U_MAX = 1.0 - 2.0**-53
_T_MAX = 1.0 - 2.0**-30


@shared
def sample_binned(cdf, u):
    """Wavelength (nm) with the piecewise-constant density of `cdf` (581 values on GRID), by inversion.

    `cdf` rises from 0 to exactly 1 (as `BinnedDistribution` makes it); `u` in [0, 1) is a scalar or an
    array of paths. Bins of zero weight are never returned."""
    u = np.minimum(np.maximum(u, 0.0), _U_MAX)
    i = np.searchsorted(cdf, u, side="right") - 1
    # A no-op for such a cdf; keeps Numba (which does not check bounds) inside the arrays for any other.
    i = np.minimum(np.maximum(i, 0), cdf.size - 2)
    c0 = cdf[i]
    t = (u - c0) / np.maximum(cdf[i + 1] - c0, 1e-300)
    return LAMBDA_MIN + i + np.minimum(np.maximum(t, 0.0), _T_MAX)


@shared
def pdf_binned(bin_pdf, lam):
    """Density per nm at wavelength(s) `lam` of the bins `bin_pdf` (580 values on GRID); 0 off the grid."""
    x = lam - LAMBDA_MIN
    i = np.int64(np.minimum(np.maximum(floor(x), 0.0), bin_pdf.size - 1.0))
    return bin_pdf[i] * ((x >= 0.0) & (x < bin_pdf.size))


@shared
def linear_over_binned(values, lam):
    """At wavelength(s) `lam` in a bin of positive mean: the linear interpolation of `values` (a spectrum
    on GRID) ÷ the bin's mean. `sample_binned` draws from the spectrum's bins with a constant density in
    each bin; this weight turns such a draw into one from the interpolated spectrum itself (it differs from
    1 only in bins where the spectrum changes, at the edges of a window, say)."""
    x = lam - LAMBDA_MIN
    i = np.int64(np.minimum(np.maximum(floor(x), 0.0), values.size - 2.0))
    t = x - i
    low, high = values[i], values[i + 1]
    return (low + (high - low) * t) / (0.5 * (low + high))


def stratified_binned(cdf, bin_pdf, u, n):
    """Hero wavelength and n−1 rotated companions: u_i = (u + i/n) mod 1, λ_i = sample_binned(cdf, u_i).

    Returns (lams, pdfs), each of shape (n,) + shape(u): for one path (Numba) two arrays of n values,
    for m paths (NumPy) two (n, m) arrays. Each u_i is uniform, so each λ_i is marginally distributed
    with density pdf(λ_i): the spectral estimator averages f(λ_i) / pdf(λ_i) over i (or weights them
    by spectral MIS); the n draws are stratified in u, which lowers the colour noise."""
    lams = np.empty((n,) + np.shape(u))
    pdfs = np.empty((n,) + np.shape(u))
    for i in range(n):
        lam = sample_binned(cdf, (u + i / n) % 1.0)
        lams[i] = lam
        pdfs[i] = pdf_binned(bin_pdf, lam)
    return lams, pdfs
