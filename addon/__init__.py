"""The Blender side of the extension: properties, operators, panels, export and engine.

`addon.tracer` is the Blender-free path tracer; importing it must never import `bpy`, so this
package's own import is free of `bpy` too and the Blender modules load only in `register()`.
"""


def register():
    from . import registration

    registration.register()


def unregister():
    from . import registration

    registration.unregister()
