"""Colorimetry: colour matching functions on the wavelength grid, spectrum → XYZ, and XYZ ↔ RGB.

Owns the CIE 1931 2° observer (the exact table, or a Wyman–Sloan–Shirley 2013 analytic fit), the XYZ
normalisation (a radiance spectrum of constant value 1 has Y = 1), the matrices to linear Rec.709
(Blender's scene-linear), Rec.2020 and ACEScg, and a few colour-difference helpers for demos and tests.
Tables and matrices come from colour-science, imported on first use (`colour_science`).

Convention: spectra and the weights w = cmf / ∫ȳ dλ are linear between grid points (wavelengths.py),
and every XYZ in the tracer is the exact integral of their product,
    XYZ = ∫ w(λ) S(λ) dλ = Σ_i c_i S(λ_i),   c_i = Δλ · (w_{i−1} + 4 w_i + w_{i+1}) / 6
(halved terms at the grid's ends), so a spectrum S ≡ 1 has Y = 1. The kernels, which draw λ with pdf p
and interpolate `xyz_weights` and the spectra linearly, converge to this same integral. It differs from
the 1 nm node sum Σ_i w_i S(λ_i) Δλ (colour-science's "Integration") by w's curvature: under 0.01 % for
broad spectra, up to 1.5 % in X for a narrow band where x̄ is near its minimum (500–510 nm).
"""

import sys
import warnings
from functools import lru_cache
from unittest import mock

import numpy as np

from .errors import SpectralError
from .wavelengths import GRID, LAMBDA_STEP

CMF_NAMES = ("cie1931", "wyman1", "wyman3")
RGB_SPACES = ("rec709", "rec2020", "acescg")

_CIE1931 = "CIE 1931 2 Degree Standard Observer"
_COLOURSPACES = {"rec709": "ITU-R BT.709", "rec2020": "ITU-R BT.2020", "acescg": "ACEScg"}
# ACEScg's white is the ACES white (≈ D60); XYZ here is D65-relative, as in the other spaces, so a CAT02
# von Kries adaptation D65 → ACES white is folded into its matrix (the transform the ACES reference output
# transforms use), mapping a D65 spectrum to R = G = B.
_ACES_ADAPTATION = "CAT02"

# Wyman, Sloan & Shirley 2013, multi-lobe fit: per CMF, lobes of (height, mean nm, σ below mean, σ above mean).
_WYMAN3_LOBES = (
    ((1.056, 599.8, 37.9, 31.0), (0.362, 442.0, 16.0, 26.7), (-0.065, 501.1, 20.4, 26.2)),
    ((0.821, 568.8, 46.9, 40.5), (0.286, 530.9, 16.3, 31.1)),
    ((1.217, 437.0, 11.8, 36.0), (0.681, 459.0, 26.0, 13.8)),
)


def colour_science():
    """The colour-science package, imported on first use: it takes about a second to import and warns
    about plotting support (Matplotlib) that the tracer does not use.

    The extension bundles no SciPy (what the tracer uses of colour-science runs without it). Without
    SciPy, colour-science puts a mock `scipy` module into `sys.modules`, which would break a later
    `import numba` (and any other add-on's SciPy check): the mock is taken out again."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*(Matplotlib|SciPy).*")
        import colour
    for name in [name for name in sys.modules if name == "scipy" or name.startswith("scipy.")]:
        if isinstance(sys.modules[name], mock.Mock):
            del sys.modules[name]
    return colour


def cie1931_observer():
    """colour-science's CIE 1931 2° standard observer (360–830 nm, 1 nm), for the APIs that take `cmfs`."""
    return colour_science().MSDS_CMFS[_CIE1931]


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


def _gaussian(lam, mean, sigma):
    return np.exp(-0.5 * ((lam - mean) / sigma) ** 2)


def _cie1931_on_grid() -> np.ndarray:
    """The exact CIE 1931 table on GRID; 0 outside its 360–830 nm range."""
    observer = cie1931_observer()
    return np.stack([np.interp(GRID, observer.wavelengths, observer.values[:, i], left=0.0, right=0.0)
                     for i in range(3)])


def _wyman1(lam) -> np.ndarray:
    """Wyman–Sloan–Shirley single-lobe fit, as in the seminar report, eq. 1–3 (y and z Gaussian in ln λ)."""
    x = 1.065 * _gaussian(lam, 595.8, 33.33) + 0.366 * _gaussian(lam, 446.8, 19.44)
    y = 1.014 * _gaussian(np.log(lam), np.log(556.3), 0.075)
    z = 1.839 * _gaussian(np.log(lam), np.log(449.8), 0.051)
    return np.stack([x, y, z])


def _wyman3(lam) -> np.ndarray:
    """Wyman–Sloan–Shirley multi-lobe fit: sums of piecewise Gaussians with a different σ on each side."""
    def lobes(params):
        return sum(h * _gaussian(lam, mu, np.where(lam < mu, s_lo, s_hi)) for h, mu, s_lo, s_hi in params)

    return np.stack([lobes(params) for params in _WYMAN3_LOBES])


@lru_cache(maxsize=None)
def cmf(name: str = "cie1931") -> np.ndarray:
    """Colour matching functions x̄, ȳ, z̄ on GRID as a read-only (3, GRID.size) array."""
    if name == "cie1931":
        return _read_only(_cie1931_on_grid())
    if name == "wyman1":
        return _read_only(_wyman1(GRID))
    if name == "wyman3":
        return _read_only(_wyman3(GRID))
    raise SpectralError(f"unknown colour matching functions {name!r}; choose one of {', '.join(CMF_NAMES)}")


