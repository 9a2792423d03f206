"""The estimator's named updates (`kernels/estimator.py`) on their own: what they promise (unbiased roulettes, the
balance heuristic's weights summing to 1, the null-scattering expectation of a collision), and that each gives on
arrays what it gives on each element, as the two backends call it. That both backends call them and trace the same
paths is tests/tracer/kernels/test_backends.py's lock-step test."""

import numpy as np
import pytest

from addon.tracer.kernels import estimator as e
from addon.tracer.kernels.layout import SHADOW_ROULETTE_STOP
from tests.support.cuda_shared import signatures

RNG = np.random.default_rng(7)


def _arguments(kinds, size):
    """Random arguments of the Numba types `kinds` (float64 in (0, 2), int64 in 1..4, boolean), arrays of `size`."""
    out = []
    for kind in kinds:
        name = str(kind)
        if name == "bool":
            out.append(RNG.random(size) < 0.5)
        elif name == "int64":
            out.append(RNG.integers(1, 5, size))
        else:
            out.append(RNG.uniform(0.05, 2.0, size))
    return out


@pytest.mark.parametrize("function", [f for f in signatures() if f.__module__.endswith(".estimator")],
                         ids=lambda f: f.__name__)
def test_arrays_give_what_each_element_gives(function):
    """The NumPy backend calls each update on arrays, the Numba kernel on one wavelength's scalars: the same
    values, element by element (exactly: the same operations in the same order)."""
    kinds = signatures()[function]
    arrays = _arguments(kinds, 50)
    whole = function(*arrays)
    whole = whole if isinstance(whole, tuple) else (whole,)
    for k in range(50):
        one = function(*(a[k].item() for a in arrays))
        one = one if isinstance(one, tuple) else (one,)
        for part, value in zip(whole, one):
            assert np.broadcast_to(part, (50,))[k] == value


def test_the_two_strategies_weights_sum_to_one():
    """Balance heuristic on one wavelength: a direction that light sampling draws with pdf p_l and phase sampling
    with p (surviving with s) gets the weight p_l / (p_l + p·s) from next-event estimation and p·s / (p·s + p_l)
    when the path's ray finds the light after phase sampling: they sum to 1, whatever the path's r_u."""
    r_u, p_l, p, s = RNG.uniform(0.1, 3.0, (4, 1000))
    light = r_u * p_l / e.light_sample_ratio(r_u, p_l, p, s, False)
    _, r_u_after, r_l = e.phase_sampled(1.0, r_u, p, p)
    unidirectional = r_u_after * s / e.hit_light_ratio(r_u_after, r_l, s, p_l, True)
    np.testing.assert_allclose(light + unidirectional, 1.0, rtol=1e-14)
    assert np.all(e.light_sample_ratio(r_u, p_l, p, s, True) == r_u * p_l)  # a delta light: light sampling alone
    assert np.all(e.hit_light_ratio(r_u, r_l, s, p_l, False) == r_u)  # from the camera: the path alone


def test_a_collision_keeps_the_null_scattering_expectation():
    """Over the hero's choice of a real (probability σ_t,0/σ̄) or null collision, each wavelength's expected
    throughput is (σ_s + σ_n)/σ̄ of its own coefficients, and the hero's r_u stays 1."""
    sigma_bar = 5.0
    sigma_a, sigma_s = RNG.uniform(0.0, 2.4, (2, 4, 200))
    p_real = e.real_probability(sigma_a[0], sigma_s[0], sigma_bar)
    p_null = 1.0 - p_real
    beta_real, r_u_real = e.real_collision(1.0, 1.0, sigma_a, sigma_s, sigma_bar, p_real)
    beta_null, r_u_null, r_l_null = e.null_collision(1.0, 1.0, 1.0, sigma_a, sigma_s, sigma_bar, p_null, False)
    expected = p_real * beta_real + p_null * beta_null
    np.testing.assert_allclose(expected, (sigma_bar - sigma_a) / sigma_bar, rtol=1e-13)
    np.testing.assert_allclose(r_u_real[0], 1.0, rtol=1e-14)
    np.testing.assert_allclose(r_u_null[0], 1.0, rtol=1e-14)
    np.testing.assert_allclose(r_l_null, 1.0 / p_null)
    assert np.all(e.null_collision(1.0, 1.0, 1.0, sigma_a, sigma_s, sigma_bar, p_null, True)[2] == 1.0)


def test_the_roulettes_are_unbiased():
    """Russian roulette on paths and on faint shadow rays keeps every expectation: over u uniform (midpoints of
    10⁴ cells), survival × (β / survival) = β and E[shadow_roulette(T, u)] = T."""
    u = (np.arange(10_000) + 0.5) / 10_000
    for largest in (0.0, 0.01, 0.3, 0.99, 1.0, 4.0):
        survival = e.roulette_survival(largest)
        assert max(largest, e.ROULETTE_LEAST) == pytest.approx(survival) if largest < 1.0 else survival == 1.0
        assert np.mean(u < survival) * (1.0 / survival) == pytest.approx(1.0, rel=1e-3)
    transmittance = 0.004
    assert np.mean(e.shadow_roulette(transmittance, u)) == pytest.approx(transmittance, rel=1e-12)
    assert np.mean(e.shadow_roulette(transmittance, u) == 0.0) == pytest.approx(SHADOW_ROULETTE_STOP, abs=1e-4)


def test_residual_tracking_ends_with_the_controls_transmittance():
    """A residual-ratio-tracked shadow ray ends with transmittance × exp(−τ_c) and survival exp(−τ_c); plain ratio
    tracking gives its survival the transmittance's factor σ_n / rate, residual tracking leaves it be."""
    transmittance, survival = e.residual_tracked(0.5, 2.0)
    assert survival == pytest.approx(np.exp(-2.0)) and transmittance == pytest.approx(0.5 * np.exp(-2.0))
    assert e.ratio_tracked(1.0, 1.0, 4.0, 1.0, False) == pytest.approx((0.75, 0.75))
    assert e.ratio_tracked(1.0, 1.0, 4.0, 1.0, True) == pytest.approx((0.75, 1.0))
    assert e.shadow_bound(0.2, 0.0) == 0.2 and e.shadow_bound(0.2, 1.0) == pytest.approx(0.2 * np.exp(-1.0))


def test_companions_are_stratified():
    """A path's n wavelengths' uniforms are u + i/n mod 1: one in each n-th of [0, 1)."""
    u = RNG.random(1000)
    strata = np.sort(np.floor(np.stack([e.companion_uniform(u, i, 4) for i in range(4)]) * 4), axis=0)
    assert np.all(strata == np.arange(4)[:, None])
