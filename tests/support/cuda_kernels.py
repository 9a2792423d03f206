"""Small CUDA kernels that evaluate shared leaf functions on a batch, one thread per item, as a CUDA path kernel
will call them: phase sampling and pdfs, a medium's density, coefficients and emission, next-event light
sampling, and the random numbers. tests/tracer/kernels/test_cuda_shared.py compiles them to PTX and runs them
in numba-cuda's simulator (`python -m tests.support.cuda_kernels OUT.npz` under NUMBA_ENABLE_CUDASIM=1),
comparing with the NumPy backend's call of the same functions on the same inputs (`inputs`, `scene`).
"""

import sys
import warnings

import numpy as np

from addon.tracer import spectra
from addon.tracer.kernels import cuda_target
from addon.tracer.kernels.light_sampling import incident_radiance, sample_light
from addon.tracer.kernels.lookups import on_grid, table_at
from addon.tracer.kernels.media import collision_coefficients, density, free_path, null_fraction, phase_pdf
from addon.tracer.kernels.rng import low_discrepancy, path_key, pixel_key, uniform
from addon.tracer.lowering import compile_scene
from addon.tracer.phase import hg_pdf, hg_sample_cos, rayleigh_pdf, rayleigh_sample_cos, sample_direction
from addon.tracer.planck import planck_radiance
from addon.tracer.scene import Light
from tests.support import scenes as s

cuda = cuda_target.compiler()
N = 96  # items per batch: three blocks of THREADS
THREADS = 32
SEED = 20261203


