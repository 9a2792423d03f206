"""The shared leaf functions on the CUDA target (`kernels/cuda_target.py`, numba-cuda) on a machine without a
GPU: every one compiles to PTX for compute capability 9.0 with the argument types the Numba kernel gives it
(the list: tests/support/cuda_shared.py), small CUDA kernels calling them (tests/support/cuda_kernels.py)
compile to PTX and, in numba-cuda's simulator, agree with the NumPy backend's call of the same functions on the
same inputs; the tracer imports no CUDA module, and a missing package or driver is named.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import shared_math
from addon.tracer.errors import SpectralError
from addon.tracer.kernels import cuda_target
from addon.tracer.kernels.light_sampling import incident_radiance, sample_light
from addon.tracer.kernels.lookups import on_grid, table_at
from addon.tracer.kernels.media import collision_coefficients, density, free_path, null_fraction, phase_pdf
from addon.tracer.kernels.rng import low_discrepancy, path_key, pixel_key, uniform
from addon.tracer.phase import hg_pdf, hg_sample_cos, rayleigh_pdf, rayleigh_sample_cos, sample_direction
from addon.tracer.planck import planck_radiance
from tests.support import cuda_kernels, cuda_shared

ROOT = Path(__file__).resolve().parents[3]
TARGET = f".target sm_{cuda_target.COMPUTE_CAPABILITY[0]}{cuda_target.COMPUTE_CAPABILITY[1]}"


def test_every_shared_function_is_listed():
    """A new `@shared` function must be added to the list (with its kernel argument types) to be compiled."""
    listed = cuda_shared.listed(cuda_shared.signatures())
    assert listed == cuda_shared.shared_in_sources()
    assert ("kernels.media", "density") in listed and len(listed) > 70


@pytest.mark.slow  # 16–19 s here (82 functions, each compiled on its own)
def test_every_shared_function_compiles_to_ptx():
    failures = {}
    for function, argument_types in cuda_shared.signatures().items():
        try:
            ptx, _ = cuda_target.compile_ptx(function, argument_types, device=True)
        except Exception as error:  # noqa: BLE001 (every failure is reported together)
            failures[function.__qualname__] = f"{type(error).__name__}: {str(error).splitlines()[0]}"
            continue
        assert TARGET in ptx and f"{len(function.__name__)}{function.__name__}" in ptx
    assert not failures


@pytest.mark.slow  # about 7 s here for the four, 5 s of it light_kernel
@pytest.mark.parametrize("kernel", cuda_kernels.KERNELS, ids=lambda kernel: kernel.__name__)
def test_kernels_calling_shared_functions_compile_and_assemble(kernel):
    """The batch kernels, the kernel scene among their arguments, are whole CUDA kernels (`.entry`) for sm_90
    that allocate nothing (no calls into Numba's runtime), and ptxas assembles them without spilling registers,
    within the 64 KiB constant bank (the Sobol table once: 32 KiB)."""
    from numba import types

    argument_types = cuda_kernels.argument_types(kernel, cuda_kernels.scene(), cuda_kernels.inputs())
    ptx, return_type = cuda_target.compile_ptx(kernel, argument_types)
    assert return_type == types.void and TARGET in ptx and ".entry" in ptx
    assert "NRT_" not in ptx and "malloc" not in ptx
    resources = cuda_target.assemble(ptx)
    assert 0 < resources["registers"] <= 255 and resources["spills"] == 0
    assert resources["constant"] == (32 * 1024 if kernel is cuda_kernels.rng_kernel else 0)


def _numpy_results(ks, batch):
    """What the NumPy backend's calls of the same functions give on the same batch (`cuda_kernels.run`)."""
    u, g, points, lams = batch["u"], batch["g"], batch["points"], batch["lams"]
    results = {}
    cos_hg, cos_rayleigh = hg_sample_cos(g, u[:, 0]), rayleigh_sample_cos(u[:, 1])
    results["phase"] = np.stack([cos_hg, hg_pdf(g, cos_hg), cos_rayleigh, rayleigh_pdf(cos_rayleigh),
                                 *sample_direction((0.6, 0.0, 0.8), cos_hg, u[:, 2])], axis=1)
    at = on_grid(lams)
    rho = density(ks, 0, *points.T) * ks.media.density_scale[0]
    scattering, absorption, _, _ = collision_coefficients(rho, table_at(ks.media.extinction, 0, at), 0.8, 0.0, 0.0,
                                                          0.0)
    sigma_bar = ks.majorant.coeff[0] * 2.0
    results["medium"] = np.stack([rho, scattering, absorption,
                                  phase_pdf(ks, 0, table_at(ks.media.anisotropy, 0, at), 2.0 * u[:, 0] - 1.0),
                                  free_path(u[:, 1], sigma_bar), null_fraction(sigma_bar, absorption, scattering),
                                  planck_radiance(lams, batch["kelvin"])], axis=1)
    for light in range(ks.lights.kind.shape[0]):
        sampled = [np.broadcast_to(v, lams.shape) for v in sample_light(ks, light, *points.T, u[:, 0], u[:, 1])]
        radiance = incident_radiance(ks, light, at, *sampled[:3], sampled[5])
        results[f"light{light}"] = np.stack([*sampled, np.broadcast_to(radiance, lams.shape)], axis=1)
    with np.errstate(over="ignore"):  # the hash wraps around in uint64 on purpose
        keys = pixel_key(cuda_kernels.SEED, 2, batch["pixels"])
        streams = path_key(keys, batch["samples"])
        results["rng"] = np.stack([low_discrepancy(keys, batch["samples"], np.uint64(c)) for c in range(4)]
                                  + [uniform(streams, np.uint64(8 + c)) for c in range(4)], axis=1)
    return results


def test_simulated_kernels_agree_with_the_numpy_backend(tmp_path):
    """numba-cuda's simulator (NUMBA_ENABLE_CUDASIM=1, set before numba.cuda is imported: a separate process)
    runs the batch kernels; every value matches the NumPy calls to float64 rounding (rng exactly)."""
    out = tmp_path / "simulated.npz"
    environment = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-m", "tests.support.cuda_kernels", str(out)], cwd=ROOT, env=environment,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    simulated = np.load(out)
    expected = _numpy_results(cuda_kernels.scene(), cuda_kernels.inputs())
    assert sorted(simulated.files) == sorted(expected)
    for name, values in expected.items():
        columns = values.shape[1]
        assert np.all(np.isnan(simulated[name][:, columns:])), name  # nothing written past what was compared
        np.testing.assert_allclose(simulated[name][:, :columns], values, rtol=1e-12, atol=1e-300, err_msg=name)
    assert np.array_equal(simulated["rng"], expected["rng"])
    assert np.all(np.isfinite(expected["light0"][:, 3])) and np.any(expected["light6"][:, 6] > 0.0)


def test_the_tracer_imports_no_cuda_module():
    """The CUDA compiler is imported on first use only: the tracer, its backends and the extension work where
    numba-cuda is absent."""
    code = ("import sys; import addon.tracer.render, addon.tracer.kernels.numba_backend, "
            "addon.tracer.kernels.numpy_backend, addon.tracer.kernels.cuda_target; "
            "print(sorted(m for m in sys.modules if m.startswith(('numba.cuda', 'numba_cuda', 'cuda'))))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "[]"


def test_a_missing_compiler_is_named(monkeypatch):
    def absent():
        raise ImportError("No module named 'numba_cuda'")

    monkeypatch.setattr(cuda_target, "_import_compiler", absent)
    monkeypatch.setattr(cuda_target, "compiler", cuda_target.compiler.__wrapped__)
    problem = cuda_target.device_problem()
    assert "numba-cuda" in problem and "requirements.lock" in problem
    with pytest.raises(SpectralError, match="numba-cuda"):
        cuda_target.require_device()


def test_a_missing_driver_is_named(monkeypatch):
    """Here (no GPU) numba-cuda finds no driver; on a machine with one the same message follows a failed probe."""
    cuda = cuda_target.compiler()
    monkeypatch.setattr(cuda, "is_available", lambda: False)
    with pytest.raises(SpectralError, match="No usable CUDA device: the NVIDIA driver or a GPU is missing"):
        cuda_target.require_device()


def _in_numba(function, arity):
    from numba import njit

    if arity == 1:
        return njit(lambda a: function(a))
    return njit(lambda a, b: function(a, b))


def test_the_shims_are_their_ufuncs_on_the_cpu():
    """In Python a shim is its NumPy ufunc, and in a Numba CPU kernel it computes exactly what the ufunc written
    in its place does (Numba's scalar ufuncs are not all NumPy's to the last bit: cbrt)."""
    x = np.array([-2.5, -0.0, 0.3, 1.0, 7.75, 1e300, np.inf])
    positive = np.abs(x) + 0.5
    with np.errstate(over="ignore"):
        for shim in shared_math.SHIMS:
            arity = shim.ufunc.nin
            args = (x, -x) if arity == 2 else (positive if shim.ufunc in (np.sqrt, np.log1p) else x,)
            assert np.array_equal(shim(*args), shim.ufunc(*args))
            through_shim, in_place = _in_numba(shim, arity), _in_numba(shim.ufunc, arity)
            for k in range(x.size):
                scalars = [a[k] for a in args]
                assert through_shim(*scalars) == in_place(*scalars), (shim.__name__, scalars)
    assert set(cuda_target.CUDA_SHIMS) == set(shared_math.SHIMS)
