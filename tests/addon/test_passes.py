"""The engine's passes reach the compositor (without rendering anything)."""

import pytest

bpy = pytest.importorskip("bpy")


def test_compositor_render_layers_offer_the_xyz_passes(registered):
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    tree = bpy.data.node_groups.new("Compositing", "CompositorNodeTree")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    layers.scene = scene
    scene.view_layers[0].update_render_passes()
    outputs = {socket.name for socket in layers.outputs if socket.enabled}
    assert {"Image", "Alpha", "XYZ", "XYZ Variance"} <= outputs