def scene():
    """A medium and one light of every kind that `sample_light` branches on."""
    axes = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    area = dict(kind="area", spectrum=spectra.constant(1.0), strength=2.0, unit="radiant",
                position=np.array([0.3, -0.2, 1.5]), area_axes=axes, size_x=0.6, size_y=0.4)
    lights = [s.sun([0.2, 0.1, 1.0], 3.0, angle=0.2), s.sun([0.0, 0.3, 1.0], 2.0), s.environment(0.5),
              Light(kind="point", spectrum=spectra.constant(1.0), strength=2.0, position=np.array([0.5, 0.0, 3.0])),
              Light(kind="spot", spectrum=spectra.constant(1.0), strength=2.0, position=np.array([0.0, 0.0, 2.0]),
                    spot_direction=np.array([0.0, 0.0, -1.0]), spot_size=np.radians(60.0), spot_blend=0.3),
              Light(area_shape="rectangle", **area), Light(area_shape="ellipse", **area),
              s.envmap(np.random.default_rng(4).random((4, 8, 3)) + 0.1)]
    grid = s.sampled_grid(lambda x, y, z: 1.0 + 0.5 * np.sin(3.0 * x) * np.cos(2.0 * y) + 0.25 * z, (6, 5, 4),
                          (-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    medium = s.medium(grid, 2.0, extinction=s.smooth_ramp(0.5, 1.5), albedo=0.8, g=0.4)
    return compile_scene(s.scene(s.ortho_camera(), [medium], lights))


def inputs():
    """The batch's inputs (fixed seed): uniforms, anisotropies, points in the medium, wavelengths, keys."""
    rng = np.random.default_rng(SEED)
    return {"u": rng.random((N, 4)), "g": rng.uniform(-0.95, 0.95, N), "points": rng.uniform(-1.2, 1.2, (N, 3)),
            "lams": rng.uniform(360.0, 830.0, N), "kelvin": rng.uniform(800.0, 6000.0, N),
            "pixels": rng.integers(0, 1 << 20, N), "samples": rng.integers(0, 1 << 16, N).astype(np.uint64)}


def phase_kernel(g, u, out):
    """Per item: Henyey–Greenstein and Rayleigh cosines and their pdfs, and a direction sampled around +x/+z."""
    i = cuda.grid(1)
    if i < u.shape[0]:
        cos_hg = hg_sample_cos(g[i], u[i, 0])
        cos_rayleigh = rayleigh_sample_cos(u[i, 1])
        out[i, 0], out[i, 1] = cos_hg, hg_pdf(g[i], cos_hg)
        out[i, 2], out[i, 3] = cos_rayleigh, rayleigh_pdf(cos_rayleigh)
        out[i, 4], out[i, 5], out[i, 6] = sample_direction((0.6, 0.0, 0.8), cos_hg, u[i, 2])


def medium_kernel(ks, points, lams, kelvin, u, out):
    """Per item: the medium's density at a point, its coefficients and phase pdf at a wavelength, the free path
    and null fraction against its majorant, and Planck's law."""
    i = cuda.grid(1)
    if i < lams.shape[0]:
        rho = density(ks, 0, points[i, 0], points[i, 1], points[i, 2]) * ks.media.density_scale[0]
        at = on_grid(lams[i])
        extinction = table_at(ks.media.extinction, 0, at)
        scattering, absorption, plain, source = collision_coefficients(rho, extinction, 0.8, 0.0, 0.0, 0.0)
        sigma_bar = ks.majorant.coeff[0] * 2.0
        out[i, 0], out[i, 1], out[i, 2] = rho, scattering, absorption
        out[i, 3] = phase_pdf(ks, 0, table_at(ks.media.anisotropy, 0, at), 2.0 * u[i, 0] - 1.0)
        out[i, 4] = free_path(u[i, 1], sigma_bar)
        out[i, 5] = null_fraction(sigma_bar, absorption, scattering)
        out[i, 6] = planck_radiance(lams[i], kelvin[i])


def light_kernel(ks, light, points, lams, u, out):
    """Per item: a direction sampled towards `light` from a point, its pdf, distance and falloff, and the
    radiance arriving along it at a wavelength."""
    i = cuda.grid(1)
    if i < lams.shape[0]:
        wx, wy, wz, pdf, distance, falloff = sample_light(ks, light, points[i, 0], points[i, 1], points[i, 2],
                                                          u[i, 0], u[i, 1])
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = wx, wy, wz, pdf, distance, falloff
        out[i, 6] = incident_radiance(ks, light, on_grid(lams[i]), wx, wy, wz, falloff)


def rng_kernel(pixels, samples, out):
    """Per item: the first low-discrepancy numbers of a path and hashed ones after them."""
    i = cuda.grid(1)
    if i < pixels.shape[0]:
        key = pixel_key(SEED, 2, pixels[i])
        stream = path_key(key, samples[i])
        for counter in range(4):
            out[i, counter] = low_discrepancy(key, samples[i], np.uint64(counter))
            out[i, 4 + counter] = uniform(stream, np.uint64(8 + counter))


KERNELS = (phase_kernel, medium_kernel, light_kernel, rng_kernel)
COLUMNS = 8


def argument_types(kernel, ks, batch):
    """The Numba types of `kernel`'s arguments as `run` launches it (for compiling it to PTX)."""
    from numba import types, typeof

    batch_types = {name: typeof(value) for name, value in batch.items()}
    return {
        phase_kernel: (batch_types["g"], batch_types["u"]),
        medium_kernel: (typeof(ks), batch_types["points"], batch_types["lams"], batch_types["kelvin"],
                        batch_types["u"]),
        light_kernel: (typeof(ks), types.int64, batch_types["points"], batch_types["lams"], batch_types["u"]),
        rng_kernel: (batch_types["pixels"], batch_types["samples"]),
    }[kernel] + (types.float64[:, ::1],)


def run(ks, batch):
    """Every kernel on the batch, on whatever `cuda` is (the simulator here): {name: (items, COLUMNS)}."""
    blocks = (N + THREADS - 1) // THREADS
    results = {}

    def launch(kernel, *args):
        out = np.full((N, COLUMNS), np.nan)
        cuda.jit(kernel)[blocks, THREADS](*args, out)
        return out

    results["phase"] = launch(phase_kernel, batch["g"], batch["u"])
    results["medium"] = launch(medium_kernel, ks, batch["points"], batch["lams"], batch["kelvin"], batch["u"])
    for light in range(ks.lights.kind.shape[0]):
        results[f"light{light}"] = launch(light_kernel, ks, light, batch["points"], batch["lams"], batch["u"])
    results["rng"] = launch(rng_kernel, batch["pixels"], batch["samples"])
    return results


if __name__ == "__main__":
    # The random streams' hash wraps around in uint64 on purpose; NumPy warns of it on scalars (the simulator's).
    warnings.filterwarnings("ignore", "overflow encountered", RuntimeWarning)
    np.savez(sys.argv[1], **run(scene(), inputs()))
