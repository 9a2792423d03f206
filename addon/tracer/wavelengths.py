"""The one wavelength grid every spectrum is tabulated on, and the named ranges of the spectrum.

Wavelengths are in nanometres. Tables are float64 arrays of `GRID.size` values, one per nanometre
from `LAMBDA_MIN` to `LAMBDA_MAX` inclusive; values between grid points are linear interpolations.
"""

import numpy as np

LAMBDA_MIN = 250.0
LAMBDA_MAX = 830.0
LAMBDA_STEP = 1.0
GRID = np.arange(LAMBDA_MIN, LAMBDA_MAX + LAMBDA_STEP / 2, LAMBDA_STEP)

# Range used for colour (CIE 1931 tables end at 830 nm) and the default camera wavelength range.
VISIBLE_MIN = 360.0
VISIBLE_MAX = 830.0
# The report's "visible" range, used by its uniform sampler.
REPORT_VISIBLE_MIN = 380.0
REPORT_VISIBLE_MAX = 700.0
# Below this is ultraviolet (drives fluorescence).
UV_MAX = 380.0


def fractional_index(lam):
    """Position of wavelength(s) `lam` on GRID as a float index (0 at LAMBDA_MIN)."""
    return (np.asarray(lam, dtype=np.float64) - LAMBDA_MIN) / LAMBDA_STEP
