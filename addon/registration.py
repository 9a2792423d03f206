"""Registers and unregisters every Blender class the add-on defines.

Each Blender-facing module lists its classes in a module-level `CLASSES` tuple (in dependency
order: property groups before the things that point at them), and may list application handlers as
(handler list, function) pairs in `HANDLERS`. This module walks those lists, so adding a class or a
handler means adding it to its module's list, nowhere else.
"""

import bpy

from . import eevee_stand_in
from .cli import command as cli
from .engine import kernel_warmup, render_engine
from .operators import albedo_levels
from .operators import emulation as emulation_operators
from .operators import export as export_operators
from .operators import import_scene as import_operators
from .operators import presets as preset_operators
from .operators import render_image
from .operators import spectrum as spectrum_operators
from .props import attach, curves, light, material, render, spectrum
from .ui import lighting, material as material_ui, passes as passes_ui, presets as preset_ui, render as render_ui
from .ui import sidebar

MODULES = (curves, spectrum, material, light, render, attach, render_engine, eevee_stand_in, kernel_warmup,
           spectrum_operators, preset_operators, albedo_levels, export_operators, import_operators,
           emulation_operators, render_image, preset_ui, material_ui, lighting, render_ui, passes_ui, sidebar, cli)


def register():
    for module in MODULES:
        for cls in module.CLASSES:
            bpy.utils.register_class(cls)
        for handlers, handler in getattr(module, "HANDLERS", ()):
            if handler not in handlers:
                handlers.append(handler)
        if hasattr(module, "register_extras"):
            module.register_extras()


def unregister():
    for module in reversed(MODULES):
        if hasattr(module, "unregister_extras"):
            module.unregister_extras()
        for handlers, handler in getattr(module, "HANDLERS", ()):
            if handler in handlers:
                handlers.remove(handler)
        for cls in reversed(module.CLASSES):
            bpy.utils.unregister_class(cls)
