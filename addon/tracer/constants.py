"""Physical constants of the tracer (SI units), from CODATA: h, c and k are exact by the 2019 definition of
the SI; the Stefan–Boltzmann and Wien constants follow from them. Here so that the extension needs no SciPy
(tests/tracer/test_constants.py checks every value against `scipy.constants`)."""

import math

PLANCK = 6.62607015e-34  # h, J·s (exact)
SPEED_OF_LIGHT = 299_792_458.0  # c, m/s (exact)
BOLTZMANN = 1.380649e-23  # k, J/K (exact)

# σ = 2π⁵k⁴ / (15h³c²), W·m⁻²·K⁻⁴
STEFAN_BOLTZMANN = 2.0 * math.pi**5 * BOLTZMANN**4 / (15.0 * PLANCK**3 * SPEED_OF_LIGHT**2)
# Wien's displacement law λ_max·T = b = hc / (k·x), x the root of x = 5(1 − e⁻ˣ); m·K
_WIEN_X = 4.965114231744276
WIEN = PLANCK * SPEED_OF_LIGHT / (BOLTZMANN * _WIEN_X)
