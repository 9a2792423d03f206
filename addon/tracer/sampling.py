"""Wavelength sampling: every pdf over λ the tracer draws wavelengths from, and the draws themselves.

For the kernels every sampler is a `BinnedDistribution`: a density that is constant over each 1 nm bin
[GRID[i], GRID[i+1]) of the shared grid (580 bins from 250 nm), stored as `cdf` (581 values, 0 … 1) and
`bin_pdf` (580 values, density per nm), which the kernels draw from with `binned.sample_binned` (the
kernel-facing functions live in `binned`, so that changing a distribution here does not recompile the kernel).

The seminar report's samplers (§3.2) are here too: uniform over 380–700 nm, D65 by rejection sampling
(`d65_rejection`, with its pdf) and the UV-extended range; plus mixtures of spectra (with a defensive share), the
visible-range importance density, the colour importance (the default: visible density mixed with the
colour matching functions' norm), and the split of a range into bands for per-wavelength passes.
"""

import numpy as np

from .binned import pdf_binned, sample_binned, stratified_binned
from .errors import SpectralError
from .spectra import Spectrum, illuminant
from .wavelengths import (
    GRID,
    LAMBDA_MAX,
    LAMBDA_MIN,
    REPORT_VISIBLE_MAX,
    REPORT_VISIBLE_MIN,
    UV_MAX,
    VISIBLE_MAX,
    VISIBLE_MIN,
)

BINS = GRID.size - 1

def _check_range(lo, hi):
    """(lo, hi) as whole nanometres within the grid, lo < hi."""
    try:
        lo_i, hi_i = int(lo), int(hi)
    except (TypeError, ValueError, OverflowError):
        raise SpectralError(f"wavelength range {lo!r}–{hi!r} nm must be two numbers") from None
    if lo_i != lo or hi_i != hi:
        raise SpectralError(f"wavelength range {lo:g}–{hi:g} nm must start and end on whole nanometres")
    if not (LAMBDA_MIN <= lo_i < hi_i <= LAMBDA_MAX):
        raise SpectralError(
            f"wavelength range {lo_i}–{hi_i} nm must be increasing and lie within {LAMBDA_MIN:g}–{LAMBDA_MAX:g} nm"
        )
    return lo_i, hi_i


def _bin_weights(spectrum: Spectrum) -> np.ndarray:
    """Integral of the (piecewise-linear) spectrum over each 1 nm bin: the mean of its two end values."""
    return 0.5 * (spectrum.values[:-1] + spectrum.values[1:])


class BinnedDistribution:
    """A piecewise-constant pdf over the 1 nm bins of GRID, zero outside [lo, hi) nm.

    `weights` holds one number per bin (580); only the bins inside [lo, hi) count (non-negative), and
    the pdf is proportional to them. `what` names the weights in the error raised when they are all zero.
    """

    def __init__(self, weights, lo, hi, what="wavelength weights"):
        self.lo, self.hi = _check_range(lo, hi)
        weights = np.asarray(weights, dtype=np.float64)
        if weights.shape != (BINS,):
            raise SpectralError(f"{what}: need {BINS} values, one per 1 nm bin, got shape {weights.shape}")
        inside = np.zeros(BINS)
        start, stop = self.lo - int(LAMBDA_MIN), self.hi - int(LAMBDA_MIN)
        inside[start:stop] = weights[start:stop]
        if not np.all(np.isfinite(inside)) or np.any(inside < 0):
            raise SpectralError(f"{what} must be finite and non-negative in {self.lo}–{self.hi} nm")
        cumulative = np.cumsum(inside)
        total = cumulative[-1]
        if not total > 0:
            raise SpectralError(f"{what} are zero in {self.lo}–{self.hi} nm")
        self.bin_pdf = inside / total
        self.cdf = np.concatenate(([0.0], cumulative / total))
        for array in (self.bin_pdf, self.cdf):
            array.flags.writeable = False

    def sample(self, u):
        """Wavelength(s) in nm for uniform number(s) `u` in [0, 1)."""
        return sample_binned(self.cdf, np.asarray(u, dtype=np.float64))

    def pdf(self, lam):
        """Density per nm at wavelength(s) `lam`."""
        return pdf_binned(self.bin_pdf, np.asarray(lam, dtype=np.float64))


def uniform(lo=REPORT_VISIBLE_MIN, hi=REPORT_VISIBLE_MAX) -> BinnedDistribution:
    """Uniform over [lo, hi) nm; the default is the report's visible range (sampleWavelength)."""
    return BinnedDistribution(np.ones(BINS), lo, hi)