@lru_cache(maxsize=None)
def xyz_weights(cmf_name: str = "cie1931") -> np.ndarray:
    """Per-nanometre XYZ weights w on GRID, a read-only (3, GRID.size) array: cmf / ∫ȳ dλ (ȳ linear
    between grid points), so that a spectrum S ≡ 1 has Y = ∫ w_y dλ = 1. The kernels interpolate them."""
    table = cmf(cmf_name)
    return _read_only(table / np.trapezoid(table[1], dx=LAMBDA_STEP))


@lru_cache(maxsize=None)
def integration_weights(cmf_name: str) -> np.ndarray:
    """Read-only (3, GRID.size) c with XYZ = c @ S for S on GRID: the exact integral of the piecewise-linear
    product of `xyz_weights` and S (node i's share of the integral)."""
    w = xyz_weights(cmf_name)
    c = 4.0 * w
    c[:, 1:] += w[:, :-1]
    c[:, :-1] += w[:, 1:]
    c[:, 0] -= 2.0 * w[:, 0]  # the end nodes have one neighbouring interval: (2 w_0 + w_1) / 6
    c[:, -1] -= 2.0 * w[:, -1]
    return _read_only(c * LAMBDA_STEP / 6.0)


def spectrum_to_xyz(values_on_grid, cmf_name: str = "cie1931") -> np.ndarray:
    """XYZ of spectra tabulated on GRID: input (..., GRID.size), output (..., 3); the integral of the
    spectra and weights linear between grid points (see the module docstring)."""
    values = np.asarray(values_on_grid, dtype=np.float64)
    if values.shape[-1:] != GRID.shape:
        raise SpectralError(f"spectrum_to_xyz needs {GRID.size} values per spectrum (the 1 nm grid), "
                            f"got shape {values.shape}")
    return values @ integration_weights(cmf_name).T


def _colourspace(space: str):
    if space not in _COLOURSPACES:
        raise SpectralError(f"unknown RGB colour space {space!r}; choose one of {', '.join(RGB_SPACES)}")
    return colour_science().RGB_COLOURSPACES[_COLOURSPACES[space]]


@lru_cache(maxsize=None)
def xyz_to_rgb_matrix(space: str = "rec709") -> np.ndarray:
    """3×3 matrix from D65-relative XYZ to linear RGB of `space` (see RGB_SPACES); rgb = M @ xyz."""
    target = _colourspace(space)
    matrix = target.matrix_XYZ_to_RGB
    if space == "acescg":
        colour = colour_science()
        d65 = colour.xy_to_XYZ(_colourspace("rec709").whitepoint)
        adaptation = colour.adaptation.matrix_chromatic_adaptation_VonKries(
            d65, colour.xy_to_XYZ(target.whitepoint), transform=_ACES_ADAPTATION)
        matrix = matrix @ adaptation
    return _read_only(np.array(matrix, dtype=np.float64))


@lru_cache(maxsize=None)
def rgb_to_xyz_matrix(space: str = "rec709") -> np.ndarray:
    """Inverse of `xyz_to_rgb_matrix(space)`."""
    return _read_only(np.linalg.inv(xyz_to_rgb_matrix(space)))


def xyz_to_rgb(xyz, space: str = "rec709") -> np.ndarray:
    """Linear RGB in `space` of XYZ values (..., 3); no clipping, so out-of-gamut colours stay negative."""
    return np.asarray(xyz, dtype=np.float64) @ xyz_to_rgb_matrix(space).T


def rgb_to_xyz(rgb, space: str = "rec709") -> np.ndarray:
    """XYZ (D65-relative) of linear RGB values (..., 3) in `space`."""
    return np.asarray(rgb, dtype=np.float64) @ rgb_to_xyz_matrix(space).T


def xyz_to_xy(xyz) -> np.ndarray:
    """CIE xy chromaticity of XYZ values (..., 3); black maps to (0, 0)."""
    return colour_science().XYZ_to_xy(np.asarray(xyz, dtype=np.float64))


def delta_e_2000(xyz1, xyz2, white_xyz) -> np.ndarray:
    """CIEDE2000 colour difference between XYZ values, through CIELAB relative to the white `white_xyz`."""
    colour = colour_science()
    white = np.asarray(white_xyz, dtype=np.float64)
    if not white[1] > 0:
        raise SpectralError(f"delta_e_2000 needs a white with positive luminance Y, got {white.tolist()}")
    white_xy = colour.XYZ_to_xy(white)

    def lab(xyz):
        return colour.XYZ_to_Lab(np.asarray(xyz, dtype=np.float64) / white[1], white_xy)

    return colour.delta_E(lab(xyz1), lab(xyz2), method="CIE 2000")


def dominant_wavelength(xy, white_xy) -> float:
    """Dominant wavelength (nm) of chromaticity `xy` seen against `white_xy`, CIE 1931 observer.

    Colours on the purple side have none; for them the result is minus the complementary wavelength."""
    wavelength, _, _ = colour_science().dominant_wavelength(
        np.asarray(xy, dtype=np.float64), np.asarray(white_xy, dtype=np.float64), cie1931_observer())
    return float(wavelength)
