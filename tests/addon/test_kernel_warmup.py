"""The kernel starts compiling in the background once a scene renders with this engine's local kernel
(addon/engine/kernel_warmup.py): after a switch to the engine or loading a file that uses it, not otherwise."""

import pytest

from addon.engine import kernel_warmup
from addon.props.render import ENGINE_ID
from addon.tracer import background_compile

bpy = pytest.importorskip("bpy")


@pytest.fixture
def starts(registered, monkeypatch):
    """The starts of a background compile (none really started), in a registered add-on."""
    calls = []
    monkeypatch.setattr(background_compile, "started", lambda: bool(calls))
    monkeypatch.setattr(background_compile, "start", lambda: calls.append(bpy.context.scene.name) or True)
    return calls


def test_switching_to_the_engine_starts_the_compile_once(starts):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    bpy.context.view_layer.update()
    assert starts == []
    scene.render.engine = ENGINE_ID
    bpy.context.view_layer.update()
    assert starts == [scene.name]
    scene.render.engine = "CYCLES"
    scene.render.engine = ENGINE_ID
    bpy.context.view_layer.update()
    assert starts == [scene.name]


@pytest.mark.parametrize("setting, value", [("backend", "numpy"), ("scheduler_address", "tcp://farm:8786"),
                                            ("device", "GPU")])
def test_no_compile_where_the_local_kernel_is_not_used(starts, setting, value):
    scene = bpy.context.scene
    setattr(scene.spectral, setting, value)
    scene.render.engine = ENGINE_ID
    bpy.context.view_layer.update()
    assert starts == []


def test_loading_a_file_that_uses_the_engine_starts_the_compile(starts, tmp_path):
    bpy.context.scene.render.engine = ENGINE_ID
    path = str(tmp_path / "uses_engine.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    starts.clear()
    assert kernel_warmup.warm_up_on_load in bpy.app.handlers.load_post
    bpy.ops.wm.open_mainfile(filepath=path)
    assert starts
    starts.clear()
    kernel_warmup.warm_up_on_load()
    assert starts == [bpy.context.scene.name]
