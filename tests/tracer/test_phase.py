"""Phase functions: pdfs integrate to 1, samplers match their pdfs (Pearson chi-square in cos θ and azimuth),
the NumPy and Numba forms agree, and bad anisotropy is refused.

Every chi-square test uses a fixed seed and passes when p > 1e-3: for a correct sampler p is uniform on
[0, 1], so a seed would fail with probability 1e-3; the deliberately wrong pdfs give p far below 1e-30.
"""

import numpy as np
import pytest
from numba import njit as jit
from scipy import integrate

from addon.tracer import phase
from tests.support.statistics import chi_square_pvalue
from addon.tracer.errors import SpectralError

P_MIN = 1e-3
N = 200_000
COS_EDGES = np.linspace(-1.0, 1.0, 101)
G_VALUES = [-0.7, 0.0, 0.3, 0.9]


def cos_bin_probabilities(pdf):
    """Probability of each COS_EDGES bin for a phase function `pdf(cos θ)` per steradian (2π ∫ pdf dcos θ)."""
    bins = zip(COS_EDGES[:-1], COS_EDGES[1:])
    return np.array([2 * np.pi * integrate.quad(pdf, a, b, epsabs=1e-13)[0] for a, b in bins])


def cos_test(samples, pdf):
    counts = np.histogram(samples, COS_EDGES)[0]
    assert counts.sum() == samples.size, "cos θ outside [-1, 1]"
    return chi_square_pvalue(counts, cos_bin_probabilities(pdf))


def random_units(rng, m):
    v = rng.normal(size=(3, m))
    return v / np.linalg.norm(v, axis=0)


@pytest.mark.parametrize(
    "pdf",
    [lambda c, g=g: phase.hg_pdf(g, c) for g in (-0.95, -0.7, 0.0, 0.3, 0.9, 0.99)]
    + [phase.rayleigh_pdf, phase.isotropic_pdf],
)
def test_pdfs_integrate_to_one_over_the_sphere(pdf):
    total = 2 * np.pi * integrate.quad(pdf, -1, 1, points=[-0.999, 0.999], epsabs=1e-13, limit=200)[0]
    assert total == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("g", G_VALUES)
def test_hg_sampler_matches_its_pdf(g):
    samples = phase.hg_sample_cos(g, np.random.default_rng(10).random(N))
    assert cos_test(samples, lambda c: phase.hg_pdf(g, c)) > P_MIN


def test_rayleigh_sampler_matches_its_pdf():
    samples = phase.rayleigh_sample_cos(np.random.default_rng(11).random(N))
    assert cos_test(samples, phase.rayleigh_pdf) > P_MIN


def test_wrong_pdfs_are_rejected():
    hg = phase.hg_sample_cos(0.3, np.random.default_rng(12).random(N))
    assert cos_test(hg, lambda c: phase.hg_pdf(0.33, c)) < 1e-30
    rayleigh = phase.rayleigh_sample_cos(np.random.default_rng(13).random(N))
    assert cos_test(rayleigh, phase.isotropic_pdf) < 1e-30


@pytest.mark.parametrize("g", G_VALUES)
def test_hg_mean_cosine_is_g(g):
    samples = phase.hg_sample_cos(g, np.random.default_rng(14).random(N))
    standard_error = samples.std() / np.sqrt(N)
    assert abs(samples.mean() - g) < 4 * standard_error  # fails with probability ~6e-5 for a correct sampler


def test_hg_inverse_is_the_textbook_one_and_stable_near_g_0():
    u = np.linspace(0, 1, 1001)
    for g in (-0.9, -0.3, 0.5, 0.9):
        textbook = (1 + g * g - ((1 - g * g) / (1 - g + 2 * g * u)) ** 2) / (2 * g)
        assert np.allclose(phase.hg_sample_cos(g, u), textbook, rtol=0, atol=1e-13)
    assert np.array_equal(phase.hg_sample_cos(0.0, u), 2 * u - 1)
    for g in (1e-12, -1e-9, 1e-6):  # first order in g: ξ + g (1 − ξ²) 3/2
        xi = 2 * u - 1
        assert np.allclose(phase.hg_sample_cos(g, u), xi + 1.5 * g * (1 - xi * xi), rtol=0, atol=10 * g * g + 4e-16)
    for g in (-0.99, 0.0, 0.5, 0.99):
        assert phase.hg_sample_cos(g, 0.0) == -1.0 and phase.hg_sample_cos(g, 1.0) == 1.0


def test_rayleigh_inverse_solves_the_cubic():
    u = np.linspace(0, 1, 1001)
    mu = phase.rayleigh_sample_cos(u)
    assert np.allclose((mu**3 + 3 * mu + 4) / 8, u, rtol=0, atol=1e-15)
    assert mu[0] == -1.0 and mu[-1] == 1.0 and mu[500] == 0.0


def test_orthonormal_basis_is_right_handed_everywhere():
    n = random_units(np.random.default_rng(15), 1000)
    n[:, :4] = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0.0], [0, 1, -0.0]]).T
    t, b = (np.array(v) for v in phase.orthonormal_basis(n))
    for x, y in ((t, t), (b, b), (n, n)):
        assert np.allclose(np.sum(x * y, axis=0), 1.0, atol=1e-14)
    for x, y in ((t, b), (t, n), (b, n)):
        assert np.allclose(np.sum(x * y, axis=0), 0.0, atol=1e-14)
    assert np.allclose(np.cross(t, b, axis=0), n, atol=1e-14)


