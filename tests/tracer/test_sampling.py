"""Wavelength samplers against their pdfs (Pearson chi-square), the kernels' NumPy and Numba forms, bad input.

Every chi-square test uses a fixed seed and passes when p > 1e-3: for a correct sampler p is uniform on
[0, 1], so a seed would fail with probability 1e-3; the deliberately wrong pdfs give p far below 1e-30.
"""

import numpy as np
import pytest
from numba import njit as jit
from scipy import integrate

from addon.tracer import binned, sampling
from addon.tracer.colorimetry import xyz_weights
from tests.support.statistics import chi_square_pvalue as counts_pvalue
from addon.tracer.errors import SpectralError
from addon.tracer.spectra import constant, gaussian, illuminant, table, window as spectra_window
from addon.tracer.wavelengths import GRID

P_MIN = 1e-3
N = 200_000
UV_ONLY = table([250, 350], [1.0, 1.0])  # exactly zero above 350 nm


def chi_square_pvalue(samples, edges, probabilities):
    """p-value of Pearson's chi-square test of `samples` binned on `edges` against the bins' probabilities."""
    observed = np.histogram(samples, edges)[0]
    assert observed.sum() == samples.size, "samples outside the tested range"
    return counts_pvalue(observed, probabilities)


def quarter_nm_test(samples, pdf, lo, hi):
    """Chi-square over 0.25 nm bins of [lo, hi], the probability of each bin from `pdf` (constant per nm)."""
    edges = np.arange(lo, hi + 0.125, 0.25)
    return chi_square_pvalue(samples, edges, pdf(edges[:-1] + 0.125) * 0.25)


DISTRIBUTIONS = {
    "uniform report range": lambda: sampling.uniform(),
    "uniform whole grid": lambda: sampling.uniform(250, 830),
    "uv extended": lambda: sampling.uv_extended(),
    "gaussian spectrum": lambda: sampling.from_spectrum(gaussian(450, 30), 360, 830),
    "visible": lambda: sampling.visible_distribution(),
    "colour": lambda: sampling.colour_distribution(xyz_weights()),
    "d65 binned": lambda: sampling.d65(360, 830),
    "two lights": lambda: sampling.defensive_composite([(gaussian(420, 10), 1.0), (constant(2.0), 3.0)],
                                                       sampling.visible_distribution(), 0.2),
}


@pytest.mark.parametrize("name", DISTRIBUTIONS)
def test_binned_sampler_matches_its_pdf(name):
    dist = DISTRIBUTIONS[name]()
    assert dist.cdf.shape == (GRID.size,) and dist.bin_pdf.shape == (GRID.size - 1,)
    assert dist.cdf[0] == 0.0 and dist.cdf[-1] == 1.0 and np.all(np.diff(dist.cdf) >= 0)
    assert dist.bin_pdf.sum() == pytest.approx(1.0, abs=1e-12)  # bins are 1 nm wide
    samples = dist.sample(np.random.default_rng(1).random(N))
    assert np.all(dist.pdf(samples) > 0)
    assert quarter_nm_test(samples, dist.pdf, dist.lo, dist.hi) > P_MIN


def test_pdf_is_zero_outside_its_range_and_the_grid():
    dist = sampling.uniform(400, 500)
    assert np.all(dist.bin_pdf[:150] == 0) and np.all(dist.bin_pdf[250:] == 0)
    assert np.all(dist.pdf([399.99, 500.0, 249.0, 830.0, 900.0]) == 0)
    assert np.all(dist.pdf([400.0, 450.5, 499.999]) == pytest.approx(0.01))


def test_only_the_range_is_read():
    spectrum = table([250, 399, 400, 830], [-5.0, -5.0, 1.0, 1.0])  # negative below 399 nm: outside the range
    assert np.all(sampling.from_spectrum(spectrum, 400, 830).bin_pdf[150:] == 1 / 430)


def test_wrong_pdfs_are_rejected():
    uniform_samples = sampling.uniform(360, 830).sample(np.random.default_rng(2).random(N))
    assert quarter_nm_test(uniform_samples, sampling.visible_distribution().pdf, 360, 830) < 1e-30
    # A 3 nm shift of a 40 nm wide Gaussian: the mean moves by 34 standard errors (40 / √N nm).
    samples = sampling.from_spectrum(gaussian(550, 40), 360, 830).sample(np.random.default_rng(3).random(N))
    assert quarter_nm_test(samples, sampling.from_spectrum(gaussian(553, 40), 360, 830).pdf, 360, 830) < 1e-30


