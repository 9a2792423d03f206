"""The EEVEE Material Preview of spectral materials (`addon.eevee_stand_in`): a Principled Volume on an
EEVEE-only output, kept in step with the spectral settings, beside the user's own nodes."""

import numpy as np
import pytest

from addon import eevee_stand_in
from addon.eevee_stand_in import OUTPUT, PRINCIPLED, sync

bpy = pytest.importorskip("bpy")


def spectral_material(name="Smoke"):
    material = bpy.data.materials.new(name)
    material.spectral.enabled = True
    return material


def test_preview_nodes_show_the_spectral_settings(registered):
    material = spectral_material()
    settings = material.spectral
    settings.density_scale, settings.extinction.value = 5.0, 2.0
    settings.albedo.value, settings.anisotropy.value = 0.3, 0.4
    assert sync(material)
    principled, output = material.node_tree.nodes[PRINCIPLED], material.node_tree.nodes[OUTPUT]
    assert output.target == "EEVEE" and output.is_active_output
    assert output.inputs["Volume"].links[0].from_node == principled
    np.testing.assert_allclose(principled.inputs["Density"].default_value, 10.0, rtol=1e-6)  # 5 × 2 (grey)
    np.testing.assert_allclose(principled.inputs["Anisotropy"].default_value, 0.4, rtol=1e-6)
    colour = np.array(principled.inputs["Color"].default_value[:3])
    np.testing.assert_allclose(colour, 0.3, atol=0.01)  # a grey albedo 0.3 under D65: grey 0.3
    assert not sync(material)  # in step: nothing written, so the depsgraph handler settles


def test_a_chromatic_extinction_is_averaged_as_the_eye_sees_it(registered, tmp_path):
    material = spectral_material()
    extinction = material.spectral.extinction
    extinction.source = "CSV"
    assert eevee_stand_in.preview_values(material.spectral)["Density"] == 0.0  # no file yet: an error counts 0
    # 100 in the UV, where the eye sees nothing, and 2 over the visible: the preview shows 2.
    rows = [(nm, 100.0 if nm < 370 else 2.0) for nm in range(250, 831)]
    (tmp_path / "extinction.csv").write_text("".join(f"{nm},{value}\n" for nm, value in rows))
    extinction.filepath = str(tmp_path / "extinction.csv")
    assert eevee_stand_in.preview_values(material.spectral)["Density"] == pytest.approx(2.0, rel=1e-3)


def test_the_users_nodes_stay_and_plain_materials_are_left_alone(registered):
    material = spectral_material()
    names = {node.name for node in material.node_tree.nodes}
    sync(material)
    assert {node.name for node in material.node_tree.nodes} == names | {PRINCIPLED, OUTPUT}
    plain = bpy.data.materials.new("Plain")
    before = {node.name for node in plain.node_tree.nodes}
    assert not sync(plain)
    assert {node.name for node in plain.node_tree.nodes} == before


def test_edits_reach_the_preview_through_the_depsgraph_handler(registered):
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    material = spectral_material()
    bpy.ops.mesh.primitive_cube_add()
    bpy.context.object.data.materials.append(material)
    assert eevee_stand_in.sync_updated in bpy.app.handlers.depsgraph_update_post
    material.spectral.density_scale = 7.0
    material.update_tag()
    bpy.context.view_layer.update()  # runs the depsgraph_update_post handlers
    principled = material.node_tree.nodes[PRINCIPLED]
    np.testing.assert_allclose(principled.inputs["Density"].default_value, 7.0, rtol=1e-6)


def test_switching_to_the_engine_syncs_every_spectral_material(registered):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    material = spectral_material()
    bpy.context.view_layer.update()
    assert PRINCIPLED not in material.node_tree.nodes  # another engine: the material is left alone
    scene.render.engine = "SPECTRAL_VOLUME"
    bpy.context.view_layer.update()
    assert PRINCIPLED in material.node_tree.nodes
