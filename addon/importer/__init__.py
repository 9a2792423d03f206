"""Tracer scene → Blender: the exporter's inverse (`import_scene`), and the building blocks it and the
demo files (`demo_blends/`) make Blender data with (`parts`)."""

from .scene import import_scene

__all__ = ["import_scene"]