def test_samples_stay_in_non_empty_bins_at_the_ends_of_u():
    dist = sampling.from_spectrum(gaussian(600, 2), 300, 700)  # most bins hold (almost) nothing
    u = np.array([0.0, 1e-300, 0.5, 1.0 - 2.0**-53, 1.0])
    lam = dist.sample(u)
    assert np.all(dist.pdf(lam) > 0) and np.all((lam >= 300) & (lam < 700))


def test_uniform_within_each_bin():
    dist = sampling.uniform(500, 501)
    assert np.array_equal(dist.sample(np.array([0.0, 0.25, 0.5])), [500.0, 500.25, 500.5])


def test_visible_distribution_is_pbrts_density_per_bin():
    dist = sampling.visible_distribution(360, 830)

    def density(lam):
        return 1.0 / np.cosh(0.0072 * (lam - 538.0)) ** 2

    total = integrate.quad(density, 360, 830)[0]
    for lam in (360, 437, 538, 700, 829):
        assert dist.bin_pdf[lam - 250] == pytest.approx(integrate.quad(density, lam, lam + 1)[0] / total, rel=1e-10)


def test_defensive_composite_is_the_weighted_mixture_of_shapes_plus_the_defensive_share():
    blue = gaussian(420, 5)  # its scale does not matter: only the shape and the weight count
    red = gaussian(650, 5, height=100.0)
    visible = sampling.visible_distribution(360, 830)
    dist = sampling.defensive_composite([(blue, 1.0), (red, 3.0), (constant(0.0), 5.0)], visible, 0.2)
    assert dist.cdf[540 - 250] == pytest.approx(0.8 * 0.25 + 0.2 * visible.cdf[540 - 250], abs=1e-12)
    only_blue = sampling.from_spectrum(blue, 360, 830)
    expected = 0.8 * 0.25 * only_blue.bin_pdf + 0.2 * visible.bin_pdf
    assert np.allclose(dist.bin_pdf[: 540 - 250], expected[: 540 - 250], rtol=1e-9, atol=1e-15)
    assert np.all(dist.bin_pdf[360 - 250 :] > 0)  # positive everywhere the defensive density is


def test_defensive_composite_of_spectra_zero_in_the_range_is_the_defensive_density():
    visible = sampling.visible_distribution(360, 830)
    dist = sampling.defensive_composite([(UV_ONLY, 1.0)], visible, 0.2)
    assert np.allclose(dist.bin_pdf, visible.bin_pdf, rtol=1e-12, atol=0)


def test_d65_rejection_sampling_matches_its_pdf():
    samples = sampling.d65_rejection(N, np.random.default_rng(4))
    assert samples.size == N and np.all((samples >= 380) & (samples < 700))
    # The pdf is linear between grid points, so the midpoint rule gives each half-nm bin's probability exactly.
    edges = np.arange(380, 700.25, 0.5)
    probabilities = sampling.d65_rejection_pdf(edges[:-1] + 0.25) * 0.5
    assert probabilities.sum() == pytest.approx(1.0, abs=1e-12)
    assert chi_square_pvalue(samples, edges, probabilities) > P_MIN
    # ... and a flat pdf is rejected.
    assert chi_square_pvalue(samples, edges, np.full(edges.size - 1, 1 / (edges.size - 1))) < 1e-30


def test_d65_binned_has_the_rejection_samplers_bin_probabilities():
    edges = np.arange(380, 701)
    exact = [integrate.quad(sampling.d65_rejection_pdf, a, a + 1)[0] for a in edges[:-1]]
    assert np.allclose(sampling.d65().bin_pdf[380 - 250 : 700 - 250], exact, rtol=1e-9)


def test_d65_pdf_is_the_shared_illuminant_normalised():
    d65 = illuminant("D65")
    assert sampling.d65_rejection_pdf(560.0) == pytest.approx(100.0 / np.trapezoid(d65.values[380 - 250 : 701 - 250]))
    # The dataset ends at 780 nm; the sampling density carries on at its 780 nm value.
    assert np.allclose(sampling.d65(360, 830).bin_pdf[780 - 250 :], sampling.d65(360, 830).bin_pdf[780 - 250])
    assert sampling.d65(360, 830).bin_pdf[829 - 250] > 0.5 * sampling.d65(360, 830).bin_pdf[560 - 250]


