"""The tracer's CODATA constants are SciPy's (which the extension does not bundle)."""

import math

import pytest
import scipy.constants

from addon.tracer import constants


@pytest.mark.parametrize("ours, scipys", [
    ("PLANCK", "h"), ("SPEED_OF_LIGHT", "c"), ("BOLTZMANN", "k"),
    ("STEFAN_BOLTZMANN", "Stefan_Boltzmann"), ("WIEN", "Wien"),
])
def test_constants_are_scipys(ours, scipys):
    assert getattr(constants, ours) == pytest.approx(getattr(scipy.constants, scipys), rel=1e-12)


def test_wiens_constant_is_where_plancks_law_peaks():
    """x = hc/(λkT) at the peak solves x = 5(1 − e⁻ˣ)."""
    x = constants.PLANCK * constants.SPEED_OF_LIGHT / (constants.BOLTZMANN * constants.WIEN)
    assert x == pytest.approx(5.0 * (1.0 - math.exp(-x)), rel=1e-14)