def uv_extended(lo=LAMBDA_MIN, hi=REPORT_VISIBLE_MAX) -> BinnedDistribution:
    """The report's sampleWavelengthUV: uniform over a range reaching below 380 nm into the UV."""
    lo, hi = _check_range(lo, hi)
    if not lo < UV_MAX:
        raise SpectralError(f"a UV-extended wavelength range must start below {UV_MAX:g} nm, got {lo} nm")
    return uniform(lo, hi)


def from_spectrum(spectrum: Spectrum, lo=VISIBLE_MIN, hi=VISIBLE_MAX, name="the spectrum") -> BinnedDistribution:
    """Proportional to `spectrum` over [lo, hi) nm (bin weight = mean of the bin's two end values)."""
    return BinnedDistribution(_bin_weights(spectrum), lo, hi, what=name)


def _composite_weights(pairs, bins: slice) -> np.ndarray:
    """Σ_k w_k p_k per bin, each spectrum's bins normalised to unit sum inside `bins` (zero ones add nothing)."""
    mixture = np.zeros(BINS)
    for spectrum, weight in pairs:
        weight = float(weight)
        if not (np.isfinite(weight) and weight >= 0):
            raise SpectralError(f"a spectrum's mixture weight must be finite and non-negative, got {weight}")
        shape = _bin_weights(spectrum)[bins]
        if np.any(shape < 0):
            raise SpectralError("spectra must be non-negative to be sampled")
        if shape.sum() > 0:
            mixture[bins] += weight * shape / shape.sum()
    return mixture


def defensive_composite(pairs, defensive: BinnedDistribution, share: float) -> BinnedDistribution:
    """`share` of the `defensive` density plus 1 − share of the mixture Σ_k w_k p_k / Σ_k w_k of the
    spectra in `pairs` of (Spectrum, weight) over the same range, where p_k is spectrum k normalised to unit
    area there (only its shape counts) and w_k its weight; all of the defensive density where the spectra
    are zero over the range. With a defensive density that is positive wherever light can reach the
    camera, so is the mixture: it is unbiased for any scene."""
    if not 0.0 < share <= 1.0:
        raise SpectralError(f"a defensive share must lie in (0, 1], got {share}")
    composite = _composite_weights(pairs, slice(defensive.lo - int(LAMBDA_MIN), defensive.hi - int(LAMBDA_MIN)))
    total = composite.sum()
    mixture = (1.0 - share) * composite / total + share * defensive.bin_pdf if total > 0 else defensive.bin_pdf
    return BinnedDistribution(mixture, defensive.lo, defensive.hi, what="the defensive composite")


# pbrt-v4's visible-wavelength importance density is proportional to 1 / cosh²(A (λ − C)).
_VISIBLE_A = 0.0072
_VISIBLE_C = 538.0


def visible_distribution(lo=VISIBLE_MIN, hi=VISIBLE_MAX) -> BinnedDistribution:
    """Importance for the visible range: 1/cosh²(0.0072 (λ − 538)) (pbrt-v4's published shape), with each
    bin weighted by its exact integral tanh(A (λ − C)) / A between the bin's edges."""
    antiderivative = np.tanh(_VISIBLE_A * (GRID - _VISIBLE_C)) / _VISIBLE_A
    return BinnedDistribution(np.diff(antiderivative), lo, hi, what="the visible importance density")


def colour_distribution(xyz_weights, lo=VISIBLE_MIN, hi=VISIBLE_MAX) -> BinnedDistribution:
    """Importance for colour: half the visible density, half ∝ ‖(x̄, ȳ, z̄)(λ)‖ of the colour matching
    functions `xyz_weights` (3 × GRID.size). The visible half keeps luminance noise where it was; the
    norm half follows z̄'s tall blue lobe, which the visible density undersamples, so the X, Y and Z
    noise is balanced (about half the summed variance of "visible" alone on a white cloud)."""
    weights = np.asarray(xyz_weights, dtype=np.float64)
    if weights.shape != (3, GRID.size):
        raise SpectralError(f"colour matching weights need shape (3, {GRID.size}), got {weights.shape}")
    visible = visible_distribution(lo, hi).bin_pdf
    cmf_norm = BinnedDistribution(np.linalg.norm(0.5 * (weights[:, :-1] + weights[:, 1:]), axis=0), lo, hi,
                                  what="the colour matching functions").bin_pdf
    return BinnedDistribution(0.5 * visible + 0.5 * cmf_norm, lo, hi, what="the colour importance density")


