"""The spectral film's bins (`Film.spectrum`, the spectral EXR): which bin a camera wavelength adds to, and how much.

The bins are uniform, their edges `ks.wavelengths.spectrum_edges` (B + 1 values in nm, `lowering`; none when the
scene keeps no spectrum). A camera wavelength λ drawn with pdf p, one of a path's n, adds L(λ) / (p · n · w) to the
bin holding it, w being the bins' width: the estimate `_path_xyz` weighs by the XYZ weights, weighed here by a box of
height 1/w. A bin's mean over samples is then the mean spectral radiance over the bin, ∫_bin L dλ / w (per nm, as
the layout of Fichet et al. 2021 stores it). Each band is its own estimator: its pdf integrates to 1 over its part of
the spectrum, so the bands' means add up to the whole, and a bin outside a band's range gets nothing from it.

Shared by both backends (`shared_math`). Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

from ..shared_math import floor, select, shared


@shared
def spectrum_bin(edges, lam):
    """The index of the bin holding `lam` among the uniform bins of `edges` (at least two), as a float; -1 outside
    them all."""
    index = floor((lam - edges[0]) / (edges[1] - edges[0]))
    return select((index >= 0.0) & (index < edges.shape[0] - 1), index, -1.0)


@shared
def spectrum_weight(edges, radiance, pdf, n):
    """A camera wavelength's addition to its bin: `radiance` / (`pdf` · `n` · the bins' width); 0 where the pdf
    is 0."""
    return select(pdf > 0.0, radiance / (pdf * n * (edges[1] - edges[0])), 0.0)
