"""The CUDA backend (`addon/tracer/kernels/cuda_backend.py`) without a GPU: its real `render_tile` in numba-cuda's
simulator against the Numba CPU kernel, its refusals (too many media, no device) and its kernel's PTX compile.

The simulator runs the kernel's Python, not its PTX: with the same seed the same random streams trace the same
paths as on the CPU, both on this host, so the two agree to float rounding (the sums' order of addition is the
threads'). The PTX compile checks that the whole kernel builds for sm_90."""

import os
import pickle
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from addon.tracer.backends import tile_arguments
from addon.tracer.errors import SpectralError
from addon.tracer.kernels import cuda_backend, cuda_target
from addon.tracer.kernels.layout import MAX_MEDIA
from addon.tracer.light_passes import light_categories
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render, render_unit
from addon.tracer.scene import Light
from addon.tracer.scene_io import save_scene
from addon.tracer.shared_math import shared_inline, shared_inline_always
from tests.support import scenes as s
from tests.tracer.kernels.test_backends import LIGHT_PASSES

REPO = Path(__file__).resolve().parents[3]
SEED, SPP = 7, 3


def smoke(light_passes=False, media=1, **settings):
    """4 × 4 pixels of smoke (in `media` media) under a sun and a sky, over a diffuse floor; with `light_passes`,
    every light pass, clamping and the spectral bins too."""
    smokes = [s.medium(s.box_grid(), 3.0 / media, name=f"smoke {index}", albedo=0.8, g=0.3) for index in range(media)]
    floor = s.parallelogram([-1.5, -1.5, -1.2], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0], reflectance=0.5)
    sky = Light(kind="sky", spectrum=s.smooth_ramp(2.0, 0.3), strength=1.0, horizon_spectrum=s.smooth_ramp(0.6, 1.0))
    if light_passes:
        settings.update(passes=LIGHT_PASSES, clamp_direct=3.0, clamp_indirect=0.5, spectrum=True)
    return s.scene(s.ortho_camera(4, 4, scale=0.8), smokes, [s.sun([0.3, 0.2, 1.0], 3.0), sky], [floor], **settings)


SCENES = {"smoke": smoke, "light passes": lambda: smoke(light_passes=True)}


def sums(scene, backend):
    """Every accumulator of samples [0, SPP) of the whole image (`render_unit`), as NumPy arrays."""
    camera = scene.camera
    return [np.array(a) for a in render_unit(compile_scene(scene), 0, (0, SPP), (0, 0, camera.width, camera.height),
                                             SEED, backend, light_categories(scene.settings), scene.settings.spectrum)]


# Renders every scene with the cuda row's render_tile in numba-cuda's simulator and pickles the sums.
SIMULATED = """
import pickle, sys, warnings
warnings.filterwarnings("ignore", category=RuntimeWarning)  # the rng's uint64 hash wraps; NumPy's x/0 is inf
from tests.tracer.kernels.test_cuda_backend import SCENES, sums
with open(sys.argv[1], "wb") as file:
    pickle.dump({name: sums(build(), "cuda") for name, build in SCENES.items()}, file)
"""


def test_the_simulator_renders_what_the_cpu_kernel_renders(tmp_path):
    """The cuda row's `render_tile` (device copies, one thread per pixel-sample, atomic sums) in the simulator
    against the Numba kernel at the same seed: Σ XYZ, Σ XYZ², transparency, light passes and spectral bins."""
    out = tmp_path / "simulated.pickle"
    done = subprocess.run([sys.executable, "-c", SIMULATED, str(out)], cwd=REPO, capture_output=True, text=True,
                          env=dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(REPO)), timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    simulated = pickle.loads(out.read_bytes())
    for name, build in SCENES.items():
        cpu = sums(build(), "numba")
        assert len(simulated[name]) == len(cpu) == 5
        assert cpu[0].sum() > 0.0
        if name == "light passes":
            assert cpu[3].shape[2] > 0 and cpu[4].shape[2] > 0 and np.abs(cpu[3]).sum() > 0 and cpu[4].sum() > 0
        for gpu, host in zip(simulated[name], cpu):
            assert gpu.shape == host.shape
            np.testing.assert_allclose(gpu, host, rtol=1e-12, atol=1e-300, err_msg=name)


