"""Blender extension entry point: hands registration to the `addon` package.

Nothing here imports `bpy` at module level, so tools that import the repository root
(packaging, tests) do not need Blender.
"""


def register():
    from .addon import register as register_addon

    register_addon()


def unregister():
    from .addon import unregister as unregister_addon

    unregister_addon()