def test_rejection_sampling_of_any_spectrum():
    spectrum = gaussian(300, 20) + constant(0.1)
    samples = sampling.rejection_sample(spectrum, N, np.random.default_rng(5), 250, 400)
    edges = np.arange(250, 400.25, 0.5)
    probabilities = sampling.rejection_pdf(spectrum, edges[:-1] + 0.25, 250, 400) * 0.5
    assert chi_square_pvalue(samples, edges, probabilities) > P_MIN


@pytest.mark.parametrize("n", [1, 3, 4])
def test_stratified_wavelengths_have_the_right_marginal_pdf(n):
    dist = sampling.visible_distribution()
    u = np.random.default_rng(6).random(N)
    lams, pdfs = sampling.stratified_wavelengths(dist, u, n)
    assert lams.shape == pdfs.shape == (n, N)
    assert np.array_equal(pdfs, dist.pdf(lams))
    for i in range(n):
        assert np.array_equal(lams[i], dist.sample((u + i / n) % 1.0))
        assert quarter_nm_test(lams[i], dist.pdf, dist.lo, dist.hi) > P_MIN


def test_stratified_draws_are_one_in_each_stratum_of_u():
    dist = sampling.uniform(400, 800)
    lams, pdfs = sampling.stratified_wavelengths(dist, 0.3, 4)
    assert lams.shape == pdfs.shape == (4,)
    assert np.allclose(np.sort(lams), [420, 520, 620, 720]) and np.all(pdfs == 1 / 400)


def test_numba_and_numpy_forms_agree_exactly():
    dist = sampling.defensive_composite([(gaussian(420, 10), 1.0), (constant(1.0), 1.0)],
                                        sampling.uniform(300, 800), 0.2)
    u = np.concatenate((np.random.default_rng(7).random(500), [0.0, 1.0 - 2.0**-53, 1.0]))
    lam = np.concatenate((binned.sample_binned(dist.cdf, u), [250.0, 299.999, 800.0, 829.9999, 830.0, 100.0]))
    sample_jit, pdf_jit, stratified_jit = (jit(f) for f in (binned.sample_binned, binned.pdf_binned,
                                                           binned.stratified_binned))
    assert np.array_equal(binned.sample_binned(dist.cdf, u), [sample_jit(dist.cdf, x) for x in u])
    pdfs = [pdf_jit(dist.bin_pdf, x) for x in lam]
    assert np.array_equal(binned.pdf_binned(dist.bin_pdf, lam), pdfs)
    lams, pdfs = binned.stratified_binned(dist.cdf, dist.bin_pdf, u, 4)
    for k, x in enumerate(u):
        jit_lams, jit_pdfs = stratified_jit(dist.cdf, dist.bin_pdf, x, 4)
        assert np.array_equal(jit_lams, lams[:, k]) and np.array_equal(jit_pdfs, pdfs[:, k])


def test_band_ranges():
    assert sampling.band_ranges(360, 830, 1) == [(360, 830)]
    bands = sampling.band_ranges(360, 830, 7)
    assert len(bands) == 7 and bands[0][0] == 360 and bands[-1][1] == 830
    assert all(a[1] == b[0] for a, b in zip(bands, bands[1:]))
    assert {hi - lo for lo, hi in bands} <= {67, 68}
    assert sampling.band_ranges(400, 410, 10) == [(400 + k, 401 + k) for k in range(10)]


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: sampling.defensive_composite([(constant(1.0), -1.0)], sampling.uniform(), 0.2), "non-negative"),
        (lambda: sampling.defensive_composite([(constant(-1.0), 1.0)], sampling.uniform(), 0.2), "non-negative"),
        (lambda: sampling.defensive_composite([], sampling.uniform(), 0.0), r"share must lie in \(0, 1\]"),
        (lambda: sampling.from_spectrum(UV_ONLY, 400, 830, name="emission"), "emission are zero in 400–830 nm"),
        (lambda: sampling.BinnedDistribution(-np.ones(580), 400, 500), "non-negative"),
        (lambda: sampling.BinnedDistribution(np.ones(10), 400, 500), "580 values"),
        (lambda: sampling.uniform(200, 700), "within 250–830 nm"),
        (lambda: sampling.uniform(700, 380), "increasing"),
        (lambda: sampling.uniform(380.5, 700), "whole nanometres"),
        (lambda: sampling.uniform("red", 700), "two numbers"),
        (lambda: sampling.uv_extended(400, 700), "below 380 nm"),
        (lambda: sampling.band_ranges(400, 410, 11), "1 to 10 bands"),
        (lambda: sampling.band_ranges(400, 410, 0), "1 to 10 bands"),
        (lambda: sampling.stratified_wavelengths(sampling.uniform(), 0.5, 0), "positive whole number"),
        (lambda: sampling.rejection_sample(constant(0.0), 9, np.random.default_rng(), 380, 700), "is zero in 380–700"),
    ],
)
def test_bad_input_raises_spectral_error(call, message):
    with pytest.raises(SpectralError, match=message):
        call()