def stratified_wavelengths(dist: BinnedDistribution, u, n=4):
    """Hero wavelength and n−1 rotated companions drawn from `dist` (see `stratified_binned`)."""
    if int(n) != n or n < 1:
        raise SpectralError(f"wavelengths per path must be a positive whole number, got {n}")
    return stratified_binned(dist.cdf, dist.bin_pdf, np.asarray(u, dtype=np.float64), int(n))


def band_ranges(lo, hi, bands):
    """Split [lo, hi] nm into `bands` contiguous whole-nm bands whose widths differ by at most 1 nm."""
    lo, hi = _check_range(lo, hi)
    if int(bands) != bands or not 1 <= bands <= hi - lo:
        raise SpectralError(f"{lo}–{hi} nm can be split into 1 to {hi - lo} bands of whole nanometres, not {bands}")
    edges = [lo + (k * (hi - lo)) // int(bands) for k in range(int(bands) + 1)]
    return list(zip(edges[:-1], edges[1:]))


# --- Rejection sampling, as in the report's sampleWavelengthD65 ---------------------------------------


def rejection_sample(spectrum: Spectrum, n, rng: np.random.Generator, lo, hi, name="the spectrum") -> np.ndarray:
    """`n` wavelengths with density ∝ `spectrum` on [lo, hi) nm: propose λ uniformly, accept with
    probability S(λ) / max S. Its pdf is `rejection_pdf`."""
    lo, hi = _check_range(lo, hi)
    knots = spectrum.values[lo - int(LAMBDA_MIN) : hi - int(LAMBDA_MIN) + 1]
    peak = knots.max()  # a piecewise-linear spectrum peaks at a grid point
    if np.any(knots < 0):
        raise SpectralError(f"{name} must be non-negative in {lo}–{hi} nm to be sampled")
    if not peak > 0:
        raise SpectralError(f"{name} is zero in {lo}–{hi} nm")
    acceptance = np.trapezoid(knots) / (peak * (hi - lo))
    out = np.empty(int(n))
    filled = 0
    while filled < out.size:
        proposals = rng.uniform(lo, hi, size=int((out.size - filled) / acceptance * 1.1) + 16)
        accepted = proposals[rng.uniform(0.0, peak, size=proposals.size) < spectrum(proposals)]
        take = min(accepted.size, out.size - filled)
        out[filled : filled + take] = accepted[:take]
        filled += take
    return out


def rejection_pdf(spectrum: Spectrum, lam, lo, hi) -> np.ndarray:
    """Density per nm of `rejection_sample`: S(λ) / ∫_lo^hi S on [lo, hi), else 0."""
    lo, hi = _check_range(lo, hi)
    lam = np.asarray(lam, dtype=np.float64)
    total = np.trapezoid(spectrum.values[lo - int(LAMBDA_MIN) : hi - int(LAMBDA_MIN) + 1])
    return np.where((lam >= lo) & (lam < hi), spectrum(lam) / total, 0.0)


def d65_sampling_shape() -> Spectrum:
    """D65 (`spectra.illuminant("D65")`, tabulated over 300–780 nm) continued outside its table at its end
    values (63 % of its 560 nm value at 780 nm), so the D65 samplers have a positive density over the whole
    grid: a sampling density must be positive wherever light reaches the camera (else that light is lost);
    its shape there changes the noise, not the mean."""
    table = illuminant("D65")
    inside = np.flatnonzero(table.values > 0)
    return Spectrum(np.interp(GRID, GRID[inside], table.values[inside]))


def d65_rejection(n, rng: np.random.Generator, lo=REPORT_VISIBLE_MIN, hi=REPORT_VISIBLE_MAX) -> np.ndarray:
    """The report's sampleWavelengthD65: `n` wavelengths ∝ D65 on [lo, hi) by rejection sampling
    (`d65_sampling_shape`: continued at its end values outside the table's 300–780 nm)."""
    return rejection_sample(d65_sampling_shape(), n, rng, lo, hi, name="D65")


def d65_rejection_pdf(lam, lo=REPORT_VISIBLE_MIN, hi=REPORT_VISIBLE_MAX) -> np.ndarray:
    """Density per nm of `d65_rejection`: D65 normalised over [lo, hi)."""
    return rejection_pdf(d65_sampling_shape(), lam, lo, hi)


def d65(lo=REPORT_VISIBLE_MIN, hi=REPORT_VISIBLE_MAX) -> BinnedDistribution:
    """D65 as a binned pdf for the kernels: the same bin probabilities as `d65_rejection`."""
    return from_spectrum(d65_sampling_shape(), lo, hi, name="D65")