def azimuth_cos_test(wo, wi, pdf, azimuth_bins=8):
    """Chi-square over (cos θ, azimuth) bins of directions `wo` (3, m) around `wi` (3,), in a frame built
    independently of the one in `phase`; the azimuth must be uniform and independent of cos θ."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(wi[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = helper - helper.dot(wi) * wi
    t /= np.linalg.norm(t)
    b = np.cross(wi, t)
    cos_theta = wi @ wo
    azimuth = np.arctan2(b @ wo, t @ wo)
    counts = np.histogram2d(cos_theta, azimuth, [COS_EDGES, np.linspace(-np.pi, np.pi, azimuth_bins + 1)])[0]
    assert counts.sum() == wo.shape[1]
    return chi_square_pvalue(counts, np.outer(cos_bin_probabilities(pdf), np.full(azimuth_bins, 1 / azimuth_bins)))


@pytest.mark.parametrize("wi", [(0, 0, 1), (0, 0, -1), (1, 0, 0), (0.48, -0.6, 0.64), (0.6, 0.0, -0.8)])
def test_sampled_directions_follow_hg_around_wi(wi):
    wi = np.array(wi, dtype=np.float64)
    rng = np.random.default_rng(16)
    cos_theta = phase.hg_sample_cos(0.5, rng.random(N))
    wo = np.array(phase.sample_direction(np.repeat(wi[:, None], N, axis=1), cos_theta, rng.random(N)))
    assert np.allclose(np.linalg.norm(wo, axis=0), 1.0, atol=1e-14)
    assert np.allclose(wi @ wo, cos_theta, atol=1e-14)
    assert azimuth_cos_test(wo, wi, lambda c: phase.hg_pdf(0.5, c)) > P_MIN
    assert azimuth_cos_test(wo, -wi, lambda c: phase.hg_pdf(0.5, c)) < 1e-30  # g > 0 is forward, not backward


def test_numba_and_numpy_forms_agree():
    rng = np.random.default_rng(18)
    u = np.concatenate((rng.random(300), [0.0, 0.5, 1.0 - 2.0**-53]))
    u2 = rng.random(u.size)
    g = np.concatenate((rng.uniform(-0.99, 0.99, 300), [0.0, 1e-9, -0.5]))
    cos = 2 * rng.random(u.size) - 1
    wi = random_units(rng, u.size)
    wi[:, :2] = np.array([[0, 0, 1], [0, 0, -1]]).T
    # Pure arithmetic (+ − × ÷ √, floor): bit-identical.
    for numpy_fn, jit_fn, args in [
        (phase.hg_pdf, jit(phase.hg_pdf), (g, cos)),
        (phase.hg_sample_cos, jit(phase.hg_sample_cos), (g, u)),
        (phase.rayleigh_pdf, jit(phase.rayleigh_pdf), (cos,)),
        (phase.isotropic_pdf, jit(phase.isotropic_pdf), (cos,)),
    ]:
        assert np.array_equal(numpy_fn(*args), [jit_fn(*a) for a in zip(*args)])
    basis = np.array(phase.orthonormal_basis(wi))  # (2, 3, m)
    basis_jit = jit(phase.orthonormal_basis)
    for k in range(u.size):
        assert np.array_equal(np.array(basis_jit(wi[:, k])), basis[:, :, k])
    # cbrt, cos and sin: identical where NumPy uses the C library, as Numba does; on AVX-512 machines NumPy
    # may use its own SIMD versions (SVML), which can differ in the last bit, hence a tolerance of a few ulp.
    rayleigh_jit, direction_jit = (jit(f) for f in (phase.rayleigh_sample_cos, phase.sample_direction))
    assert np.allclose(phase.rayleigh_sample_cos(u), [rayleigh_jit(x) for x in u], rtol=0, atol=1e-15)
    wo = np.array(phase.sample_direction(wi, cos, u2))
    wo_jit = np.array([direction_jit(wi[:, k], cos[k], u2[k]) for k in range(u.size)]).T
    assert np.allclose(wo, wo_jit, rtol=0, atol=1e-15)
    as_tuple = direction_jit((0.0, 0.0, 1.0), 0.5, 0.25)
    assert as_tuple == direction_jit(np.array([0.0, 0.0, 1.0]), 0.5, 0.25)


@pytest.mark.parametrize("g", [phase.HG_G_LIMIT, -phase.HG_G_LIMIT, 1 - 1e-10, -(1 - 1e-10)])
def test_hg_pdf_is_accurate_at_its_peak_as_g_nears_one(g):
    """At the peak (cosθ = sign g) the pdf is (1 + |g|) / (4π (1 − |g|)²); the textbook denominator
    1 + g² − 2g cosθ cancels there (relative error 1e-4 at 1 − 1e-6, NaN or inf at 1 − 1e-10)."""
    a = abs(g)
    peak = (1 + a) / (4 * np.pi * (1 - a) ** 2)
    cos_peak = np.copysign(1.0, g)
    assert phase.hg_pdf(g, cos_peak) == pytest.approx(peak, rel=1e-12)
    cos_theta = phase.hg_sample_cos(g, np.random.default_rng(17).random(10_000))
    values = phase.hg_pdf(g, np.append(cos_theta, [-1.0, 1.0]))
    assert np.all(np.isfinite(values)) and np.all(values > 0)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("g", [phase.HG_G_LIMIT, -phase.HG_G_LIMIT])
def test_the_sharpest_allowed_lobe_renders_finite_pixels(backend, g):
    """At 1 − 1e-10 both backends rendered NaN pixels (issue 14); at the bound the image is finite."""
    from addon.tracer.render import render
    from tests.support import scenes as s

    medium = s.medium(s.box_grid(), scale=3.0, albedo=0.9, g=g)
    scene = s.scene(s.perspective_camera(16, 16), [medium], [s.environment(), s.sun([0, 0, 1])], spp=4)
    xyz = render(scene, backend=backend).film.xyz
    assert np.all(np.isfinite(xyz)) and xyz.mean() > 0