def test_colour_distribution_is_half_visible_half_cmf_norm():
    weights = xyz_weights()
    dist = sampling.colour_distribution(weights, 360, 830)
    norm = np.linalg.norm(0.5 * (weights[:, :-1] + weights[:, 1:]), axis=0)
    norm[:110] = 0.0  # below 360 nm
    expected = 0.5 * sampling.visible_distribution(360, 830).bin_pdf + 0.5 * norm / norm.sum()
    assert np.allclose(dist.bin_pdf, expected, rtol=1e-12, atol=0)


def single_wavelength_variance(dist, spectrum):
    """Exact per-sample variance of the one-wavelength estimate c(λ) S(λ) / p(λ) of X, Y and Z, by
    summation over the 1 nm bins (midpoint values; the same for every distribution compared)."""
    weights = xyz_weights()
    integrand = 0.5 * (weights[:, :-1] + weights[:, 1:]) * 0.5 * (spectrum.values[:-1] + spectrum.values[1:])
    p = dist.bin_pdf
    inside = p > 0
    second_moment = (integrand[:, inside] ** 2 / p[inside]).sum(axis=1)
    return second_moment - integrand[:, inside].sum(axis=1) ** 2


@pytest.mark.parametrize("light", ["D65", "A"])
def test_colour_importance_lowers_colour_noise_without_raising_luminance_noise(light):
    """Exact one-wavelength variances: D65 gives X, Y, Z ratios 0.66, 0.90, 0.52 (sum 0.59); A 0.81,
    0.80, 0.56 (sum 0.78)."""
    spectrum = illuminant(light)
    visible = single_wavelength_variance(sampling.visible_distribution(360, 830), spectrum)
    colour = single_wavelength_variance(sampling.colour_distribution(xyz_weights(), 360, 830), spectrum)
    assert colour.sum() < 0.8 * visible.sum()
    assert colour[2] < 0.6 * visible[2]  # Z: the blue lobe the visible density undersamples
    assert colour[1] < visible[1]


def test_linear_over_binned_weights_binned_draws_to_the_interpolated_spectrum():
    """Draws from a window's binned distribution (constant within each bin), weighted by
    `linear_over_binned`, estimate integrals over the linearly interpolated spectrum: the share of each
    half of the window's edge bins (a ramp from 0 to 1 within a nanometre: 1/4 and 3/4 of the bin's mass)
    within 5 standard errors, and the weights average to 1."""
    window = spectra_window(constant(1.0), 300, 340)
    dist = sampling.from_spectrum(window, 250, 830)
    u = (np.arange(400_000) + 0.5) / 400_000
    lam = binned.sample_binned(dist.cdf, u)
    weight = binned.linear_over_binned(window.values, lam)
    total = window.integral()
    for lo, expected in ((299.0, 0.125), (299.5, 0.375), (340.0, 0.375), (340.5, 0.125)):
        inside = (lam >= lo) & (lam < lo + 0.5)
        estimate = weight * inside
        error = estimate.std() / np.sqrt(lam.size)
        assert abs(estimate.mean() - expected / total) <= 5 * error + 1e-12, (lo, estimate.mean(), expected / total)
    assert abs(weight.mean() - 1.0) < 1e-3
