"""The table of kernel backends (addon/tracer/backends.py): one row per name a scene may choose, each with its
`prepare`, which a render asks before its first unit (the Numba kernel loaded or compiled, after any compile
running in the background; nothing for NumPy; the CUDA row's: tests/tracer/kernels/test_cuda_backend.py), and a `False` from it stops the render before any unit."""

import dataclasses

import numba
import numpy as np
import pytest

from addon.tracer import background_compile, backends, render
from addon.tracer.errors import SpectralError
from addon.tracer.kernels import numba_cache
from addon.tracer.lowering import compile_scene
from addon.tracer.scene import RenderSettings
from addon.tracer.validation import check_settings


def never(*_arguments):
    pytest.fail("asked, though there is nothing to wait for")


def test_each_name_has_one_row_and_the_scene_format_offers_exactly_those():
    assert backends.NAMES == ("numba", "numpy", "cuda")
    assert [backends.named(name).name for name in backends.NAMES] == list(backends.NAMES)
    with pytest.raises(SpectralError, match="unknown backend 'vulkan': choose one of numba, numpy, cuda"):
        backends.named("vulkan")
    with pytest.raises(SpectralError, match=r"render.backend: unknown value .*vulkan.* \(allowed: numba, numpy, "
                                            r"cuda\)"):
        check_settings(dataclasses.replace(RenderSettings(), backend="vulkan"))
    check_settings(dataclasses.replace(RenderSettings(), backend="cuda"))


def test_the_numpy_backend_has_nothing_to_prepare(tiny_scene):
    numpy = backends.named("numpy")
    kernel_scene = compile_scene(tiny_scene)
    assert numpy.prepare(kernel_scene, 7, never, never) is True
    assert numpy.prepare_first_hits(kernel_scene, never, never) is True
    assert numpy.kernels.render_tile.__module__ == "addon.tracer.kernels.numpy_backend"


def test_the_numba_backend_waits_for_a_background_compile_and_a_cancel_stops_it_there(tiny_scene, monkeypatch):
    """While the background process compiles, `prepare` waits (a cancel returns False, nothing compiled here);
    once it has finished, the kernel is loaded from the cache it filled."""
    kernel_scene = compile_scene(tiny_scene)
    running, readied = [True], []
    monkeypatch.setattr(background_compile, "running", lambda: running[0])
    monkeypatch.setattr(numba_cache, "ready", lambda dispatcher, prepare, cancel, notice: readied.append(dispatcher))
    assert backends.named("numba").prepare(kernel_scene, 0, lambda: True, None) is False
    assert readied == []
    running[0] = False
    backends.named("numba").prepare(kernel_scene, 0, never, None)
    assert readied == [backends.named("numba").kernels.render_tile]


def test_the_numba_backend_readies_the_kernel_that_every_unit_runs(tiny_scene):
    """The argument types `prepare` compiles for are those of any unit: another band, tile, sample range or
    seed (up to 2⁶⁴ − 1) runs the same compiled kernel, never a second compile in the render loop."""
    kernel_scene = compile_scene(tiny_scene)
    numba_row = backends.named("numba")
    assert numba_row.prepare(kernel_scene, 0, None, None) is True
    unit = backends.tile_arguments(kernel_scene, 3, (8, 24), (5, 2, 7, 4), 2**64 - 1)
    assert tuple(numba.typeof(argument) for argument in unit) in numba_row.kernels.render_tile.signatures


def test_a_backend_that_says_cancelled_while_preparing_stops_the_render_before_any_unit(tiny_scene, monkeypatch):
    notices = []

    def cancelled_while_compiling(kernel_scene, seed, cancel, notice):
        notice("Compiling the kernel (about 1 s on this machine)…")
        return False

    numpy = dataclasses.replace(backends.named("numpy"), prepare=cancelled_while_compiling)
    monkeypatch.setattr(backends, "ROWS", (numpy,))
    result = render.render(tiny_scene, backend="numpy", cancel=lambda: False, notice=notices.append)
    assert result.cancelled and notices == ["Compiling the kernel (about 1 s on this machine)…"]
    assert not np.any(result.film.samples)
