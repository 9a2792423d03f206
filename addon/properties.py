"""Settings the add-on stores in the .blend file (PropertyGroups) and where they attach."""

import bpy


class SpectralRenderSettings(bpy.types.PropertyGroup):
    """Per-scene render settings of the spectral tracer."""

    samples: bpy.props.IntProperty(
        name="Samples", description="Paths per pixel", default=64, min=1, soft_max=4096
    )
    seed: bpy.props.IntProperty(
        name="Seed", description="Random seed: the same seed gives the same image", default=0, min=0
    )


CLASSES = (SpectralRenderSettings,)


def register_extras():
    bpy.types.Scene.spectral = bpy.props.PointerProperty(type=SpectralRenderSettings)


def unregister_extras():
    del bpy.types.Scene.spectral
