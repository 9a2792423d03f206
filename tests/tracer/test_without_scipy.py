"""The tracer runs without SciPy, which the extension does not bundle: every module imports, colour-science
gives the same spectra and colours without it, and leaves no mock `scipy` behind to break Numba."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np

from addon.tracer import colorimetry, glow, spectra

ROOT = Path(__file__).resolve().parents[2]
COLOURS = [(0.2, 0.5, 0.7), (0.9, 0.1, 0.05), (0.0, 1.0, 1.0)]


def figures() -> dict:
    """What the tracer computes with colour-science (and, before, SciPy): spectra of RGB colours, illuminants,
    a black body, the glow table, colour differences and matrices."""
    return {
        "rgb": [spectra.from_rgb(rgb, method).values.tolist() for rgb in COLOURS for method in spectra.RGB_METHODS],
        "illuminants": [spectra.illuminant(name).values.tolist() for name in ("D65", "FL2", "LED-B1")],
        "blackbody": spectra.blackbody(3000.0).values.tolist(),
        "glow": glow.normalisation_table("cie1931")[1].tolist(),
        "delta_e": float(colorimetry.delta_e_2000((0.2, 0.3, 0.4), (0.21, 0.3, 0.38), (0.95, 1.0, 1.09))),
        "acescg": colorimetry.xyz_to_rgb_matrix("acescg").tolist(),
    }


WITHOUT_SCIPY = textwrap.dedent(
    """
    import importlib, json, pkgutil, sys

    class NoSciPy:
        def find_spec(self, name, path=None, target=None):
            if name == "scipy" or name.startswith("scipy."):
                raise ImportError("SciPy is blocked in this test")

    sys.meta_path.insert(0, NoSciPy())
    import addon.tracer
    for info in pkgutil.walk_packages(addon.tracer.__path__, "addon.tracer."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)
    from tests.tracer.test_without_scipy import figures
    result = figures()
    import numba  # a mock scipy left in sys.modules breaks this
    assert not [name for name in sys.modules if name.split(".")[0] == "scipy"]
    print("FIGURES", json.dumps(result))
    """
)


def test_the_tracer_computes_the_same_without_scipy():
    done = subprocess.run([sys.executable, "-c", WITHOUT_SCIPY], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)
    assert "FIGURES " in done.stdout, done.stderr
    without = json.loads(done.stdout.split("FIGURES ", 1)[1])
    with_scipy = figures()
    assert without.keys() == with_scipy.keys()
    for key, values in with_scipy.items():
        assert np.allclose(without[key], values, rtol=1e-12, atol=1e-15), key
