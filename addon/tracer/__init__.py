"""The spectral volume path tracer: a plain Python package that never imports `bpy`.

Usable alone (`python -m addon.tracer ...`), from the add-on, and on distributed workers.
"""
