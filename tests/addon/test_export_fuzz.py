"""The Blender exporter on randomised scenes (issue 30, item 7), with hypothesis, deterministic and bounded:
Blender's factory scene with random lights, a random volume or surface shader on its cube, a random World
and random object scales, extreme numbers included (0, tiny, huge, infinite, NaN where Blender takes them).
Each example exports to a valid scene that renders a finite image, or is refused with a clear SpectralError
that names Blender's objects, never the exported indices (`lights[0]`). Nothing else may escape."""

import dataclasses
import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from addon.export.scene import export_scene
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from tests.addon.test_blender_scene import factory_scene, volume_shader

bpy = pytest.importorskip("bpy")

EXAMPLES = settings(derandomize=True, deadline=None, database=None, max_examples=40,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
VALUES = st.floats(min_value=0.0, max_value=10.0)
COLOURS = st.tuples(*(st.floats(min_value=0.0, max_value=1.0),) * 3)
EXTREMES = st.sampled_from([0.0, 1e-30, 1e6, 1e30, 1e300, math.inf, -math.inf, math.nan, -1.0, -1e30])
LIGHT = st.fixed_dictionaries({"type": st.sampled_from(["POINT", "SUN", "SPOT", "AREA"]), "energy": VALUES,
                               "color": COLOURS, "use_temperature": st.booleans(),
                               "temperature": st.floats(min_value=800.0, max_value=12000.0),
                               "shape": st.sampled_from(["SQUARE", "RECTANGLE", "DISK", "ELLIPSE"]),
                               "size": VALUES, "exposure": st.sampled_from([0.0, -10.0, 10.0])})
VOLUME = st.fixed_dictionaries({"Density": VALUES, "Color": COLOURS, "Anisotropy": st.floats(-0.9, 0.9),
                                "Emission Strength": VALUES, "Emission Color": COLOURS,
                                "Blackbody Intensity": VALUES, "Temperature": st.floats(0.0, 10000.0)})
SURFACE = st.fixed_dictionaries({"Base Color": COLOURS, "Emission Strength": VALUES, "Emission Color": COLOURS,
                                 "Metallic": st.floats(0.0, 1.0)})
# One setting at an extreme value (or none): where it lands is hypothesis' choice.
TARGETS = ["light energy", "light color", "light temperature", "light size", "cube 0", "cube 1", "cube 2",
           "world", "world colour", "scale"]
SCENES = st.fixed_dictionaries({"light": LIGHT, "cube": st.one_of(VOLUME, SURFACE), "world": VALUES,
                                "world_colour": COLOURS, "scale": st.just(1.0),
                                "extreme": st.one_of(st.none(), st.tuples(st.sampled_from(TARGETS), EXTREMES))})
# A refusal names what it refuses in Blender's terms: a quoted object, light, material or World name, or
# the scene as a whole.
NAMED = re.compile(r"'[^']+'|^the scene has no lights|^render settings")
INDEX = re.compile(r"\b(lights|media|surfaces)\[\d+\]")


def _set(owner, name: str, value) -> None:
    """Set a Blender property or socket value as a user's script would; what Blender itself refuses (a
    TypeError or ValueError from its RNA) is Blender's business, not the exporter's."""
    try:
        if isinstance(value, tuple) and len(getattr(owner, name)) == 4:
            value = (*value, 1.0)
        setattr(owner, name, value)
    except (TypeError, ValueError, OverflowError):
        pass


def _with_extreme(description):
    """The description with its extreme value (if any) put in place."""
    if description["extreme"] is None:
        return description
    target, value = description["extreme"]
    description = {key: dict(item) if isinstance(item, dict) else item for key, item in description.items()}
    if target.startswith("light "):
        key = target.split(" ", 1)[1]
        description["light"][key] = (value,) * 3 if key == "color" else value
    elif target.startswith("cube "):
        key = sorted(description["cube"])[int(target.split()[1])]
        old = description["cube"][key]
        description["cube"][key] = (value,) * 3 if isinstance(old, tuple) else value
    elif target == "world colour":
        description["world_colour"] = (value,) * 3
    else:
        description[target] = value
    return description


def _build(description) -> None:
    description = _with_extreme(description)
    scene = factory_scene(width=6, height=4)
    light = bpy.data.objects["Light"].data
    _set(light, "type", description["light"]["type"])
    light = bpy.data.objects["Light"].data
    for key in ("energy", "color", "use_temperature", "temperature", "shape", "size", "exposure"):
        if hasattr(light, key):
            _set(light, key, description["light"][key])
    cube = bpy.data.objects["Cube"]
    _set(cube, "scale", (description["scale"],) * 3)
    inputs = description["cube"]
    if "Density" in inputs:
        node = volume_shader(cube.active_material)
    else:
        node = cube.active_material.node_tree.nodes["Principled BSDF"]
    for name, value in inputs.items():
        _set(node.inputs[name], "default_value", value)
    background = scene.world.node_tree.nodes["Background"]
    _set(background.inputs["Strength"], "default_value", description["world"])
    _set(background.inputs["Color"], "default_value", description["world_colour"])


@EXAMPLES
@given(description=SCENES)
def test_a_random_blender_scene_exports_and_renders_finite_or_is_refused_naming_blender_objects(registered,
                                                                                                  description):
    _build(description)
    try:
        export = export_scene(bpy.context.evaluated_depsgraph_get())
    except SpectralError as problem:
        message = str(problem)
        assert NAMED.search(message) and not INDEX.search(message), message
        return
    scene = dataclasses.replace(export.scene, settings=dataclasses.replace(export.scene.settings, backend="numpy",
                                                                           max_depth=8))
    try:
        film = render(scene, spp=1).film
    except SpectralError as problem:  # e.g. an image too bright for the float32 outputs
        assert str(problem), description
        return
    assert np.all(np.isfinite(film.xyz)), description
