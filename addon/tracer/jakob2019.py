"""Jakob & Hanika 2019 RGB → spectrum recovery: the smooth reflectance R(t) = ½ + U / (2√(1 + U²)) with
U = c₀t² + c₁t + c₂ (a sigmoid of a quadratic; t the wavelength scaled to [0, 1] across the matching
functions' range) whose colour under an illuminant is a target XYZ.

The three coefficients are fitted by Levenberg–Marquardt (damped Gauss–Newton) on the CIELAB difference,
the error colour-science's `XYZ_to_sd_Jakob2019` minimises, with the same discrete colour sums (XYZ = Σ
cmf·E·R / Σ ȳ·E over the table's wavelengths), so it recovers the same spectra without SciPy's optimiser.
Colours far from grey are reached by continuation: a path of targets from grey to the colour, each fit
starting from the last. Colours the model only approaches (black, white: U → ∓∞) end at the best fit.
"""

import numpy as np

_TOLERANCE = 1e-6  # CIELAB ΔE at which a fit is done (colour-science stops at 0.023)
_ITERATIONS = 200  # per target of the continuation
_PATHS = (1, 4, 16)  # continuation steps tried, the next when a fit ends above the tolerance
_GREY = np.zeros(3)  # coefficients of R ≡ ½
_LAB_KNEE = (6.0 / 29.0) ** 3


def reflectance(coefficients, t) -> np.ndarray:
    """R(t) of `coefficients` (c₀, c₁, c₂) at scaled wavelengths `t`."""
    c0, c1, c2 = coefficients
    u = (c0 * t + c1) * t + c2
    return 0.5 + u / (2.0 * np.sqrt(1.0 + u * u))


def fit(xyz, cmfs: np.ndarray, illuminant: np.ndarray) -> tuple[np.ndarray, float]:
    """(coefficients, CIELAB ΔE left) of the reflectance whose XYZ under `illuminant` is `xyz` (white Y = 1).

    `cmfs` (3, N) and `illuminant` (N,) are tabulated at N evenly spaced wavelengths, t = 0 … 1 across them."""
    weights = cmfs * illuminant / float(np.sum(cmfs[1] * illuminant))
    t = np.linspace(0.0, 1.0, weights.shape[1])
    white = weights.sum(axis=1)
    target = np.asarray(xyz, dtype=np.float64)
    start = weights @ reflectance(_GREY, t)
    best = (_GREY, np.inf)
    for steps in _PATHS:
        coefficients, error = _GREY, np.inf
        for step in range(1, steps + 1):
            coefficients, error = _solve(start + (target - start) * step / steps, coefficients, weights, t, white)
        if error < best[1]:
            best = (coefficients, error)
        if error <= _TOLERANCE:
            break
    return best


def _lab(xyz: np.ndarray, white: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CIELAB of `xyz` and its 3×3 derivative d Lab / d XYZ."""
    q = xyz / white
    cube = q > _LAB_KNEE
    f = np.where(cube, np.cbrt(np.maximum(q, _LAB_KNEE)), q * (841.0 / 108.0) + 4.0 / 29.0)
    df = np.where(cube, 1.0 / (3.0 * np.cbrt(np.maximum(q, _LAB_KNEE)) ** 2), 841.0 / 108.0) / white
    mix = np.array([[0.0, 116.0, 0.0], [500.0, -500.0, 0.0], [0.0, 200.0, -200.0]])
    return mix @ f - np.array([16.0, 0.0, 0.0]), mix * df


def _solve(xyz, coefficients, weights, t, white) -> tuple[np.ndarray, float]:
    """Levenberg–Marquardt from `coefficients` to the reflectance of `xyz`: (coefficients, ΔE left)."""
    goal, _ = _lab(xyz, white)
    powers = np.stack([t * t, t, np.ones_like(t)])

    def residual(c):
        lab, dlab = _lab(weights @ reflectance(c, t), white)
        return lab - goal, dlab

    r, dlab = residual(coefficients)
    error, damping = float(np.linalg.norm(r)), 1e-3
    for _ in range(_ITERATIONS):
        if error <= _TOLERANCE:
            break
        u = powers.T @ coefficients
        slope = 0.5 / (1.0 + u * u) ** 1.5  # dR/dU
        jacobian = dlab @ (weights @ (powers * slope).T)  # d Lab / d coefficients
        normal, gradient = jacobian.T @ jacobian, jacobian.T @ r
        while damping < 1e12:
            try:
                step = np.linalg.solve(normal + damping * np.diag(np.diag(normal) + 1e-12), -gradient)
            except np.linalg.LinAlgError:
                damping *= 4.0
                continue
            trial = coefficients + step
            trial_r, trial_dlab = residual(trial)
            trial_error = float(np.linalg.norm(trial_r))
            if trial_error < error:
                coefficients, r, dlab, error = trial, trial_r, trial_dlab, trial_error
                damping = max(damping / 3.0, 1e-9)
                break
            damping *= 4.0
        else:
            break  # no step lowers the error: a minimum (or the model's edge)
    return coefficients, error
