"""Export: the Blender scene as a tracer Scene (addon.tracer.scene), a pure data transformation."""
