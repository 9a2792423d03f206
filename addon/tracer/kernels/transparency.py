"""Film ▸ Transparent and holdouts: how much of the background a camera path would have seen, its
transparency; a pixel's alpha is 1 − its mean transparency, and its colour is premultiplied (no background).

A camera path adds to its transparency when, before any real scattering or surface event, it escapes to the
background (the infinite lights: environment, sky, envmaps, a sun's disc) with Film ▸ Transparent on, or
reaches a holdout surface (Film ▸ Transparent on; off, a holdout is black and opaque, as in Cycles). It adds
its throughput there, as Cycles adds `average(throughput)`: the arithmetic mean of its R, G and B throughputs,
so a grey medium of transmittance T gives alpha 1 − T.

The spectral equivalent chosen here is the luminance-weighted mean: ∫ T(λ) ȳ(λ) dλ / ∫ ȳ(λ) dλ over the
camera's wavelengths, T being the path's throughput (its transmittance estimate) per wavelength. Why not the
plain mean over the path's wavelengths: that would weigh wavelengths by the hero's sampling pdf, a choice of
estimator (and of the scene's lights in "light" mode), so alpha would change with it; and a uniform mean over
the wavelength range weighs the deep red and violet, which the eye hardly sees, as much as green. ȳ is what a
channel average approximates: Rec.709's R + G + B of an equal-energy white is mostly its luminance. Compositing
this alpha "over" a plate is then exact in luminance for a white plate behind a chromatic medium, and exact in
every channel for a grey one. The estimate, a camera wavelength's throughput × `transparency_weight`, summed over
the path's wavelengths, is unbiased per band: a band's pdf integrates to 1 over its part of the spectrum, so
the bands' means add up to the whole (as their XYZ do).

Shared by both backends (`shared_math`). Part of the kernel cache's key (`numba_cache.KERNEL_SOURCES`).
"""

from ..shared_math import select, shared
from .lookups import on_grid, table_at


@shared
def transparency_weight(ks, lam, pdf, n):
    """The weight of camera wavelength `lam` (drawn with pdf `pdf`, one of the path's `n`) in the path's
    transparency: ȳ(λ) / (pdf · n · Y of a unit equal-energy radiance); 0 where the pdf is 0."""
    return select(pdf > 0.0, table_at(ks.wavelengths.xyz_weights, 1, on_grid(lam)) / (pdf * n * ks.camera.white_y),
                  0.0)