def test_a_scene_with_more_media_than_a_thread_holds_is_refused():
    """The scene file's backend (validation) and a render asking for the cuda backend (before any device is
    looked for) name the count and the limit."""
    many = smoke(media=MAX_MEDIA + 1)
    with pytest.raises(SpectralError, match=rf"media: {MAX_MEDIA + 1} media, and the cuda backend renders at most "
                                            rf"{MAX_MEDIA}"):
        compile_scene(smoke(media=MAX_MEDIA + 1, backend="cuda"))
    with pytest.raises(SpectralError, match=rf"{MAX_MEDIA + 1} media, and the cuda backend renders at most"):
        render(many, spp=1, backend="cuda")
    compile_scene(smoke(media=MAX_MEDIA, backend="cuda"))  # the limit itself is fine


# Where no driver can be loaded, `backend cuda` fails with the sentence `cuda_target.device_problem` gives: through
# `render` and through the CLI.
NO_DEVICE = """
import sys
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from tests.tracer.kernels.test_cuda_backend import smoke
try:
    render(smoke(), spp=1, backend="cuda")
except SpectralError as error:
    print(error)
"""


def test_without_a_device_a_cuda_render_says_what_is_missing(tmp_path):
    env = dict(os.environ, NUMBA_CUDA_DRIVER=str(tmp_path / "no-driver.so"), PYTHONPATH=str(REPO))
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", NO_DEVICE], cwd=REPO, capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
    assert "No usable CUDA device: the NVIDIA driver or a GPU is missing" in done.stdout
    scene = save_scene(smoke(), tmp_path / "scene")
    done = subprocess.run([sys.executable, "-m", "addon.tracer", "render", str(scene), "--backend", "cuda", "--spp", "1",
                           "--out", str(tmp_path / "image.exr")], cwd=REPO, capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 1 and "No usable CUDA device" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "image.exr").exists()
    assert time.perf_counter() - start < 120  # refused before any kernel compiles


@shared_inline
def _twice(x):
    return 2.0 * x


@shared_inline_always
def _thrice(x):
    return 3.0 * x


def _uses_both(out, x):
    out[0] = _twice(x) + _thrice(x)


def test_shared_inline_is_a_device_function_on_cuda_and_shared_inline_always_is_inlined():
    """Before typing, CUDA inlines only `shared_inline_always` (a path state's constructors); `shared_inline`
    functions are device functions, seen as calls in PTX that NVVM did not optimise."""
    from numba import types

    ptx, _ = cuda_target.compile_ptx(_uses_both, (types.float64[::1], types.float64), opt=False)
    functions = re.findall(r"^\.(?:weak|visible) \.func .*?(\w+)\($", ptx, re.M)
    assert len(functions) == 1 and "6_twice" in functions[0]  # Itanium-mangled: the name's length, the name
    assert "_thrice" not in ptx


@pytest.mark.slow  # 84 s here with a CPU kernel compiling beside it (ptxas included); 755–1215 s inlined
def test_the_whole_kernel_compiles_to_ptx_for_sm_90():
    """`render_samples` with every stage of the path: one CUDA kernel for sm_90 (`.entry`) that allocates nothing
    (no call into Numba's runtime), which ptxas assembles without spilling."""
    cuda_backend.kernel()
    arguments = tile_arguments(compile_scene(smoke()), 0, (0, 1), (0, 0, 1, 1), SEED)
    ptx, _ = cuda_target.compile_ptx(cuda_backend.render_samples, cuda_backend.kernel_types(arguments))
    assert f".target sm_{cuda_target.COMPUTE_CAPABILITY[0]}{cuda_target.COMPUTE_CAPABILITY[1]}" in ptx
    assert ".entry" in ptx and "render_samples" in ptx
    assert "NRT_" not in ptx and "malloc" not in ptx
    resources = cuda_target.assemble(ptx)
    assert resources["spills"] == 0 and 0 < resources["registers"] <= 255
